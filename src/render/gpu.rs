//! The GPU side, shared by the offscreen renderer and the editor's viewport: the per-frame uniforms
//! and their bind group ([`FrameBinding`]), pipeline creation ([`pipeline`]), the multisampled
//! colour, resolve and depth targets and their read-back ([`Targets`]), and the offscreen
//! renderer's two pipelines (surface, curves; [`SurfaceRenderer`]). Nothing here knows about models
//! or charts: it draws what [`super::scene`] (or the editor's live mesh) prepared.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

use super::{Image, RenderError};

/// One vertex of the (unindexed) triangle list: each triangle's corners carry their barycentric
/// coordinates, which the fragment shader turns into wireframe lines.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct SurfaceVertex {
    pub position: [f32; 3],
    pub normal: [f32; 3],
    pub colour: [f32; 3],
    pub bary: [f32; 3],
}

/// One segment of a curve drawn on top of the surface.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct Segment {
    pub a: [f32; 3],
    pub b: [f32; 3],
    pub colour: [f32; 3],
}

/// The per-frame uniforms (`Frame` in `shaders/frame.wgsl`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FrameUniforms {
    pub view_proj: [[f32; 4]; 4],
    pub eye: [f32; 4],
    pub light: [f32; 4],
    /// Wireframe on/off, its width in pixels, ambient, specular strength.
    pub params: [f32; 4],
    /// Viewport width and height in pixels, curve width in pixels, depth pull.
    pub viewport: [f32; 4],
}

pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;

/// The surface's shader: the frame's uniforms (`shaders/frame.wgsl`), then `shaders/surface.wgsl`
/// (vertex stage `vs_main`, fragment stage `fs_main`).
pub const SURFACE_SHADER: &str = concat!(
    include_str!("../../shaders/frame.wgsl"),
    include_str!("../../shaders/surface.wgsl")
);
/// The curves' shader: the frame's uniforms, then `shaders/curves.wgsl`.
pub const CURVES_SHADER: &str = concat!(
    include_str!("../../shaders/frame.wgsl"),
    include_str!("../../shaders/curves.wgsl")
);

/// Pipelines and the uniform buffer, for one colour format and sample count.
pub struct SurfaceRenderer {
    surface: wgpu::RenderPipeline,
    curves: wgpu::RenderPipeline,
    frame: FrameBinding,
}

/// Geometry uploaded to the GPU.
pub struct GpuScene {
    vertices: wgpu::Buffer,
    vertex_count: u32,
    segments: Option<(wgpu::Buffer, u32)>,
}

impl GpuScene {
    /// Uploads the geometry, after checking every buffer against the device's limits (an error
    /// naming the limit, where wgpu would panic).
    pub fn new(
        device: &wgpu::Device,
        vertices: &[SurfaceVertex],
        segments: &[Segment],
    ) -> Result<Self, RenderError> {
        let limits = device.limits();
        let size = |bytes: usize| u64::try_from(bytes).unwrap_or(u64::MAX);
        super::check_buffer(
            &limits,
            "surface's vertex buffer",
            size(std::mem::size_of_val(vertices)),
            false,
        )?;
        super::check_buffer(
            &limits,
            "curves' segment buffer",
            size(std::mem::size_of_val(segments)),
            false,
        )?;
        // Both checked against MAX_SCENE_BUFFER (2 GiB) above, so both counts fit a u32.
        let vertex_count = vertices.len() as u32;
        let vertex_buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("ntori surface vertices"),
            contents: bytemuck::cast_slice(vertices),
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
        });
        let segments = (!segments.is_empty()).then(|| {
            let buffer = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some("ntori curve segments"),
                contents: bytemuck::cast_slice(segments),
                usage: wgpu::BufferUsages::VERTEX,
            });
            (buffer, segments.len() as u32)
        });
        Ok(GpuScene {
            vertices: vertex_buffer,
            vertex_count,
            segments,
        })
    }

    /// Overwrites the vertices in place (same count), e.g. after an edit.
    pub fn update_vertices(&self, queue: &wgpu::Queue, vertices: &[SurfaceVertex]) {
        debug_assert_eq!(vertices.len() as u32, self.vertex_count);
        queue.write_buffer(&self.vertices, 0, bytemuck::cast_slice(vertices));
    }
}

