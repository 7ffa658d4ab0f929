//! An all-quad tessellation: the quality tessellation's triangles paired into quads where the pair
//! makes a good one, then every face split at its centre and edge midpoints (as Catmull–Clark's
//! first step does), so a quad becomes four quads and a lone triangle three.
//!
//! The split adds vertices on the surface, which shrinks the chordal error about fourfold and
//! halves the bend between neighbours, so the triangles are made to a coarser tolerance and bend
//! first and the quads end up about as fine as the triangles would be. Every new vertex is a
//! chart point (midpoints and centres are taken in the face's chart), so the quads carry chart
//! coordinates like the triangles. The mesh stays closed and manifold and χ does not change:
//! V + E + F − 2E − (Σ corners) + (Σ corners) = V − E + F.

use std::collections::HashMap;

use charts::{ChartId, ChartPoint};
use num_complex::Complex64;

use super::{QualityMesh, QualitySettings, quality_mesh};
use crate::{EmbeddingError, Point3, Surface};

/// How much coarser a tolerance the triangles are made to than the quads': splitting each edge at
/// its surface midpoint would divide a triangle's chordal error by about four, but a quad is not
/// flat, and its halves (what a renderer draws) keep more of it. Measured on the example models:
/// at 1.4 the halves stay within the tolerance (at 2 they reach 1.6 times it).
pub const TOLERANCE_FACTOR: f64 = 1.4;

/// How much more the triangles may bend than the quads: the split halves the bend across each
/// edge, and √2 leaves room for the bend within a quad, between its halves.
const COARSER: f64 = std::f64::consts::SQRT_2;

/// The most a paired quad's corner angle may differ from 90° (degrees); worse pairs stay triangles.
const MAX_SKEW: f64 = 70.0;

/// A face before the split: its corners (three or four, counter-clockwise), its chart and the
/// corners' coordinates there.
struct Face {
    corners: Vec<u32>,
    chart: ChartId,
    coords: Vec<Complex64>,
}

/// The all-quad tessellation at `settings`' tolerance (see the module documentation). Its
/// triangles come in pairs, `2k` and `2k + 1` halves of quad `k` ([`QualityMesh::quads`],
/// [`quad_of`]).
pub fn quad_mesh(
    surface: &Surface,
    settings: &QualitySettings,
) -> Result<QualityMesh, EmbeddingError> {
    settings.check()?;
    let coarse = QualitySettings {
        tolerance: (settings.tolerance * TOLERANCE_FACTOR).min(QualitySettings::MAX_TOLERANCE),
        bend: COARSER * settings.bend,
        max_edge: 2.0 * settings.max_edge,
        max_bend: COARSER * settings.max_bend,
        ..*settings
    };
    let triangles = quality_mesh(surface, &coarse)?;
    let faces = pair(surface.atlas(), &triangles);
    split(surface, &triangles, &faces)
}

