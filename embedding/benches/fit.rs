//! The fits, end to end, and the loops of a user's mesh:
//!
//! - `initial_fit`: `ntori new`'s pipeline (mesh, cut, Floater, relaxation, least squares) for
//!   genus 2, 5 and 10 at `ntori new`'s resolution, grid and smoothness (genus 5 and 10:
//!   resolution 40), and with `--bench` genus 32 too (on its 377 252 triangles, grid of 64 and
//!   564 018 edge samples: 50.9 s a fit here on 2026-11-29, 8.9 GB; 46 s and 6.4 GB before the
//!   samples; issue 12's targets: 1 s, 5 s and 60 s for genus 2, 10 and 32, read 0.69 s and 4.73 s
//!   in the same run). The map and the factorization dominate: `ntori new -v` reports the stages.
//!   The plates' wider bands (`holed::PLATE_BAND`) kept the time: on a busier day genus 2 and 10
//!   read 1.13 s and 7.20 s against 1.07 s and 7.16 s on the narrow bands, one run each in turn
//!   (genus 32's mesh is now 372 392 triangles, at resolution 29).
//!   On 2026-11-30 (baseline 35–39 ms) genus 2, 5 and 10 read 0.67–0.70 s, 2.37 s and 4.70–4.75 s,
//!   and one genus-32 fit the same way outside the bench 53.6 s, 9.0 GB at its peak.
//! - `mesh_fit`: `ntori fit`'s pipeline (greedy loops from several base vertices, the canonical
//!   words, the map, least squares) on a genus-4 plate mesh of about 10 000 vertices (issue 14's
//!   target: 10 s).
//! - `loops`: one greedy loop system and its canonical words on a genus-8 plate mesh split to
//!   about 10⁶ triangles (issue 14's target: 5 s).
//!
//! - `baseline`: a fixed workload of the same kind, measured in the same run: faer's sparse LU of
//!   a 160 × 160 grid's Laplacian (25 600 unknowns) and a solve. After the criterion groups, the
//!   fits are timed once more between runs of it and printed as multiples of it, since fit times
//!   on this shared machine moved by 50% from one day to the next (genus 2: 0.69 s, 1.07 s,
//!   1.34 s in sessions 44, 45 and 47) while the code did not.
//!
//! In test mode (`cargo test --benches`) each runs once, on meshes a quarter as fine, and the
//! ratios are not printed.

use criterion::{BenchmarkId, Criterion};
use embedding::Point3;
use embedding::fit::{default_mesh, default_settings, initial_model_of};
use embedding::holed::HoledMesh;
use embedding::mesh_fit::{self, mesh_model};
use mesh::HalfEdgeMesh;
use mesh::schema;

fn main() {
    let full = std::env::args().any(|a| a == "--bench");
    let mut c = Criterion::default().configure_from_args();
    initial_fit(&mut c, if full { &[2, 5, 10, 32] } else { &[2, 5, 10] });
    whole_mesh_fit(&mut c, if full { 34 } else { 12 });
    loops(&mut c, if full { 42 } else { 12 });
    baseline(&mut c);
    c.final_summary();
    if full {
        ratios(&[2, 5, 10], 34);
    }
}

/// The grid of [`grid_solve`] on a side.
const BASELINE_SIDE: usize = 160;

/// The baseline workload: the 5-point Laplacian of a `side` × `side` grid (Dirichlet boundary)
/// factored by faer's sparse LU, as the map's Newton steps and the fit's normal equations are, and
/// solved for a right-hand side of ones. Returns the solution's middle value, for `black_box`.
fn grid_solve(side: usize) -> f64 {
    use faer::prelude::Solve;
    use faer::sparse::{SparseColMat, Triplet};
    let index = |i: usize, j: usize| i * side + j;
    let mut triplets = Vec::with_capacity(5 * side * side);
    for i in 0..side {
        for j in 0..side {
            triplets.push(Triplet::new(index(i, j), index(i, j), 4.0));
            let mut neighbour = |a: usize, b: usize| {
                triplets.push(Triplet::new(index(i, j), index(a, b), -1.0));
            };
            if i > 0 {
                neighbour(i - 1, j);
            }
            if i + 1 < side {
                neighbour(i + 1, j);
            }
            if j > 0 {
                neighbour(i, j - 1);
            }
            if j + 1 < side {
                neighbour(i, j + 1);
            }
        }
    }
    let n = side * side;
    let a = SparseColMat::<usize, f64>::try_new_from_triplets(n, n, &triplets).unwrap();
    let lu = a.sp_lu().unwrap();
    let x = lu.solve(faer::Mat::<f64>::ones(n, 1));
    x[(index(side / 2, side / 2), 0)]
}

fn baseline(c: &mut Criterion) {
    let mut group = c.benchmark_group("baseline");
    group.sample_size(20);
    let id = format!("sparse_lu_grid_{BASELINE_SIDE}");
    group.bench_function(id, |b| {
        b.iter(|| std::hint::black_box(grid_solve(BASELINE_SIDE)))
    });
    group.finish();
}

/// Seconds of the fastest of `runs` runs of `f`.
fn best_of(runs: usize, mut f: impl FnMut()) -> f64 {
    (0..runs)
        .map(|_| {
            let start = std::time::Instant::now();
            f();
            start.elapsed().as_secs_f64()
        })
        .fold(f64::INFINITY, f64::min)
}