impl SurfaceRenderer {
    pub fn new(device: &wgpu::Device, format: wgpu::TextureFormat, samples: u32) -> Self {
        let frame = FrameBinding::new(device, "ntori frame");
        let pipeline_layout = pipeline_layout(device, "ntori", &[frame.layout()]);
        let surface = pipeline(
            device,
            &pipeline_layout,
            PipelineSpec {
                label: "ntori surface",
                source: SURFACE_SHADER,
                vertex_entry: "vs_main",
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<SurfaceVertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3, 3 => Float32x3],
                })],
                format,
                samples,
            },
        );
        let curves = pipeline(
            device,
            &pipeline_layout,
            PipelineSpec {
                label: "ntori curves",
                source: CURVES_SHADER,
                vertex_entry: "vs_main",
                buffers: &[Some(wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<Segment>() as u64,
                    step_mode: wgpu::VertexStepMode::Instance,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3],
                })],
                format,
                samples,
            },
        );
        SurfaceRenderer {
            surface,
            curves,
            frame,
        }
    }

    pub fn set_frame(&self, queue: &wgpu::Queue, frame: &FrameUniforms) {
        self.frame.write(queue, frame);
    }

    /// Records the draw calls into an open render pass.
    pub fn paint(&self, pass: &mut wgpu::RenderPass<'_>, scene: &GpuScene) {
        pass.set_bind_group(0, self.frame.group(), &[]);
        pass.set_pipeline(&self.surface);
        pass.set_vertex_buffer(0, scene.vertices.slice(..));
        pass.draw(0..scene.vertex_count, 0..1);
        if let Some((buffer, count)) = &scene.segments {
            pass.set_pipeline(&self.curves);
            pass.set_vertex_buffer(0, buffer.slice(..));
            pass.draw(0..6, 0..*count);
        }
    }
}

/// The layout entry of a buffer binding.
pub fn buffer_entry(
    binding: u32,
    visibility: wgpu::ShaderStages,
    ty: wgpu::BufferBindingType,
) -> wgpu::BindGroupLayoutEntry {
    wgpu::BindGroupLayoutEntry {
        binding,
        visibility,
        ty: wgpu::BindingType::Buffer {
            ty,
            has_dynamic_offset: false,
            min_binding_size: None,
        },
        count: None,
    }
}

/// The per-frame uniform buffer ([`FrameUniforms`]) and its bind group: group 0 of every pipeline
/// (`var<uniform> frame` in the shaders).
pub struct FrameBinding {
    buffer: wgpu::Buffer,
    layout: wgpu::BindGroupLayout,
    group: wgpu::BindGroup,
}

impl FrameBinding {
    pub fn new(device: &wgpu::Device, label: &str) -> FrameBinding {
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(&format!("{label} uniforms")),
            size: std::mem::size_of::<FrameUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(label),
            entries: &[buffer_entry(
                0,
                wgpu::ShaderStages::VERTEX_FRAGMENT,
                wgpu::BufferBindingType::Uniform,
            )],
        });
        let group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: buffer.as_entire_binding(),
            }],
        });
        FrameBinding {
            buffer,
            layout,
            group,
        }
    }

    pub fn layout(&self) -> &wgpu::BindGroupLayout {
        &self.layout
    }

    pub fn group(&self) -> &wgpu::BindGroup {
        &self.group
    }

    pub fn write(&self, queue: &wgpu::Queue, frame: &FrameUniforms) {
        queue.write_buffer(&self.buffer, 0, bytemuck::bytes_of(frame));
    }
}

/// A pipeline layout of bind groups 0, 1, … in order.
pub fn pipeline_layout(
    device: &wgpu::Device,
    label: &str,
    groups: &[&wgpu::BindGroupLayout],
) -> wgpu::PipelineLayout {
    let groups: Vec<Option<&wgpu::BindGroupLayout>> = groups.iter().copied().map(Some).collect();
    device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(label),
        bind_group_layouts: &groups,
        immediate_size: 0,
    })
}

/// What differs between the pipelines: the shader, its vertex input, the target.
pub struct PipelineSpec<'a> {
    pub label: &'a str,
    /// WGSL with the vertex entry point and a fragment stage `fs_main`.
    pub source: &'a str,
    pub vertex_entry: &'a str,
    /// The vertex buffers (none where the vertex stage pulls from storage buffers).
    pub buffers: &'a [Option<wgpu::VertexBufferLayout<'a>>],
    pub format: wgpu::TextureFormat,
    pub samples: u32,
}

