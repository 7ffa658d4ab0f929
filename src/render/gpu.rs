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

// TEMPORARY: the renderer before the GPU setup was shared, to check that pictures keep their bytes.
#[cfg(test)]
mod old_check {
    use super::*;
    use crate::render::camera::Camera;
    use crate::render::scene::{self, SceneGeometry};
    use crate::render::{CurvatureKind, Curve, Offscreen, RenderOptions, Style, View};
    use glam::Vec3;

    struct OldRenderer {
        surface: wgpu::RenderPipeline,
        curves: wgpu::RenderPipeline,
        uniforms: wgpu::Buffer,
        bind_group: wgpu::BindGroup,
    }

    impl OldRenderer {
        fn new(device: &wgpu::Device, format: wgpu::TextureFormat, samples: u32) -> Self {
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
            let surface = old_pipeline(
                device,
                &pipeline_layout,
                Pipe {
                    label: "ntori surface",
                    source: include_str!("/tmp/oldshaders/surface.wgsl"),
                    buffer: wgpu::VertexBufferLayout {
                        array_stride: std::mem::size_of::<SurfaceVertex>() as u64,
                        step_mode: wgpu::VertexStepMode::Vertex,
                        attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3, 3 => Float32x3],
                    },
                    format,
                    samples,
                },
            );
            let curves = old_pipeline(
                device,
                &pipeline_layout,
                Pipe {
                    label: "ntori curves",
                    source: include_str!("/tmp/oldshaders/curves.wgsl"),
                    buffer: wgpu::VertexBufferLayout {
                        array_stride: std::mem::size_of::<Segment>() as u64,
                        step_mode: wgpu::VertexStepMode::Instance,
                        attributes: &wgpu::vertex_attr_array![0 => Float32x3, 1 => Float32x3, 2 => Float32x3],
                    },
                    format,
                    samples,
                },
            );
            OldRenderer {
                surface,
                curves,
                uniforms,
                bind_group,
            }
        }

