//! The viewport on the GPU: the renderer's surface shading (`shaders/frame.wgsl` and
//! `shaders/surface.wgsl`, fragment stage) fed by a vertex stage that pulls shared vertices through
//! an index buffer (`shaders/pulled.wgsl`), drawn into the editor's own colour, depth and
//! multisample targets. egui shows the resolved colour target as a texture, so the 3D view has a
//! depth buffer whatever egui's own pass has, and the same picture serves for screenshots and the
//! tests. The uniforms, the pipeline, the targets and the read-back are the offscreen renderer's
//! ([`crate::render::gpu`]).

use embedding::Vector3;

use super::drag::DragRow;
use super::mesh::LiveMesh;
use crate::render::gpu::{
    FrameBinding, FrameUniforms, PipelineSpec, Targets, buffer_entry, pipeline, pipeline_layout,
};
use crate::render::{Image, RenderError, check_buffer};

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

/// Pipelines, buffers and targets of the viewport.
pub struct ViewportRenderer {
    pipeline: wgpu::RenderPipeline,
    frame: FrameBinding,
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
        let frame = FrameBinding::new(device, "ntori editor frame");
        let vertex_buffer = |binding, ty| buffer_entry(binding, wgpu::ShaderStages::VERTEX, ty);
        let storage = wgpu::BufferBindingType::Storage { read_only: true };
        let mesh_layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("ntori editor mesh"),
            entries: &[
                vertex_buffer(0, storage),
                vertex_buffer(1, storage),
                vertex_buffer(2, storage),
                vertex_buffer(3, wgpu::BufferBindingType::Uniform),
            ],
        });
        let drag_uniform = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("ntori editor drag"),
            size: 16,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let drag_rows = drag_buffer(device, &[]);
        let layout = pipeline_layout(device, "ntori editor", &[frame.layout(), &mesh_layout]);
        let source = concat!(
            include_str!("../../shaders/frame.wgsl"),
            include_str!("../../shaders/surface.wgsl"),
            include_str!("../../shaders/pulled.wgsl")
        );
        let pipeline = pipeline(
            device,
            &layout,
            PipelineSpec {
                label: "ntori editor surface",
                source,
                vertex_entry: "vs_pulled",
                buffers: &[],
                format: COLOUR_FORMAT,
                samples: SAMPLES,
            },
        );
        ViewportRenderer {
            pipeline,
            frame,
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
    /// only the vertex ranges that changed; and the drag in progress (its rows once per drag, the
    /// displacement every time). Returns whether anything the picture depends on changed, or,
    /// where a buffer would exceed the device's limits, an error naming the limit (nothing of that
    /// size is allocated, and no mesh is drawn until a smaller one comes).
    pub fn sync(
        &mut self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        mesh: &mut LiveMesh,
        drag: Option<(u64, &[DragRow], Vector3)>,
    ) -> Result<bool, RenderError> {
        let mut new_group = false;
        if let Some((id, rows, _)) = drag
            && id != self.drag_id
        {
            check_buffer(&device.limits(), "drag's row buffer", byte_size(rows), true)?;
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
                // Dropped first: a mesh that cannot be uploaded leaves nothing stale drawn.
                self.mesh = None;
                self.mesh = Some(self.upload(device, mesh)?);
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
        Ok(new_group || moved || written != Some(0))
    }

    fn upload(&self, device: &wgpu::Device, mesh: &LiveMesh) -> Result<MeshBuffers, RenderError> {
        use wgpu::util::DeviceExt as _;
        let limits = device.limits();
        let vertex_bytes = byte_size(mesh.vertices());
        check_buffer(&limits, "editor's vertex buffer", vertex_bytes, true)?;
        check_buffer(
            &limits,
            "editor's index buffer",
            byte_size(mesh.indices()),
            true,
        )?;
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
        Ok(MeshBuffers {
            vertices,
            _indices: indices,
            vertex_count: mesh.vertex_count(),
            // At most MAX_SCENE_BUFFER / 4 indices (checked above): fits a u32.
            index_count: mesh.indices().len() as u32,
            group,
        })
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
        if self.targets.as_ref().is_none_or(|t| t.size() != size) {
            self.targets = Some(Targets::new(
                device,
                "ntori editor",
                size,
                COLOUR_FORMAT,
                SAMPLES,
                wgpu::TextureUsages::TEXTURE_BINDING,
            ));
            self.generation += 1;
        }
        self.frame.write(queue, frame);
        let Some(targets) = &self.targets else {
            unreachable!("made above")
        };
        let mut encoder = device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
            label: Some("ntori editor viewport"),
        });
        {
            let [r, g, b] = BACKGROUND;
            let clear = wgpu::Color { r, g, b, a: 1.0 };
            let mut pass = targets.begin_pass(&mut encoder, "ntori editor viewport", clear);
            if let Some(mesh) = &self.mesh
                && mesh.index_count > 0
            {
                pass.set_pipeline(&self.pipeline);
                pass.set_bind_group(0, self.frame.group(), &[]);
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
        targets.read_back(device, queue, encoder)
    }

    /// The resolved colour target, if anything was drawn.
    pub fn texture_view(&self) -> Option<&wgpu::TextureView> {
        self.targets.as_ref().map(Targets::view)
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

/// The bytes a slice takes, as the limits count them.
fn byte_size<T>(data: &[T]) -> u64 {
    u64::try_from(std::mem::size_of_val(data)).unwrap_or(u64::MAX)
}

/// wgpu refuses empty buffers bound as storage: give it one zero element.
fn nonempty<T: bytemuck::Pod + bytemuck::Zeroable>(data: &[T]) -> std::borrow::Cow<'_, [T]> {
    if data.is_empty() {
        std::borrow::Cow::Owned(vec![T::zeroed()])
    } else {
        std::borrow::Cow::Borrowed(data)
    }
}
