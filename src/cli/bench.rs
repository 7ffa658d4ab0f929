//! `ntori bench`: quick throughput figures as JSON, each also as a ratio to baselines measured in the
//! same run (this machine is shared and noisy; ratios travel better than seconds).

use std::hint::black_box;
use std::process::ExitCode;
use std::time::Instant;

use charts::{Atlas, ChartPoint};
use embedding::edit::{Constraint, RefreshScratch, refresh, solve};
use embedding::{Layout, Point3, SplineSettings, Stencil, StencilKernel, TensorStencil, Vector3};
use serde::Serialize;

use super::{GenusArg, spinner, write_stdout};

/// Measure throughput and print it as JSON.
///
/// Figures for tessellation, point location, stencil building (the tensor stencil on all cores, and
/// the full f64 stencil with derivatives), re-embedding (the tensor stencil on one thread and on
/// all cores, and the full stencil; each also as a fraction of memory copy bandwidth) and drag
/// events. Baselines (copy bandwidth, a chain of scalar multiply-adds) are measured in the same
/// run, and every figure is also given per baseline operation, since this machine is shared and
/// noisy.
///
/// For statistics and history use `cargo bench`; this is the quick look.
#[derive(clap::Args, Debug)]
pub struct Args {
    #[command(flatten)]
    genus: GenusArg,
    /// About how many vertices to measure with.
    #[arg(long, default_value_t = 100_000, value_name = "V",
          value_parser = clap::value_parser!(u64).range(10..=5_000_000))]
    vertices: u64,
    /// Also time re-embedding on the GPU (the adapter `ntori render` would use): the kernel alone,
    /// and with the control points' upload and the results' read-back.
    #[arg(long)]
    gpu: bool,
    /// No progress messages on stderr.
    #[arg(short, long)]
    quiet: bool,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let Args {
        genus: GenusArg { genus },
        vertices,
        gpu,
        quiet,
    } = args;
    let bar = spinner(quiet);
    let report = measure(genus, vertices as usize, gpu, &|stage| {
        bar.set_message(format!("measuring {stage}"));
        bar.tick();
    })?;
    bar.finish_and_clear();
    write_stdout(&(serde_json::to_string_pretty(&report)? + "\n"))?;
    Ok(ExitCode::SUCCESS)
}

/// One measured figure.
#[derive(Debug, Serialize)]
pub struct Figure {
    pub name: String,
    /// Items per second (points, vertices, triangles, events).
    pub per_second: f64,
    pub unit: &'static str,
    /// per_second × bytes per item ÷ copy bandwidth, where the figure is memory-bound: the
    /// all-cores copy bandwidth for the figures named `…_all_cores`, the one-thread copy's for the
    /// others.
    pub fraction_of_copy_bandwidth: Option<f64>,
    /// per_second ÷ the scalar baseline (multiply-adds per second in a dependent chain).
    pub per_baseline_op: f64,
}

/// How far the GPU's results are from the CPU's.
#[derive(Debug, Serialize)]
pub struct GpuAgreement {
    pub position_of_diagonal: f64,
    pub tangent_of_largest: f64,
}

/// The whole report.
#[derive(Debug, Serialize)]
pub struct BenchReport {
    pub genus: u32,
    pub vertices: usize,
    /// Baselines, measured in this run.
    pub copy_bandwidth_bytes_per_second: f64,
    /// The same copy split over every core (`threads` of them): what the `…_all_cores` figures'
    /// scaling is bounded by where they are memory-bound (this machine's 2 cores copied 1.5 to 2.3
    /// times as fast as one, in three runs).
    pub copy_bandwidth_all_cores_bytes_per_second: f64,
    pub threads: usize,
    pub scalar_ops_per_second: f64,
    /// The adapter the GPU figures ran on (with `--gpu`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gpu_adapter: Option<String>,
    /// With `--gpu`: the GPU's positions and tangents against the CPU's tensor stencil, the
    /// largest differences as fractions of the diagonal and of the largest tangent.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gpu_agreement: Option<GpuAgreement>,
    pub figures: Vec<Figure>,
}

