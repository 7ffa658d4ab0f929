//! The mesh an export writes: the t_e/t_r tessellation, the quality tessellation or its quads, or a
//! fit's input mesh, evaluated at every vertex (position, analytic normal, home chart), oriented
//! outward.

use charts::Tessellation;
use embedding::remesh::{self, QualitySettings, quality_mesh};
use embedding::{EmbeddingError, Point3, Sample, Surface, Vector3, Wants, evaluate};

use super::atlas::{self, UvAtlas};
use super::{
    ChartMesh, ExportError, Format, MAX_RESOLUTION, MAX_TRIANGLES, MeshSource, SurfaceMesh,
    UvLayout,
};

/// How many triangles an export at t_e, t_r makes, or why it is refused (before any work is done).
/// t_e = 1 is refused at genus ≥ 1 ([`ExportError::SharedEdges`]).
pub fn check_resolution(genus: u32, te: u32, tr: u32) -> Result<u64, ExportError> {
    for (name, value) in [("t_e", te), ("t_r", tr)] {
        if !(1..=MAX_RESOLUTION).contains(&value) {
            return Err(ExportError::Resolution { name, value });
        }
    }
    if te == 1 && genus >= 1 {
        return Err(ExportError::SharedEdges { genus });
    }
    let triangles = Tessellation::expected_triangles(genus, te, tr);
    if triangles > MAX_TRIANGLES {
        return Err(ExportError::TooManyTriangles {
            genus,
            te,
            tr,
            triangles,
        });
    }
    Ok(triangles)
}

/// Tessellates the surface at t_e, t_r and evaluates it ([`evaluate_mesh`]) with texture
/// coordinates laid out as `uv` says.
pub fn surface_mesh(
    surface: &Surface,
    (te, tr): (u32, u32),
    uv: UvLayout,
) -> Result<SurfaceMesh, ExportError> {
    check_resolution(surface.genus(), te, tr)?;
    check_not_degenerate(
        surface,
        Tessellation::expected_vertices(surface.genus(), te, tr),
    )?;
    let t = surface
        .atlas()
        .tessellate(te, tr)
        .map_err(EmbeddingError::from)?;
    let mut mesh = evaluate_mesh(surface, ChartMesh::from(&t), uv)?;
    mesh.source = MeshSource::Tessellation { te, tr };
    Ok(mesh)
}

/// How an export tessellates the surface.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Meshing {
    /// The paper's t_e/t_r scheme ([`surface_mesh`]).
    TeTr { te: u32, tr: u32 },
    /// The quality tessellation ([`quality_surface_mesh`]) to this chordal tolerance, a fraction
    /// of the surface's diagonal.
    Quality { tolerance: f64 },
    /// The all-quad tessellation ([`quad_surface_mesh`]) to this chordal tolerance, for the
    /// formats that store polygons ([`Format::has_quads`]).
    Quads { tolerance: f64 },
}

impl Meshing {
    /// Whether `format` can store what this meshing makes.
    pub fn check(&self, format: Format) -> Result<(), ExportError> {
        if matches!(self, Meshing::Quads { .. }) && !format.has_quads() {
            return Err(ExportError::NoQuads(format));
        }
        Ok(())
    }
}

impl Default for Meshing {
    /// The quality tessellation at [`QualitySettings`]' default tolerance (0.001 of the diagonal).
    fn default() -> Meshing {
        Meshing::Quality {
            tolerance: QualitySettings::default().tolerance,
        }
    }
}

impl From<(u32, u32)> for Meshing {
    fn from((te, tr): (u32, u32)) -> Meshing {
        Meshing::TeTr { te, tr }
    }
}

impl std::fmt::Display for Meshing {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Meshing::TeTr { te, tr } => write!(f, "t_e = {te}, t_r = {tr}"),
            Meshing::Quality { tolerance } => {
                write!(f, "quality tessellation to {tolerance} of the diagonal")
            }
            Meshing::Quads { tolerance } => {
                write!(f, "quad tessellation to {tolerance} of the diagonal")
            }
        }
    }
}

/// Tessellates the surface with `meshing` and evaluates it, texture coordinates laid out as `uv`
/// says.
pub fn mesh_surface(
    surface: &Surface,
    meshing: Meshing,
    uv: UvLayout,
) -> Result<SurfaceMesh, ExportError> {
    match meshing {
        Meshing::TeTr { te, tr } => surface_mesh(surface, (te, tr), uv),
        Meshing::Quality { tolerance } => quality_surface_mesh(surface, tolerance, uv),
        Meshing::Quads { tolerance } => quad_surface_mesh(surface, tolerance, uv),
    }
}

