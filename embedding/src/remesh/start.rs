//! The mesh the remesher starts from.
//!
//! The t_e/t_r tessellation has the right topology, but each of its wheels is a fan about the
//! wheel's centre: 4n·t_e triangles meet there (160 at genus 5, 320 at genus 10), every one a
//! sliver a few degrees wide. Remeshing such a fan away takes many rounds and can leave triangles
//! turned against the surface. So the start keeps only the t_e/t_r squares and fills each wheel
//! with a constrained Delaunay triangulation of its region in the wheel's chart, refined to angles
//! of at least [`WHEEL_ANGLE`] with triangles about the size of the boundary's pieces. The wheel's
//! boundary edges are the squares' edges, kept unsplit, so the mesh stays closed with χ = 2 − 2n.

use std::collections::{BTreeMap, HashMap, HashSet};

use charts::{Atlas, ChartId, ChartPoint, Region};
use num_complex::Complex64;
use spade::handles::FixedVertexHandle;
use spade::{ConstrainedDelaunayTriangulation, Point2, Triangulation};

use crate::EmbeddingError;

/// The smallest angle (degrees) the wheels' triangulation aims for.
pub const WHEEL_ANGLE: f64 = 28.0;

/// A closed triangle mesh whose vertices are chart points, counter-clockwise in a chart holding
/// each triangle.
pub(super) struct StartMesh {
    pub vertices: Vec<ChartPoint>,
    pub triangles: Vec<[u32; 3]>,
}

/// The squares of the t_e = t_r = `resolution` tessellation and a Delaunay triangulation of each
/// wheel (see the module documentation).
pub(super) fn start_mesh(atlas: &Atlas, resolution: u32) -> Result<StartMesh, EmbeddingError> {
    let tess = atlas.tessellate(resolution, 1)?;
    let mut vertices = tess.vertices.clone();
    let mut triangles = Vec::with_capacity(tess.triangles.len());
    let mut wheels: BTreeMap<ChartId, Vec<usize>> = BTreeMap::new();
    for (t, &tri) in tess.triangles.iter().enumerate() {
        match tess.triangle_regions[t] {
            Region::Square => triangles.push(tri),
            Region::InsideWheel | Region::VertexWheel => {
                wheels.entry(tess.triangle_charts[t]).or_default().push(t)
            }
        }
    }
    for (chart, wheel) in wheels {
        let mut coords = HashMap::new();
        for &t in &wheel {
            for k in 0..3 {
                coords.insert(tess.triangles[t][k], tess.triangle_coords[t][k]);
            }
        }
        let fan: Vec<[u32; 3]> = wheel.iter().map(|&t| tess.triangles[t]).collect();
        let boundary =
            crate::fit::boundary_cycle(tess.vertices.len(), &fan, None).map_err(|e| match e {
                EmbeddingError::Parameterization(why) => wheel_error(chart, &why),
                other => other,
            })?;
        let outline: Vec<Complex64> = boundary.iter().map(|i| coords[i]).collect();
        let (ids, faces) = triangulate_disk(&outline).map_err(|why| wheel_error(chart, &why))?;
        let ids: Vec<u32> = ids
            .into_iter()
            .map(|id| match id {
                DiskVertex::Boundary(k) => boundary[k],
                DiskVertex::Inner(w) => {
                    vertices.push(ChartPoint::new(chart, w));
                    (vertices.len() - 1) as u32
                }
            })
            .collect();
        triangles.extend(faces.into_iter().map(|f| f.map(|k| ids[k])));
    }
    Ok(drop_unused(vertices, triangles))
}

fn wheel_error(chart: ChartId, why: &str) -> EmbeddingError {
    EmbeddingError::Parameterization(format!(
        "cannot triangulate the wheel of chart {}: {why}",
        chart.0
    ))
}

/// A vertex of [`triangulate_disk`]'s output: a boundary point by its index, or a new one inside.
enum DiskVertex {
    Boundary(usize),
    Inner(Complex64),
}

