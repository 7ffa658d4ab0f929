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
use std::path::{Path, PathBuf};

use embedding::{Point3, Vector3, bounding_box};
use mesh::HalfEdgeMesh;

pub mod glb;
pub mod obj;
pub mod off;
pub mod ply;
pub mod stl;

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

/// Where in a file something was found.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Location {
    Unknown,
    /// A line of a text file, from 1.
    Line(usize),
    /// A line and column (glTF's JSON).
    LineColumn(usize, usize),
    /// A byte offset into a binary file.
    Byte(usize),
    /// A glTF mesh's primitive.
    Primitive {
        mesh: usize,
        primitive: usize,
    },
}

impl fmt::Display for Location {
    /// " (line 12)", " (byte 84)", …; nothing when unknown.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Location::Unknown => Ok(()),
            Location::Line(l) => write!(f, " (line {l})"),
            Location::LineColumn(l, c) => write!(f, " (line {l}, column {c})"),
            Location::Byte(b) => write!(f, " (byte {b})"),
            Location::Primitive { mesh, primitive } => {
                write!(f, " (mesh {mesh}, primitive {primitive})")
            }
        }
    }
}

/// A position as messages show it: each coordinate as the f32 a file most likely stored, when it is
/// one, so the digits are the file's.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Place(pub Point3);

impl fmt::Display for Place {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let c = |x: f64| {
            let single = x as f32;
            if f64::from(single) == x {
                format!("{single}")
            } else {
                format!("{x}")
            }
        };
        write!(f, "({}, {}, {})", c(self.0.x), c(self.0.y), c(self.0.z))
    }
}

/// Component sizes as messages list them: the first few, largest first.
fn list_sizes(sizes: &[usize]) -> String {
    let shown: Vec<String> = sizes.iter().take(6).map(|s| s.to_string()).collect();
    let more = if sizes.len() > 6 { ", …" } else { "" };
    match shown.len() {
        0 | 1 => format!("{}{more}", shown.join("")),
        n if more.is_empty() => format!("{} and {}", shown[..n - 1].join(", "), shown[n - 1]),
        _ => format!("{}{more}", shown.join(", ")),
    }
}

/// Holes after the first that a "not closed" message names.
const MORE_HOLES_NAMED: usize = 3;

/// "; the others run through vertex 7 at (…) (4 edges), vertex 9 at (…) (3 edges) and 2 more":
/// the holes after the first, or nothing when there is one.
fn list_holes(others: &[(u32, Place, usize)], loops: usize) -> String {
    if others.is_empty() {
        return String::new();
    }
    let mut named: Vec<String> = others
        .iter()
        .map(|(v, p, n)| format!("vertex {v} at {p} ({})", plural(*n, "edge", "edges")))
        .collect();
    let rest = loops.saturating_sub(1 + others.len());
    if rest > 0 {
        named.push(format!("{rest} more"));
    }
    let list = match named.split_last() {
        Some((last, init)) if !init.is_empty() => format!("{} and {last}", init.join(", ")),
        _ => named.join(""),
    };
    let verb = if loops == 2 {
        "the other runs"
    } else {
        "the others run"
    };
    format!("; {verb} through {list}")
}

fn plural(n: usize, one: &str, many: &str) -> String {
    format!("{n} {}", if n == 1 { one } else { many })
}

