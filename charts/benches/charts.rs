//! Throughput of the chart layer: applying one transition function, locating a chart point in every
//! chart that holds it, and locating a model-space point (reduce into the polygon, then every chart).
//! Criterion reports elements (points) per second; compare genera within one run.

use charts::{Atlas, ChartId, ChartPoint, Domain, ModelPoint};
use criterion::{BenchmarkId, Criterion, Throughput, criterion_group, criterion_main};
use num_complex::Complex64;
use std::hint::black_box;

const BATCH: usize = 4096;

/// Deterministic points spread over each chart's domain, cycling through the charts.
fn chart_points(atlas: &Atlas) -> Vec<ChartPoint> {
    (0..BATCH)
        .map(|i| {
            let chart = &atlas.charts()[i % atlas.charts().len()];
            let (u, v) = (
                (i as f64 * 0.754_877_666).fract(),
                (i as f64 * 0.569_840_291).fract(),
            );
            let w = match chart.domain() {
                Domain::Square => Complex64::new(u - 0.5, v - 0.5) * 0.999,
                Domain::Disk => Complex64::from_polar(0.4995 * u.sqrt(), std::f64::consts::TAU * v),
            };
            ChartPoint::new(chart.id(), w)
        })
        .collect()
}

fn transition_apply(c: &mut Criterion) {
    let mut group = c.benchmark_group("transition_apply");
    group.throughput(Throughput::Elements(BATCH as u64));
    for genus in [2u32, 8, 64] {
        let atlas = Atlas::new(genus).unwrap();
        // vertex → first edge chart, first component: a representative LFT.
        let t = atlas.transitions(ChartId(1), ChartId(2))[0].clone();
        let pts: Vec<Complex64> = chart_points(&atlas).iter().map(|p| p.coords).collect();
        group.bench_with_input(BenchmarkId::from_parameter(genus), &pts, |b, pts| {
            b.iter(|| {
                pts.iter()
                    .map(|&w| t.apply(black_box(w)))
                    .fold(Complex64::ZERO, |a, z| a + z)
            })
        });
    }
    group.finish();
}

fn locate(c: &mut Criterion) {
    let mut group = c.benchmark_group("locate_chart_point");
    group.throughput(Throughput::Elements(BATCH as u64));
    for genus in [0u32, 1, 2, 8, 64] {
        let atlas = Atlas::new(genus).unwrap();
        let pts = chart_points(&atlas);
        group.bench_with_input(BenchmarkId::from_parameter(genus), &pts, |b, pts| {
            b.iter(|| {
                pts.iter()
                    .map(|&p| atlas.locate_unchecked(black_box(p)).representations().len())
                    .sum::<usize>()
            })
        });
    }
    group.finish();
}

fn locate_model(c: &mut Criterion) {
    let mut group = c.benchmark_group("locate_model_point");
    group.throughput(Throughput::Elements(BATCH as u64));
    for genus in [2u32, 8, 64] {
        let atlas = Atlas::new(genus).unwrap();
        let pts: Vec<ModelPoint> = charts::check::spread_points(&atlas, BATCH);
        group.bench_with_input(BenchmarkId::from_parameter(genus), &pts, |b, pts| {
            b.iter(|| {
                pts.iter()
                    .map(|&z| atlas.locate_model(black_box(z)).representations().len())
                    .sum::<usize>()
            })
        });
    }
    group.finish();
}

fn build(c: &mut Criterion) {
    let mut group = c.benchmark_group("atlas_new");
    group.sample_size(10);
    for genus in [2u32, 16, 64] {
        group.bench_function(BenchmarkId::from_parameter(genus), |b| {
            b.iter(|| Atlas::new(black_box(genus)).unwrap())
        });
    }
    group.finish();
}

fn tessellate(c: &mut Criterion) {
    let mut group = c.benchmark_group("tessellate_genus_10");
    group.sample_size(10);
    let atlas = Atlas::new(10).unwrap();
    for t in [32u32, 64] {
        let triangles = charts::Tessellation::expected_triangles(10, t, t);
        group.throughput(Throughput::Elements(triangles));
        group.bench_function(BenchmarkId::from_parameter(t), |b| {
            b.iter(|| {
                atlas
                    .tessellate(black_box(t), black_box(t))
                    .unwrap()
                    .triangles
                    .len()
            })
        });
    }
    group.finish();
}

criterion_group!(
    benches,
    transition_apply,
    locate,
    locate_model,
    build,
    tessellate
);
criterion_main!(benches);
