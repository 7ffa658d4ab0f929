//! Import: a user's triangle or polygon mesh read from OBJ, PLY, OFF, STL or glTF (GLB), and checked
//! for what a fit needs (issue 14).
//!
//! Reading ([`read_mesh`], [`read_mesh_bytes`]) gives an [`ImportedMesh`]: positions (f64) and
//! triangles, polygons triangulated ([`triangulate`]: ear clipping in the polygon's best-fit plane,
//! so non-convex polygons work), and, for the formats that store no shared vertices (STL) or split
//! them at seams (glTF), exactly coincident positions merged into one vertex. Readers:
//!
//! | format | reader | notes |
//! |--------|--------|-------|
//! | OBJ | [`obj`], by hand | `v` and `f` (`v`, `v/vt`, `v//vn`, `v/vt/vn`, negative indices); other statements ignored; f64 |
//! | PLY | ply-rs-bw (ASCII, binary either endian) | `vertex` `x y z` (any numeric type); `face` `vertex_indices` or `vertex_index` lists |
//! | OFF | [`off`], by hand | `OFF`, `COFF`, `NOFF`, `STOFF`… headers (or none); `#` comments; polygons; colours ignored |
//! | STL | [`stl`], by hand | binary when its size is 84 + 50 × its triangle count, else ASCII; coincident corners merged |
//! | GLB | [`glb`], gltf-json + the container by hand | every triangle primitive (lists, strips, fans) of the default scene, node transforms applied (mirroring transforms reverse the winding); `.gltf` with `data:` buffers too; coincident vertices merged |
//!
//! Errors say where: the line for text formats, the byte offset for binary ones, the mesh and
//! primitive for glTF. Vertex and face indices in messages count from 0 in file order (OBJ files count
//! from 1; the messages quote OBJ's own index and line).
//!
//! Validation ([`validate`]) turns an [`ImportedMesh`] into a [`ValidMesh`] — one connected,
//! closed, orientable manifold of genus 0 to 64 with no degenerate triangles, consistently oriented
//! (outward: the signed volume is made positive), every vertex used — or says what is wrong and
//! where, naming vertices by index and position (`(x, y, z)`) so a person can find them in a
//! modelling program. The checks run in this order, and the first that fails is the answer:
//! components (`keep_largest` keeps the largest instead), degenerate triangles, non-manifold edges,
//! non-manifold vertices, holes (boundary loops), orientability, genus.
//!
//! Nothing here panics on any input: every index, count and offset a file gives is checked before
//! it is used, and nothing is allocated from a count before the bytes behind it are known to exist.

use std::fmt;
use std::path::Path;

use embedding::{Point3, Vector3};

use crate::io::export::Units;

use crate::io::input::{self, InputProblem};

pub mod cage;
mod error;
pub mod glb;
pub mod obj;
pub mod off;
pub mod ply;
pub mod stl;
mod triangulate;
mod validate;

pub use error::{ImportError, Location, Place};
pub use triangulate::triangulate;
use triangulate::triangulate_into;
pub use validate::validate;

/// The largest mesh file read, in bytes (a 20-million-triangle binary STL is 1 GB).
pub const MAX_MESH_BYTES: u64 = 2 << 30;
/// The most triangles a mesh may have (after triangulation; as for exports).
pub const MAX_TRIANGLES: usize = 20_000_000;
/// The largest genus ntori fits.
pub const MAX_GENUS: u32 = 64;
/// A triangle is degenerate when twice its area, |(b − a) × (c − a)|, is at most this fraction of
/// the square of the mesh's bounding-box diagonal (or when a vertex repeats). For a mesh a metre
/// across this is a triangle of about 5e-13 m²: sides of a micrometre would pass, but nothing a
/// fit could use. Sliver triangles from f32 rounding of collinear points land well below it.
pub const DEGENERATE_AREA: f64 = 1e-12;
/// Polygons with more sides than this are fanned rather than ear-clipped (ear clipping is
/// quadratic in the sides).
pub const MAX_EAR_CLIPPED_SIDES: usize = 1024;

/// A mesh file format, known by its extension.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MeshFormat {
    Obj,
    Ply,
    Off,
    Stl,
    /// Binary glTF, or glTF JSON (`.gltf`) whose buffers are inside it (`data:` URIs).
    Glb,
}

