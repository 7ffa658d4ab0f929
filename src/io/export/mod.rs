//! Export: a model's surface as a triangle mesh, written as OBJ, PLY, STL, GLB, 3MF or OFF.
//!
//! [`surface_mesh`] tessellates the surface with the paper's t_e/t_r scheme (`charts::tessellation`)
//! and [`evaluate_mesh`] evaluates any such mesh of chart points ([`ChartMesh`]) at every vertex:
//! the position and the analytic unit normal S_u × S_v / |S_u × S_v| (not an average of face
//! normals), and the vertex's *home chart* and coordinates there. Triangles wind counter-clockwise
//! seen from outside, and the normals point outward: the mesh is oriented so that its signed volume
//! is positive.
//!
//! What each format carries:
//!
//! | format | positions | normals | texture coordinates | chart id | object name | up | unit |
//! |--------|-----------|---------|---------------------|----------|-------------|----|------|
//! | OBJ    | f32 text  | per vertex (`vn`) | per vertex (`vt`) | no: OBJ has no per-vertex attribute for it | `o` | +y | none |
//! | PLY    | f32       | `nx ny nz` | `s t`            | `chart` (uint) | a comment | +z | none |
//! | STL    | f32, per triangle corner | one per triangle (the face's) | no | no | `solid` (text), the header (binary) | +z | mm (by convention) |
//! | GLB    | f32 (with min/max) | `NORMAL` | `TEXCOORD_0` (v flipped), used by a checker base colour texture | `_CHART` (u8; f32 past 256 charts) | node and mesh | +y | m |
//! | 3MF    | f32 text  | no      | no                  | no       | the object's | +z | mm (declared) |
//! | OFF    | f32 text  | no      | no                  | no       | a comment   | +z | none |
//!
//! [`ExportOptions`] set the up axis (each format's convention by default; ntori's own up is z),
//! the size (one model unit becomes `scale` × `units`; formats with a unit are converted to it),
//! the texture coordinate layout ([`UvLayout`]: each vertex's home chart coordinates moved from
//! [−½, ½]² to [0, 1]², or a packed atlas with the mesh split at chart seams, see [`atlas`]) and
//! the object's name.
//!
//! Every file is written atomically ([`crate::io::atomic`]): whole, or not at all.

use std::path::{Path, PathBuf};

use charts::{ChartId, ChartPoint, Tessellation};
use embedding::remesh;
use embedding::{EmbeddingError, Point3, Surface, Vector3};
use num_complex::Complex64;

pub use crate::io::atomic::WriteSeek;
use crate::io::atomic::{FileError, write_atomically_with};

pub mod atlas;
mod glb;
mod meshing;
mod obj;
mod off;
mod options;
mod ply;
mod stl;
pub mod texture;
mod threemf;

pub use atlas::UvAtlas;
pub use glb::{ChartComponent, chart_component};
use meshing::face_normal;
pub use meshing::{
    Meshing, check_resolution, evaluate_mesh, input_mesh, mesh_surface, quad_surface_mesh,
    quality_surface_mesh, signed_volume, surface_mesh,
};
use options::FileInfo;
pub use options::{DEFAULT_UNITS, ExportOptions, MAX_NAME_CHARS, Units, Up, UvLayout};
pub use threemf::MODEL_PART;

/// The largest t_e and t_r an export accepts.
pub const MAX_RESOLUTION: u32 = 512;
/// The most 32-bit rounding may move a vertex, as a fraction of the surface's size (the diagonal of
/// its bounding box), for an export to be written ([`SurfaceMesh::check_storable`]). A surface about
/// the origin rounds by about 3e-8 of its size; the bound is reached about 170 sizes away from it.
pub const MAX_ROUNDING: f64 = 1e-5;
/// The most triangles an export makes (about 10⁷ vertices: a 1 GB binary STL, 2 GB of OBJ text).
pub const MAX_TRIANGLES: u64 = 20_000_000;

