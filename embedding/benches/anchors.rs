//! ntori's stencils side by side with OpenSubdiv's, in one run, as ratios.
//!
//! At about 10⁴, 10⁵ and 10⁶ vertices (or `NTORI_BENCH_VERTICES`, a comma-separated list) of a
//! genus-g surface (g = 2, or `NTORI_BENCH_GENUS`):
//! - OpenSubdiv 3.5: Catmull–Clark uniform refinement stencils of a genus-g quad cage at the level
//!   with that many vertices, and limit stencils (with and without first derivatives) at as many
//!   points; the factories' time per point and the CPU evaluator's vertices per second.
//! - ntori: the tensor stencil (positions) and the full f64 stencil (with derivatives) at as many
//!   tessellation vertices; build time per point and re-embedding vertices per second, on one
//!   thread and on all cores; and the tensor stencil's bytes streamed without its arithmetic
//!   (`TensorStencil::stream_rows`), the ceiling memory sets for them on one core.
//! - A triad (a = b + s·c over 192 MiB) for the memory bandwidth of this run, on one thread (what
//!   the one-thread rates are set against) and on all (what the all-core rate is set against).
//!
//! Each figure is the best of several runs, OpenSubdiv's and ntori's measured back to back. `cargo bench
//! --bench anchors` prints the whole table; in test mode (`cargo test --benches`) it runs 10⁴ once.
//! Without OpenSubdiv (no `libosd-dev`) its columns say so and the rest still runs.

use std::hint::black_box;
use std::time::Instant;

use anchors::{QuadMesh, Refiner};
use charts::{Atlas, ChartPoint, Tessellation};
use embedding::{Layout, Point3, SplineSettings, Stencil, TensorStencil, Vector3};

/// Limit stencils need adaptive refinement round extraordinary vertices; 4 levels is OpenSubdiv's
/// usual choice for evaluation at a few digits.
const ISOLATION: u32 = 4;

fn main() {
    let full = std::env::args().any(|a| a == "--bench");
    let genus: u32 = std::env::var("NTORI_BENCH_GENUS")
        .ok()
        .and_then(|g| g.parse().ok())
        .unwrap_or(2);
    let (mut targets, runs) = if full {
        (vec![10_000, 100_000, 1_000_000], 7)
    } else {
        (vec![10_000], 1)
    };
    if let Ok(list) = std::env::var("NTORI_BENCH_VERTICES") {
        targets = list
            .split(',')
            .filter_map(|n| n.trim().parse().ok())
            .collect();
    }
    if anchors::available() {
        println!("OpenSubdiv 3.5 (system libosd), genus {genus}, best of {runs} runs");
    } else if std::env::var_os("NTORI_REQUIRE_TOOLS").is_some() {
        panic!(
            "NTORI_REQUIRE_TOOLS is set but OpenSubdiv is not linked (apt-get install libosd-dev)"
        );
    } else {
        println!("OpenSubdiv is not linked (apt-get install libosd-dev): ntori's side only");
    }
    let triad = Triad::measure(runs.max(3));
    println!(
        "triad bandwidth this run: {:.2} GB/s on one thread, {:.2} GB/s on {} threads",
        triad.one / 1e9,
        triad.all / 1e9,
        rayon::current_num_threads()
    );
    let (best, median) = round_trip(if full { 101 } else { 11 });
    println!(
        "rayon's round trip from this thread (an empty task on each core): best {best:.0} µs, \
         median {median:.0} µs; work under twice that runs on the calling thread alone\n"
    );
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a pool");
    let cores = rayon::current_num_threads();
    let cage = QuadMesh::genus_cage(genus);
    let atlas = Atlas::new(genus).expect("genus ≤ 64");
    let layout = Layout::new(&atlas, SplineSettings::default()).expect("default settings");
    let control = controls(&layout);
    for &target in &targets {
        let level = (1..=8)
            .min_by_key(|&l| {
                (cage.refined_vertex_count(l) as f64 / target as f64)
                    .ln()
                    .abs()
                    .to_bits()
            })
            .expect("levels");
        let vertices = cage.refined_vertex_count(level);
        println!("== {vertices} vertices (OpenSubdiv uniform level {level})");
        let osd = Osd::measure(&cage, level, vertices, runs);
        let pts = tessellation_points(&atlas, vertices);
        // OpenSubdiv's fastest way, run in turns with ntori's tensor stencil so that both see the
        // same machine (it is shared, and its speed changes from minute to minute).
        let mut rival = osd.uniform.as_ref().map(|u| {
            let mut out = vec![[0f32; 3]; u.table.rows()];
            let cage = &cage;
            move || {
                u.table
                    .update_values(&cage.positions, &mut out)
                    .expect("applies")
            }
        });
        let rival = rival.as_mut().map(|f| f as &mut dyn FnMut());
        let ours = Ntori::measure(&layout, &control, &pts, runs, &one, rival);
        report(&osd, &ours, &triad, cores);
    }
}

