//! abut's contact page: beads poured onto an inclined rigid plate, their contact computed each
//! increment by abut's kernels device-resident on the page's WebGPU device (the penalty
//! increment and the central-difference integrator recorded together, nothing waited for),
//! drawn with WebGPU from the same buffers: the plate coloured by contact pressure (each node's
//! force over its tributary area), the beads by whether they touch it. `web/index.html` drives it: [`Page::start`] once per setting,
//! then [`Page::advance`] once per animation frame, which reports what the plot and the
//! panel show. Natively this crate is empty.
#![cfg(target_arch = "wasm32")]

mod render;

use std::cell::RefCell;
use std::rc::Rc;
use std::sync::{Arc, Mutex};

use abut::testing::incline::{summary, InclineGpu};
use abut::testing::scenes::{incline, Incline, InclineSettings};
use abut::Sliding;
use wasm_bindgen::prelude::*;

/// An error for the page: abut's message, or what failed.
fn js(e: impl std::fmt::Display) -> JsValue {
    JsValue::from_str(&e.to_string())
}

/// The running scene and what draws it.
struct State {
    device: abut::Device,
    wgpu: (wgpu::Device, wgpu::Queue),
    scene: Incline,
    run: InclineGpu,
    renderer: render::Renderer,
    /// MAP_READ copy of the last increment's forces and the positions (for the numbers).
    readback: wgpu::Buffer,
    /// The page's uncaptured WebGPU errors and a lost device's message.
    errors: Arc<Mutex<Vec<String>>>,
    increments: u64,
}

/// The page's scene on its WebGPU device (one per setting of the controls).
#[wasm_bindgen]
pub struct Page {
    state: Rc<RefCell<State>>,
}