/// What a [`SurfaceMesh`] was made from, for file headers.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum MeshSource {
    /// The t_e/t_r tessellation ([`surface_mesh`]).
    Tessellation { te: u32, tr: u32 },
    /// The quality tessellation ([`quality_surface_mesh`]) at this chordal tolerance, a fraction
    /// of the surface's diagonal.
    Quality { tolerance: f64 },
    /// The all-quad tessellation ([`quad_surface_mesh`]) at this chordal tolerance.
    Quads { tolerance: f64 },
    /// The mesh a fit targets ([`input_mesh`]).
    FitInput,
    /// Another mesh of chart points ([`evaluate_mesh`]).
    #[default]
    ChartMesh,
}

/// A tessellated surface with its attributes, ready to write.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SurfaceMesh {
    pub genus: u32,
    pub source: MeshSource,
    /// How `uvs` are laid out.
    pub uv_layout: UvLayout,
    pub positions: Vec<Point3>,
    /// Analytic unit normals, outward.
    pub normals: Vec<Vector3>,
    /// [`UvLayout::Chart`]: the vertex's coordinates in its home chart, plus ½, within [0, 1]².
    /// [`UvLayout::Atlas`]: its place in its chart's tile.
    pub uvs: Vec<[f64; 2]>,
    /// The vertex's home chart ([`UvLayout::Atlas`]: the chart of its tile).
    pub charts: Vec<u32>,
    /// Counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
    /// Whether the triangles are halves of quads: triangles 2k and 2k + 1 share an edge, the
    /// quad's diagonal ([`SurfaceMesh::quad_faces`]). Formats with polygons write the quads.
    pub quads: bool,
}

/// A triangle mesh of the surface whose vertices are chart points, borrowed: what
/// [`evaluate_mesh`] evaluates. The t_e/t_r [`Tessellation`] is one (`ChartMesh::from`); any
/// other tessellation of the surface can be fed through the same path.
#[derive(Clone, Copy, Debug)]
pub struct ChartMesh<'a> {
    /// Each vertex in its home chart.
    pub vertices: &'a [ChartPoint],
    /// Vertex indices, counter-clockwise in the triangle's home chart.
    pub triangles: &'a [[u32; 3]],
    /// Each triangle's home chart.
    pub triangle_charts: &'a [ChartId],
    /// Each triangle's corners in its home chart's coordinates (the atlas's texture coordinates
    /// come from these).
    pub triangle_coords: &'a [[Complex64; 3]],
}

impl<'a> From<&'a Tessellation> for ChartMesh<'a> {
    fn from(t: &'a Tessellation) -> Self {
        ChartMesh {
            vertices: &t.vertices,
            triangles: &t.triangles,
            triangle_charts: &t.triangle_charts,
            triangle_coords: &t.triangle_coords,
        }
    }
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
    /// Binary glTF 2.0: positions, normals, texture coordinates, chart ids, a material.
    Glb,
    /// 3MF, for slicers: positions and triangles in millimetres (a ZIP package).
    #[value(name = "3mf")]
    ThreeMf,
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
    pub const ALL: [Format; 6] = [
        Format::Obj,
        Format::Ply,
        Format::Stl,
        Format::Glb,
        Format::ThreeMf,
        Format::Off,
    ];

    /// The file extension, without the dot.
    pub fn extension(self) -> &'static str {
        match self {
            Format::Obj => "obj",
            Format::Ply => "ply",
            Format::Stl => "stl",
            Format::Glb => "glb",
            Format::ThreeMf => "3mf",
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

    /// Whether the format stores polygons (quads) as well as triangles.
    pub fn has_quads(self) -> bool {
        matches!(self, Format::Obj | Format::Ply | Format::Off)
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
        "t_e = 1 is refused at genus {genus}: at t_e = 1 some squares of the tessellation share three \
         corners, so two different edges join the same two vertices, which mesh readers \
         take for a non-manifold mesh; use --te 2 or more"
    )]
    SharedEdges { genus: u32 },
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
        "{} has no known extension (.obj, .ply, .stl, .glb, .3mf, .off); name one or pass --format",
        .path.display()
    )]
    UnknownFormat { path: PathBuf },
    #[error("{0} has no text and binary variants; --ascii applies to PLY and STL only")]
    NoEncodings(Format),
    #[error("{0} stores no texture coordinates; --uv atlas applies to OBJ, PLY and GLB only")]
    NoUvs(Format),
    #[error("{0} stores triangles only; --quads applies to OBJ, PLY and OFF")]
    NoQuads(Format),
    #[error("the scale must be a finite number above 0, got {0}")]
    Scale(f64),
    #[error(
        "vertex {index} lies at ({x:e}, {y:e}, {z:e}), beyond the 32-bit floats {format} stores (±3.4e38); lower --scale or scale the model down"
    )]
    NotStorable {
        format: Format,
        index: usize,
        x: f64,
        y: f64,
        z: f64,
    },
    #[error(
        "the surface spans {extent:e}, below what the 32-bit floats {format} stores can tell apart at up to {magnitude:e} from the origin (they would move its points by up to {error:e}); raise --scale, scale the model up or move it nearer the origin"
    )]
    Collapses {
        format: Format,
        extent: f64,
        /// The largest coordinate's magnitude.
        magnitude: f64,
        /// The most f32 rounding moves a coordinate.
        error: f64,
    },
    #[error("the mesh needs {0} bytes of GLB, over the format's limit of 4 GiB")]
    GlbTooLarge(u64),
    #[error(transparent)]
    File(#[from] FileError),
    #[error("cannot write the mesh: {0}")]
    Write(std::io::Error),
}