/// Why a mesh could not be read, or is not one ntori can fit.
#[derive(Debug, thiserror::Error)]
pub enum ImportError {
    // ----- the file
    #[error("cannot read {}: no such file", .path.display())]
    Missing { path: PathBuf },
    #[error("cannot read {}: {source}", .path.display())]
    Unreadable {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("cannot read {}: it is a {kind}, not a regular file", .path.display())]
    NotRegular { path: PathBuf, kind: &'static str },
    #[error("cannot read {}: it has {size} bytes, and a mesh file may have at most {max}", .path.display())]
    TooLargeFile { path: PathBuf, size: u64, max: u64 },
    #[error(
        "cannot read {}: unknown mesh format {}; ntori reads {}",
        .path.display(),
        if .extension.is_empty() { "(no extension)".to_owned() } else { format!("`.{}`", .extension) },
        MeshFormat::EXTENSIONS
    )]
    UnknownFormat { path: PathBuf, extension: String },
    /// Anything below, found in this file ([`read_mesh`] names the file once).
    #[error("cannot read {}: {error}", .path.display())]
    InFile {
        path: PathBuf,
        error: Box<ImportError>,
    },

    // ----- reading
    #[error("not a valid {format} file{at}: {message}")]
    Parse {
        format: MeshFormat,
        at: Location,
        message: String,
    },
    #[error("{format}: {what} is not supported{at}")]
    Unsupported {
        format: MeshFormat,
        at: Location,
        what: String,
    },
    #[error("face {face}{at} refers to vertex {index}, but there are only {vertex_count} vertices")]
    IndexOutOfRange {
        face: usize,
        at: Location,
        /// As the file writes it (OBJ: from 1, or negative).
        index: i64,
        vertex_count: usize,
    },
    #[error("vertex {vertex}{at} has a coordinate that is not a finite number: {x}, {y}, {z}")]
    NonFinite {
        vertex: usize,
        at: Location,
        x: f64,
        y: f64,
        z: f64,
    },
    #[error(
        "the file is empty{}",
        if *.bytes == 0 { " (0 bytes)".to_owned() } else { format!(": its {} bytes are all white space", .bytes) }
    )]
    Blank { bytes: usize },
    #[error("the {format} file holds no {what}")]
    Empty {
        format: MeshFormat,
        what: &'static str,
    },
    #[error("the mesh has more than {max} triangles{at}, the most ntori reads")]
    TooManyTriangles { at: Location, max: usize },

    // ----- validation
    #[error("the mesh has no triangles")]
    NoTriangles,
    #[error("the mesh's connectivity: {0}")]
    Connectivity(#[from] mesh::MeshError),
    #[error(
        "the mesh has {} separate components (of {} triangles); pass --largest to fit the largest",
        .sizes.len(), list_sizes(.sizes)
    )]
    Components {
        /// Triangles per component, largest first.
        sizes: Vec<usize>,
    },
    #[error(
        "{} (zero area or a repeated vertex){}; the first is triangle {triangle}, vertices {} at {}, {} at {}, {} at {}",
        if .count == .total && *.total == 1 {
            "the mesh's one triangle is degenerate".to_owned()
        } else if .count == .total {
            format!("all {} triangles of the mesh are degenerate", .count)
        } else {
            format!("the mesh has {}", plural(*.count, "degenerate triangle", "degenerate triangles"))
        },
        if .count == .total { ", so it has no surface to fit" } else { "" },
        .vertices[0], .positions[0], .vertices[1], .positions[1], .vertices[2], .positions[2]
    )]
    Degenerate {
        count: usize,
        /// Triangles checked (those of the kept component).
        total: usize,
        triangle: usize,
        vertices: [u32; 3],
        positions: [Place; 3],
    },
    #[error(
        "the mesh has {} (more than two faces on one edge); the first joins vertex {} at {} and vertex {} at {} and has {faces} faces",
        plural(*.count, "non-manifold edge", "non-manifold edges"),
        .vertices[0], .positions[0], .vertices[1], .positions[1]
    )]
    NonManifoldEdges {
        count: usize,
        vertices: [u32; 2],
        positions: [Place; 2],
        faces: usize,
    },
    #[error(
        "the mesh has {} (its faces meet there but do not form one fan, like two cones touching at their tips); the first is vertex {vertex} at {position}",
        plural(*.count, "non-manifold vertex", "non-manifold vertices")
    )]
    NonManifoldVertices {
        count: usize,
        vertex: u32,
        position: Place,
    },
    #[error(
        "the mesh is not closed: it has {}; the first runs through vertex {vertex} at {position} and has {} edges{}",
        plural(*.loops, "hole (boundary loop)", "holes (boundary loops)"), .length,
        list_holes(.others, *.loops)
    )]
    NotClosed {
        loops: usize,
        vertex: u32,
        position: Place,
        length: usize,
        /// The next few loops (up to `MORE_HOLES_NAMED`): a vertex of each, its position, its
        /// edges.
        others: Vec<(u32, Place, usize)>,
    },
    #[error(
        "the mesh is not orientable (like a Möbius strip or a Klein bottle): its faces cannot agree on a side at the edge from vertex {} at {} to vertex {} at {}",
        .vertices[0], .positions[0], .vertices[1], .positions[1]
    )]
    NonOrientable {
        vertices: [u32; 2],
        positions: [Place; 2],
    },
    #[error("the mesh has genus {genus}; ntori fits genus 0 to {}", MAX_GENUS)]
    Genus { genus: u64 },
}

