//! The fits, end to end, and the loops of a user's mesh:
//!
//! - `initial_fit`: `ntori new`'s pipeline (mesh, cut, Floater, relaxation, least squares) for
//!   genus 2, 5 and 10 at the default resolution and spline settings. The map dominates: its
//!   sweeps and Newton steps are reported by `ntori new`.
//! - `mesh_fit`: `ntori fit`'s pipeline (greedy loops from several base vertices, the canonical
//!   words, the map, least squares) on a genus-4 plate mesh of about 10 000 vertices (issue 14's
//!   target: 10 s).
//! - `loops`: one greedy loop system and its canonical words on a genus-8 plate mesh of about
//!   10⁶ triangles (issue 14's target: 5 s).
//!
//! In test mode (`cargo test --benches`) each runs once, on meshes a quarter as fine.

use criterion::{BenchmarkId, Criterion};
use embedding::SplineSettings;
use embedding::fit::{FitSettings, initial_model};
use embedding::holed::HoledMesh;
use embedding::mesh_fit::{MESH_FIT_GRID, mesh_model};
use mesh::HalfEdgeMesh;
use mesh::schema;

fn main() {
    let full = std::env::args().any(|a| a == "--bench");
    let mut c = Criterion::default().configure_from_args();
    initial_fit(&mut c);
    whole_mesh_fit(&mut c, if full { 38 } else { 12 });
    loops(&mut c, if full { 170 } else { 24 });
    c.final_summary();
}

fn initial_fit(c: &mut Criterion) {
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

/// The genus-4 plate at `resolution` (38: 10 466 vertices), fitted as a user's mesh.
fn whole_mesh_fit(c: &mut Criterion, resolution: usize) {
    let mesh = HoledMesh::new(4, resolution).unwrap();
    let settings = SplineSettings {
        grid: MESH_FIT_GRID,
        ..SplineSettings::default()
    };
    let mut group = c.benchmark_group("mesh_fit");
    group.sample_size(10);
    let id = format!("genus4_{}v", mesh.positions.len());
    group.bench_function(id, |b| {
        b.iter(|| {
            let fit = mesh_model(
                &mesh.positions,
                &mesh.triangles,
                settings,
                FitSettings::default(),
                &|_| {},
            )
            .unwrap();
            assert_eq!((fit.genus, fit.parameterization.folded), (4, 0));
            fit
        })
    });
    group.finish();
}

/// The genus-8 plate at `resolution` (170: about 10⁶ triangles): its greedy loop system through
/// one vertex (shortest-path tree, cotree, the 2g shortest loops) and the loops' canonical words.
fn loops(c: &mut Criterion, resolution: usize) {
    let mesh = HoledMesh::new(8, resolution).unwrap();
    let he =
        HalfEdgeMesh::from_polygons(mesh.positions.len(), mesh.triangles.iter().map(|t| &t[..]))
            .unwrap();
    let positions = &mesh.positions;
    let length =
        |h: u32| (positions[he.target(h) as usize] - positions[he.origin(h) as usize]).norm();
    let mut group = c.benchmark_group("loops");
    group.sample_size(10);
    let id = format!("genus8_{}t", mesh.triangles.len());
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