/// Pairs neighbouring triangles into quads convex in a chart holding all four corners (the first
/// triangle's), squarest first; the rest stay triangles.
fn pair(atlas: &charts::Atlas, mesh: &QualityMesh) -> Vec<Face> {
    let mut owner: HashMap<(u32, u32), usize> = HashMap::with_capacity(3 * mesh.triangles.len());
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            owner.insert((tri[k], tri[(k + 1) % 3]), t);
        }
    }
    // (skew, t, u, the quad's corners and their coordinates in t's chart)
    let mut candidates = Vec::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        for k in 0..3 {
            let (a, b) = (tri[k], tri[(k + 1) % 3]);
            let Some(&u) = owner.get(&(b, a)) else {
                continue;
            };
            if u <= t {
                continue;
            }
            let chart = mesh.triangle_charts[t];
            // Corners from the far end of the shared edge round to the other triangle's apex.
            let other = (0..3)
                .find(|&j| mesh.triangles[u][j] != a && mesh.triangles[u][j] != b)
                .unwrap_or(0);
            let order = [(k + 1) % 3, (k + 2) % 3, k];
            let corners = [
                tri[order[0]],
                tri[order[1]],
                tri[order[2]],
                mesh.triangles[u][other],
            ];
            let apex = if mesh.triangle_charts[u] == chart {
                Some(mesh.triangle_coords[u][other])
            } else {
                in_chart(
                    atlas,
                    mesh.vertices[mesh.triangles[u][other] as usize],
                    chart,
                )
            };
            let Some(apex) = apex else {
                continue;
            };
            let coords = [
                mesh.triangle_coords[t][order[0]],
                mesh.triangle_coords[t][order[1]],
                mesh.triangle_coords[t][order[2]],
                apex,
            ];
            if !convex(&coords) {
                continue;
            }
            let skew = skew(&corners.map(|i| mesh.positions[i as usize]));
            if skew <= MAX_SKEW.to_radians() {
                candidates.push((skew, t, u, corners, coords));
            }
        }
    }
    candidates.sort_by(|x, y| x.0.total_cmp(&y.0));
    let mut used = vec![false; mesh.triangles.len()];
    let mut faces = Vec::with_capacity(mesh.triangles.len());
    for (_, t, u, corners, coords) in candidates {
        if used[t] || used[u] {
            continue;
        }
        used[t] = true;
        used[u] = true;
        faces.push(Face {
            corners: corners.to_vec(),
            chart: mesh.triangle_charts[t],
            coords: coords.to_vec(),
        });
    }
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if !used[t] {
            faces.push(Face {
                corners: tri.to_vec(),
                chart: mesh.triangle_charts[t],
                coords: mesh.triangle_coords[t].to_vec(),
            });
        }
    }
    faces
}

/// `p`'s coordinates in `chart`, if it holds `p`.
fn in_chart(atlas: &charts::Atlas, p: ChartPoint, chart: ChartId) -> Option<Complex64> {
    if p.chart == chart {
        return Some(p.coords);
    }
    let located = atlas.locate(p).ok()?;
    located
        .representations()
        .iter()
        .find(|r| r.chart == chart)
        .map(|r| r.coords)
}

/// The midpoint of the chart segment between `ends` in the deepest of their home charts that
/// holds both (by the smaller margin).
fn deepest_midpoint(atlas: &charts::Atlas, ends: [ChartPoint; 2]) -> Option<ChartPoint> {
    let margin = |chart: ChartId, w: Complex64| atlas.charts()[chart.index()].domain().margin(w);
    ends.iter()
        .filter_map(|home| {
            let [wa, wc] = ends.map(|p| in_chart(atlas, p, home.chart));
            let (wa, wc) = (wa?, wc?);
            Some((
                margin(home.chart, wa).min(margin(home.chart, wc)),
                home.chart,
                wa,
                wc,
            ))
        })
        .max_by(|x, y| x.0.total_cmp(&y.0))
        .map(|(_, chart, wa, wc)| ChartPoint::new(chart, 0.5 * (wa + wc)))
}

/// Whether the polygon turns left at every corner (strictly convex, counter-clockwise).
fn convex(w: &[Complex64]) -> bool {
    let n = w.len();
    (0..n).all(|k| {
        let (u, v) = (w[(k + 1) % n] - w[k], w[(k + 2) % n] - w[(k + 1) % n]);
        u.re * v.im - u.im * v.re > 0.0
    })
}

/// The largest difference between a corner angle of the quad and a right angle (radians).
fn skew(p: &[Point3; 4]) -> f64 {
    (0..4)
        .map(|k| {
            let (prev, next) = (p[(k + 3) % 4] - p[k], p[(k + 1) % 4] - p[k]);
            (prev.angle(&next) - std::f64::consts::FRAC_PI_2).abs()
        })
        .fold(0.0, f64::max)
}

