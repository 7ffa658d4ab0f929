//! Re-embedding on the GPU: [`embedding::TensorStencil`]'s rows applied by a compute shader
//! (`shaders/reembed.wgsl`), the same sums as the CPU's kernel, in f32 about the control points'
//! centre; for a stencil built with tangents, the first derivatives too (for normals). Tested
//! against the CPU on lavapipe (`tests/library/render.rs`); timed by `ntori bench` where a GPU is.

use embedding::{ControlFrame, Point3, TensorStencil, Vector3};
use wgpu::util::DeviceExt;

use super::gpu::{buffer_entry, pipeline_layout};
use super::{RenderError, check_buffer};

/// Rows per workgroup (the shader's `@workgroup_size`).
const GROUP: u32 = 64;
/// The most workgroups in one dimension of a dispatch (WebGPU's limit).
const MAX_GROUPS: u32 = 65_535;

/// A tensor stencil uploaded to a device, with buffers for the control points and the positions.
pub struct GpuReembed {
    pipeline: wgpu::ComputePipeline,
    bind_group: wgpu::BindGroup,
    control: wgpu::Buffer,
    positions: wgpu::Buffer,
    readback: wgpu::Buffer,
    rows: u32,
    control_count: usize,
    /// Position, S_u and S_v per row (else the position alone).
    tangents: bool,
}

/// vec4s the shader writes per row.
fn outputs_per_row(tangents: bool) -> u64 {
    if tangents { 3 } else { 1 }
}

