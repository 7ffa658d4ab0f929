//! Export: a model's surface as a triangle mesh, written as OBJ, PLY, STL, GLB or OFF.
//!
//! [`surface_mesh`] tessellates the surface with the paper's t_e/t_r scheme (`charts::tessellation`)
//! and evaluates it at every vertex: the position and the analytic unit normal S_u × S_v / |S_u × S_v|
//! (not an average of face normals), and the vertex's *home chart* and coordinates there. Triangles
//! wind counter-clockwise seen from outside, and the normals point outward: the mesh is oriented so
//! that its signed volume is positive.
//!
//! What each format carries:
//!
//! | format | positions | normals | texture coordinates | chart id | encoding |
//! |--------|-----------|---------|---------------------|----------|----------|
//! | OBJ    | f32 text  | per vertex (`vn`) | per vertex (`vt`) | no: OBJ has no per-vertex attribute for it | text |
//! | PLY    | f32       | `nx ny nz` | `u v`           | `chart` (uint) | binary little endian, or `--ascii` |
//! | STL    | f32, per triangle corner | one per triangle (the face's) | no | no | binary, or `--ascii` |
//! | GLB    | f32 (with min/max) | `NORMAL` | `TEXCOORD_0` (v flipped, glTF's convention) | `_CHART` (u16) | binary glTF 2.0 |
//! | OFF    | f32 text  | no      | no                  | no       | text |
//!
//! Texture coordinates are the vertex's home chart coordinates moved from [−½, ½]² to [0, 1]², so
//! they are continuous inside one chart only; a triangle whose corners have different home charts
//! spans a seam of the texture. The chart id (where stored) tells which.
//!
//! Every file is written atomically ([`crate::io::atomic`]): whole, or not at all.

use std::io::Write;
use std::path::{Path, PathBuf};

use charts::Tessellation;
use embedding::{EmbeddingError, Point3, Sample, Surface, Vector3, Wants, evaluate};

use crate::io::atomic::{FileError, write_atomically_with};

mod glb;
mod obj;
mod off;
mod ply;
mod stl;

pub use glb::write_glb;
pub use obj::write_obj;
pub use off::write_off;
pub use ply::write_ply;
pub use stl::write_stl;

/// The largest t_e and t_r an export accepts.
pub const MAX_RESOLUTION: u32 = 512;
/// The most triangles an export makes (about 10⁷ vertices: a 1 GB binary STL, 2 GB of OBJ text).
pub const MAX_TRIANGLES: u64 = 20_000_000;

/// A tessellated surface with its attributes, ready to write.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SurfaceMesh {
    pub genus: u32,
    pub te: u32,
    pub tr: u32,
    pub positions: Vec<Point3>,
    /// Analytic unit normals, outward.
    pub normals: Vec<Vector3>,
    /// The vertex's coordinates in its home chart, plus ½: within [0, 1]².
    pub uvs: Vec<[f64; 2]>,
    /// The vertex's home chart.
    pub charts: Vec<u32>,
    /// Counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
}

/// A file format [`write()`] can produce.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, clap::ValueEnum)]
pub enum Format {
    /// Wavefront OBJ: positions, normals, texture coordinates (text).
    Obj,
    /// Stanford PLY: positions, normals, texture coordinates, chart ids (binary or text).
    Ply,
    /// STL: triangles with face normals only (binary or text).
    Stl,
    /// Binary glTF 2.0: positions, normals, texture coordinates, chart ids.
    Glb,
    /// Object File Format: positions and triangles only (text).
    Off,
}

/// Binary or text, for the formats that have both (PLY and STL).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Encoding {
    #[default]
    Binary,
    Ascii,
}

impl Format {
    pub const ALL: [Format; 5] = [
        Format::Obj,
        Format::Ply,
        Format::Stl,
        Format::Glb,
        Format::Off,
    ];

