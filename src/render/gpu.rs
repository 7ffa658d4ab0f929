//! The GPU side: two pipelines (surface, curves) over one uniform buffer, shared by the offscreen
//! renderer and the editor's viewport. Nothing here knows about models or charts: it draws what
//! [`super::scene`] prepared.

use bytemuck::{Pod, Zeroable};
use wgpu::util::DeviceExt;

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

/// The per-frame uniforms (see `shaders/surface.wgsl`).
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

/// Pipelines and the uniform buffer, for one colour format and sample count.
pub struct SurfaceRenderer {
    surface: wgpu::RenderPipeline,
    curves: wgpu::RenderPipeline,
    uniforms: wgpu::Buffer,
    bind_group: wgpu::BindGroup,
}

/// Geometry uploaded to the GPU.
pub struct GpuScene {
    vertices: wgpu::Buffer,
    vertex_count: u32,
    segments: Option<(wgpu::Buffer, u32)>,
}

impl GpuScene {
    pub fn new(device: &wgpu::Device, vertices: &[SurfaceVertex], segments: &[Segment]) -> Self {
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
        GpuScene {
            vertices: vertex_buffer,
            vertex_count: vertices.len() as u32,
            segments,
        }
    }

    /// Overwrites the vertices in place (same count), e.g. after an edit.
    pub fn update_vertices(&self, queue: &wgpu::Queue, vertices: &[SurfaceVertex]) {
        debug_assert_eq!(vertices.len() as u32, self.vertex_count);
        queue.write_buffer(&self.vertices, 0, bytemuck::cast_slice(vertices));
    }
}

impl SurfaceRenderer {
    pub fn new(device: &wgpu::Device, format: wgpu::TextureFormat, samples: u32) -> Self {
        let uniforms = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("ntori frame uniforms"),
            size: std::mem::size_of::<FrameUniforms>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("ntori frame"),
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
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("ntori frame"),
            layout: &layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: uniforms.as_entire_binding(),
            }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("ntori"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let surface = pipeline(
            device,
            &pipeline_layout,
            Pipe {
                label: "ntori surface",
                source: include_str!("../../shaders/surface.wgsl"),
                buffer: wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<SurfaceVertex>() as u64,
                    step_mode: wgpu::VertexStepMode::Vertex,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3, 3 => Float32x3],
                },
                format,
                samples,
            },
        );
        let curves = pipeline(
            device,
            &pipeline_layout,
            Pipe {
                label: "ntori curves",
                source: include_str!("../../shaders/curves.wgsl"),
                buffer: wgpu::VertexBufferLayout {
                    array_stride: std::mem::size_of::<Segment>() as u64,
                    step_mode: wgpu::VertexStepMode::Instance,
                    attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3],
                },
                format,
                samples,
            },
        );
        SurfaceRenderer {
            surface,
            curves,
            uniforms,
            bind_group,
        }
    }

    pub fn set_frame(&self, queue: &wgpu::Queue, frame: &FrameUniforms) {
        queue.write_buffer(&self.uniforms, 0, bytemuck::bytes_of(frame));
    }

    /// Records the draw calls into an open render pass.
    pub fn paint(&self, pass: &mut wgpu::RenderPass<'_>, scene: &GpuScene) {
        pass.set_bind_group(0, &self.bind_group, &[]);
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

struct Pipe<'a> {
    label: &'a str,
    source: &'a str,
    buffer: wgpu::VertexBufferLayout<'a>,
    format: wgpu::TextureFormat,
    samples: u32,
}

fn pipeline(device: &wgpu::Device, layout: &wgpu::PipelineLayout, p: Pipe) -> wgpu::RenderPipeline {
    let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(p.label),
        source: wgpu::ShaderSource::Wgsl(p.source.into()),
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(p.label),
        layout: Some(layout),
        vertex: wgpu::VertexState {
            module: &module,
            entry_point: Some("vs_main"),
            compilation_options: Default::default(),
            buffers: &[Some(p.buffer)],
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