/// Each fit timed once more, between two rounds of the baseline (the fastest of five each), and
/// printed as a multiple of the faster round: a ratio measured in the same minute.
fn ratios(genera: &[u32], mesh_resolution: usize) {
    let base = || {
        best_of(5, || {
            std::hint::black_box(grid_solve(BASELINE_SIDE));
        })
    };
    let report = |name: &str, f: &mut dyn FnMut()| {
        let before = base();
        let secs = best_of(1, &mut *f);
        let after = base();
        let baseline = before.min(after);
        println!(
            "{name}: {secs:.3} s = {:.1} × the baseline ({:.1} ms; {:.1} and {:.1} ms around it)",
            secs / baseline,
            baseline * 1e3,
            before * 1e3,
            after * 1e3
        );
    };
    println!("ratios to the baseline (sparse LU of a {BASELINE_SIDE}² grid), measured in turns:");
    for &genus in genera {
        report(&format!("initial_fit/{genus}"), &mut || {
            drop(plate_fit(genus))
        });
    }
    let mesh = HoledMesh::new(4, mesh_resolution).unwrap();
    report(
        &format!("mesh_fit/genus4_{}v", mesh.positions.len()),
        &mut || drop(genus4_mesh_fit(&mesh)),
    );
}

fn initial_fit(c: &mut Criterion, genera: &[u32]) {
    let mut group = c.benchmark_group("initial_fit");
    group.sample_size(10);
    for &genus in genera {
        group.bench_with_input(BenchmarkId::from_parameter(genus), &genus, |b, &g| {
            b.iter(|| plate_fit(g))
        });
    }
    group.finish();
}

/// The genus-4 plate at `resolution` (34: 10 276 vertices), fitted as a user's mesh.
fn whole_mesh_fit(c: &mut Criterion, resolution: usize) {
    let mesh = HoledMesh::new(4, resolution).unwrap();
    let mut group = c.benchmark_group("mesh_fit");
    group.sample_size(10);
    let id = format!("genus4_{}v", mesh.positions.len());
    group.bench_function(id, |b| b.iter(|| genus4_mesh_fit(&mesh)));
    group.finish();
}

/// `ntori new`'s fit of its genus-`genus` plate at its default resolution and settings.
/// As `ntori new` does: the mesh that choosing the resolution builds is the one fitted (until
/// 2026-11-30 this built it twice, through `default_resolution` and `initial_model`, 0.26 s more
/// at genus 10 than `ntori new` spends).
fn plate_fit(genus: u32) -> embedding::fit::InitialFit {
    let (spline, settings) = default_settings(genus);
    let (resolution, mesh) = default_mesh(genus).unwrap();
    initial_model_of(mesh, resolution, spline, settings, &|_| {}).unwrap()
}

/// `ntori fit`'s fit of a genus-4 plate mesh, checked to map without a fold.
fn genus4_mesh_fit(mesh: &HoledMesh) -> mesh_fit::MeshFit {
    let (settings, fit_settings) = mesh_fit::default_settings(4, mesh.positions.len());
    let fit = mesh_model(
        &mesh.positions,
        &mesh.triangles,
        settings,
        fit_settings,
        &|_| {},
    )
    .unwrap();
    assert_eq!((fit.genus, fit.parameterization.folded), (4, 0));
    fit
}

/// The genus-8 plate at `resolution` (42: 64 k triangles), split 1-to-4 twice (about 10⁶): its
/// greedy loop system through one vertex (shortest-path tree, cotree, the 2g shortest loops) and
/// the loops' canonical words. (The plates themselves are capped at the fit's 400 000 triangles.)
fn loops(c: &mut Criterion, resolution: usize) {
    let plate = HoledMesh::new(8, resolution).unwrap();
    let (positions, triangles) = split(split((plate.positions, plate.triangles)));
    let he =
        HalfEdgeMesh::from_polygons(positions.len(), triangles.iter().map(|t| &t[..])).unwrap();
    let length =
        |h: u32| (positions[he.target(h) as usize] - positions[he.origin(h) as usize]).norm();
    let mut group = c.benchmark_group("loops");
    group.sample_size(10);
    let id = format!("genus8_{}t", triangles.len());
    group.bench_function(id, |b| {
        b.iter(|| {
            let system = schema::loop_system(&he, length, 0).unwrap();
            let canonical =
                schema::canonicalize(&system.relation, system.generators.len()).unwrap();
            assert_eq!(canonical.originals.len(), 16);
            (system, canonical)
        })
    });
    group.finish();
}

type Mesh = (Vec<Point3>, Vec<[u32; 3]>);

/// Each triangle cut into four at its edges' midpoints (shared between neighbours).
fn split((mut positions, triangles): Mesh) -> Mesh {
    let mut midpoints = std::collections::HashMap::new();
    let mut midpoint = |a: u32, b: u32, positions: &mut Vec<Point3>| {
        *midpoints.entry((a.min(b), a.max(b))).or_insert_with(|| {
            let m =
                Point3::from((positions[a as usize].coords + positions[b as usize].coords) / 2.0);
            positions.push(m);
            (positions.len() - 1) as u32
        })
    };
    let mut out = Vec::with_capacity(4 * triangles.len());
    for [a, b, c] in triangles {
        let (ab, bc, ca) = (
            midpoint(a, b, &mut positions),
            midpoint(b, c, &mut positions),
            midpoint(c, a, &mut positions),
        );
        out.extend([[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
    }
    (positions, out)
}
