//! The one evaluation path: a [`Surface`] and a set of chart points (a tessellation's vertices) →
//! each point's position, tangents, unit normal and, on request, its curvatures and blend weights,
//! handed in order to a sink the caller owns.
//!
//! In the manner of lyon's geometry builders, nothing here builds an output: export fills its mesh
//! arrays, the renderer its vertex colours, the editor its live mesh, each from the same
//! [`Sample`]s. Positions and tangents come from stencil rows ([`Stencil`], control points sorted
//! per row), so a consumer that keeps a stencil for later edits ([`evaluate_rows`]) sees exactly
//! the numbers a one-off evaluation ([`evaluate`]) gives. The work is spread over the available
//! cores in bounded batches; the sink is called on the caller's thread, in index order.

use charts::{ChartId, ChartPoint};

use crate::spline_surface::Surface;
use crate::stencil::Stencil;
use crate::surface::{Layout, Point3, Vector3};

/// What a sink needs beyond position, tangents and normal.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Wants {
    /// Gaussian and mean curvature (second derivatives: costs about twice the rest).
    pub curvature: bool,
    /// Every chart's normalised blend weight at the point.
    pub blends: bool,
}

/// Gaussian and mean curvature at a surface point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Curvatures {
    pub gaussian: f64,
    pub mean: f64,
}

impl Curvatures {
    /// The principal curvatures κ₁ ≥ κ₂: H ± √(H² − K).
    pub fn principal(&self) -> (f64, f64) {
        // H² ≥ K holds exactly; rounding can make the difference a hair negative at umbilics.
        let root = (self.mean * self.mean - self.gaussian).max(0.0).sqrt();
        (self.mean + root, self.mean - root)
    }
}

/// One evaluated surface point.
#[derive(Clone, Debug, PartialEq)]
pub struct Sample {
    /// The point's index in the caller's list (a tessellation vertex, a stencil row).
    pub index: usize,
    pub point: ChartPoint,
    pub position: Point3,
    /// S_u and S_v in the point's own chart.
    pub du: Vector3,
    pub dv: Vector3,
    /// S_u × S_v / |S_u × S_v|, or `None` where |S_u × S_v| is below the evaluation's threshold
    /// (the surface is pinched there and has no tangent plane).
    pub normal: Option<Vector3>,
    /// With [`Wants::curvature`].
    pub curvature: Option<Curvatures>,
    /// With [`Wants::blends`]: (chart, normalised weight) for every chart holding the point.
    pub blends: Vec<(ChartId, f64)>,
}

/// Receives samples in index order.
pub trait SampleSink {
    fn sample(&mut self, sample: &Sample);
}

impl<F: FnMut(&Sample)> SampleSink for F {
    fn sample(&mut self, sample: &Sample) {
        self(sample)
    }
}

/// Points evaluated per stencil built (a stencil of 10⁷ points would not fit in memory).
const CHUNK: usize = 8192;

/// Evaluates `surface` at every point of `points` into `sink` (see the module documentation).
/// A normal is `None` where |S_u × S_v| ≤ `min_normal_length`.
pub fn evaluate(
    surface: &Surface,
    points: &[ChartPoint],
    wants: Wants,
    min_normal_length: f64,
    sink: &mut impl SampleSink,
) {
    let layout = surface.layout();
    let control = surface.control_points();
    // Asked once: `available_parallelism` reads the cgroup's files on Linux.
    let threads = threads();
    let batch = CHUNK * threads;
    for (b, batch_points) in points.chunks(batch).enumerate() {
        // Equal chunks, one a thread: 10⁴ points as 8192 and 1808 would keep one core waiting.
        let chunk = batch_points.len().div_ceil(threads).clamp(1, CHUNK);
        let chunks: Vec<&[ChartPoint]> = batch_points.chunks(chunk).collect();
        let results = in_parallel(&chunks, |k, pts| {
            let stencil = Stencil::build(&layout, pts);
            let first = b * batch + k * chunk;
            (0..pts.len())
                .map(|r| {
                    let jet = stencil.position_and_tangents(control, r);
                    sample(
                        &layout,
                        control,
                        first + r,
                        pts[r],
                        jet,
                        wants,
                        min_normal_length,
                    )
                })
                .collect()
        });
        feed(results, sink);
    }
}