/// Best (smallest) time of `runs` calls of `f`, in seconds.
fn best_of(runs: usize, mut f: impl FnMut()) -> f64 {
    (0..runs)
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Bytes read and written per second copying 128 MiB: on one thread, or (`all_cores`) in chunks
/// over rayon's threads.
fn copy_bandwidth(all_cores: bool) -> f64 {
    use rayon::prelude::*;
    let words = 16 << 20;
    let src: Vec<u64> = (0..words as u64).collect();
    let mut dst = vec![0u64; words];
    let t = best_of(3, || {
        if all_cores {
            const CHUNK: usize = 1 << 16;
            dst.par_chunks_mut(CHUNK)
                .zip(black_box(&src).par_chunks(CHUNK))
                .for_each(|(d, s)| d.copy_from_slice(s));
        } else {
            dst.copy_from_slice(black_box(&src));
        }
        black_box(&mut dst);
    });
    (2 * 8 * words) as f64 / t
}

fn scalar_ops() -> f64 {
    let n = 20_000_000u64;
    let t = best_of(3, || {
        let mut x = 1.0f64;
        for _ in 0..n {
            x = black_box(x) * 0.999_999_9 + 1e-9;
        }
        black_box(x);
    });
    n as f64 / t
}

/// Measures chart location, tessellation, stencil building, re-embedding and a drag event for genus
/// `genus` at about `vertices` vertices.
pub fn measure(
    genus: u32,
    vertices: usize,
    gpu: bool,
    progress: &dyn Fn(&str),
) -> anyhow::Result<BenchReport> {
    progress("baselines");
    let (bandwidth, scalar) = (copy_bandwidth(false), scalar_ops());
    let bandwidth_all_cores = copy_bandwidth(true);
    let atlas = Atlas::new(genus)?;
    let t = tessellation_size(genus, vertices);
    let mut figures = Vec::new();
    let mut add = |name: &str, per_second: f64, unit, bytes: Option<f64>| {
        figures.push(Figure {
            name: name.into(),
            per_second,
            unit,
            fraction_of_copy_bandwidth: bytes.map(|b| {
                let baseline = if name.ends_with("_all_cores") {
                    bandwidth_all_cores
                } else {
                    bandwidth
                };
                per_second * b / baseline
            }),
            per_baseline_op: per_second / scalar,
        })
    };
    progress("tessellation");
    let mut tess = None;
    let secs = best_of(3, || tess = Some(atlas.tessellate(t, t)));
    let tess = tess.expect("ran")?;
    add(
        "tessellate",
        tess.triangles.len() as f64 / secs,
        "triangles",
        None,
    );
    let pts: Vec<ChartPoint> = tess.vertices;
    progress("point location");
    let secs = best_of(3, || {
        black_box(
            pts.iter()
                .map(|&p| atlas.locate_unchecked(p).representations().len())
                .sum::<usize>(),
        );
    });
    add(
        "locate_chart_point",
        pts.len() as f64 / secs,
        "points",
        None,
    );
    let layout = Layout::new(&atlas, SplineSettings::default())?;
    let mut control: Vec<Point3> = (0..layout.control_count())
        .map(|i| {
            Point3::new(
                (i as f64 * 0.37).sin(),
                (i as f64 * 0.71).cos(),
                (i as f64 * 0.13).sin(),
            )
        })
        .collect();
    progress("stencil build");
    let mut tensor = TensorStencil::default();
    let secs = best_of(2, || tensor = TensorStencil::build(&layout, &pts));
    add("stencil_build", pts.len() as f64 / secs, "vertices", None);
    let mut stencil = Stencil::default();
    let secs = best_of(2, || stencil = Stencil::build(&layout, &pts));
    add(
        "stencil_build_full",
        pts.len() as f64 / secs,
        "vertices",
        None,
    );
    let secs = best_of(2, || stencil = Stencil::build_parallel(&layout, &pts));
    add(
        "stencil_build_full_all_cores",
        pts.len() as f64 / secs,
        "vertices",
        None,
    );
    progress("re-embedding");
    let mut out = vec![Point3::origin(); stencil.rows()];
    let bytes = Some(tensor.bytes_per_row());
    let secs = best_of(5, || tensor.positions(black_box(&control), &mut out));
    add("reembed", pts.len() as f64 / secs, "vertices", bytes);
    let secs = best_of(5, || {
        tensor.positions_parallel(black_box(&control), &mut out)
    });
    add(
        "reembed_all_cores",
        pts.len() as f64 / secs,
        "vertices",
        bytes,
    );
    let secs = best_of(5, || stencil.positions(black_box(&control), &mut out));
    let full_bytes = 8.0 + 12.0 * stencil.nonzeros() as f64 / stencil.rows() as f64 + 24.0;
    add(
        "reembed_full_f64",
        pts.len() as f64 / secs,
        "vertices",
        Some(full_bytes),
    );
    progress("re-embedding with tangents");
    let mut framed = TensorStencil::default();
    let secs = best_of(2, || {
        framed = TensorStencil::build_with_tangents(&layout, &pts)
    });
    add(
        "stencil_build_tangents",
        pts.len() as f64 / secs,
        "vertices",
        None,
    );
    let mut tangents = vec![[Vector3::zeros(); 2]; pts.len()];
    let bytes = Some(framed.bytes_per_row_with_tangents());
    let secs = best_of(5, || {
        framed.positions_and_tangents(black_box(&control), &mut out, &mut tangents)
    });
    add(
        "reembed_tangents",
        pts.len() as f64 / secs,
        "vertices",
        bytes,
    );
    // The same by the portable kernel (not the cubic AVX or AVX-512 one), for the ratio.
    let secs = best_of(5, || {
        framed.positions_and_tangents_by(
            StencilKernel::Portable,
            black_box(&control),
            &mut out,
            &mut tangents,
        )
    });
    add(
        "reembed_tangents_portable",
        pts.len() as f64 / secs,
        "vertices",
        bytes,
    );
    let secs = best_of(5, || {
        framed.positions_and_tangents_parallel(black_box(&control), &mut out, &mut tangents)
    });
    add(
        "reembed_tangents_all_cores",
        pts.len() as f64 / secs,
        "vertices",
        bytes,
    );
    let secs = best_of(5, || {
        for (r, (o, t)) in out.iter_mut().zip(&mut tangents).enumerate() {
            (*o, *t) = stencil.position_and_tangents(black_box(&control), r);
        }
    });
    let full_bytes = 8.0 + 28.0 * stencil.nonzeros() as f64 / stencil.rows() as f64 + 72.0;
    add(
        "reembed_tangents_full_f64",
        pts.len() as f64 / secs,
        "vertices",
        Some(full_bytes),
    );
    let (gpu_adapter, gpu_agreement) = if gpu {
        progress("re-embedding on the GPU");
        let mut gpu_figures = GpuRun::default();
        framed.positions_and_tangents_parallel(&control, &mut out, &mut tangents);
        let cpu = (out.clone(), tangents.clone());
        let name = gpu_reembedding(&tensor, &framed, &control, &mut gpu_figures)?;
        for (figure, rate) in gpu_figures.figures {
            add(figure, rate, "vertices", None);
        }
        let agreement = agreement(&cpu, &gpu_figures.frames);
        (Some(name), Some(agreement))
    } else {
        (None, None)
    };
    progress("drag events");
    let index = stencil.column_index(layout.control_count());
    let mut scratch = RefreshScratch::default();
    let q = pts[pts.len() / 3];
    let events = 20;
    let secs = best_of(1, || {
        for k in 0..events {
            let target = out[pts.len() / 3] + Vector3::new(1e-3 * k as f64, 0.0, 0.0);
            if let Ok(edit) = solve(&layout, &control, &[Constraint { point: q, target }]) {
                edit.apply(&mut control);
                refresh(&stencil, &index, &edit, &control, &mut out, &mut scratch);
            }
        }
    });
    add("drag_event", f64::from(events) / secs, "events", None);
    Ok(BenchReport {
        genus,
        vertices: pts.len(),
        copy_bandwidth_bytes_per_second: bandwidth,
        copy_bandwidth_all_cores_bytes_per_second: bandwidth_all_cores,
        threads: rayon::current_num_threads(),
        scalar_ops_per_second: scalar,
        gpu_adapter,
        gpu_agreement,
        figures,
    })
}

/// Positions and tangents per row.
type Frames = (Vec<Point3>, Vec<[Vector3; 2]>);

/// What the GPU measured: figures, and the last round trip's results.
#[derive(Default)]
struct GpuRun {
    figures: Vec<(&'static str, f64)>,
    frames: Frames,
}

/// The largest differences between two sets of frames (see [`GpuAgreement`]).
fn agreement(a: &Frames, b: &Frames) -> GpuAgreement {
    let (lo, hi) = embedding::bounding_box(&a.0);
    let diagonal = (hi - lo).norm();
    let largest = a.1.iter().flatten().map(|t| t.norm()).fold(0.0, f64::max);
    let worst = |d: &mut dyn Iterator<Item = f64>| d.fold(0.0, f64::max);
    let position = worst(&mut a.0.iter().zip(&b.0).map(|(p, q)| (p - q).norm()));
    let tangent = worst(
        &mut a
            .1
            .iter()
            .flatten()
            .zip(b.1.iter().flatten())
            .map(|(p, q)| (p - q).norm()),
    );
    GpuAgreement {
        position_of_diagonal: position / diagonal,
        tangent_of_largest: tangent / largest,
    }
}

/// Rows per second on the GPU for `positions` (positions only) and `framed` (with tangents): the
/// kernel alone (repeated dispatches, one wait) and, with tangents, the round trip an editor makes
/// (upload, kernel, read-back). Returns the adapter's name.
fn gpu_reembedding(
    positions: &TensorStencil,
    framed: &TensorStencil,
    control: &[Point3],
    run: &mut GpuRun,
) -> anyhow::Result<String> {
    let figures = &mut run.figures;
    use ntori::render::reembed::GpuReembed;
    let (device, queue, name) = ntori::render::open_device(None)?;
    let rows = positions.rows() as f64;
    const REPEATS: u32 = 20;
    for (figure, stencil) in [("reembed_gpu", positions), ("reembed_gpu_tangents", framed)] {
        let gpu = GpuReembed::new(&device, stencil, control.len())?;
        // The first run compiles and warms up.
        gpu.dispatch(&device, &queue, control, 1);
        gpu.wait(&device)?;
        let mut failed = None;
        let secs = best_of(5, || {
            gpu.dispatch(&device, &queue, control, REPEATS);
            failed = gpu.wait(&device).err().or(failed.take());
        });
        if let Some(e) = failed {
            return Err(e.into());
        }
        figures.push((figure, rows * f64::from(REPEATS) / secs));
    }
    let gpu = GpuReembed::new(&device, framed, control.len())?;
    let mut out = vec![Point3::origin(); framed.rows()];
    let mut tangents = vec![[Vector3::zeros(); 2]; framed.rows()];
    let mut failed = None;
    let secs = best_of(5, || {
        let result = gpu.positions_and_tangents(&device, &queue, control, &mut out, &mut tangents);
        failed = result.err().or(failed.take());
    });
    if let Some(e) = failed {
        return Err(e.into());
    }
    figures.push(("reembed_gpu_tangents_round_trip", rows / secs));
    run.frames = (out, tangents);
    Ok(name)
}

/// t_e = t_r = t giving about `vertices` vertices.
fn tessellation_size(genus: u32, vertices: usize) -> u32 {
    (1..=charts::MAX_RESOLUTION)
        .find(|&t| charts::Tessellation::expected_vertices(genus, t, t) >= vertices as u64)
        .unwrap_or(charts::MAX_RESOLUTION)
}