/// A triangulation of the simple polygon `outline` (counter-clockwise) whose boundary edges are the
/// polygon's sides, refined inside to angles of at least [`WHEEL_ANGLE`] and to triangles about the
/// size of the sides: its vertices and its counter-clockwise triangles.
fn triangulate_disk(outline: &[Complex64]) -> Result<(Vec<DiskVertex>, Vec<[usize; 3]>), String> {
    let mut cdt = ConstrainedDelaunayTriangulation::<Point2<f64>>::new();
    let handles = outline
        .iter()
        .map(|w| cdt.insert(Point2::new(w.re, w.im)))
        .collect::<Result<Vec<FixedVertexHandle>, _>>()
        .map_err(|e| format!("{e:?}"))?;
    let n = handles.len();
    for k in 0..n {
        let (a, b) = (handles[k], handles[(k + 1) % n]);
        if a == b || !cdt.can_add_constraint(a, b) {
            return Err("its boundary crosses itself".into());
        }
        cdt.add_constraint(a, b);
    }
    let side = (0..n)
        .map(|k| (outline[(k + 1) % n] - outline[k]).norm())
        .sum::<f64>()
        / n as f64;
    // Triangles of the sides' size: as many new vertices as about the polygon's area in such
    // triangles, and more for the grading along the sides. (A fixed 64 per side had been too few
    // from genus 20, where the inside wheel's area grows as the square of its 4n·t_e sides: at
    // genus 32 it needs 1.2·10⁵, and `ntori export` failed on every model there.)
    let target = 3f64.sqrt() / 4.0 * side * side;
    let area = (0..n)
        .map(|k| {
            let (a, b) = (outline[k], outline[(k + 1) % n]);
            a.re * b.im - a.im * b.re
        })
        .sum::<f64>()
        .abs()
        / 2.0;
    let result = cdt.refine(
        spade::RefinementParameters::new()
            .keep_constraint_edges()
            .exclude_outer_faces(true)
            .with_angle_limit(spade::AngleLimit::from_deg(WHEEL_ANGLE))
            .with_max_allowed_area(target)
            .with_max_additional_vertices(64 * n + 2 * (area / target) as usize),
    );
    if !result.refinement_complete {
        return Err("its refinement did not finish".into());
    }
    let excluded: HashSet<_> = result.excluded_faces.into_iter().collect();
    let boundary: HashMap<FixedVertexHandle, usize> =
        handles.iter().enumerate().map(|(k, &h)| (h, k)).collect();
    let vertices: Vec<DiskVertex> = cdt
        .vertices()
        .map(|v| match boundary.get(&v.fix()) {
            Some(&k) => DiskVertex::Boundary(k),
            None => DiskVertex::Inner(Complex64::new(v.position().x, v.position().y)),
        })
        .collect();
    let faces = cdt
        .inner_faces()
        .filter(|f| !excluded.contains(&f.fix()))
        .map(|f| f.vertices().map(|v| v.fix().index()))
        .collect();
    Ok((vertices, faces))
}

/// Renumbers the vertices the triangles use, dropping the rest (the wheels' old centres).
fn drop_unused(vertices: Vec<ChartPoint>, triangles: Vec<[u32; 3]>) -> StartMesh {
    let mut remap = vec![u32::MAX; vertices.len()];
    let mut mesh = StartMesh {
        vertices: Vec::with_capacity(vertices.len()),
        triangles: Vec::with_capacity(triangles.len()),
    };
    for t in triangles {
        mesh.triangles.push(t.map(|i| {
            let slot = &mut remap[i as usize];
            if *slot == u32::MAX {
                *slot = mesh.vertices.len() as u32;
                mesh.vertices.push(vertices[i as usize]);
            }
            *slot
        }));
    }
    mesh
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The start is closed and manifold with χ = 2 − 2n, every triangle counter-clockwise in a
    /// chart holding its corners, and no vertex of a wheel has more than a dozen neighbours.
    #[test]
    fn the_start_mesh_is_a_closed_surface_without_fans() {
        for genus in [0, 1, 2, 5, 10] {
            let atlas = Atlas::new(genus).unwrap();
            let start = start_mesh(&atlas, 8).unwrap();
            assert_closed_without_fans(genus, &start);
            for t in &start.triangles {
                let held: Vec<[Complex64; 3]> = atlas
                    .charts()
                    .iter()
                    .filter_map(|c| {
                        let w: Option<Vec<Complex64>> = t
                            .iter()
                            .map(|&i| {
                                atlas
                                    .locate(start.vertices[i as usize])
                                    .ok()?
                                    .in_chart(c.id())
                            })
                            .collect();
                        w.map(|w| [w[0], w[1], w[2]])
                    })
                    .collect();
                assert!(!held.is_empty(), "genus {genus}: no chart holds {t:?}");
                for [a, b, c] in held {
                    let (u, v) = (b - a, c - a);
                    assert!(
                        u.re * v.im - u.im * v.re > 0.0,
                        "genus {genus}: {t:?} turned"
                    );
                }
            }
        }
    }

    /// Closed, manifold and orientable with χ = 2 − 2n, and no vertex of more than a dozen
    /// neighbours (no fan left).
    fn assert_closed_without_fans(genus: u32, start: &StartMesh) {
        let topology = mesh::HalfEdgeMesh::from_polygons(
            start.vertices.len(),
            start.triangles.iter().map(|t| &t[..]),
        )
        .unwrap()
        .topology();
        assert!(topology.closed && topology.manifold && topology.orientable);
        assert_eq!(topology.euler_characteristic, 2 - 2 * genus as i64);
        let mut valence = vec![0usize; start.vertices.len()];
        for &i in start.triangles.iter().flatten() {
            valence[i as usize] += 1;
        }
        let most = valence.iter().max().unwrap();
        assert!(*most <= 12, "genus {genus}: a vertex of valence {most}");
    }

    /// From genus 20 the inside wheel holds 10⁵ triangles and more (its area grows as the square
    /// of its boundary's 4n·t_e sides): its refinement finishes there too, and the start is a
    /// closed surface of the genus without fans, up to genus 64.
    #[test]
    fn the_start_mesh_is_made_up_to_genus_64() {
        for genus in [20, 64] {
            let atlas = Atlas::new(genus).unwrap();
            let start = start_mesh(&atlas, 8).unwrap_or_else(|e| panic!("genus {genus}: {e}"));
            assert_closed_without_fans(genus, &start);
        }
    }
}