    /// The file extension, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            Format::Obj => "obj",
            Format::Ply => "ply",
            Format::Stl => "stl",
            Format::Glb => "glb",
            Format::Off => "off",
        }
    }

    /// The format a path's extension names (case-insensitive).
    pub fn from_path(path: &Path) -> Result<Format, ExportError> {
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase);
        Format::ALL
            .into_iter()
            .find(|f| ext.as_deref() == Some(f.extension()))
            .ok_or_else(|| ExportError::UnknownFormat {
                path: path.to_owned(),
            })
    }

    /// Whether the format has a text and a binary variant.
    pub fn has_encodings(self) -> bool {
        matches!(self, Format::Ply | Format::Stl)
    }
}

impl std::fmt::Display for Format {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.extension().to_ascii_uppercase())
    }
}

/// Why an export failed.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("{name} = {value} is out of range: it must lie in 1..={MAX_RESOLUTION}")]
    Resolution { name: &'static str, value: u32 },
    #[error(
        "t_e = {te}, t_r = {tr} would make {triangles} triangles at genus {genus}; an export makes \
         at most {MAX_TRIANGLES} (lower t_e or t_r)"
    )]
    TooManyTriangles {
        genus: u32,
        te: u32,
        tr: u32,
        triangles: u64,
    },
    #[error(transparent)]
    Model(#[from] EmbeddingError),
    #[error(
        "the surface is degenerate: {count} vertices have no normal (e.g. at ({x}, {y}, {z})), and \
         the triangles around them have no area"
    )]
    Degenerate {
        count: usize,
        x: f64,
        y: f64,
        z: f64,
    },
    #[error(
        "{} has no known extension (.obj, .ply, .stl, .glb, .off); name one or pass --format",
        .path.display()
    )]
    UnknownFormat { path: PathBuf },
    #[error("{0} has no text and binary variants; --ascii applies to PLY and STL only")]
    NoEncodings(Format),
    #[error(
        "vertex {index} lies at ({x:e}, {y:e}, {z:e}), beyond the 32-bit floats {format} stores (±3.4e38); scale the model down"
    )]
    NotStorable {
        format: Format,
        index: usize,
        x: f64,
        y: f64,
        z: f64,
    },
    #[error(
        "the surface spans {extent:e}, below what the 32-bit floats {format} stores can tell apart: every vertex would be written at the same point; scale the model up"
    )]
    Collapses { format: Format, extent: f64 },
    #[error("the mesh needs {0} bytes of GLB, over the format's limit of 4 GiB")]
    GlbTooLarge(u64),
    #[error(transparent)]
    File(#[from] FileError),
}