impl GpuReembed {
    /// Uploads `stencil` (for `control_count` control points) to `device`. A stencil built with
    /// tangents gives them too ([`GpuReembed::positions_and_tangents`]).
    pub fn new(
        device: &wgpu::Device,
        stencil: &TensorStencil,
        control_count: usize,
    ) -> Result<GpuReembed, RenderError> {
        let limits = device.limits();
        let rows = u32::try_from(stencil.rows()).map_err(|_| too_many(stencil.rows()))?;
        let tangents = stencil.has_tangents();
        let (blocks, stride) = pack_blocks(stencil);
        let position_bytes = 16 * outputs_per_row(tangents) * u64::from(rows.max(1));
        check_buffer(
            &limits,
            "re-embedding stencil",
            4 * blocks.len() as u64,
            true,
        )?;
        check_buffer(&limits, "re-embedded positions", position_bytes, true)?;
        check_buffer(&limits, "control points", 16 * control_count as u64, true)?;
        let storage = |label, contents: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let grids = stencil.grids();
        // Eight words: the shader's Params, padded to a multiple of 16 bytes for a uniform. Grids
        // are at most 4096 per side (`UniformBasis`), so the disks hold fewer than 2³² points.
        let params = [
            rows,
            stencil.order() as u32,
            grids.square as u32,
            stride as u32,
            grids.disk as u32,
            (grids.disks * grids.disk * grids.disk) as u32,
            0,
            0,
        ];
        let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("ntori reembed params"),
            contents: bytemuck::cast_slice(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let starts = storage(
            "ntori reembed rows",
            bytemuck::cast_slice(padded(stencil.row_starts())),
        );
        // An empty binding is not allowed: one word stands in for no blocks.
        let blocks = storage(
            "ntori reembed blocks",
            bytemuck::cast_slice(padded(&blocks)),
        );
        let buffer = |label, size: u64, usage| {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size,
                usage,
                mapped_at_creation: false,
            })
        };
        use wgpu::BufferUsages as U;
        let control = buffer(
            "ntori reembed control",
            16 * control_count.max(1) as u64,
            U::STORAGE | U::COPY_DST,
        );
        let positions = buffer(
            "ntori reembed positions",
            position_bytes,
            U::STORAGE | U::COPY_SRC,
        );
        let readback = buffer(
            "ntori reembed readback",
            position_bytes,
            U::MAP_READ | U::COPY_DST,
        );
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("reembed.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("../../shaders/reembed.wgsl").into()),
        });
        use wgpu::BufferBindingType as B;
        let compute = wgpu::ShaderStages::COMPUTE;
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("ntori reembed"),
            entries: &[
                buffer_entry(0, compute, B::Uniform),
                buffer_entry(1, compute, B::Storage { read_only: true }),
                buffer_entry(2, compute, B::Storage { read_only: true }),
                buffer_entry(3, compute, B::Storage { read_only: true }),
                buffer_entry(4, compute, B::Storage { read_only: false }),
            ],
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("ntori reembed"),
            layout: &layout,
            entries: &[&params, &starts, &blocks, &control, &positions]
                .iter()
                .enumerate()
                .map(|(k, b)| wgpu::BindGroupEntry {
                    binding: k as u32,
                    resource: b.as_entire_binding(),
                })
                .collect::<Vec<_>>(),
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some("ntori reembed"),
            layout: Some(&pipeline_layout(device, "ntori reembed", &[&layout])),
            module: &module,
            entry_point: Some(if tangents {
                "reembed_with_tangents"
            } else {
                "reembed"
            }),
            compilation_options: Default::default(),
            cache: None,
        });
        Ok(GpuReembed {
            pipeline,
            bind_group,
            control,
            positions,
            readback,
            rows,
            control_count,
            tangents,
        })
    }

    pub fn rows(&self) -> usize {
        self.rows as usize
    }

    /// Built from a stencil with tangents: [`GpuReembed::positions_and_tangents`] gives them.
    pub fn has_tangents(&self) -> bool {
        self.tangents
    }

    /// Uploads `control`, applies the stencil on the device and reads the positions back into `out`.
    pub fn positions(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        control: &[Point3],
        out: &mut [Point3],
    ) -> Result<(), RenderError> {
        let centre = self.dispatch(device, queue, control, 1);
        let per = outputs_per_row(self.tangents) as usize;
        self.read_back(device, queue, |lanes| {
            for (o, p) in out.iter_mut().zip(lanes.chunks_exact(per)) {
                *o = centre + wide(p[0]);
            }
        })
    }

    /// [`GpuReembed::positions`] with the first derivatives S_u, S_v in each row's own chart.
    ///
    /// # Panics
    /// If the stencil was built without tangents.
    pub fn positions_and_tangents(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        control: &[Point3],
        positions: &mut [Point3],
        tangents: &mut [[Vector3; 2]],
    ) -> Result<(), RenderError> {
        assert!(self.tangents, "a stencil built with tangents");
        let centre = self.dispatch(device, queue, control, 1);
        self.read_back(device, queue, |lanes| {
            let rows = positions.iter_mut().zip(tangents.iter_mut());
            for ((p, t), l) in rows.zip(lanes.chunks_exact(3)) {
                *p = centre + wide(l[0]);
                *t = [wide(l[1]), wide(l[2])];
            }
        })
    }

    /// Uploads `control` and submits `repeats` applications of the stencil (each the same) without
    /// waiting; the results stay on the device. Returns the centre they are about. Repeats are for
    /// timing the kernel without the transfers (`ntori bench`, which then waits with
    /// [`GpuReembed::wait`]).
    pub fn dispatch(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        control: &[Point3],
        repeats: u32,
    ) -> Point3 {
        assert_eq!(
            control.len(),
            self.control_count,
            "the stencil's control points"
        );
        let frame = ControlFrame::new(control);
        let lanes: Vec<[f32; 4]> = frame.points.iter().map(|v| v.to_array()).collect();
        queue.write_buffer(&self.control, 0, bytemuck::cast_slice(&lanes));
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &self.bind_group, &[]);
            let groups = self.rows.div_ceil(GROUP);
            for _ in 0..repeats {
                pass.dispatch_workgroups(groups.min(MAX_GROUPS), groups.div_ceil(MAX_GROUPS), 1);
            }
        }
        queue.submit([encoder.finish()]);
        frame.centre
    }

    /// Waits until the device has done all that was submitted to it.
    pub fn wait(&self, device: &wgpu::Device) -> Result<(), RenderError> {
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| RenderError::Readback(e.to_string()))
    }

    /// Copies the device's results back and hands them to `unpack` as f32 lanes
    /// ([`outputs_per_row`] vec4s per row).
    fn read_back(
        &self,
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        unpack: impl FnOnce(&[[f32; 4]]),
    ) -> Result<(), RenderError> {
        let bytes = 16 * outputs_per_row(self.tangents) * u64::from(self.rows);
        if bytes == 0 {
            return Ok(());
        }
        let mut encoder = device.create_command_encoder(&Default::default());
        encoder.copy_buffer_to_buffer(&self.positions, 0, &self.readback, 0, bytes);
        queue.submit([encoder.finish()]);
        let slice = self.readback.slice(..bytes);
        let (sender, receiver) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |r| {
            let _ = sender.send(r);
        });
        let failed = |e: &dyn std::fmt::Display| RenderError::Readback(e.to_string());
        device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| failed(&e))?;
        receiver
            .recv()
            .map_err(|e| failed(&e))?
            .map_err(|e| failed(&e))?;
        {
            let data = slice.get_mapped_range().map_err(|e| failed(&e))?;
            unpack(bytemuck::cast_slice(&data));
        }
        self.readback.unmap();
        Ok(())
    }
}

fn wide(p: [f32; 4]) -> Vector3 {
    Vector3::new(f64::from(p[0]), f64::from(p[1]), f64::from(p[2]))
}

/// Each block as u32 words: its first control point, then its factors' f32 bits, then (built with
/// tangents) its tangent factors' bits; and the words per block.
fn pack_blocks(stencil: &TensorStencil) -> (Vec<u32>, usize) {
    let per = 2 * stencil.order();
    let extra = if stencil.blocks() > 0 && stencil.has_tangents() {
        embedding::tangent_words(stencil.order())
    } else {
        0
    };
    let stride = 1 + per + extra;
    let mut words = Vec::with_capacity(stencil.blocks() * stride);
    for (k, (first, factors)) in stencil
        .firsts()
        .iter()
        .zip(stencil.factors().chunks_exact(per))
        .enumerate()
    {
        words.push(*first);
        words.extend(factors.iter().map(|f| f.to_bits()));
        let tangent = &stencil.tangent_factors()[extra * k..extra * (k + 1)];
        words.extend(tangent.iter().map(|f| f.to_bits()));
    }
    (words, stride)
}

fn padded(words: &[u32]) -> &[u32] {
    if words.is_empty() { &[0] } else { words }
}

fn too_many(rows: usize) -> RenderError {
    RenderError::Mesh(format!(
        "{rows} rows are more than a GPU dispatch can index"
    ))
}
