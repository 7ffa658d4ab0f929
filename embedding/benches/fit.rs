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
//! - `mesh_fit`: `ntori fit`'s pipeline (greedy loops from several base vertices, the canonical
//!   words, the map, least squares) on a genus-4 plate mesh of about 10 000 vertices (issue 14's
//!   target: 10 s).
//! - `loops`: one greedy loop system and its canonical words on a genus-8 plate mesh split to
//!   about 10⁶ triangles (issue 14's target: 5 s).
//!
//! In test mode (`cargo test --benches`) each runs once, on meshes a quarter as fine.

use criterion::{BenchmarkId, Criterion};
use embedding::Point3;
use embedding::fit::{default_resolution, default_settings, initial_model};
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
    c.final_summary();
}

fn initial_fit(c: &mut Criterion, genera: &[u32]) {
    let mut group = c.benchmark_group("initial_fit");
    group.sample_size(10);
    for &genus in genera {
        group.bench_with_input(BenchmarkId::from_parameter(genus), &genus, |b, &g| {
            let (spline, settings) = default_settings(g);
            let resolution = default_resolution(g).unwrap();
            b.iter(|| initial_model(g, resolution, spline, settings).unwrap())
        });
    }
    group.finish();
}

/// The genus-4 plate at `resolution` (34: 10 276 vertices), fitted as a user's mesh.
fn whole_mesh_fit(c: &mut Criterion, resolution: usize) {
    let mesh = HoledMesh::new(4, resolution).unwrap();
    let (settings, fit_settings) = mesh_fit::default_settings(4);
    let mut group = c.benchmark_group("mesh_fit");
    group.sample_size(10);
    let id = format!("genus4_{}v", mesh.positions.len());
    group.bench_function(id, |b| {
        b.iter(|| {
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
        })
    });
    group.finish();
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