impl MeshFormat {
    /// The extensions read, as listed in messages.
    pub const EXTENSIONS: &'static str = ".obj, .ply, .off, .stl, .glb and .gltf";
    /// The same, for file dialogs' filters (what [`MeshFormat::from_extension`] takes).
    pub const EXTENSION_LIST: [&'static str; 6] = ["obj", "ply", "off", "stl", "glb", "gltf"];

    /// The format of a file name's extension (case-insensitive).
    pub fn from_extension(extension: &str) -> Option<MeshFormat> {
        Some(match extension.to_ascii_lowercase().as_str() {
            "obj" => MeshFormat::Obj,
            "ply" => MeshFormat::Ply,
            "off" => MeshFormat::Off,
            "stl" => MeshFormat::Stl,
            "glb" | "gltf" => MeshFormat::Glb,
            _ => return None,
        })
    }

    /// The format of a path, from its extension.
    pub fn from_path(path: &Path) -> Result<MeshFormat, ImportError> {
        let extension = path
            .extension()
            .map(|e| e.to_string_lossy().into_owned())
            .unwrap_or_default();
        MeshFormat::from_extension(&extension).ok_or_else(|| ImportError::UnknownFormat {
            path: path.to_owned(),
            extension,
        })
    }
}

impl fmt::Display for MeshFormat {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            MeshFormat::Obj => "OBJ",
            MeshFormat::Ply => "PLY",
            MeshFormat::Off => "OFF",
            MeshFormat::Stl => "STL",
            MeshFormat::Glb => "glTF",
        })
    }
}

/// A mesh as read from a file: positions and triangles (polygons triangulated, coincident vertices
/// merged where the format needs it), not yet checked beyond its indices and numbers.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImportedMesh {
    pub positions: Vec<Point3>,
    pub triangles: Vec<[u32; 3]>,
    /// Vertices that were exactly coincident with an earlier one and merged into it (STL, glTF).
    pub merged_vertices: usize,
    /// Polygons with more than three sides that were cut into triangles.
    pub triangulated_polygons: usize,
    /// The faces as the file gave them, before triangulation, numbered as `positions` (what a
    /// subdivision cage is made of).
    pub polygons: Polygons,
}

/// Polygons, flat: polygon f has `sides[f]` corners, the next ones of `corners`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Polygons {
    pub sides: Vec<u32>,
    pub corners: Vec<u32>,
}

/// A mesh ready to fit: one closed, connected, consistently oriented manifold of genus 0..=64.
#[derive(Clone, Debug, PartialEq)]
pub struct ValidMesh {
    /// Only the vertices the triangles use, in their original order.
    pub positions: Vec<Point3>,
    /// Counter-clockwise seen from outside (the signed volume is positive).
    pub triangles: Vec<[u32; 3]>,
    pub genus: u32,
    /// Components left out (`keep_largest`), and their triangles.
    pub dropped_components: usize,
    pub dropped_triangles: usize,
    /// Vertices no kept triangle used.
    pub removed_vertices: usize,
    /// Triangles reversed to agree with their neighbours.
    pub reoriented_triangles: usize,
    /// Whether every triangle was then reversed, the mesh having been inside out.
    pub flipped: bool,
}

/// Refuses, before any work, a valid mesh with more triangles than the fit takes
/// ([`embedding::fit::MAX_FIT_TRIANGLES`]): `ntori fit` and the editor's import alike.
pub fn check_fittable(valid: &ValidMesh) -> Result<(), ImportError> {
    let max = embedding::fit::MAX_FIT_TRIANGLES;
    if valid.triangles.len() > max {
        return Err(ImportError::TooLargeToFit {
            triangles: valid.triangles.len(),
            max,
        });
    }
    Ok(())
}

/// Reads a mesh file, its format from its extension. File errors and format errors name the file.
pub fn read_mesh(path: &Path) -> Result<ImportedMesh, ImportError> {
    // What the path is comes first: a missing file, a directory or a FIFO is named as such, whatever
    // its extension.
    let meta = file_metadata(path)?;
    let format = MeshFormat::from_path(path)?;
    let bytes = read_file(path, &meta)?;
    read_mesh_bytes(&bytes, format).map_err(|error| ImportError::InFile {
        path: path.to_owned(),
        error: Box::new(error),
    })
}

/// Whether `path` could be a mesh to read: it exists, is a regular file within the size cap, and its
/// extension names a format. Cheap, so a command can say so before it checks its output.
pub fn check_input(path: &Path) -> Result<(), ImportError> {
    file_metadata(path)?;
    MeshFormat::from_path(path)?;
    Ok(())
}

/// The file's metadata, refusing what is missing, not a regular file, or too large to read.
fn file_metadata(path: &Path) -> Result<std::fs::Metadata, ImportError> {
    input::regular_file(path, MAX_MESH_BYTES).map_err(|p| file_error(path, p))
}