#[wasm_bindgen]
impl Page {
    /// Starts the scene in `canvas` with `beads` beads, Coulomb `friction`, the penalty
    /// stiffness scaled by `penalty_scale` and small sliding when `small_sliding`: asks the
    /// browser for a WebGPU adapter and device (without blocking), hands them to abut, builds
    /// the scene and uploads it.
    pub async fn start(
        canvas: web_sys::HtmlCanvasElement,
        beads: u32,
        friction: f64,
        penalty_scale: f64,
        small_sliding: bool,
    ) -> Result<Page, JsValue> {
        let settings = InclineSettings {
            beads: beads as usize,
            friction,
            penalty_scale,
            sliding: if small_sliding {
                Sliding::Small
            } else {
                Sliding::Finite
            },
            ..Default::default()
        };
        let scene = incline(&settings).map_err(js)?;
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::BROWSER_WEBGPU;
        let instance = wgpu::Instance::new(desc);
        let (width, height) = (canvas.width(), canvas.height());
        let surface = instance
            .create_surface(wgpu::SurfaceTarget::Canvas(canvas))
            .map_err(js)?;
        let adapter = instance
            .request_adapter(&wgpu::RequestAdapterOptions {
                power_preference: wgpu::PowerPreference::HighPerformance,
                compatible_surface: Some(&surface),
                ..Default::default()
            })
            .await
            .map_err(|e| js(format!("no WebGPU adapter ({e}): this page needs WebGPU")))?;
        let (d, q) = adapter
            .request_device(&wgpu::DeviceDescriptor {
                label: Some("abut page"),
                required_limits: adapter.limits(),
                ..Default::default()
            })
            .await
            .map_err(js)?;
        // what the page's own drawing does wrong, and a lost device, reported on the console
        // and by the next advance (abut's own passes report through their error scopes)
        let errors: Arc<Mutex<Vec<String>>> = Arc::default();
        let sink = errors.clone();
        d.on_uncaptured_error(Arc::new(move |e| {
            web_sys::console::error_1(&format!("WebGPU: {e}").into());
            if let Ok(mut list) = sink.lock() {
                list.push(e.to_string());
            }
        }));
        let sink = errors.clone();
        d.set_device_lost_callback(move |reason, message| {
            web_sys::console::error_1(
                &format!("WebGPU device lost ({reason:?}): {message}").into(),
            );
            if let Ok(mut list) = sink.lock() {
                list.push(format!("device lost: {message}"));
            }
        });
        let device = abut::Device::from_wgpu(d.clone(), q.clone()).map_err(js)?;
        let run = InclineGpu::new(&device, &scene).map_err(js)?;
        let renderer = render::Renderer::new(&d, &adapter, surface, width, height, &scene, &run)?;
        let bytes = (2 * run.n_nodes * 16) as u64;
        let readback = d.create_buffer(&wgpu::BufferDescriptor {
            label: Some("page readback"),
            size: bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        Ok(Page {
            state: Rc::new(RefCell::new(State {
                device,
                wgpu: (d, q),
                scene,
                run,
                renderer,
                readback,
                errors,
                increments: 0,
            })),
        })
    }

    /// The contact pressure at the top of the plate's colour ramp (Pa).
    pub fn pressure_scale(&self) -> f64 {
        f64::from(render::PRESSURE_SCALE)
    }

    /// The increment (s).
    pub fn dt(&self) -> f64 {
        self.state.borrow().scene.dt
    }

    /// The beads' total weight across the plate, m·g·cos(slope)·beads (N): what the normal
    /// contact force settles to while every bead lies on it.
    pub fn weight_normal(&self) -> f64 {
        let s = self.state.borrow();
        let n = (s.scene.beads.end - s.scene.beads.start) as f64;
        -s.scene.gravity[2] * s.scene.bead_mass * n
    }

    /// Runs `increments` increments on the device, draws the frame and reads the numbers back
    /// (awaited, not blocking): a JSON object with the increments run, the simulated time (s),
    /// the wall time of this call per increment (ms, the readback's wait included), the beads
    /// on the plate, their mean position (m) and the total normal contact force (N).
    pub fn advance(&self, increments: u32) -> js_sys::Promise {
        let state = self.state.clone();
        wasm_bindgen_futures::future_to_promise(async move {
            let mut s = state
                .try_borrow_mut()
                .map_err(|_| js("advance called again before the last one finished"))?;
            let now = || {
                web_sys::window()
                    .and_then(|w| w.performance())
                    .map_or(0.0, |p| p.now())
            };
            let t0 = now();
            let s = &mut *s;
            let (d, q) = (&s.wgpu.0, &s.wgpu.1);
            let mut enc = d.create_command_encoder(&Default::default());
            s.run
                .encode(&mut enc, increments as usize, s.scene.dt)
                .map_err(js)?;
            let row = (s.run.n_nodes * 16) as u64;
            enc.copy_buffer_to_buffer(&s.run.last_forces, 0, &s.readback, 0, row);
            enc.copy_buffer_to_buffer(&s.run.positions, 0, &s.readback, row, row);
            q.submit([enc.finish()]);
            s.renderer.draw(d, q)?;
            s.increments += u64::from(increments);
            let (tx, rx) = futures_channel::oneshot::channel();
            s.readback
                .slice(..)
                .map_async(wgpu::MapMode::Read, move |r| {
                    let _ = tx.send(r);
                });
            let _ = d.poll(wgpu::PollType::Poll);
            let mapped = rx.await.map_err(js)?;
            let errors = s.errors.lock().map(|e| e.join("; ")).unwrap_or_default();
            if !errors.is_empty() {
                return Err(js(errors));
            }
            mapped.map_err(js)?;
            let (forces, positions): (Vec<[f32; 4]>, Vec<[f32; 4]>) = {
                let view = s.readback.slice(..).get_mapped_range().map_err(js)?;
                (
                    bytemuck::pod_collect_to_vec(&view[..row as usize]),
                    bytemuck::pod_collect_to_vec(&view[row as usize..]),
                )
            };
            s.readback.unmap();
            s.run.collect().map_err(js)?;
            if let abut::device::DeviceKind::Gpu(ctx) = s.device.kind() {
                ctx.take_uncaptured("the page's increments").map_err(js)?;
            }
            let t1 = now();
            let [on, mx, my, mz, normal] = summary(&s.scene, &positions, &forces);
            Ok(JsValue::from_str(&format!(
                "{{\"increments\":{},\"time\":{},\"ms_per_increment\":{},\"on_plate\":{},\
                 \"mean\":[{},{},{}],\"normal_force\":{}}}",
                s.increments,
                s.increments as f64 * s.scene.dt,
                (t1 - t0) / f64::from(increments.max(1)),
                on,
                mx,
                my,
                mz,
                normal
            )))
        })
    }
}
