//! The initial fit, end to end (mesh, cut, Floater, relaxation, least squares), for genus 2, 5 and
//! 10 at the default resolution and spline settings. The relaxation dominates: its sweeps are
//! reported by `ntori new`.

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use embedding::SplineSettings;
use embedding::fit::{FitSettings, initial_model};

fn fit(c: &mut Criterion) {
    let mut group = c.benchmark_group("initial_fit");
    group.sample_size(10);
    for genus in [2u32, 5, 10] {
        group.bench_with_input(BenchmarkId::from_parameter(genus), &genus, |b, &g| {
            b.iter(|| {
                initial_model(g, 32, SplineSettings::default(), FitSettings::default()).unwrap()
            })
        });
    }
    group.finish();
}

criterion_group!(benches, fit);
criterion_main!(benches);