fn read_file(path: &Path, meta: &std::fs::Metadata) -> Result<Vec<u8>, ImportError> {
    input::read_capped(path, meta, MAX_MESH_BYTES).map_err(|p| file_error(path, p))
}

fn file_error(path: &Path, problem: InputProblem) -> ImportError {
    let path = path.to_owned();
    match problem {
        InputProblem::Missing => ImportError::Missing { path },
        InputProblem::Unreadable(source) => ImportError::Unreadable { path, source },
        InputProblem::NotRegular(kind) => ImportError::NotRegular { path, kind },
        InputProblem::TooLarge(size) => ImportError::TooLargeFile {
            path,
            size,
            max: MAX_MESH_BYTES,
        },
    }
}

/// Reads a mesh from a file's bytes (no file system: what the fuzz tests call).
pub fn read_mesh_bytes(bytes: &[u8], format: MeshFormat) -> Result<ImportedMesh, ImportError> {
    if bytes.iter().all(u8::is_ascii_whitespace) {
        return Err(ImportError::Blank { bytes: bytes.len() });
    }
    let raw = match format {
        MeshFormat::Obj => obj::read(bytes)?,
        MeshFormat::Ply => ply::read(bytes)?,
        MeshFormat::Off => off::read(bytes)?,
        MeshFormat::Stl => stl::read(bytes)?,
        MeshFormat::Glb => glb::read(bytes)?,
    };
    raw.finish(format)
}

/// Polygons as a reader found them, before triangulation.
#[derive(Clone, Debug, Default)]
pub(crate) struct RawMesh {
    pub positions: Vec<Point3>,
    /// Every polygon's corners, one after the other.
    pub corners: Vec<u32>,
    /// Every polygon's number of corners (at least 3).
    pub sides: Vec<u32>,
    /// Merge exactly coincident positions.
    pub merge: bool,
}

impl RawMesh {
    pub fn push_polygon(&mut self, corners: &[u32]) -> Result<(), ImportError> {
        self.corners.extend_from_slice(corners);
        self.sides.push(corners.len() as u32);
        // Each polygon makes at least one triangle; corners bound the memory.
        if self.sides.len() > MAX_TRIANGLES || self.corners.len() > 3 * MAX_TRIANGLES {
            return Err(ImportError::TooManyTriangles {
                at: Location::Unknown,
                max: MAX_TRIANGLES,
            });
        }
        Ok(())
    }

    fn finish(self, format: MeshFormat) -> Result<ImportedMesh, ImportError> {
        if self.positions.is_empty() {
            return Err(ImportError::Empty {
                format,
                what: "vertices",
            });
        }
        if self.sides.is_empty() {
            return Err(ImportError::Empty {
                format,
                what: "faces",
            });
        }
        for (v, p) in self.positions.iter().enumerate() {
            if !p.iter().all(|x| x.is_finite()) {
                return Err(ImportError::NonFinite {
                    vertex: v,
                    at: Location::Unknown,
                    x: p.x,
                    y: p.y,
                    z: p.z,
                });
            }
        }
        let n = self.positions.len();
        let mut triangles = Vec::with_capacity(self.sides.len());
        let mut triangulated = 0;
        let mut start = 0usize;
        for (f, &s) in self.sides.iter().enumerate() {
            let Some(poly) = self.corners.get(start..start + s as usize) else {
                break;
            };
            start += s as usize;
            if let Some(&bad) = poly.iter().find(|&&v| v as usize >= n) {
                return Err(ImportError::IndexOutOfRange {
                    face: f,
                    at: Location::Unknown,
                    index: i64::from(bad),
                    vertex_count: n,
                });
            }
            if poly.len() > 3 {
                triangulated += 1;
            }
            triangulate_into(&self.positions, poly, &mut triangles);
            if triangles.len() > MAX_TRIANGLES {
                return Err(ImportError::TooManyTriangles {
                    at: Location::Unknown,
                    max: MAX_TRIANGLES,
                });
            }
        }
        let mut mesh = ImportedMesh {
            positions: self.positions,
            triangles,
            merged_vertices: 0,
            triangulated_polygons: triangulated,
            polygons: Polygons {
                sides: self.sides,
                corners: self.corners,
            },
        };
        if self.merge {
            merge_coincident(&mut mesh);
        }
        Ok(mesh)
    }
}

