//! The compute pipelines of one device, compiled once: the first executor that needs a pass
//! compiles its shader module and pipeline, every later one (another pair, a balanced pair's
//! second side, a new `Contact` on the same device) gets the same pipeline back. Compilations are
//! counted in the device's [`Traffic`](super::Traffic).

use std::collections::HashMap;

use super::GpuContext;
use crate::abi::passes::Pass;
use crate::error::{Error, Result};

/// A pipeline's key: shader stem, entry point and the bits of its overridable constants.
type Key = (&'static str, &'static str, Vec<(&'static str, u64)>);

/// Shader modules by stem and pipelines by key, for one device.
#[derive(Default)]
pub(crate) struct PipelineCache {
    modules: HashMap<&'static str, wgpu::ShaderModule>,
    pipelines: HashMap<Key, wgpu::ComputePipeline>,
}

impl GpuContext {
    /// The pipeline of `pass` with the pipeline-overridable `constants`, compiled (with its
    /// shader module, preludes prepended) on first use and kept for the device's lifetime. A
    /// validation error names the pass.
    pub(crate) fn pipeline(
        &self,
        pass: &'static Pass,
        constants: &[(&'static str, f64)],
    ) -> Result<wgpu::ComputePipeline> {
        let key: Key = (
            pass.stem,
            pass.entry,
            constants.iter().map(|&(n, v)| (n, v.to_bits())).collect(),
        );
        let mut cache = self.pipelines.lock().map_err(|_| Error::Gpu {
            during: format!("compiling {}::{}", pass.stem, pass.entry),
            message: "the pipeline cache was poisoned by a panic".into(),
        })?;
        if let Some(p) = cache.pipelines.get(&key) {
            return Ok(p.clone());
        }
        let d = &self.device;
        let scope = d.push_error_scope(wgpu::ErrorFilter::Validation);
        let mut compiled_module = false;
        if !cache.modules.contains_key(pass.stem) {
            let Some(src) = crate::abi::shaders::source(pass.stem) else {
                let _ = self.scope_error(scope);
                return Err(Error::Gpu {
                    during: "compiling the pipelines".into(),
                    message: format!("no kernel file '{}'", pass.stem),
                });
            };
            let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(pass.stem),
                source: wgpu::ShaderSource::Wgsl(src.into()),
            });
            cache.modules.insert(pass.stem, module);
            compiled_module = true;
        }
        let pipeline = d.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(pass.entry),
            layout: None,
            module: &cache.modules[pass.stem],
            entry_point: Some(pass.entry),
            compilation_options: wgpu::PipelineCompilationOptions {
                constants,
                ..Default::default()
            },
            cache: None,
        });
        if let Some(e) = self.scope_error(scope) {
            if compiled_module {
                cache.modules.remove(pass.stem);
            }
            return Err(Error::Gpu {
                during: format!("compiling {}::{}", pass.stem, pass.entry),
                message: e.to_string(),
            });
        }
        cache.pipelines.insert(key, pipeline.clone());
        if let Ok(mut t) = self.traffic.lock() {
            t.shader_modules_compiled += compiled_module as u64;
            t.pipelines_compiled += 1;
        }
        Ok(pipeline)
    }
}
