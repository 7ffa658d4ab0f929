//! The viewport on the GPU: the renderer's surface shading (`shaders/surface.wgsl`, fragment stage)
//! fed by a vertex stage that pulls shared vertices through an index buffer (`pulled.wgsl`), drawn
//! into the editor's own colour, depth and multisample targets. egui shows the resolved colour target
//! as a texture, so the 3D view has a depth buffer whatever egui's own pass has, and the same
//! picture serves for screenshots and the tests.

use embedding::Point3;

use super::drag::DragRow;
use super::mesh::LiveMesh;
use crate::render::gpu::{DEPTH_FORMAT, FrameUniforms};
use crate::render::{Image, RenderError};

/// The colour format egui accepts for native textures.
pub const COLOUR_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
/// Multisampling for smooth silhouettes.
pub const SAMPLES: u32 = 4;
/// The viewport's background (sRGB values, as the shader writes its colours).
pub const BACKGROUND: [f64; 3] = [0.19, 0.20, 0.22];

struct MeshBuffers {
    vertices: wgpu::Buffer,
    // Held by the bind group too; kept here to say what the mesh owns.
    _indices: wgpu::Buffer,
    vertex_count: usize,
    index_count: u32,
    group: wgpu::BindGroup,
}

/// The colour, resolve and depth targets for one size.
struct Targets {
    size: [u32; 2],
    msaa: wgpu::TextureView,
    resolved: wgpu::Texture,
    resolved_view: wgpu::TextureView,
    depth: wgpu::TextureView,
}

/// Pipelines, buffers and targets of the viewport.
pub struct ViewportRenderer {
    pipeline: wgpu::RenderPipeline,
    uniforms: wgpu::Buffer,
    frame_group: wgpu::BindGroup,
    mesh_layout: wgpu::BindGroupLayout,
    mesh: Option<MeshBuffers>,
    /// The drag rows of the last drag plan uploaded (its id), and the displacement uniform.
    drag_rows: wgpu::Buffer,
    drag_id: u64,
    drag_uniform: wgpu::Buffer,
    drag_delta: [f32; 4],
    targets: Option<Targets>,
    /// Bumped whenever the resolved texture is made anew (egui must be told).
    pub generation: u64,
    /// Bytes of vertices uploaded by the last [`ViewportRenderer::sync`], and of drag rows by the
    /// last drag start.
    pub last_upload: usize,
    pub last_drag_upload: usize,
}