/// Evaluates the stencil rows `rows` (increasing) of `stencil`, built for `points` over `surface`'s
/// layout, into `sink`; each sample's index is its row. For callers that keep a stencil to
/// re-evaluate the rows an edit touched.
pub fn evaluate_rows(
    surface: &Surface,
    stencil: &Stencil,
    points: &[ChartPoint],
    rows: &[u32],
    wants: Wants,
    min_normal_length: f64,
    sink: &mut impl SampleSink,
) {
    let layout = surface.layout();
    let control = surface.control_points();
    let threads = threads();
    let per_chunk = rows.len().div_ceil(threads).clamp(1, CHUNK);
    let batch = per_chunk * threads;
    for batch_rows in rows.chunks(batch) {
        let chunks: Vec<&[u32]> = batch_rows.chunks(per_chunk).collect();
        let results = in_parallel(&chunks, |_, rows| {
            rows.iter()
                .map(|&r| {
                    let r = r as usize;
                    let jet = stencil.position_and_tangents(control, r);
                    sample(
                        &layout,
                        control,
                        r,
                        points[r],
                        jet,
                        wants,
                        min_normal_length,
                    )
                })
                .collect()
        });
        feed(results, sink);
    }
}

fn sample(
    layout: &Layout,
    control: &[Point3],
    index: usize,
    point: ChartPoint,
    (position, [du, dv]): (Point3, [Vector3; 2]),
    wants: Wants,
    min_normal_length: f64,
) -> Sample {
    let n = du.cross(&dv);
    let length = n.norm();
    let normal = (length > min_normal_length).then(|| n / length);
    let curvature = wants.curvature.then(|| {
        let jet = layout.eval(control, point);
        Curvatures {
            gaussian: jet.gaussian_curvature(),
            mean: jet.mean_curvature(),
        }
    });
    let blends = if wants.blends {
        layout.blends(point)
    } else {
        Vec::new()
    };
    Sample {
        index,
        point,
        position,
        du,
        dv,
        normal,
        curvature,
        blends,
    }
}

fn feed(results: Vec<Vec<Sample>>, sink: &mut impl SampleSink) {
    for s in results.iter().flatten() {
        sink.sample(s);
    }
}

fn threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get().min(16))
}

/// `work(k, chunks[k])` for every k, on up to [`threads`] scoped threads; results in chunk order.
fn in_parallel<T: Sync, R: Send>(chunks: &[T], work: impl Fn(usize, &T) -> R + Sync) -> Vec<R> {
    if chunks.len() <= 1 {
        return chunks.iter().enumerate().map(|(k, c)| work(k, c)).collect();
    }
    std::thread::scope(|scope| {
        let handles: Vec<_> = chunks
            .iter()
            .enumerate()
            .map(|(k, c)| {
                let work = &work;
                scope.spawn(move || work(k, c))
            })
            .collect();
        handles
            .into_iter()
            .map(|h| h.join().unwrap_or_else(|e| std::panic::resume_unwind(e)))
            .collect()
    })
}

/// Runs `work` over matching chunks of `input` and `output` on the available cores (one chunk when
/// there is little to do). For per-point work outside the sample path (the editor's drag rows).
pub fn parallel_chunks<T: Sync, U: Send>(
    input: &[T],
    output: &mut [U],
    work: impl Fn(&[T], &mut [U]) + Sync,
) {
    const MIN_PER_THREAD: usize = 16_384;
    let threads = threads().min(input.len().div_ceil(MIN_PER_THREAD)).max(1);
    if threads == 1 {
        work(input, output);
        return;
    }
    let per = input.len().div_ceil(threads);
    std::thread::scope(|scope| {
        for (i, o) in input.chunks(per).zip(output.chunks_mut(per)) {
            let work = &work;
            scope.spawn(move || work(i, o));
        }
    });
}