/// The mesh being built by [`split`]: vertices and triangle pairs.
struct Builder<'a> {
    surface: &'a Surface,
    out: QualityMesh,
}

impl Builder<'_> {
    /// A new vertex at `p`, kept in its deepest chart.
    fn vertex(&mut self, p: ChartPoint) -> Result<u32, EmbeddingError> {
        let atlas = self.surface.atlas();
        let located = atlas.locate(p)?;
        let home = located
            .representations()
            .iter()
            .copied()
            .max_by(|a, b| {
                let m = |r: &ChartPoint| atlas.charts()[r.chart.index()].domain().margin(r.coords);
                m(a).total_cmp(&m(b))
            })
            .unwrap_or(p);
        self.out.vertices.push(home);
        self.out.positions.push(self.surface.position(home));
        Ok(self.out.vertices.len() as u32 - 1)
    }

    /// `v`'s coordinates in `chart`.
    fn coords_in(&self, v: u32, chart: ChartId) -> Result<Complex64, EmbeddingError> {
        in_chart(self.surface.atlas(), self.out.vertices[v as usize], chart).ok_or_else(|| {
            EmbeddingError::Parameterization(format!(
                "an edge midpoint of a face in chart {} lies outside it",
                chart.0
            ))
        })
    }

    /// Quad (a, b, c, d), counter-clockwise, as two triangles of `chart` split along a diagonal
    /// whose halves both wind counter-clockwise in the chart (one through a reflex corner, where
    /// the quad has one), and of two such, the one through its widest corner on the surface: a
    /// corner near 180° (where a lone triangle's quads meet its long side) then opens into both
    /// halves instead of flattening one of them.
    fn quad(&mut self, q: [u32; 4], w: [Complex64; 4], chart: ChartId) {
        let p = q.map(|i| self.out.positions[i as usize]);
        let angle = |k: usize| (p[(k + 3) % 4] - p[k]).angle(&(p[(k + 1) % 4] - p[k]));
        let ccw = |i: usize, j: usize, k: usize| {
            let (u, v) = (w[j] - w[i], w[k] - w[i]);
            u.re * v.im - u.im * v.re > 0.0
        };
        // Diagonal 0–2 makes (0, 1, 2) and (0, 2, 3); diagonal 1–3 makes (1, 2, 3) and (1, 3, 0).
        let first = ccw(0, 1, 2) && ccw(0, 2, 3);
        let second = ccw(1, 2, 3) && ccw(1, 3, 0);
        let widest = (0..4)
            .max_by(|&i, &j| angle(i).total_cmp(&angle(j)))
            .unwrap_or(0);
        let through_1_3 = match (first, second) {
            (true, false) => false,
            (false, true) => true,
            _ => widest % 2 == 1,
        };
        let (q, w) = if through_1_3 {
            ([q[1], q[2], q[3], q[0]], [w[1], w[2], w[3], w[0]])
        } else {
            (q, w)
        };
        self.out.triangles.push([q[0], q[1], q[2]]);
        self.out.triangles.push([q[0], q[2], q[3]]);
        self.out.triangle_coords.push([w[0], w[1], w[2]]);
        self.out.triangle_coords.push([w[0], w[2], w[3]]);
        self.out.triangle_charts.extend([chart, chart]);
    }
}