impl ImportError {
    /// The error itself, without the file it was found in.
    pub fn inner(&self) -> &ImportError {
        match self {
            ImportError::InFile { error, .. } => error.inner(),
            e => e,
        }
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
    let meta = std::fs::metadata(path).map_err(|source| match source.kind() {
        std::io::ErrorKind::NotFound => ImportError::Missing {
            path: path.to_owned(),
        },
        _ => ImportError::Unreadable {
            path: path.to_owned(),
            source,
        },
    })?;
    if !meta.is_file() {
        return Err(ImportError::NotRegular {
            path: path.to_owned(),
            kind: crate::io::atomic::kind_of(&meta.file_type()),
        });
    }
    if meta.len() > MAX_MESH_BYTES {
        return Err(ImportError::TooLargeFile {
            path: path.to_owned(),
            size: meta.len(),
            max: MAX_MESH_BYTES,
        });
    }
    Ok(meta)
}

fn read_file(path: &Path, meta: &std::fs::Metadata) -> Result<Vec<u8>, ImportError> {
    use std::io::Read;
    let unreadable = |source| ImportError::Unreadable {
        path: path.to_owned(),
        source,
    };
    let file = std::fs::File::open(path).map_err(unreadable)?;
    let mut bytes = Vec::with_capacity(meta.len() as usize);
    // A file that grew since: read one byte past the limit to know.
    file.take(MAX_MESH_BYTES + 1)
        .read_to_end(&mut bytes)
        .map_err(unreadable)?;
    if bytes.len() as u64 > MAX_MESH_BYTES {
        return Err(ImportError::TooLargeFile {
            path: path.to_owned(),
            size: bytes.len() as u64,
            max: MAX_MESH_BYTES,
        });
    }
    Ok(bytes)
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
    let merged = mesh.positions.len() - positions.len();
    mesh.positions = positions;
    mesh.merged_vertices += merged;
    merged
}

/// Cuts a polygon (vertex indices into `positions`, all in range) into triangles with the same
/// winding: a fan when it is convex, else ear clipping in its best-fit plane (Newell's normal),
/// so non-convex polygons come out right; polygons of more than [`MAX_EAR_CLIPPED_SIDES`] sides,
/// and those with no plane (all corners on a line), are fanned.
pub fn triangulate(positions: &[Point3], polygon: &[u32]) -> Vec<[u32; 3]> {
    let mut out = Vec::with_capacity(polygon.len().saturating_sub(2));
    triangulate_into(positions, polygon, &mut out);
    out
}

fn triangulate_into(positions: &[Point3], poly: &[u32], out: &mut Vec<[u32; 3]>) {
    let n = poly.len();
    if n < 3 {
        return;
    }
    let fan = |out: &mut Vec<[u32; 3]>| {
        for k in 1..n - 1 {
            out.push([poly[0], poly[k], poly[k + 1]]);
        }
    };
    if n == 3 || n > MAX_EAR_CLIPPED_SIDES {
        return fan(out);
    }
    let p = |k: usize| positions[poly[k] as usize];
    // Newell's normal and a basis of the plane.
    let mut normal = Vector3::zeros();
    for k in 0..n {
        let (a, b) = (p(k), p((k + 1) % n));
        normal.x += (a.y - b.y) * (a.z + b.z);
        normal.y += (a.z - b.z) * (a.x + b.x);
        normal.z += (a.x - b.x) * (a.y + b.y);
    }
    let Some(normal) = normal.try_normalize(0.0) else {
        return fan(out);
    };
    let helper = if normal.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let u = normal.cross(&helper).normalize();
    let v = normal.cross(&u);
    let flat: Vec<[f64; 2]> = (0..n)
        .map(|k| {
            let d = p(k) - p(0);
            [d.dot(&u), d.dot(&v)]
        })
        .collect();
    // Counter-clockwise in (u, v) seen along the normal.
    let cross = |a: [f64; 2], b: [f64; 2], c: [f64; 2]| {
        (b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0])
    };
    let convex = (0..n).all(|k| cross(flat[k], flat[(k + 1) % n], flat[(k + 2) % n]) >= 0.0);
    if convex {
        return fan(out);
    }
    // Corners within this of an ear's sides count as on them (so an ear never takes a corner lying
    // on its third side, which would leave a zero-area triangle behind).
    let size = flat
        .iter()
        .fold(0.0f64, |m, q| m.max(q[0].abs()).max(q[1].abs()));
    let eps = 1e-10 * size * size;
    let mut left: Vec<usize> = (0..n).collect();
    while left.len() > 3 {
        let m = left.len();
        let is_ear = |i: usize| {
            let (a, b, c) = (left[(i + m - 1) % m], left[i], left[(i + 1) % m]);
            if cross(flat[a], flat[b], flat[c]) <= eps {
                return false;
            }
            left.iter().all(|&q| {
                q == a
                    || q == b
                    || q == c
                    || !(cross(flat[a], flat[b], flat[q]) >= -eps
                        && cross(flat[b], flat[c], flat[q]) >= -eps
                        && cross(flat[c], flat[a], flat[q]) >= -eps)
            })
        };
        // No ear (a self-intersecting polygon): cut the most convex corner anyway.
        let i = (0..m).find(|&i| is_ear(i)).unwrap_or_else(|| {
            (0..m)
                .max_by(|&i, &j| {
                    let turn = |i: usize| {
                        cross(
                            flat[left[(i + m - 1) % m]],
                            flat[left[i]],
                            flat[left[(i + 1) % m]],
                        )
                    };
                    turn(i).total_cmp(&turn(j))
                })
                .unwrap_or(0)
        });
        let (a, b, c) = (left[(i + m - 1) % m], left[i], left[(i + 1) % m]);
        out.push([poly[a], poly[b], poly[c]]);
        left.remove(i);
    }
    out.push([poly[left[0]], poly[left[1]], poly[left[2]]]);
}