/// OpenSubdiv's uniform stencils: vertices/s by the evaluator on float3, on float4, and by Far's
/// UpdateValues; the factory's µs per vertex; bytes per vertex.
struct Uniform {
    table: anchors::StencilTable,
    rates: [f64; 3],
    build: f64,
    bytes: f64,
}

impl Uniform {
    fn fastest(&self) -> f64 {
        self.rates.into_iter().fold(0.0, f64::max)
    }
}

/// OpenSubdiv's figures at one size (None where OpenSubdiv is not linked).
struct Osd {
    uniform: Option<Uniform>,
    /// Limit stencils: vertices/s applied, factory µs per point; the same with derivatives.
    limit: Option<(f64, f64)>,
    limit_derivatives: Option<(f64, f64)>,
}

impl Osd {
    fn measure(cage: &QuadMesh, level: u32, vertices: usize, runs: usize) -> Osd {
        let uniform = (|| {
            let refiner = Refiner::new(cage).ok()?;
            refiner.refine_uniform(level).ok()?;
            let (table, build) = timed(|| refiner.stencils());
            let table = table.ok()?;
            // OpenSubdiv's fastest of three ways to apply them, run in turns: the CPU evaluator on
            // float3 and on float4 (its SIMD kernel), and Far's UpdateValues template.
            let mut out = vec![[0f32; 3]; table.rows()];
            let four: Vec<[f32; 4]> = cage
                .positions
                .iter()
                .map(|p| [p[0], p[1], p[2], 0.0])
                .collect();
            let mut out4 = vec![[0f32; 4]; table.rows()];
            let mut best = [f64::INFINITY; 3];
            for _ in 0..runs {
                best[0] = best[0].min(timed(|| table.apply(&cage.positions, &mut out)).1);
                best[1] = best[1].min(timed(|| table.apply4(&four, &mut out4)).1);
                best[2] = best[2].min(timed(|| table.update_values(&cage.positions, &mut out)).1);
            }
            let rates = best.map(|secs| table.rows() as f64 / secs);
            Some(Uniform {
                rates,
                build: 1e6 * build / table.rows() as f64,
                bytes: table.bytes_per_row(),
                table,
            })
        })();
        let k = ((vertices as f64 / cage.faces.len() as f64).sqrt().round() as u32).max(1);
        let locations = cage.limit_locations(k);
        let limit = |derivatives: bool| -> Option<(f64, f64)> {
            let refiner = Refiner::new(cage).ok()?;
            refiner.refine_adaptive(ISOLATION).ok()?;
            let (table, build) = timed(|| refiner.limit_stencils(&locations, derivatives));
            let table = table.ok()?;
            let n = table.rows();
            let (mut p, mut du, mut dv) =
                (vec![[0f32; 3]; n], vec![[0f32; 3]; n], vec![[0f32; 3]; n]);
            let apply = best_of(runs, || {
                if derivatives {
                    table.apply_with_derivatives(&cage.positions, &mut p, &mut du, &mut dv)
                } else {
                    table.apply(&cage.positions, &mut p)
                }
                .expect("applies")
            });
            Some((n as f64 / apply, 1e6 * build / n as f64))
        };
        Osd {
            uniform,
            limit: limit(false),
            limit_derivatives: limit(true),
        }
    }
}