/// A triangle-list pipeline, two-sided, depth-tested against [`DEPTH_FORMAT`], writing one colour
/// target without blending.
pub fn pipeline(
    device: &wgpu::Device,
    layout: &wgpu::PipelineLayout,
    p: PipelineSpec,
) -> wgpu::RenderPipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(p.label),
        source: wgpu::ShaderSource::Wgsl(p.source.into()),
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(p.label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some(p.vertex_entry),
            compilation_options: Default::default(),
            buffers: p.buffers,
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
            count: p.samples,
            ..Default::default()
        },
        fragment: Some(wgpu::FragmentState {
            module: &module,
            entry_point: Some("fs_main"),
            compilation_options: Default::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format: p.format,
                blend: None,
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        multiview_mask: None,
        cache: None,
    })
}

/// The colour (multisampled), resolved colour and depth targets of one picture size.
pub struct Targets {
    size: [u32; 2],
    msaa: wgpu::TextureView,
    resolved: wgpu::Texture,
    resolved_view: wgpu::TextureView,
    depth: wgpu::TextureView,
}

impl Targets {
    /// Targets of `size` pixels; the resolved texture can be copied from and is a render attachment,
    /// with `usage` besides (e.g. for sampling it as a texture).
    pub fn new(
        device: &wgpu::Device,
        label: &str,
        [width, height]: [u32; 2],
        format: wgpu::TextureFormat,
        samples: u32,
        usage: wgpu::TextureUsages,
    ) -> Targets {
        let texture = |what: &str, format, samples, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(&format!("{label} {what}")),
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
        let msaa = texture("msaa", format, samples, attachment);
        let resolved = texture(
            "picture",
            format,
            1,
            attachment | wgpu::TextureUsages::COPY_SRC | usage,
        );
        let depth = texture("depth", DEPTH_FORMAT, samples, attachment);
        Targets {
            size: [width, height],
            msaa: msaa.create_view(&Default::default()),
            resolved_view: resolved.create_view(&Default::default()),
            resolved,
            depth: depth.create_view(&Default::default()),
        }
    }

    pub fn size(&self) -> [u32; 2] {
        self.size
    }

    /// The resolved colour target.
    pub fn view(&self) -> &wgpu::TextureView {
        &self.resolved_view
    }

    /// A render pass that clears colour and depth and resolves into the picture.
    pub fn begin_pass<'e>(
        &self,
        encoder: &'e mut wgpu::CommandEncoder,
        label: &str,
        clear: wgpu::Color,
    ) -> wgpu::RenderPass<'e> {
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some(label),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &self.msaa,
                depth_slice: None,
                resolve_target: Some(&self.resolved_view),
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(clear),
                    store: wgpu::StoreOp::Discard,
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
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        })
    }

    /// The picture (an RGBA8 format), after the commands in `encoder`.
    pub fn read_back(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        encoder: wgpu::CommandEncoder,
    ) -> Result<Image, RenderError> {
        read_texture(device, queue, encoder, &self.resolved, self.size)
    }
}

/// Copies a single-sampled RGBA8 texture into an [`Image`], after the commands in `encoder`.
pub fn read_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    mut encoder: wgpu::CommandEncoder,
    texture: &wgpu::Texture,
    [width, height]: [u32; 2],
) -> Result<Image, RenderError> {
    let row = 4 * width;
    let padded =
        row.div_ceil(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT) * wgpu::COPY_BYTES_PER_ROW_ALIGNMENT;
    let buffer = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("ntori readback"),
        size: u64::from(padded) * u64::from(height),
        usage: wgpu::BufferUsages::COPY_DST | wgpu::BufferUsages::MAP_READ,
        mapped_at_creation: false,
    });
    encoder.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &buffer,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(height),
            },
        },
        wgpu::Extent3d {
            width,
            height,
            depth_or_array_layers: 1,
        },
    );
    queue.submit([encoder.finish()]);
    let slice = buffer.slice(..);
    let (sender, receiver) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |r| {
        let _ = sender.send(r);
    });
    device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|e| RenderError::Readback(e.to_string()))?;
    receiver
        .recv()
        .map_err(|e| RenderError::Readback(e.to_string()))?
        .map_err(|e| RenderError::Readback(e.to_string()))?;
    let data = slice
        .get_mapped_range()
        .map_err(|e| RenderError::Readback(e.to_string()))?;
    let mut rgba = Vec::with_capacity((row * height) as usize);
    for y in 0..height as usize {
        let start = y * padded as usize;
        rgba.extend_from_slice(&data[start..start + row as usize]);
    }
    drop(data);
    buffer.unmap();
    Ok(Image {
        width,
        height,
        rgba,
    })
}