/// Checks an imported mesh for what a fit needs (see the module's documentation for the order of
/// the checks) and returns it oriented outward with every vertex used. With `keep_largest`, a mesh
/// of several components keeps its largest (by triangles; the first of equals) instead of failing.
pub fn validate(mesh: ImportedMesh, keep_largest: bool) -> Result<ValidMesh, ImportError> {
    let ImportedMesh {
        positions,
        triangles,
        ..
    } = mesh;
    let n = positions.len();
    let place = |v: u32| Place(positions[v as usize]);
    if let Some((f, t)) = triangles
        .iter()
        .enumerate()
        .find(|(_, t)| t.iter().any(|&v| v as usize >= n))
    {
        let bad = t.iter().find(|&&v| v as usize >= n).copied().unwrap_or(0);
        return Err(ImportError::IndexOutOfRange {
            face: f,
            at: Location::Unknown,
            index: i64::from(bad),
            vertex_count: n,
        });
    }
    if triangles.is_empty() {
        return Err(ImportError::NoTriangles);
    }
    // Components, by shared vertices.
    let (component, count) = mesh::validate::face_components(n, triangles.iter().map(|t| &t[..]));
    let mut sizes = vec![0usize; count];
    for &c in &component {
        sizes[c as usize] += 1;
    }
    let (mut kept, mut dropped_components, mut dropped_triangles) = (triangles, 0, 0);
    // Each kept triangle's index in the input, for messages.
    let mut original: Vec<usize> = (0..kept.len()).collect();
    if count > 1 {
        if !keep_largest {
            let mut sorted = sizes.clone();
            sorted.sort_unstable_by(|a, b| b.cmp(a));
            return Err(ImportError::Components { sizes: sorted });
        }
        let largest = (0..count)
            .max_by_key(|&c| (sizes[c], std::cmp::Reverse(c)))
            .unwrap_or(0) as u32;
        let keep: Vec<bool> = component.iter().map(|&c| c == largest).collect();
        original.retain(|&f| keep[f]);
        let mut k = 0;
        kept.retain(|_| {
            k += 1;
            keep[k - 1]
        });
        dropped_components = count - 1;
        dropped_triangles = keep.len() - kept.len();
    }
    // Degenerate triangles, relative to the kept part's size.
    let used: Vec<Point3> = kept
        .iter()
        .flatten()
        .map(|&v| positions[v as usize])
        .collect();
    let (lo, hi) = bounding_box(&used);
    let diagonal2 = (hi - lo).norm_squared();
    let degenerate = |t: &[u32; 3]| {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        t[0] == t[1]
            || t[1] == t[2]
            || t[0] == t[2]
            || (b - a).cross(&(c - a)).norm() <= DEGENERATE_AREA * diagonal2
    };
    let bad: Vec<usize> = (0..kept.len()).filter(|&i| degenerate(&kept[i])).collect();
    if let Some(&first) = bad.first() {
        let t = kept[first];
        return Err(ImportError::Degenerate {
            count: bad.len(),
            total: kept.len(),
            triangle: original[first],
            vertices: t,
            positions: t.map(place),
        });
    }
    // Compact: only used vertices, in their original order.
    let mut new_index = vec![u32::MAX; n];
    for t in &kept {
        for &v in t {
            new_index[v as usize] = 0;
        }
    }
    let mut old_index = Vec::new();
    for (v, slot) in new_index.iter_mut().enumerate() {
        if *slot == 0 {
            *slot = old_index.len() as u32;
            old_index.push(v as u32);
        }
    }
    let removed_vertices = n - old_index.len();
    let mut tris: Vec<[u32; 3]> = kept
        .iter()
        .map(|t| t.map(|v| new_index[v as usize]))
        .collect();
    let compact: Vec<Point3> = old_index.iter().map(|&v| positions[v as usize]).collect();
    let old = |v: u32| old_index[v as usize];
    let he = HalfEdgeMesh::from_polygons(compact.len(), tris.iter().map(|t| &t[..]))?;
    let edges = mesh::validate::nonmanifold_edges(&he);
    if let Some(&(a, b, faces)) = edges.first() {
        let (a, b) = (old(a), old(b));
        return Err(ImportError::NonManifoldEdges {
            count: edges.len(),
            vertices: [a, b],
            positions: [place(a), place(b)],
            faces,
        });
    }
    let vertices = mesh::validate::nonmanifold_vertices(&he);
    if let Some(&v) = vertices.first() {
        let v = old(v);
        return Err(ImportError::NonManifoldVertices {
            count: vertices.len(),
            vertex: v,
            position: place(v),
        });
    }
    let loops = mesh::validate::boundary_loops(&he);
    if let Some(first) = loops.first() {
        let v = old(first.first().copied().unwrap_or(0));
        return Err(ImportError::NotClosed {
            loops: loops.len(),
            vertex: v,
            position: place(v),
            length: first.len(),
            others: loops[1..]
                .iter()
                .take(MORE_HOLES_NAMED)
                .map(|l| {
                    let v = old(l.first().copied().unwrap_or(0));
                    (v, place(v), l.len())
                })
                .collect(),
        });
    }
    let flips = mesh::validate::orient(&he).map_err(|(a, b)| {
        let (a, b) = (old(a), old(b));
        ImportError::NonOrientable {
            vertices: [a, b],
            positions: [place(a), place(b)],
        }
    })?;
    // Flip the minority, so a mesh mostly right keeps its own orientation before the volume test.
    let majority_flipped = flips.iter().filter(|&&f| f).count() * 2 > flips.len();
    let mut reoriented = 0;
    for (t, &f) in tris.iter_mut().zip(&flips) {
        if f != majority_flipped {
            t.swap(1, 2);
            reoriented += 1;
        }
    }
    // χ = V − E + F on a closed triangle mesh: E = 3F/2.
    let chi = compact.len() as i64 - (3 * tris.len() / 2) as i64 + tris.len() as i64;
    let genus = (2 - chi).max(0) as u64 / 2;
    if genus > u64::from(MAX_GENUS) {
        return Err(ImportError::Genus { genus });
    }
    let volume: f64 = tris
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|v| compact[v as usize].coords);
            a.dot(&b.cross(&c))
        })
        .sum();
    let flipped = volume < 0.0;
    if flipped {
        for t in &mut tris {
            t.swap(1, 2);
        }
    }
    Ok(ValidMesh {
        positions: compact,
        triangles: tris,
        genus: genus as u32,
        dropped_components,
        dropped_triangles,
        removed_vertices,
        reoriented_triangles: reoriented,
        flipped,
    })
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