impl ViewportRenderer {
    pub fn new(device: &wgpu::Device) -> ViewportRenderer {
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("ntori editor frame"),
            size: std::mem::size_of::<FrameUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let frame_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("ntori editor frame"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            }],
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
        let mesh_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("ntori editor mesh"),
            entries: &[
                storage(0),
                storage(1),
                storage(2),
                wgpu::BindGroupLayoutEntry {
                    binding: 3,
                    visibility: wgpu::ShaderStages::VERTEX,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: false,
                        min_binding_size: None,
                    },
                    count: None,
                },
            ],
        });
        let drag_uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("ntori editor drag"),
            size: 16,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let drag_rows = drag_buffer(device, &[]);
        let frame_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("ntori editor frame"),
            layout: &frame_layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: uniforms.as_entire_binding(),
            }],
        });
        let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("ntori editor"),
            bind_group_layouts: &[Some(&frame_layout), Some(&mesh_layout)],
            immediate_size: 0,
        });
        let source = format!(
            "{}\n{}",
            include_str!("../../shaders/surface.wgsl"),
            include_str!("pulled.wgsl")
        );
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("ntori editor surface"),
            source: wgpu::ShaderSource::Wgsl(source.into()),
        });
        let pipeline = device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
            label: Some("ntori editor surface"),
            layout: Some(&layout),
            vertex: wgpu::VertexState {
                module: &module,
                entry_point: Some("vs_pulled"),
                compilation_options: Default::default(),
                buffers: &[],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
                // Two-sided: the shader lights whichever side faces the camera.
                cull_mode: None,
                ..Default::default()
            },
            depth_stencil: Some(wgpu::DepthStencilState {
                format: DEPTH_FORMAT,
                depth_write_enabled: Some(true),
                depth_compare: Some(wgpu::CompareFunction::LessEqual),
                stencil: Default::default(),
                bias: Default::default(),
            }),
            multisample: wgpu::MultisampleState {
                count: SAMPLES,
                ..Default::default()
            },
            fragment: Some(wgpu::FragmentState {
                module: &module,
                entry_point: Some("fs_main"),
                compilation_options: Default::default(),
                targets: &[Some(wgpu::ColorTargetState {
                    format: COLOUR_FORMAT,
                    blend: None,
                    write_mask: wgpu::ColorWrites::ALL,
                })],
            }),
            multiview_mask: None,
            cache: None,
        });
        ViewportRenderer {
            pipeline,
            uniforms,
            frame_group,
            mesh_layout,
            mesh: None,
            drag_rows,
            drag_id: 0,
            drag_uniform,
            drag_delta: [0.0; 4],
            targets: None,
            generation: 0,
            last_upload: 0,
            last_drag_upload: 0,
        }
    }

    /// Brings the GPU's copy of the mesh up to date: new buffers after a new tessellation, else
    /// only the vertex ranges that changed.
    /// Brings the GPU's copy of the mesh up to date: new buffers after a new tessellation, else
    /// only the vertex ranges that changed; and the drag in progress (its rows once per drag, the
    /// displacement every time). Returns whether anything the picture depends on changed.
    pub fn sync(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        mesh: &mut LiveMesh,
        drag: Option<(u64, &[DragRow], Point3)>,
    ) -> bool {
        let mut new_group = false;
        if let Some((id, rows, _)) = drag
            && id != self.drag_id
        {
            self.drag_rows = drag_buffer(device, rows);
            self.drag_id = id;
            self.last_drag_upload = std::mem::size_of_val(rows);
            new_group = true;
        }
        let delta = drag.map_or([0.0; 4], |(_, _, d)| {
            [d.x as f32, d.y as f32, d.z as f32, 0.0]
        });
        let moved = delta != self.drag_delta;
        if moved {
            queue.write_buffer(&self.drag_uniform, 0, bytemuck::cast_slice(&delta));
            self.drag_delta = delta;
        }
        let count = mesh.vertex_count();
        let new_buffers = self.mesh.as_ref().is_none_or(|m| m.vertex_count != count);
        let written = match &self.mesh {
            Some(buffers) if !new_buffers => mesh.upload(false, |offset, bytes| {
                queue.write_buffer(&buffers.vertices, offset, bytes)
            }),
            _ => mesh.upload(true, |_, _| {}),
        };
        self.last_upload = match written {
            Some(bytes) => bytes,
            None => {
                self.mesh = Some(self.upload(device, mesh));
                std::mem::size_of_val(mesh.vertices()) + 4 * mesh.indices().len()
            }
        };
        if new_group
            && written.is_some()
            && let Some(buffers) = &mut self.mesh
        {
            buffers.group = mesh_group(
                device,
                &self.mesh_layout,
                &buffers.vertices,
                &buffers._indices,
                &self.drag_rows,
                &self.drag_uniform,
            );
        }
        new_group || moved || written != Some(0)
    }

    fn upload(&self, device: &wgpu::Device, mesh: &LiveMesh) -> MeshBuffers {
        use wgpu::util::DeviceExt as _;
        let vertices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("ntori editor vertices"),
            contents: bytemuck::cast_slice(&nonempty(mesh.vertices())),
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        });
        let indices = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("ntori editor indices"),
            contents: bytemuck::cast_slice(&nonempty(mesh.indices())),
            usage: wgpu::BufferUsages::STORAGE,
        });
        let group = mesh_group(
            device,
            &self.mesh_layout,
            &vertices,
            &indices,
            &self.drag_rows,
            &self.drag_uniform,
        );
        MeshBuffers {
            vertices,
            _indices: indices,
            vertex_count: mesh.vertex_count(),
            index_count: mesh.indices().len() as u32,
            group,
        }
    }

    /// Draws the mesh into the targets (made anew when the size changed; see
    /// [`ViewportRenderer::texture_view`]).
    pub fn render(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        size: [u32; 2],
        frame: &FrameUniforms,
    ) {
        let size = [size[0].max(1), size[1].max(1)];
        if self.targets.as_ref().is_none_or(|t| t.size != size) {
            self.targets = Some(targets(device, size));
            self.generation += 1;
        }
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(frame));
        let Some(targets) = &self.targets else {
            unreachable!("made above")
        };
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("ntori editor viewport"),
        });
        {
            let [r, g, b] = BACKGROUND;
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("ntori editor viewport"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &targets.msaa,
                    depth_slice: None,
                    resolve_target: Some(&targets.resolved_view),
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color { r, g, b, a: 1.0 }),
                        store: wgpu::StoreOp::Discard,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &targets.depth,
                    depth_ops: Some(wgpu::Operations {
                        load: wgpu::LoadOp::Clear(1.0),
                        store: wgpu::StoreOp::Discard,
                    }),
                    stencil_ops: None,
                }),
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            if let Some(mesh) = &self.mesh
                && mesh.index_count > 0
            {
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, &self.frame_group, &[]);
                pass.set_bind_group(1, &mesh.group, &[]);
                pass.draw(0..mesh.index_count, 0..1);
            }
        }
        queue.submit([encoder.finish()]);
    }

    /// The last rendered picture, read back from the GPU.
    pub fn read_back(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
    ) -> Result<Image, RenderError> {
        let Some(targets) = &self.targets else {
            return Err(RenderError::Readback("nothing has been drawn yet".into()));
        };
        let encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("ntori editor readback"),
        });
        crate::render::read_texture(device, queue, encoder, &targets.resolved, targets.size)
    }

    /// The resolved colour target, if anything was drawn.
    pub fn texture_view(&self) -> Option<&wgpu::TextureView> {
        self.targets.as_ref().map(|t| &t.resolved_view)
    }
}