/// Splits every face into quads at its centre and its edges' midpoints.
fn split(
    surface: &Surface,
    mesh: &QualityMesh,
    faces: &[Face],
) -> Result<QualityMesh, EmbeddingError> {
    let mut b = Builder {
        surface,
        out: QualityMesh {
            vertices: mesh.vertices.clone(),
            positions: mesh.positions.clone(),
            quads: true,
            ..QualityMesh::default()
        },
    };
    // Each edge's midpoint, in the deepest chart holding both ends (not the chart of whichever
    // face meets the edge first: where a face is thin in its chart, a midpoint made in another
    // chart can land on the wrong side of the centre).
    let mut midpoints: HashMap<(u32, u32), u32> = HashMap::new();
    for face in faces {
        let n = face.corners.len();
        let mut mids = Vec::with_capacity(n);
        for k in 0..n {
            let (a, c) = (face.corners[k], face.corners[(k + 1) % n]);
            let key = (a.min(c), a.max(c));
            let m = match midpoints.get(&key) {
                Some(&m) => m,
                None => {
                    let ends = [a, c].map(|v| b.out.vertices[v as usize]);
                    let w = 0.5 * (face.coords[k] + face.coords[(k + 1) % n]);
                    let mid = deepest_midpoint(surface.atlas(), ends)
                        .unwrap_or(ChartPoint::new(face.chart, w));
                    let m = b.vertex(mid)?;
                    midpoints.insert(key, m);
                    m
                }
            };
            mids.push((m, b.coords_in(m, face.chart)?));
        }
        let centre_w = face.coords.iter().sum::<Complex64>() / n as f64;
        let centre = b.vertex(ChartPoint::new(face.chart, centre_w))?;
        for k in 0..n {
            let (m_next, w_next) = mids[k];
            let (m_prev, w_prev) = mids[(k + n - 1) % n];
            b.quad(
                [face.corners[k], m_next, centre, m_prev],
                [face.coords[k], w_next, centre_w, w_prev],
                face.chart,
            );
        }
    }
    Ok(b.out)
}

/// The quads whose halves `triangles` are, in pairs (2k, 2k + 1), as [`quad_of`] puts them
/// together.
pub fn quads_of(triangles: &[[u32; 3]]) -> Vec<[u32; 4]> {
    triangles
        .chunks_exact(2)
        .filter_map(|p| quad_of(p[0], p[1]))
        .collect()
}

/// The quad two triangles sharing an edge make, counter-clockwise as they are: the first's
/// corners from the far end of the shared edge, then the second's apex. `None` where they share
/// no edge the same way round.
pub fn quad_of(first: [u32; 3], second: [u32; 3]) -> Option<[u32; 4]> {
    (0..3).find_map(|k| {
        let (a, b) = (first[k], first[(k + 1) % 3]);
        let reversed = (0..3).any(|j| second[j] == b && second[(j + 1) % 3] == a);
        let apex = second.into_iter().find(|&v| v != a && v != b)?;
        reversed.then_some([first[(k + 1) % 3], first[(k + 2) % 3], a, apex])
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn two_halves_make_their_quad_either_way_round() {
        assert_eq!(quad_of([0, 1, 2], [0, 2, 3]), Some([0, 1, 2, 3]));
        assert_eq!(quad_of([0, 2, 1], [0, 3, 2]), Some([2, 1, 0, 3]));
        assert_eq!(quad_of([5, 6, 7], [0, 2, 3]), None);
        // Sharing an edge the same way round: not two halves of one oriented quad.
        assert_eq!(quad_of([0, 1, 2], [0, 1, 3]), None);
    }

    #[test]
    fn convexity_and_skew() {
        let square =
            [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)].map(|(x, y)| Complex64::new(x, y));
        assert!(convex(&square));
        let mut reversed = square;
        reversed.reverse();
        assert!(!convex(&reversed));
        let dart =
            [(0.0, 0.0), (1.0, 0.0), (0.2, 0.2), (0.0, 1.0)].map(|(x, y)| Complex64::new(x, y));
        assert!(!convex(&dart));
        let p = square.map(|w| Point3::new(w.re, w.im, 0.0));
        assert!(skew(&p) < 1e-12);
        let rhombus =
            [(0.0, 0.0), (1.0, 0.0), (1.5, 1.0), (0.5, 1.0)].map(|(x, y)| Point3::new(x, y, 0.0));
        assert!((skew(&rhombus).to_degrees() - (90.0 - 63.43494882292201)).abs() < 1e-9);
    }
}