/// ntori's figures at one size.
struct Ntori {
    vertices: usize,
    /// Tensor stencil: build µs per point on one thread and on all cores; vertices/s on one thread
    /// and on all cores; bytes per vertex; blocks per vertex; worst position error against f64 as a
    /// fraction of the bounding-box diagonal.
    tensor_build: (f64, f64),
    tensor_apply: (f64, f64),
    /// The same rows' bytes streamed without the arithmetic ([`TensorStencil::stream_rows`]),
    /// vertices/s on one thread.
    tensor_stream: f64,
    /// OpenSubdiv's Far UpdateValues, vertices/s, timed in turns with the tensor stencil.
    rival: Option<f64>,
    tensor_bytes: f64,
    tensor_blocks: f64,
    tensor_error: f64,
    /// Full f64 stencil: build µs per point (one thread, all cores); positions/s and positions
    /// with S_u and S_v/s (one thread).
    full_build: (f64, f64),
    full_positions: f64,
    full_derivatives: f64,
}

impl Ntori {
    fn measure(
        layout: &Layout,
        control: &[Point3],
        pts: &[ChartPoint],
        runs: usize,
        one: &rayon::ThreadPool,
        mut rival: Option<&mut dyn FnMut()>,
    ) -> Ntori {
        let n = pts.len() as f64;
        let build_runs = runs.min(3);
        let mut tensor = TensorStencil::default();
        let build_one =
            one.install(|| best_of(build_runs, || tensor = TensorStencil::build(layout, pts)));
        let build_all = best_of(build_runs, || tensor = TensorStencil::build(layout, pts));
        let mut full = Stencil::default();
        let full_one = best_of(build_runs.min(2), || full = Stencil::build(layout, pts));
        let full_all = best_of(build_runs.min(2), || {
            full = Stencil::build_parallel(layout, pts)
        });
        let mut out = vec![Point3::origin(); pts.len()];
        let (mut apply_one, mut rival_secs) = (f64::INFINITY, f64::INFINITY);
        for _ in 0..runs {
            apply_one = apply_one.min(timed(|| tensor.positions(black_box(control), &mut out)).1);
            if let Some(rival) = rival.as_mut() {
                rival_secs = rival_secs.min(timed(&mut *rival).1);
            }
        }
        let apply_all = best_of(runs, || {
            tensor.positions_parallel(black_box(control), &mut out)
        });
        let mut streamed = vec![Point3::origin(); pts.len()];
        let stream = best_of(runs, || black_box(&tensor).stream_rows(&mut streamed));
        let mut exact = vec![Point3::origin(); pts.len()];
        let full_positions = best_of(runs, || full.positions(black_box(control), &mut exact));
        let (mut du, mut dv) = (
            vec![Vector3::zeros(); pts.len()],
            vec![Vector3::zeros(); pts.len()],
        );
        let full_derivatives = best_of(runs, || {
            full.positions(black_box(control), &mut exact);
            full.derivatives(control, &mut du, &mut dv);
        });
        let (lo, hi) = embedding::bounding_box(&exact);
        let diagonal = (hi - lo).norm();
        let error = out
            .iter()
            .zip(&exact)
            .map(|(a, b)| (a - b).norm())
            .fold(0.0, f64::max);
        Ntori {
            vertices: pts.len(),
            tensor_build: (1e6 * build_one / n, 1e6 * build_all / n),
            tensor_apply: (n / apply_one, n / apply_all),
            tensor_stream: n / stream,
            rival: rival.map(|_| n / rival_secs),
            tensor_bytes: tensor.bytes_per_row(),
            tensor_blocks: tensor.blocks() as f64 / n,
            tensor_error: error / diagonal,
            full_build: (1e6 * full_one / n, 1e6 * full_all / n),
            full_positions: n / full_positions,
            full_derivatives: n / full_derivatives,
        }
    }
}