        fn paint(&self, pass: &mut wgpu::RenderPass<'_>, scene: &GpuScene) {
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

    fn old_pipeline(
        device: &wgpu::Device,
        layout: &wgpu::PipelineLayout,
        p: Pipe,
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
                entry_point: Some("vs_main"),
                compilation_options: Default::default(),
                buffers: &[Some(p.buffer)],
            },
            primitive: wgpu::PrimitiveState {
                topology: wgpu::PrimitiveTopology::TriangleList,
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

    fn old_light(c: &Camera) -> Vec3 {
        let back = c.direction();
        let right = Vec3::Z.cross(back).try_normalize().unwrap_or(Vec3::X);
        let up = back.cross(right);
        (back + 0.8 * up - 0.5 * right).normalize()
    }

    fn old_uniforms(c: &Camera, style: Style, size: (u32, u32)) -> FrameUniforms {
        let wire = matches!(style, Style::Wireframe);
        FrameUniforms {
            view_proj: c.view_proj().to_cols_array_2d(),
            eye: c.eye().extend(1.0).to_array(),
            light: old_light(c).extend(0.0).to_array(),
            params: [f32::from(u8::from(wire)), 1.2, 0.22, 0.25],
            viewport: [
                size.0 as f32,
                size.1 as f32,
                (size.1 as f32 / 180.0).max(3.0),
                2e-4,
            ],
        }
    }

    const OFFSCREEN_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8Unorm;
    const SAMPLES: u32 = 4;

    fn old_draw(
        off: &Offscreen,
        renderer: &OldRenderer,
        geometry: &SceneGeometry,
        options: &RenderOptions,
    ) -> Image {
        let (width, height) = (options.width, options.height);
        let camera = Camera {
            centre: geometry.centre,
            radius: geometry.radius,
            view: options.view,
            aspect: width as f32 / height as f32,
        };
        let scene = GpuScene::new(&off.device, &geometry.vertices, &geometry.segments);
        let mut frame = old_uniforms(&camera, options.style, (width, height));
        if geometry.legend.is_some() {
            let shift = glam::Mat4::from_translation(glam::Vec3::new(-0.14, 0.0, 0.0));
            frame.view_proj =
                (shift * glam::Mat4::from_cols_array_2d(&frame.view_proj)).to_cols_array_2d();
        }
        off.queue
            .write_buffer(&renderer.uniforms, 0, bytemuck::bytes_of(&frame));
        let target = |label, format, samples, usage| {
            off.device.create_texture(&wgpu::TextureDescriptor {
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
        let msaa = target("ntori msaa", OFFSCREEN_FORMAT, SAMPLES, attachment);
        let resolved = target(
            "ntori picture",
            OFFSCREEN_FORMAT,
            1,
            attachment | wgpu::TextureUsages::COPY_SRC,
        );
        let depth = target("ntori depth", DEPTH_FORMAT, SAMPLES, attachment);
        let views = [&msaa, &resolved, &depth].map(|t| t.create_view(&Default::default()));
        let mut encoder = off
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: None });
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("ntori picture"),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: &views[0],
                    depth_slice: None,
                    resolve_target: Some(&views[1]),
                    ops: wgpu::Operations {
                        load: wgpu::LoadOp::Clear(wgpu::Color::WHITE),
                        store: wgpu::StoreOp::Discard,
                    },
                })],
                depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                    view: &views[2],
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
            renderer.paint(&mut pass, &scene);
        }
        let mut image =
            read_texture(&off.device, &off.queue, encoder, &resolved, [width, height]).unwrap();
        if let Some((kind, range)) = geometry.legend {
            crate::render::legend::draw(&mut image, kind, range);
        }
        image
    }

    #[test]
    fn uniforms_keep_their_bytes() {
        let mut n = 0;
        for az in (-400..=400).step_by(7) {
            for el in (-90..=90).step_by(3) {
                for &distance in &[1.05, 1.7, 3.6, 11.0, 999.0] {
                    for &(w, h) in &[(320, 240), (1024, 768), (7, 1999)] {
                        let camera = Camera {
                            centre: Vec3::new(0.3, -1.7, 0.01),
                            radius: 2.3,
                            view: View {
                                azimuth_deg: f64::from(az) + 0.37,
                                elevation_deg: f64::from(el) * 0.999,
                                distance,
                            },
                            aspect: w as f32 / h as f32,
                        };
                        for style in [Style::Shaded, Style::Wireframe] {
                            let old = old_uniforms(&camera, style, (w, h));
                            let new = camera.uniforms(style, (w, h));
                            assert_eq!(bytemuck::bytes_of(&old), bytemuck::bytes_of(&new));
                            n += 1;
                        }
                    }
                }
            }
        }
        println!("{n} uniforms compared");
    }

    #[test]
    fn offscreen_pictures_keep_their_bytes() {
        let settings = embedding::SplineSettings {
            grid: 8,
            ..embedding::SplineSettings::default()
        };
        let surface = embedding::fit::initial_model(2, 16, settings, Default::default())
            .unwrap()
            .surface;
        let mut off = Offscreen::new().unwrap();
        let old = OldRenderer::new(&off.device, OFFSCREEN_FORMAT, SAMPLES);
        let curves = [Curve {
            points: (0..40)
                .map(|i| {
                    let t = f64::from(i) / 39.0 * std::f64::consts::TAU;
                    [1.2 * t.cos(), 0.8 * t.sin(), 0.1]
                })
                .collect(),
            colour: [0.9, 0.2, 0.1],
        }];
        let (mut n, mut curves_seen) = (0, 0);
        for style in [
            Style::Shaded,
            Style::Wireframe,
            Style::Charts,
            Style::Curvature(CurvatureKind::Gaussian),
            Style::Curvature(CurvatureKind::Mean),
        ] {
            for view in [
                View::default(),
                View {
                    azimuth_deg: 200.0,
                    elevation_deg: -60.0,
                    distance: 2.0,
                },
                View {
                    azimuth_deg: 45.0,
                    elevation_deg: 89.95,
                    distance: 5.0,
                },
            ] {
                for (width, height) in [(320, 240), (101, 77)] {
                    let options = RenderOptions {
                        width,
                        height,
                        view,
                        style,
                        tessellation: 10,
                    };
                    let geometry = scene::model_geometry(&surface, 10, style, &curves).unwrap();
                    let a = old_draw(&off, &old, &geometry, &options);
                    let b = off.render_model(&surface, &options, &curves).unwrap();
                    assert!(a == b, "{style:?} {view:?} {width}×{height} differ");
                    let plain = off.render_model(&surface, &options, &[]).unwrap();
                    if plain != b {
                        curves_seen += 1;
                    }
                    n += 1;
                }
            }
        }
        println!("{n} pictures compared, {curves_seen} showing the curve");
        assert!(curves_seen > 0);
    }
}
