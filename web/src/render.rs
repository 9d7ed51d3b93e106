//! Draws the page's scene with WebGPU from abut's increment buffers (`scene.wgsl`): the plate
//! coloured by the contact pressure at its nodes (nodal force over tributary area), the beads
//! as discs.

use abut::testing::incline::InclineGpu;
use abut::testing::scenes::Incline;
use glam::{Mat4, Vec3, Vec4};
use wasm_bindgen::JsValue;
use wgpu::util::DeviceExt;

/// The uniform of `scene.wgsl` (`View`).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct View {
    view_proj: [[f32; 4]; 4],
    right: [f32; 4],
    up: [f32; 4],
    params: [f32; 4],
}

/// The canvas, its pipelines and the bind group over the increment's buffers.
pub struct Renderer {
    surface: wgpu::Surface<'static>,
    depth: wgpu::TextureView,
    plate: wgpu::RenderPipeline,
    beads: wgpu::RenderPipeline,
    bind: wgpu::BindGroup,
    quads: u32,
    bead_count: u32,
}

/// The contact pressure at the top of the colour ramp (Pa): the beads' weight, 1,024 of them
/// spread over the plate's 2 m², four times over.
pub const PRESSURE_SCALE: f32 = 200.0;

/// Each plate node's tributary area (m²): a quarter of every quad around it.
fn tributary_areas(scene: &Incline) -> Vec<f32> {
    let x = scene.model.positions();
    let mut areas = vec![0.0f32; scene.beads.start as usize];
    for q in &scene.plate_quads {
        let p = |k: usize| glam::DVec3::from_array(x[q[k] as usize]);
        let area = 0.5 * (p(2) - p(0)).cross(p(3) - p(1)).length();
        for &n in q {
            areas[n as usize] += (area / 4.0) as f32;
        }
    }
    // a node of no quad draws nothing
    areas
        .iter()
        .map(|&a| if a > 0.0 { a } else { 1.0 })
        .collect()
}

/// The camera over the inclined plate: the model turned so that gravity points down the
/// screen, seen from the front and above.
fn view(scene: &Incline, aspect: f32) -> View {
    let g = scene.gravity;
    let slope = (g[0] as f32).atan2(-(g[2] as f32));
    let turn = Mat4::from_rotation_y(slope);
    let centre = turn.transform_point3(Vec3::new(1.0, 0.5, 0.0));
    let eye = centre + Vec3::new(0.3, -1.9, 1.5);
    let look = Mat4::look_at_rh(eye, centre, Vec3::Z);
    let proj = Mat4::perspective_rh(0.7, aspect, 0.05, 20.0);
    let forward = (centre - eye).normalize();
    let right = forward.cross(Vec3::Z).normalize();
    let up = right.cross(forward);
    // camera axes back in the model frame: the inverse (transpose) turn
    let back = turn.transpose();
    let r = back.transform_vector3(right);
    let u = back.transform_vector3(up);
    View {
        view_proj: (proj * look * turn).to_cols_array_2d(),
        right: Vec4::from((r, 0.0)).to_array(),
        up: Vec4::from((u, 0.0)).to_array(),
        params: [PRESSURE_SCALE, 0.014, scene.beads.start as f32, 0.0],
    }
}

impl Renderer {
    /// Configures `surface` (`width` × `height`) on `d` and builds the pipelines and the bind
    /// group over `run`'s positions and forces.
    pub fn new(
        d: &wgpu::Device,
        adapter: &wgpu::Adapter,
        surface: wgpu::Surface<'static>,
        width: u32,
        height: u32,
        scene: &Incline,
        run: &InclineGpu,
    ) -> Result<Self, JsValue> {
        let config = surface
            .get_default_config(adapter, width.max(1), height.max(1))
            .ok_or_else(|| JsValue::from_str("the canvas does not support this adapter"))?;
        surface.configure(d, &config);
        let depth = d
            .create_texture(&wgpu::TextureDescriptor {
                label: Some("page depth"),
                size: wgpu::Extent3d {
                    width: config.width,
                    height: config.height,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Depth32Float,
                usage: wgpu::TextureUsages::RENDER_ATTACHMENT,
                view_formats: &[],
            })
            .create_view(&Default::default());
        let uniform = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("page view"),
            contents: bytemuck::bytes_of(&view(scene, config.width as f32 / config.height as f32)),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let quad_ids: Vec<[u32; 4]> = scene.plate_quads.clone();
        let quads = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("plate quads"),
            contents: bytemuck::cast_slice(&quad_ids),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let areas = d.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("plate node areas"),
            contents: bytemuck::cast_slice(&tributary_areas(scene)),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let module = d.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("scene.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("scene.wgsl").into()),
        });
        let storage = |binding| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::VERTEX,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only: true },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let layout = d.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("page scene"),
            entries: &[
                wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
                storage(1),
                storage(2),
                storage(3),
                storage(4),
            ],
        });
        let bind = d.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("page scene"),
            layout: &layout,
            entries: &[
                wgpu::BindGroupEntry {
                    binding: 0,
                    resource: uniform.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 1,
                    resource: run.positions.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 2,
                    resource: run.last_forces.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 3,
                    resource: quads.as_entire_binding(),
                },
                wgpu::BindGroupEntry {
                    binding: 4,
                    resource: areas.as_entire_binding(),
                },
            ],
        });
        let pl = d.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("page scene"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = |vs: &str, fs: &str| {
            d.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(vs),
                layout: Some(&pl),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some(vs),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some(fs),
                    compilation_options: Default::default(),
                    targets: &[Some(config.format.into())],
                }),
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: wgpu::TextureFormat::Depth32Float,
                    depth_write_enabled: Some(true),
                    depth_compare: Some(wgpu::CompareFunction::Less),
                    stencil: Default::default(),
                    bias: Default::default(),
                }),
                multisample: Default::default(),
                multiview_mask: None,
                cache: None,
            })
        };
        Ok(Self {
            surface,
            depth,
            plate: pipeline("plate_vs", "plate_fs"),
            beads: pipeline("bead_vs", "bead_fs"),
            bind,
            quads: scene.plate_quads.len() as u32,
            bead_count: scene.beads.end - scene.beads.start,
        })
    }

    /// Draws the current state into the canvas and presents it.
    pub fn draw(&mut self, d: &wgpu::Device, q: &wgpu::Queue) -> Result<(), JsValue> {
        let frame = match self.surface.get_current_texture() {
            wgpu::CurrentSurfaceTexture::Success(t)
            | wgpu::CurrentSurfaceTexture::Suboptimal(t) => t,
            // nothing to draw into this frame (hidden, resized): the next frame tries again
            _ => return Ok(()),
        };
        let target = frame.texture.create_view(&Default::default());
        let mut enc = d.create_command_encoder(&Default::default());
        {
            let mut pass = enc.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("page scene"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color {
                            r: 0.96,
                            g: 0.96,
                            b: 0.97,
                            a: 1.0,
                        }),
                        store: wgpu::StoreOp::Store,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &self.depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                ..Default::default()
            });
            pass.set_bind_group(0, &self.bind, &[]);
            pass.set_pipeline(&self.plate);
            pass.draw(0..6 * self.quads, 0..1);
            pass.set_pipeline(&self.beads);
            pass.draw(0..6, 0..self.bead_count);
        }
        q.submit([enc.finish()]);
        q.present(frame);
        Ok(())
    }
}