fn report(osd: &Osd, ours: &Ntori, triad: &Triad, cores: usize) {
    let m = |x: f64| format!("{:.1} M/s", x / 1e6);
    let ratio = |a: f64, b: Option<f64>| b.map_or("—".into(), |b| format!("{:.2}×", a / b));
    let osd_uniform = osd.uniform.as_ref().map(Uniform::fastest);
    println!(
        "  re-embedding, one thread (vertices/s; ratio = ntori ÷ OpenSubdiv's fastest uniform)"
    );
    if let Some(u) = &osd.uniform {
        for (name, rate) in ["evaluator, float3", "evaluator, float4", "Far UpdateValues"]
            .iter()
            .zip(u.rates)
        {
            println!(
                "    OpenSubdiv uniform, {name:<18}{:>10}  {:.0} B/vertex  {:.2} of triad",
                m(rate),
                u.bytes,
                rate * u.bytes / triad.one
            );
        }
    }
    if let Some((rate, _)) = osd.limit {
        println!("    OpenSubdiv limit stencils     {:>10}", m(rate));
    }
    if let Some((rate, _)) = osd.limit_derivatives {
        println!("    OpenSubdiv limit + S_s, S_t   {:>10}", m(rate));
    }
    let (one, all) = ours.tensor_apply;
    println!(
        "    ntori tensor stencil          {:>10}  {:.0} B/vertex  {:.2} of triad  {} ({:.2} blocks/vertex, error {:.1e} of the diagonal)",
        m(one),
        ours.tensor_bytes,
        one * ours.tensor_bytes / triad.one,
        ratio(one, osd_uniform),
        ours.tensor_blocks,
        ours.tensor_error
    );
    println!(
        "    its bytes alone (no arithmetic){:>10}  {:.0} B/vertex  {:.2} of triad: the kernel spends {:.0}% of its time on the sums",
        m(ours.tensor_stream),
        ours.tensor_bytes,
        ours.tensor_stream * ours.tensor_bytes / triad.one,
        100.0 * (1.0 - one / ours.tensor_stream).max(0.0)
    );
    if let Some(rival) = ours.rival {
        println!(
            "    in turns: ntori tensor {} against OpenSubdiv Far UpdateValues {}: {:.2}×",
            m(one),
            m(rival),
            one / rival
        );
    }
    println!(
        "    ntori full f64 stencil        {:>10}  {}",
        m(ours.full_positions),
        ratio(ours.full_positions, osd_uniform)
    );
    println!(
        "    ntori full + S_u, S_v         {:>10}  {} (against limit + derivatives)",
        m(ours.full_derivatives),
        ratio(ours.full_derivatives, osd.limit_derivatives.map(|l| l.0))
    );
    println!(
        "  re-embedding on {cores} threads: ntori tensor {} ({:.2}× its one thread, {:.2} of the {cores}-thread triad)",
        m(all),
        all / one,
        all * ours.tensor_bytes / triad.all
    );
    println!("  stencil build (µs per point; ratio = OpenSubdiv's limit factory ÷ ntori)");
    if let Some(u) = &osd.uniform {
        println!("    OpenSubdiv uniform factory    {:>8.3}", u.build);
    }
    let limit = osd.limit.map(|l| l.1);
    if let Some(b) = limit {
        println!("    OpenSubdiv limit factory      {b:>8.3}");
    }
    if let Some((_, b)) = osd.limit_derivatives {
        println!("    OpenSubdiv limit + derivatives{b:>8.3}");
    }
    let (b1, ball) = ours.tensor_build;
    let speedup = |ours: f64| limit.map_or("—".into(), |l| format!("{:.2}×", l / ours));
    println!(
        "    ntori tensor, one thread      {b1:>8.3}  {}",
        speedup(b1)
    );
    println!(
        "    ntori tensor, {cores} threads       {ball:>8.3}  ({:.2}× its one thread)",
        b1 / ball
    );
    let (f1, fall) = ours.full_build;
    println!(
        "    ntori full f64 + derivatives  {f1:>8.3}  {}",
        speedup(f1)
    );
    println!(
        "    ntori full f64, {cores} threads     {fall:>8.3}  ({:.2}× its one thread)",
        f1 / fall
    );
    println!("  ({} ntori vertices)\n", ours.vertices);
}

