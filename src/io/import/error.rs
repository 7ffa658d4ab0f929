//! What can be wrong with a mesh file or a mesh, said once, with where: the line or byte offset,
//! and vertices by index and position.

use std::fmt;
use std::path::PathBuf;

use embedding::Point3;

use super::{MAX_GENUS, MeshFormat};

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
pub(super) const MORE_HOLES_NAMED: usize = 3;

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
    /// Anything below, found in this file ([`super::read_mesh`] names the file once).
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

    // ----- the fit's size
    #[error("it has {triangles} triangles, and the fit takes at most {max} (decimate it first)")]
    TooLargeToFit { triangles: usize, max: usize },

    // ----- subdivision cages (`ntori fit --cage`)
    #[error(
        "a cage is refined as its faces are given, so they must agree in orientation, and {triangles} of its triangles (its faces cut) turn the other way"
    )]
    CageOrientation { triangles: usize },
    #[error(
        "refining the cage {level} times would make {triangles} triangles; the fit takes at most {max}, and 1 to {} levels (--cage-level)",
        super::cage::MAX_CAGE_LEVEL
    )]
    CageTooFine {
        level: u32,
        triangles: usize,
        max: usize,
    },
    #[error("the subdivision cage cannot be refined: {0}")]
    Subdivision(anchors::Error),

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