impl SurfaceMesh {
    /// A one-line description for file headers.
    fn describe(&self) -> String {
        let what = match self.source {
            MeshSource::Tessellation { te, tr } => {
                format!("genus {}, t_e = {te}, t_r = {tr}", self.genus)
            }
            MeshSource::Quality { tolerance } => format!(
                "genus {}, quality tessellation to {tolerance} of the diagonal",
                self.genus
            ),
            MeshSource::Quads { tolerance } => format!(
                "genus {}, quad tessellation to {tolerance} of the diagonal",
                self.genus
            ),
            MeshSource::FitInput => format!("the input mesh of a genus-{} fit", self.genus),
            MeshSource::ChartMesh => format!("genus {}", self.genus),
        };
        format!(
            "ntori {}: {what}, {} vertices, {}",
            env!("CARGO_PKG_VERSION"),
            self.positions.len(),
            self.face_count()
        )
    }

    /// "N triangles", or "N quads" where the triangles are halves of quads.
    pub fn face_count(&self) -> String {
        face_count(self.triangles.len(), self.quads)
    }

    /// The quads whose halves the triangles are ([`SurfaceMesh::quads`]), counter-clockwise as
    /// the triangles wind; none where they are not.
    pub fn quad_faces(&self) -> Vec<[u32; 4]> {
        if !self.quads {
            return Vec::new();
        }
        remesh::quads_of(&self.triangles)
    }