/// Tessellation vertices of a genus-`genus` surface, exactly `count` of them (the first ones of the
/// smallest t_e = t_r tessellation with enough).
fn tessellation_points(atlas: &Atlas, count: usize) -> Vec<ChartPoint> {
    let genus = atlas.genus();
    let t = (1..=charts::MAX_RESOLUTION)
        .find(|&t| Tessellation::expected_vertices(genus, t, t) >= count as u64)
        .unwrap_or(charts::MAX_RESOLUTION);
    let mut v = atlas.tessellate(t, t).expect("a tessellation").vertices;
    v.truncate(count);
    v
}

fn controls(layout: &Layout) -> Vec<Point3> {
    (0..layout.control_count())
        .map(|i| {
            let i = i as f64;
            Point3::new((i * 0.37).sin(), (i * 0.71).cos(), (i * 0.13).sin())
        })
        .collect()
}

fn timed<T>(f: impl FnOnce() -> T) -> (T, f64) {
    let t = Instant::now();
    let out = f();
    (out, t.elapsed().as_secs_f64())
}

fn best_of(runs: usize, mut f: impl FnMut()) -> f64 {
    (0..runs.max(1))
        .map(|_| timed(&mut f).1)
        .fold(f64::INFINITY, f64::min)
}

/// Microseconds for an empty task on each of the pool's threads, called from outside the pool as
/// the editor and the commands call it, a millisecond after the last (the workers asleep): the
/// best and the median of `runs`. Small jobs scale less than 2× by about this much.
fn round_trip(runs: usize) -> (f64, f64) {
    let threads = rayon::current_num_threads();
    let mut times: Vec<f64> = (0..runs.max(1))
        .map(|_| {
            std::thread::sleep(std::time::Duration::from_millis(1));
            1e6 * timed(|| {
                rayon::scope(|s| {
                    for k in 0..threads {
                        s.spawn(move |_| {
                            black_box(k);
                        });
                    }
                })
            })
            .1
        })
        .collect();
    times.sort_by(f64::total_cmp);
    (times[0], times[times.len() / 2])
}

/// The memory bandwidth of this run: bytes per second of a = b + s·c over three 64 MiB arrays (24
/// bytes per element, as STREAM counts them), best of several runs, on the calling thread and on
/// all the pool's threads (each summing its own part of the arrays).
struct Triad {
    one: f64,
    all: f64,
}

impl Triad {
    fn measure(runs: usize) -> Triad {
        use rayon::prelude::*;
        let n = 8 << 20;
        let b: Vec<f64> = (0..n).map(|i| i as f64).collect();
        let c: Vec<f64> = (0..n).map(|i| (n - i) as f64).collect();
        let mut a = vec![0f64; n];
        let triad = |a: &mut [f64], b: &[f64], c: &[f64]| {
            for ((a, b), c) in a.iter_mut().zip(b).zip(c) {
                *a = b + 3.0 * c;
            }
        };
        let one = best_of(runs, || {
            triad(&mut a, black_box(&b), black_box(&c));
            black_box(&mut a);
        });
        let part = n.div_ceil(rayon::current_num_threads());
        let all = best_of(runs, || {
            a.par_chunks_mut(part)
                .zip(black_box(&b).par_chunks(part))
                .zip(black_box(&c).par_chunks(part))
                .for_each(|((a, b), c)| triad(a, b, c));
            black_box(&mut a);
        });
        Triad {
            one: 24.0 * n as f64 / one,
            all: 24.0 * n as f64 / all,
        }
    }
}