/// How many triangles an export at t_e, t_r makes, or why it is refused (before any work is done).
pub fn check_resolution(genus: u32, te: u32, tr: u32) -> Result<u64, ExportError> {
    for (name, value) in [("t_e", te), ("t_r", tr)] {
        if !(1..=MAX_RESOLUTION).contains(&value) {
            return Err(ExportError::Resolution { name, value });
        }
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

/// Tessellates the surface at t_e, t_r and evaluates it (see the module documentation).
pub fn surface_mesh(surface: &Surface, te: u32, tr: u32) -> Result<SurfaceMesh, ExportError> {
    let genus = surface.genus();
    check_resolution(genus, te, tr)?;
    // The control net's size: derivatives in chart units are of its order. A net of one point has
    // no surface at all.
    let size = surface.control_net_size();
    let control = surface.control_points();
    if surface.is_degenerate() {
        let p = control.first().copied().unwrap_or_default();
        return Err(ExportError::Degenerate {
            count: Tessellation::expected_vertices(genus, te, tr) as usize,
            x: p.x,
            y: p.y,
            z: p.z,
        });
    }
    let t = surface
        .atlas()
        .tessellate(te, tr)
        .map_err(EmbeddingError::from)?;
    let n = t.vertices.len();
    let mut mesh = SurfaceMesh {
        genus,
        te,
        tr,
        positions: Vec::with_capacity(n),
        normals: Vec::with_capacity(n),
        uvs: Vec::with_capacity(n),
        charts: Vec::with_capacity(n),
        triangles: t.triangles,
    };
    let tiny = 1e-9 * size;
    evaluate(
        surface,
        &t.vertices,
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
    mesh.repair_normals()?;
    mesh.orient_outward();
    Ok(mesh)
}

/// The mesh a fit targets (`ntori new --input-mesh`), as an exportable mesh: its own positions, the
/// area-weighted normals of its triangles (outward), and as UVs and chart ids the chart point each
/// vertex was fitted at. Its t_e and t_r are 0 (it is no tessellation of the surface).
pub fn input_mesh(
    genus: u32,
    positions: &[Point3],
    triangles: &[[u32; 3]],
    points: &[charts::ChartPoint],
) -> Result<SurfaceMesh, ExportError> {
    let mut mesh = SurfaceMesh {
        genus,
        te: 0,
        tr: 0,
        positions: positions.to_vec(),
        normals: vec![Vector3::repeat(f64::NAN); positions.len()],
        uvs: points
            .iter()
            .map(|p| [p.coords.re + 0.5, p.coords.im + 0.5])
            .collect(),
        charts: points.iter().map(|p| p.chart.0).collect(),
        triangles: triangles.to_vec(),
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
fn face_normal(positions: &[Point3], t: &[u32; 3]) -> Vector3 {
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

impl SurfaceMesh {
    /// A one-line description for file headers.
    fn describe(&self) -> String {
        if self.te == 0 {
            return format!(
                "ntori {}: the input mesh of a genus-{} fit, {} vertices, {} triangles",
                env!("CARGO_PKG_VERSION"),
                self.genus,
                self.positions.len(),
                self.triangles.len()
            );
        }
        format!(
            "ntori {}: genus {}, t_e = {}, t_r = {}, {} vertices, {} triangles",
            env!("CARGO_PKG_VERSION"),
            self.genus,
            self.te,
            self.tr,
            self.positions.len(),
            self.triangles.len()
        )
    }

    fn position_f32(&self, i: usize) -> [f32; 3] {
        self.positions[i].coords.cast::<f32>().into()
    }
    fn normal_f32(&self, i: usize) -> [f32; 3] {
        self.normals[i].cast::<f32>().into()
    }

    /// Triangles whose winding faces against the surface's normals at their corners (the normal
    /// from the winding has a negative dot product with the corners' mean normal): a tessellation
    /// too coarse for the surface folds there. Zero for a faithful mesh.
    pub fn folded_triangles(&self) -> usize {
        (0..self.triangles.len())
            .filter(|&k| {
                let n = face_normal(&self.positions, &self.triangles[k]);
                let m = self.triangles[k]
                    .iter()
                    .fold(Vector3::zeros(), |s, &v| s + self.normals[v as usize]);
                n.dot(&m) < 0.0
            })
            .count()
    }

    /// Checks that every number `format` stores survives its 32-bit floats: positions within the
    /// f32 range (beyond it they would be written as `inf`, and GLB bounds as `null`), the surface
    /// not collapsed to one point (a model scaled to 1e-46 rounds to all zeros), and normals,
    /// STL's face normals among them, finite.
    pub fn check_storable(&self, format: Format) -> Result<(), ExportError> {
        let (mut lo, mut hi) = ([f32::INFINITY; 3], [f32::NEG_INFINITY; 3]);
        for i in 0..self.positions.len() {
            let p = self.position_f32(i);
            if !p.iter().all(|x| x.is_finite()) {
                let q = self.positions[i];
                return Err(ExportError::NotStorable {
                    format,
                    index: i,
                    x: q.x,
                    y: q.y,
                    z: q.z,
                });
            }
            for k in 0..3 {
                lo[k] = lo[k].min(p[k]);
                hi[k] = hi[k].max(p[k]);
            }
        }
        if !self.positions.is_empty() && (0..3).all(|k| lo[k] == hi[k]) {
            let (plo, phi) = embedding::bounding_box(&self.positions);
            let extent = (phi - plo).norm();
            return Err(ExportError::Collapses { format, extent });
        }
        let degenerate = |count, i: usize| {
            let q = self.positions[i];
            ExportError::Degenerate {
                count,
                x: q.x,
                y: q.y,
                z: q.z,
            }
        };
        let bad_normals: Vec<usize> = (0..self.normals.len())
            .filter(|&i| !self.normal_f32(i).iter().all(|x| x.is_finite()))
            .collect();
        if let Some(&first) = bad_normals.first() {
            return Err(degenerate(bad_normals.len(), first));
        }
        if format == Format::Stl {
            let bad: Vec<usize> = (0..self.triangles.len())
                .filter(|&t| !self.face_normal(t).iter().all(|x| (*x as f32).is_finite()))
                .collect();
            if let Some(&first) = bad.first() {
                return Err(degenerate(bad.len(), self.triangles[first][0] as usize));
            }
        }
        Ok(())
    }

    /// The unit normal of triangle `t` from its winding (outward), for STL. The edges are scaled
    /// to their largest coordinate first, so far-off or huge coordinates (1e155) do not overflow
    /// the cross product into a NaN normal.
    pub fn face_normal(&self, t: usize) -> Vector3 {
        let [a, b, c] = self.triangles[t].map(|i| self.positions[i as usize]);
        let (e1, e2) = (b - a, c - a);
        let scale = e1.amax().max(e2.amax());
        let n = if scale > 0.0 && scale.is_finite() {
            (e1 / scale).cross(&(e2 / scale)).normalize()
        } else {
            Vector3::repeat(f64::NAN)
        };
        if n.iter().all(|x| x.is_finite()) {
            n
        } else {
            // A sliver with no area: the corners' analytic normals say which way is out.
            self.triangles[t]
                .iter()
                .fold(Vector3::zeros(), |s, &v| s + self.normals[v as usize])
                .normalize()
        }
    }
}

/// What [`export_surface`] wrote.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Exported {
    pub vertices: usize,
    pub triangles: usize,
    /// Triangles facing against the surface's normals ([`SurfaceMesh::folded_triangles`]): the
    /// tessellation is too coarse for the surface where this is not zero.
    pub folded: usize,
}

/// The export behind `ntori export` and the editor's: tessellates and evaluates `surface` at
/// t_e, t_r ([`surface_mesh`]) and writes it to `path` ([`write()`]).
pub fn export_surface(
    surface: &Surface,
    (te, tr): (u32, u32),
    path: &Path,
    format: Format,
    encoding: Encoding,
) -> Result<Exported, ExportError> {
    let mesh = surface_mesh(surface, te, tr)?;
    write(&mesh, path, format, encoding)?;
    Ok(Exported {
        vertices: mesh.positions.len(),
        triangles: mesh.triangles.len(),
        folded: mesh.folded_triangles(),
    })
}

/// Writes `mesh` to `path` atomically in `format` (`encoding` matters for PLY and STL only).
pub fn write(
    mesh: &SurfaceMesh,
    path: &Path,
    format: Format,
    encoding: Encoding,
) -> Result<(), ExportError> {
    mesh.check_storable(format)?;
    if format == Format::Glb {
        glb::glb_size(mesh)?;
    }
    write_atomically_with(path, |out| write_to(mesh, format, encoding, out))?;
    Ok(())
}

/// Writes `mesh` in `format` to any writer.
pub fn write_to(
    mesh: &SurfaceMesh,
    format: Format,
    encoding: Encoding,
    out: &mut dyn Write,
) -> std::io::Result<()> {
    match format {
        Format::Obj => write_obj(mesh, out),
        Format::Ply => write_ply(mesh, encoding, out),
        Format::Stl => write_stl(mesh, encoding, out),
        Format::Glb => write_glb(mesh, out),
        Format::Off => write_off(mesh, out),
    }
}
