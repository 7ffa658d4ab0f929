//! The packed UV atlas (`--uv atlas`): each chart's region of the mesh in its own square tile of
//! a grid in [0, 1]², vertices duplicated where triangles of different charts meet.
//!
//! Chart c's tile is cell (c mod k, c div k) of a k × k grid, k = ⌈√charts⌉, so tiles never
//! overlap. Inside its tile, a chart's region (the bounding box of its triangles' corners in the
//! chart's coordinates) is scaled uniformly (a chart's map keeps its shapes) to fill the tile less a
//! gutter of [`GUTTER`] of the tile on every side, so painting across a tile's edge and mipmapping
//! do not bleed into a neighbour. Every triangle takes its corners' coordinates in its *home chart*
//! (`Tessellation::triangle_coords`), so a triangle lies whole in one tile and never spans a seam.

use std::collections::HashMap;

use super::ChartMesh;

/// The empty margin on each side of a chart's region, as a fraction of its tile.
pub const GUTTER: f64 = 1.0 / 32.0;

/// Where a chart's region goes: its lower corner in chart coordinates, the scale to texture units
/// and the texture point the corner goes to.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Placement {
    from: [f64; 2],
    scale: f64,
    to: [f64; 2],
}

/// Where each chart's region goes in [0, 1]².
#[derive(Clone, Debug, PartialEq)]
pub struct UvAtlas {
    /// Tiles per row (and at most as many rows).
    pub columns: u32,
    /// Per chart (`None` for a chart without triangles).
    placements: Vec<Option<Placement>>,
}

impl UvAtlas {
    /// The layout of `charts` tiles for the triangles of `mesh`.
    pub fn new(mesh: &ChartMesh<'_>, charts: usize) -> UvAtlas {
        let columns = (charts.max(1) as f64).sqrt().ceil() as u32;
        let mut boxes: Vec<Option<([f64; 2], [f64; 2])>> = vec![None; charts];
        for (chart, corners) in mesh.triangle_charts.iter().zip(mesh.triangle_coords) {
            let Some(slot) = boxes.get_mut(chart.index()) else {
                continue;
            };
            for w in corners {
                let (lo, hi) = slot.get_or_insert(([w.re, w.im], [w.re, w.im]));
                *lo = [lo[0].min(w.re), lo[1].min(w.im)];
                *hi = [hi[0].max(w.re), hi[1].max(w.im)];
            }
        }
        let mut atlas = UvAtlas {
            columns,
            placements: Vec::with_capacity(charts),
        };
        for (c, b) in boxes.into_iter().enumerate() {
            let placement = b.map(|(lo, hi)| {
                let (tile_lo, tile_hi) = atlas.tile(c as u32);
                let side = tile_hi[0] - tile_lo[0];
                let room = side * (1.0 - 2.0 * GUTTER);
                let extent = (hi[0] - lo[0]).max(hi[1] - lo[1]);
                let scale = if extent > 0.0 { room / extent } else { 0.0 };
                // Centred in the tile.
                let to = [0, 1].map(|k| tile_lo[k] + 0.5 * (side - scale * (hi[k] - lo[k])));
                Placement {
                    from: lo,
                    scale,
                    to,
                }
            });
            atlas.placements.push(placement);
        }
        atlas
    }

    /// Chart `chart`'s tile, as its lower and upper corners in [0, 1]².
    pub fn tile(&self, chart: u32) -> ([f64; 2], [f64; 2]) {
        let side = 1.0 / f64::from(self.columns);
        let (col, row) = (chart % self.columns, chart / self.columns);
        let lo = [f64::from(col) * side, f64::from(row) * side];
        (lo, [lo[0] + side, lo[1] + side])
    }

    /// Where chart coordinates `w` of chart `chart` go.
    pub fn uv(&self, chart: u32, w: num_complex::Complex64) -> [f64; 2] {
        match self.placements.get(chart as usize).copied().flatten() {
            Some(Placement { from, scale, to }) => [
                to[0] + scale * (w.re - from[0]),
                to[1] + scale * (w.im - from[1]),
            ],
            // A chart without triangles: its tile's centre.
            None => {
                let (lo, hi) = self.tile(chart);
                [0.5 * (lo[0] + hi[0]), 0.5 * (lo[1] + hi[1])]
            }
        }
    }
}

/// The mesh split along the charts' seams: a vertex used by triangles of several home charts
/// becomes one vertex per chart.
pub(super) struct Split {
    /// Each new vertex's original (the first `vertices` are the originals themselves).
    pub extra: Vec<u32>,
    pub triangles: Vec<[u32; 3]>,
    pub uvs: Vec<[f64; 2]>,
    pub charts: Vec<u32>,
}

/// Splits `mesh` for `atlas`: vertex v keeps its index for the chart of the first triangle that
/// uses it; for each other chart whose triangles use it, a copy is appended.
pub(super) fn split(mesh: &ChartMesh<'_>, atlas: &UvAtlas) -> Split {
    let n = mesh.vertices.len();
    let mut first = vec![u32::MAX; n];
    let mut uvs = vec![[0.0; 2]; n];
    let mut copies: HashMap<(u32, u32), u32> = HashMap::new();
    let mut extra = Vec::new();
    let mut extra_uvs = Vec::new();
    let mut extra_charts = Vec::new();
    let mut triangles = Vec::with_capacity(mesh.triangles.len());
    for ((t, chart), corners) in mesh
        .triangles
        .iter()
        .zip(mesh.triangle_charts)
        .zip(mesh.triangle_coords)
    {
        let c = chart.0;
        let mut out = [0u32; 3];
        for j in 0..3 {
            let v = t[j];
            let slot = &mut first[v as usize];
            out[j] = if *slot == u32::MAX || *slot == c {
                if *slot == u32::MAX {
                    *slot = c;
                    uvs[v as usize] = atlas.uv(c, corners[j]);
                }
                v
            } else {
                *copies.entry((v, c)).or_insert_with(|| {
                    extra.push(v);
                    extra_uvs.push(atlas.uv(c, corners[j]));
                    extra_charts.push(c);
                    (n + extra.len() - 1) as u32
                })
            };
        }
        triangles.push(out);
    }
    // A vertex no triangle uses (none in ntori's tessellations) keeps its home chart.
    let mut charts = Vec::with_capacity(n + extra.len());
    for (v, c) in first.iter().enumerate() {
        if *c == u32::MAX {
            let p = mesh.vertices[v];
            uvs[v] = atlas.uv(p.chart.0, p.coords);
            charts.push(p.chart.0);
        } else {
            charts.push(*c);
        }
    }
    charts.extend(extra_charts);
    uvs.extend(extra_uvs);
    Split {
        extra,
        triangles,
        uvs,
        charts,
    }
}