/// Merges exactly coincident positions (−0 and +0 alike) into the first of them, keeping the
/// vertices' order of first appearance; returns how many were merged.
pub fn merge_coincident(mesh: &mut ImportedMesh) -> usize {
    use std::collections::HashMap;
    let key = |p: &Point3| p.coords.map(|x| (x + 0.0).to_bits());
    let mut index: HashMap<_, u32> = HashMap::with_capacity(mesh.positions.len());
    let mut positions = Vec::new();
    let remap: Vec<u32> = mesh
        .positions
        .iter()
        .map(|p| {
            *index.entry(key(p)).or_insert_with(|| {
                positions.push(*p);
                (positions.len() - 1) as u32
            })
        })
        .collect();
    for t in &mut mesh.triangles {
        *t = t.map(|v| remap[v as usize]);
    }
    for c in &mut mesh.polygons.corners {
        *c = remap[*c as usize];
    }
    let merged = mesh.positions.len() - positions.len();
    mesh.positions = positions;
    mesh.merged_vertices += merged;
    merged
}

/// Parses a number of a text format (Rust's float syntax, which also takes `inf` and `nan`: those
/// are caught as non-finite coordinates, with their vertex).
pub(crate) fn parse_f64(token: &str) -> Option<f64> {
    token.parse::<f64>().ok()
}

/// A vertex's three coordinates from the tokens of text line `line` (OBJ, OFF, ASCII STL). `who`
/// names it in messages ("a vertex", "vertex 3"); `vertex` is its index, for the non-finite error.
pub(crate) fn text_vertex<'a>(
    tokens: &mut impl Iterator<Item = &'a str>,
    format: MeshFormat,
    line: usize,
    who: &str,
    vertex: usize,
) -> Result<Point3, ImportError> {
    let error = |message: String| ImportError::Parse {
        format,
        at: Location::Line(line),
        message,
    };
    let mut xyz = [0.0; 3];
    for (k, slot) in xyz.iter_mut().enumerate() {
        let token = tokens
            .next()
            .ok_or_else(|| error(format!("{who} needs three coordinates, found {k}")))?;
        *slot = parse_f64(token)
            .ok_or_else(|| error(format!("`{}` is not a number", obj::quote(token))))?;
    }
    if !xyz.iter().all(|x| x.is_finite()) {
        return Err(ImportError::NonFinite {
            vertex,
            at: Location::Line(line),
            x: xyz[0],
            y: xyz[1],
            z: xyz[2],
        });
    }
    Ok(Point3::from(xyz))
}

/// Lines of a text file, numbered from 1, with `\r` removed and invalid UTF-8 replaced.
pub(crate) fn text_lines(bytes: &[u8]) -> impl Iterator<Item = (usize, std::borrow::Cow<'_, str>)> {
    bytes.split(|&b| b == b'\n').enumerate().map(|(i, line)| {
        let line = line.strip_suffix(b"\r").unwrap_or(line);
        (i + 1, String::from_utf8_lossy(line))
    })
}

/// How a mesh file's coordinates become the model's: the file's up axis, and what one of its
/// units is in model units (a model unit is a centimetre, as `ntori export` writes by default).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placement {
    pub up: crate::io::export::Up,
    pub factor: f64,
}

impl Placement {
    /// The conventions `ntori export` writes `path`'s format with, so that a mesh exported and read
    /// back keeps its size and orientation: glTF (GLB) is in metres and +y up (its
    /// specification), STL in millimetres (slicers) and +z up, OBJ +y up (Blender, most viewers),
    /// PLY and OFF +z up; OBJ, PLY and OFF have no unit, and their numbers are taken in `units`.
    /// `up` overrides the format's axis.
    pub fn for_file(path: &Path, up: Option<crate::io::export::Up>, units: Units) -> Placement {
        use crate::io::export::{Format, Up};
        let extension = path.extension().and_then(|e| e.to_str()).unwrap_or("");
        // `.gltf` is read as glTF too; the export's formats know only `.glb`.
        let format = if extension.eq_ignore_ascii_case("gltf") {
            Some(Format::Glb)
        } else {
            Format::from_path(path).ok()
        };
        let file_up = format.map_or(Up::Z, Format::default_up);
        let unit = format.and_then(Format::unit).unwrap_or(units);
        Placement {
            up: up.unwrap_or(file_up),
            factor: unit.metres() / crate::io::export::DEFAULT_UNITS.metres(),
        }
    }

    /// The file's points, in place, in the model: turned and scaled.
    pub fn place_points(&self, points: &mut [Point3]) {
        for p in points {
            p.coords = self.up.unapply(p.coords) * self.factor;
        }
    }

    /// A direction of the file (a normal) in the model: turned only.
    pub fn direction(&self, v: Vector3) -> Vector3 {
        self.up.unapply(v)
    }
}