fn mesh_group(
    device: &wgpu::Device,
    layout: &wgpu::BindGroupLayout,
    vertices: &wgpu::Buffer,
    indices: &wgpu::Buffer,
    drag_rows: &wgpu::Buffer,
    drag_uniform: &wgpu::Buffer,
) -> wgpu::BindGroup {
    fn entry(binding: u32, buffer: &wgpu::Buffer) -> wgpu::BindGroupEntry<'_> {
        wgpu::BindGroupEntry {
            binding,
            resource: buffer.as_entire_binding(),
        }
    }
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("ntori editor mesh"),
        layout,
        entries: &[
            entry(0, vertices),
            entry(1, indices),
            entry(2, drag_rows),
            entry(3, drag_uniform),
        ],
    })
}

fn drag_buffer(device: &wgpu::Device, rows: &[DragRow]) -> wgpu::Buffer {
    use wgpu::util::DeviceExt as _;
    device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("ntori editor drag rows"),
        contents: bytemuck::cast_slice(&nonempty(rows)),
        usage: wgpu::BufferUsages::STORAGE,
    })
}

/// wgpu refuses empty buffers bound as storage: give it one zero element.
fn nonempty<T: bytemuck::Pod + bytemuck::Zeroable>(data: &[T]) -> std::borrow::Cow<'_, [T]> {
    if data.is_empty() {
        std::borrow::Cow::Owned(vec![T::zeroed()])
    } else {
        std::borrow::Cow::Borrowed(data)
    }
}

fn targets(device: &wgpu::Device, [width, height]: [u32; 2]) -> Targets {
    let texture = |label, format, samples, usage| {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d {
                width,
                height,
                depth_or_array_layers: 1,
            },
            mip_level_count: 1,
            sample_count: samples,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    let attachment = wgpu::TextureUsages::RENDER_ATTACHMENT;
    let msaa = texture("ntori editor msaa", COLOUR_FORMAT, SAMPLES, attachment);
    let resolved = texture(
        "ntori editor picture",
        COLOUR_FORMAT,
        1,
        attachment | wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_SRC,
    );
    let depth = texture("ntori editor depth", DEPTH_FORMAT, SAMPLES, attachment);
    Targets {
        size: [width, height],
        msaa: msaa.create_view(&Default::default()),
        resolved_view: resolved.create_view(&Default::default()),
        resolved,
        depth: depth.create_view(&Default::default()),
    }
}