/// The quality tessellation of the surface (`embedding::remesh`: well-shaped triangles sized by
/// the curvature, chordal error within `tolerance` of the diagonal), evaluated ([`evaluate_mesh`]).
pub fn quality_surface_mesh(
    surface: &Surface,
    tolerance: f64,
    uv: UvLayout,
) -> Result<SurfaceMesh, ExportError> {
    remeshed(surface, tolerance, uv, false)
}

/// The all-quad tessellation of the surface (`embedding::remesh::quad_mesh`: the quality
/// tessellation's triangles paired and split into quads, chordal error about `tolerance` of the
/// diagonal), evaluated ([`evaluate_mesh`]); its triangles are the quads' halves.
pub fn quad_surface_mesh(
    surface: &Surface,
    tolerance: f64,
    uv: UvLayout,
) -> Result<SurfaceMesh, ExportError> {
    remeshed(surface, tolerance, uv, true)
}

/// The quality tessellation (`quads`: the all-quad one) at `tolerance`, evaluated.
fn remeshed(
    surface: &Surface,
    tolerance: f64,
    uv: UvLayout,
    quads: bool,
) -> Result<SurfaceMesh, ExportError> {
    // Refused before remeshing, counting the vertices the remesher would start from.
    if surface.is_degenerate() {
        check_not_degenerate(surface, remesh::start_vertex_count(surface.atlas())? as u64)?;
    }
    let settings = QualitySettings::with_tolerance(tolerance);
    let q = if quads {
        remesh::quad_mesh(surface, &settings)?
    } else {
        quality_mesh(surface, &settings)?
    };
    let mut mesh = evaluate_mesh(surface, ChartMesh::from(&q), uv)?;
    mesh.source = if quads {
        MeshSource::Quads { tolerance }
    } else {
        MeshSource::Quality { tolerance }
    };
    mesh.quads = quads;
    Ok(mesh)
}

impl<'a> From<&'a remesh::QualityMesh> for ChartMesh<'a> {
    fn from(q: &'a remesh::QualityMesh) -> Self {
        ChartMesh {
            vertices: &q.vertices,
            triangles: &q.triangles,
            triangle_charts: &q.triangle_charts,
            triangle_coords: &q.triangle_coords,
        }
    }
}

/// A surface whose control points coincide has no surface to export: refused, naming how many
/// vertices would have no normal.
fn check_not_degenerate(surface: &Surface, vertices: u64) -> Result<(), ExportError> {
    if surface.is_degenerate() {
        let p = surface
            .control_points()
            .first()
            .copied()
            .unwrap_or_default();
        return Err(ExportError::Degenerate {
            count: vertices as usize,
            x: p.x,
            y: p.y,
            z: p.z,
        });
    }
    Ok(())
}

/// Evaluates a mesh of chart points on the surface: each vertex's position, analytic outward
/// normal (repaired from its triangles where S_u × S_v vanishes), home chart and texture
/// coordinates ([`UvLayout::Atlas`] splits the mesh at chart seams, see [`atlas`]); triangles
/// turned outward. Its source is [`MeshSource::ChartMesh`].
pub fn evaluate_mesh(
    surface: &Surface,
    input: ChartMesh<'_>,
    uv: UvLayout,
) -> Result<SurfaceMesh, ExportError> {
    let n = input.vertices.len();
    check_not_degenerate(surface, n as u64)?;
    // The control net's size: derivatives in chart units are of its order.
    let tiny = 1e-9 * surface.control_net_size();
    let mut mesh = SurfaceMesh {
        genus: surface.genus(),
        source: MeshSource::ChartMesh,
        uv_layout: UvLayout::Chart,
        positions: Vec::with_capacity(n),
        normals: Vec::with_capacity(n),
        uvs: Vec::with_capacity(n),
        charts: Vec::with_capacity(n),
        triangles: input.triangles.to_vec(),
        quads: false,
    };
    evaluate(
        surface,
        input.vertices,
        Wants::default(),
        tiny * tiny,
        &mut |s: &Sample| {
            mesh.positions.push(s.position);
            mesh.normals
                .push(s.normal.unwrap_or(Vector3::repeat(f64::NAN)));
            mesh.uvs
                .push([s.point.coords.re + 0.5, s.point.coords.im + 0.5]);
            mesh.charts.push(s.point.chart.0);
        },
    );
    // Repaired on the whole mesh: a seam vertex takes the normals of all its triangles.
    mesh.repair_normals()?;
    if uv == UvLayout::Atlas {
        let layout = UvAtlas::new(&input, surface.atlas().charts().len());
        let split = atlas::split(&input, &layout);
        for &v in &split.extra {
            mesh.positions.push(mesh.positions[v as usize]);
            mesh.normals.push(mesh.normals[v as usize]);
        }
        mesh.triangles = split.triangles;
        mesh.uvs = split.uvs;
        mesh.charts = split.charts;
        mesh.uv_layout = UvLayout::Atlas;
    }
    mesh.orient_outward();
    Ok(mesh)
}