    /// What the texture coordinates are, for file headers.
    fn describe_uvs(&self) -> &'static str {
        match self.uv_layout {
            UvLayout::Chart => "the vertex's home chart coordinates + 0.5",
            UvLayout::Atlas => {
                "a packed atlas: each chart's region in its own tile, vertices split at seams"
            }
        }
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
    /// not blurred by rounding (f32 moves a point by up to half an ulp of its largest coordinate,
    /// at least 2⁻¹⁵⁰ among the subnormals; that must stay below [`MAX_ROUNDING`] of the surface's
    /// size: a model scaled to 1e-46 rounds to all zeros, one at 1e-45 to three values), and
    /// normals, STL's face normals among them, finite.
    pub fn check_storable(&self, format: Format) -> Result<(), ExportError> {
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
        }
        if !self.positions.is_empty() {
            let (lo, hi) = embedding::bounding_box(&self.positions);
            let extent = (hi - lo).norm();
            let magnitude = self
                .positions
                .iter()
                .fold(0.0f64, |m, p| m.max(p.coords.amax()));
            let error = (0.5 * magnitude * f64::from(f32::EPSILON)).max(2f64.powi(-150));
            // False for a NaN extent too: refused.
            let resolved = error <= MAX_ROUNDING * extent;
            if !resolved {
                return Err(ExportError::Collapses {
                    format,
                    extent,
                    magnitude,
                    error,
                });
            }
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
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Exported {
    pub vertices: usize,
    pub triangles: usize,
    /// Whether the file holds the triangles paired into quads.
    pub quads: bool,
    /// Triangles facing against the surface's normals ([`SurfaceMesh::folded_triangles`]): the
    /// tessellation is too coarse for the surface where this is not zero.
    pub folded: usize,
    /// The bounding box's size along x, y, z as written, in `unit`.
    pub size: [f64; 3],
    /// The unit the file's numbers are in.
    pub unit: Units,
}

impl Exported {
    /// "N triangles", or "N quads" where the file holds quads.
    pub fn face_count(&self) -> String {
        face_count(self.triangles, self.quads)
    }
}

/// "N triangles", or "N quads" where the `triangles` are halves of quads.
fn face_count(triangles: usize, quads: bool) -> String {
    if quads {
        format!("{} quads", triangles / 2)
    } else {
        format!("{triangles} triangles")
    }
}

/// The export behind `ntori export` and the editor's: tessellates and evaluates `surface` as
/// `meshing` says ([`mesh_surface`]) and writes it to `path` ([`write()`]).
pub fn export_surface(
    surface: &Surface,
    meshing: Meshing,
    path: &Path,
    format: Format,
    options: &ExportOptions,
) -> Result<Exported, ExportError> {
    options.check(format)?;
    meshing.check(format)?;
    let mut mesh = mesh_surface(surface, meshing, options.uv)?;
    let info = FileInfo::new(&mesh, format, options);
    // Placed where it lies (no copy: an export may hold 10⁷ vertices).
    mesh.place(options.up_for(format), options.factor_for(format));
    let size = write_placed_file(&mesh, path, format, &info)?;
    Ok(Exported {
        vertices: mesh.positions.len(),
        triangles: mesh.triangles.len(),
        quads: mesh.quads,
        folded: mesh.folded_triangles(),
        size,
        unit: info.unit,
    })
}

/// Writes `mesh` to `path` atomically in `format`, placed as `options` say (up axis, scale and
/// unit; the mesh's texture coordinates are written as they are). Returns the bounding box's size
/// as written.
pub fn write(
    mesh: &SurfaceMesh,
    path: &Path,
    format: Format,
    options: &ExportOptions,
) -> Result<[f64; 3], ExportError> {
    options.check(format)?;
    if mesh.quads && !format.has_quads() {
        return Err(ExportError::NoQuads(format));
    }
    let placed = mesh.placed(options.up_for(format), options.factor_for(format));
    write_placed_file(&placed, path, format, &FileInfo::new(mesh, format, options))
}

/// Checks and writes a mesh already placed; its bounding box's size.
fn write_placed_file(
    mesh: &SurfaceMesh,
    path: &Path,
    format: Format,
    info: &FileInfo,
) -> Result<[f64; 3], ExportError> {
    mesh.check_storable(format)?;
    if format == Format::Glb {
        glb::glb_size(mesh)?;
    }
    write_atomically_with(path, |out| write_placed(mesh, format, info, out))?;
    let (lo, hi) = embedding::bounding_box(&mesh.positions);
    Ok((hi - lo).into())
}

/// Writes `mesh` in `format` to any seekable writer, placed as `options` say (see [`write()`]).
pub fn write_to(
    mesh: &SurfaceMesh,
    format: Format,
    options: &ExportOptions,
    out: &mut dyn WriteSeek,
) -> Result<(), ExportError> {
    options.check(format)?;
    if mesh.quads && !format.has_quads() {
        return Err(ExportError::NoQuads(format));
    }
    let placed = mesh.placed(options.up_for(format), options.factor_for(format));
    placed.check_storable(format)?;
    let info = FileInfo::new(mesh, format, options);
    write_placed(&placed, format, &info, out).map_err(ExportError::Write)
}

fn write_placed(
    mesh: &SurfaceMesh,
    format: Format,
    info: &FileInfo,
    out: &mut dyn WriteSeek,
) -> std::io::Result<()> {
    match format {
        Format::Obj => obj::write_obj(mesh, info, out),
        Format::Ply => ply::write_ply(mesh, info, out),
        Format::Stl => stl::write_stl(mesh, info, out),
        Format::Glb => glb::write_glb(mesh, info, out),
        Format::ThreeMf => threemf::write_3mf(mesh, info, out),
        Format::Off => off::write_off(mesh, info, out),
    }
}