/// The mesh a fit targets (`ntori new --input-mesh`), as an exportable mesh: its own positions, the
/// area-weighted normals of its triangles (outward), and as UVs and chart ids the chart point each
/// vertex was fitted at. Its source is [`MeshSource::FitInput`] (it is no tessellation of the
/// surface).
pub fn input_mesh(
    genus: u32,
    positions: &[Point3],
    triangles: &[[u32; 3]],
    points: &[charts::ChartPoint],
) -> Result<SurfaceMesh, ExportError> {
    let mut mesh = SurfaceMesh {
        genus,
        source: MeshSource::FitInput,
        uv_layout: UvLayout::Chart,
        positions: positions.to_vec(),
        normals: vec![Vector3::repeat(f64::NAN); positions.len()],
        uvs: points
            .iter()
            .map(|p| [p.coords.re + 0.5, p.coords.im + 0.5])
            .collect(),
        charts: points.iter().map(|p| p.chart.0).collect(),
        triangles: triangles.to_vec(),
        quads: false,
    };
    // No analytic normals: every vertex takes its triangles' (what repair does for a pinched one).
    mesh.repair_normals()?;
    mesh.orient_outward();
    Ok(mesh)
}

impl SurfaceMesh {
    /// Where S_u × S_v vanishes (an edit pinched the surface), the normal of the triangles around
    /// the vertex; an error where those have no area either.
    fn repair_normals(&mut self) -> Result<(), ExportError> {
        let bad: Vec<usize> = (0..self.normals.len())
            .filter(|&i| !self.normals[i].iter().all(|x| x.is_finite()))
            .collect();
        if bad.is_empty() {
            return Ok(());
        }
        let mut sums = vec![Vector3::zeros(); self.positions.len()];
        for t in &self.triangles {
            let n = face_normal(&self.positions, t);
            for &v in t {
                sums[v as usize] += n;
            }
        }
        let mut still = bad.iter().filter_map(|&i| {
            let n = sums[i].normalize();
            if n.iter().all(|x| x.is_finite()) {
                self.normals[i] = n;
                None
            } else {
                Some(i)
            }
        });
        match still.next() {
            Some(first) => {
                let count = 1 + still.count();
                let p = self.positions[first];
                Err(ExportError::Degenerate {
                    count,
                    x: p.x,
                    y: p.y,
                    z: p.z,
                })
            }
            None => Ok(()),
        }
    }

    /// Winds the triangles counter-clockwise seen from outside (positive signed volume), the
    /// normals outward.
    fn orient_outward(&mut self) {
        if signed_volume(&self.positions, &self.triangles) < 0.0 {
            for t in &mut self.triangles {
                t.swap(1, 2);
            }
            for n in &mut self.normals {
                *n = -*n;
            }
        }
    }
}

/// Twice the area times the unit normal of a triangle, from its winding.
pub(super) fn face_normal(positions: &[Point3], t: &[u32; 3]) -> Vector3 {
    let [a, b, c] = t.map(|i| positions[i as usize]);
    (b - a).cross(&(c - a))
}

/// Σ a·(b × c) / 6 over the triangles, about the centroid (so far-off models keep their digits).
pub fn signed_volume(positions: &[Point3], triangles: &[[u32; 3]]) -> f64 {
    let n = positions.len().max(1) as f64;
    let centre = Point3::from(positions.iter().fold(Vector3::zeros(), |s, p| s + p.coords) / n);
    triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| positions[i as usize] - centre);
            a.dot(&b.cross(&c))
        })
        .sum::<f64>()
        / 6.0
}
