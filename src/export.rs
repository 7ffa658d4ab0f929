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
//! Every file is written atomically ([`crate::files`]): whole, or not at all.

use std::io::Write;
use std::path::{Path, PathBuf};

use charts::{Atlas, Tessellation};
use embedding::{EmbeddingError, Layout, Model, Point3, Stencil};

use crate::files::{FileError, write_atomically_with};

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
    pub positions: Vec<[f64; 3]>,
    /// Analytic unit normals, outward.
    pub normals: Vec<[f64; 3]>,
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

/// Tessellates the model's surface at t_e, t_r and evaluates it (see the module documentation).
pub fn surface_mesh(model: &Model, te: u32, tr: u32) -> Result<SurfaceMesh, ExportError> {
    check_resolution(model.genus, te, tr)?;
    let atlas = Atlas::new(model.genus).map_err(EmbeddingError::from)?;
    let layout = Layout::new(&atlas, model.settings)?;
    model.validate(&layout)?;
    let control = model.points();
    // The control net's size: derivatives in chart units are of its order. A net of one point has
    // no surface at all.
    let (lo, hi) = control.iter().fold(
        (
            Point3::repeat(f64::INFINITY),
            Point3::repeat(f64::NEG_INFINITY),
        ),
        |(lo, hi), p| (lo.inf(p), hi.sup(p)),
    );
    let size = (hi - lo).norm();
    if size.is_nan() || size <= 1e-12 * hi.abs().max().max(lo.abs().max()) {
        return Err(ExportError::Degenerate {
            count: Tessellation::expected_vertices(model.genus, te, tr) as usize,
            x: lo.x,
            y: lo.y,
            z: lo.z,
        });
    }
    let t = atlas.tessellate(te, tr).map_err(EmbeddingError::from)?;
    let (positions, mut normals) = evaluate(&layout, &control, &t.vertices, 1e-9 * size);
    let mut triangles = t.triangles;

    let bad: Vec<usize> = (0..normals.len())
        .filter(|&i| !normals[i].iter().all(|x| x.is_finite()))
        .collect();
    if !bad.is_empty() {
        // S_u × S_v vanishes there (an edit pinched the surface): fall back to the mesh's normal.
        let mut sums = vec![[0.0; 3]; positions.len()];
        for t in &triangles {
            let n = face_normal(&positions, t);
            for &v in t {
                sums[v as usize] = add(sums[v as usize], n);
            }
        }
        let mut still = bad.iter().filter_map(|&i| {
            let n = normalize(sums[i]);
            if n.iter().all(|x| x.is_finite()) {
                normals[i] = n;
                None
            } else {
                Some(i)
            }
        });
        if let Some(first) = still.next() {
            let [x, y, z] = positions[first];
            return Err(ExportError::Degenerate {
                count: 1 + still.count(),
                x,
                y,
                z,
            });
        }
    }

    if signed_volume(&positions, &triangles) < 0.0 {
        for t in &mut triangles {
            t.swap(1, 2);
        }
        for n in &mut normals {
            *n = n.map(|x| -x);
        }
    }

    Ok(SurfaceMesh {
        genus: model.genus,
        te,
        tr,
        positions,
        normals,
        uvs: t
            .vertices
            .iter()
            .map(|p| [p.coords.re + 0.5, p.coords.im + 0.5])
            .collect(),
        charts: t.vertices.iter().map(|p| p.chart.0).collect(),
        triangles,
    })
}

/// Positions and unit normals at `points`, in chunks (a stencil for 10⁷ points would not fit in
/// memory) spread over the available cores. Where |S_u × S_v| ≤ `tiny`², the normal is NaN.
fn evaluate(
    layout: &Layout,
    control: &[Point3],
    points: &[charts::ChartPoint],
    tiny: f64,
) -> (Vec<[f64; 3]>, Vec<[f64; 3]>) {
    const CHUNK: usize = 8192;
    let mut positions = vec![[0.0; 3]; points.len()];
    let mut normals = vec![[0.0; 3]; points.len()];
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get().min(16));
    let per_thread = points.len().div_ceil(threads).max(1);
    std::thread::scope(|scope| {
        for ((pts, pos), nor) in points
            .chunks(per_thread)
            .zip(positions.chunks_mut(per_thread))
            .zip(normals.chunks_mut(per_thread))
        {
            scope.spawn(move || {
                let mut p = vec![Point3::zeros(); CHUNK];
                let mut du = vec![Point3::zeros(); CHUNK];
                let mut dv = vec![Point3::zeros(); CHUNK];
                for ((pts, pos), nor) in pts
                    .chunks(CHUNK)
                    .zip(pos.chunks_mut(CHUNK))
                    .zip(nor.chunks_mut(CHUNK))
                {
                    let stencil = Stencil::build(layout, pts);
                    let k = pts.len();
                    stencil.positions(control, &mut p[..k]);
                    stencil.derivatives(control, &mut du[..k], &mut dv[..k]);
                    for (o, v) in pos.iter_mut().zip(&p[..k]) {
                        *o = [v.x, v.y, v.z];
                    }
                    for (o, (a, b)) in nor.iter_mut().zip(du[..k].iter().zip(&dv[..k])) {
                        let n = a.cross(b);
                        let length = n.norm();
                        *o = if length > tiny * tiny {
                            [n.x / length, n.y / length, n.z / length]
                        } else {
                            [f64::NAN; 3]
                        };
                    }
                }
            });
        }
    });
    (positions, normals)
}

fn sub(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn add(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn normalize(a: [f64; 3]) -> [f64; 3] {
    let l = dot(a, a).sqrt();
    a.map(|x| x / l)
}

/// Twice the area times the unit normal of a triangle, from its winding.
fn face_normal(positions: &[[f64; 3]], t: &[u32; 3]) -> [f64; 3] {
    let [a, b, c] = t.map(|i| positions[i as usize]);
    cross(sub(b, a), sub(c, a))
}

/// Σ a·(b × c) / 6 over the triangles, about the centroid (so far-off models keep their digits).
pub fn signed_volume(positions: &[[f64; 3]], triangles: &[[u32; 3]]) -> f64 {
    let n = positions.len().max(1) as f64;
    let centre = positions
        .iter()
        .fold([0.0; 3], |s, p| add(s, *p))
        .map(|x| x / n);
    triangles
        .iter()
        .map(|t| {
            let [a, b, c] = t.map(|i| sub(positions[i as usize], centre));
            dot(a, cross(b, c))
        })
        .sum::<f64>()
        / 6.0
}

impl SurfaceMesh {
    /// A one-line description for file headers.
    fn describe(&self) -> String {
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
        self.positions[i].map(|x| x as f32)
    }
    fn normal_f32(&self, i: usize) -> [f32; 3] {
        self.normals[i].map(|x| x as f32)
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
                    .fold([0.0; 3], |s, &v| add(s, self.normals[v as usize]));
                dot(n, m) < 0.0
            })
            .count()
    }

    /// The unit normal of triangle `t` from its winding (outward), for STL.
    pub fn face_normal(&self, t: usize) -> [f64; 3] {
        let n = normalize(face_normal(&self.positions, &self.triangles[t]));
        if n.iter().all(|x| x.is_finite()) {
            n
        } else {
            // A sliver with no area: the corners' analytic normals say which way is out.
            normalize(
                self.triangles[t]
                    .iter()
                    .fold([0.0; 3], |s, &v| add(s, self.normals[v as usize])),
            )
        }
    }
}

/// Writes `mesh` to `path` atomically in `format` (`encoding` matters for PLY and STL only).
pub fn write(
    mesh: &SurfaceMesh,
    path: &Path,
    format: Format,
    encoding: Encoding,
) -> Result<(), ExportError> {
    if format == Format::Glb {
        glb_size(mesh)?;
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

/// Wavefront OBJ: `v`, `vt`, `vn` per vertex (same index), faces `f a/a/a b/b/b c/c/c`. OBJ has no
/// per-vertex attribute that could carry the chart id.
pub fn write_obj(mesh: &SurfaceMesh, out: &mut dyn Write) -> std::io::Result<()> {
    writeln!(out, "# {}", mesh.describe())?;
    writeln!(
        out,
        "# vt: the vertex's home chart coordinates + 0.5; vn: the analytic unit normal, outward"
    )?;
    writeln!(out, "o ntori_genus_{}", mesh.genus)?;
    for i in 0..mesh.positions.len() {
        let [x, y, z] = mesh.position_f32(i);
        writeln!(out, "v {x} {y} {z}")?;
    }
    for uv in &mesh.uvs {
        let [u, v] = uv.map(|x| x as f32);
        writeln!(out, "vt {u} {v}")?;
    }
    for i in 0..mesh.normals.len() {
        let [x, y, z] = mesh.normal_f32(i);
        writeln!(out, "vn {x} {y} {z}")?;
    }
    for t in &mesh.triangles {
        let [a, b, c] = t.map(|i| i + 1);
        writeln!(out, "f {a}/{a}/{a} {b}/{b}/{b} {c}/{c}/{c}")?;
    }
    Ok(())
}

/// Object File Format: positions and triangles.
pub fn write_off(mesh: &SurfaceMesh, out: &mut dyn Write) -> std::io::Result<()> {
    writeln!(out, "OFF")?;
    writeln!(out, "# {}", mesh.describe())?;
    writeln!(out, "{} {} 0", mesh.positions.len(), mesh.triangles.len())?;
    for i in 0..mesh.positions.len() {
        let [x, y, z] = mesh.position_f32(i);
        writeln!(out, "{x} {y} {z}")?;
    }
    for [a, b, c] in &mesh.triangles {
        writeln!(out, "3 {a} {b} {c}")?;
    }
    Ok(())
}

/// STL: one facet per triangle with its (outward) face normal; no shared vertices, no attributes.
pub fn write_stl(
    mesh: &SurfaceMesh,
    encoding: Encoding,
    out: &mut dyn Write,
) -> std::io::Result<()> {
    match encoding {
        Encoding::Ascii => {
            writeln!(out, "solid ntori")?;
            for (k, t) in mesh.triangles.iter().enumerate() {
                let [nx, ny, nz] = mesh.face_normal(k).map(|x| x as f32);
                writeln!(out, "  facet normal {nx:e} {ny:e} {nz:e}")?;
                writeln!(out, "    outer loop")?;
                for &v in t {
                    let [x, y, z] = mesh.position_f32(v as usize);
                    writeln!(out, "      vertex {x:e} {y:e} {z:e}")?;
                }
                writeln!(out, "    endloop")?;
                writeln!(out, "  endfacet")?;
            }
            writeln!(out, "endsolid ntori")
        }
        Encoding::Binary => {
            // An 80-byte header that must not begin with "solid" (readers would take it for text).
            let mut header = [b' '; 80];
            let text = mesh.describe();
            let n = text.len().min(80);
            header[..n].copy_from_slice(&text.as_bytes()[..n]);
            out.write_all(&header)?;
            out.write_all(&(mesh.triangles.len() as u32).to_le_bytes())?;
            let mut record = [0u8; 50];
            for (k, t) in mesh.triangles.iter().enumerate() {
                let normal = mesh.face_normal(k).map(|x| x as f32);
                let corners = t.map(|v| mesh.position_f32(v as usize));
                let values = std::iter::once(normal).chain(corners).flatten();
                for (slot, x) in record.chunks_exact_mut(4).zip(values) {
                    slot.copy_from_slice(&x.to_le_bytes());
                }
                // Bytes 48..50: the attribute byte count, zero.
                out.write_all(&record)?;
            }
            Ok(())
        }
    }
}

mod ply {
    //! PLY records for ply-rs-bw's writer (its element type is a trait, so no hash maps).
    use ply_rs_bw::ply::PropertyAccess;

    #[derive(Clone, Copy, Debug, Default)]
    pub struct Vertex {
        pub position: [f32; 3],
        pub normal: [f32; 3],
        pub uv: [f32; 2],
        pub chart: u32,
    }

    impl PropertyAccess for Vertex {
        fn new() -> Self {
            Vertex::default()
        }
        fn get_float(&self, name: &str) -> Option<f32> {
            Some(match name {
                "x" => self.position[0],
                "y" => self.position[1],
                "z" => self.position[2],
                "nx" => self.normal[0],
                "ny" => self.normal[1],
                "nz" => self.normal[2],
                "u" => self.uv[0],
                "v" => self.uv[1],
                _ => return None,
            })
        }
        fn get_uint(&self, name: &str) -> Option<u32> {
            (name == "chart").then_some(self.chart)
        }
    }

    #[derive(Clone, Copy, Debug, Default)]
    pub struct Face(pub [i32; 3]);

    impl PropertyAccess for Face {
        fn new() -> Self {
            Face::default()
        }
        fn get_list_int(&self, name: &str) -> Option<&[i32]> {
            (name == "vertex_indices").then_some(&self.0[..])
        }
    }
}

/// Stanford PLY, binary little endian or ASCII: vertex `x y z nx ny nz u v` (float) and `chart`
/// (uint); face `vertex_indices` (list uchar int).
pub fn write_ply(
    mesh: &SurfaceMesh,
    encoding: Encoding,
    out: &mut dyn Write,
) -> std::io::Result<()> {
    use ply_rs_bw::ply::{
        Addable, ElementDef, Encoding as PlyEncoding, Header, PropertyDef, PropertyType, ScalarType,
    };
    use ply_rs_bw::writer::Writer;

    let mut header = Header::new();
    header.encoding = match encoding {
        Encoding::Ascii => PlyEncoding::Ascii,
        Encoding::Binary => PlyEncoding::BinaryLittleEndian,
    };
    header.comments.push(mesh.describe());
    header
        .comments
        .push("u v: the vertex's home chart coordinates + 0.5; chart: its home chart".into());
    header
        .comments
        .push("nx ny nz: the analytic unit normal, outward".into());
    let mut vertex = ElementDef::new("vertex".into());
    vertex.count = mesh.positions.len();
    for name in ["x", "y", "z", "nx", "ny", "nz", "u", "v"] {
        vertex.properties.add(PropertyDef::new(
            name.into(),
            PropertyType::Scalar(ScalarType::Float),
        ));
    }
    vertex.properties.add(PropertyDef::new(
        "chart".into(),
        PropertyType::Scalar(ScalarType::UInt),
    ));
    let mut face = ElementDef::new("face".into());
    face.count = mesh.triangles.len();
    face.properties.add(PropertyDef::new(
        "vertex_indices".into(),
        PropertyType::List(ScalarType::UChar, ScalarType::Int),
    ));
    header.elements.add(vertex.clone());
    header.elements.add(face.clone());

    let mut out = out;
    let vertices: Vec<ply::Vertex> = (0..mesh.positions.len())
        .map(|i| ply::Vertex {
            position: mesh.position_f32(i),
            normal: mesh.normal_f32(i),
            uv: mesh.uvs[i].map(|x| x as f32),
            chart: mesh.charts[i],
        })
        .collect();
    let vertex_writer = Writer::<ply::Vertex>::new();
    vertex_writer.write_header(&mut out, &header)?;
    vertex_writer.write_payload_of_element(&mut out, &vertices, &vertex, &header)?;
    drop(vertices);
    let faces: Vec<ply::Face> = mesh
        .triangles
        .iter()
        .map(|t| ply::Face(t.map(|i| i as i32)))
        .collect();
    Writer::<ply::Face>::new().write_payload_of_element(&mut out, &faces, &face, &header)?;
    Ok(())
}

/// The GLB BIN chunk's length: positions, normals (12 bytes a vertex each), texture coordinates
/// (8), charts (a u16 in a 4-byte stride) and indices (12 a triangle); all multiples of 4.
fn glb_bin_length(mesh: &SurfaceMesh) -> u64 {
    let v = mesh.positions.len() as u64;
    let f = mesh.triangles.len() as u64;
    36 * v + 12 * f
}

fn glb_size(mesh: &SurfaceMesh) -> Result<u64, ExportError> {
    let bin = glb_bin_length(mesh);
    // The JSON is a few kilobytes.
    let total = 12 + 8 + 8192 + 8 + bin;
    if total > u64::from(u32::MAX) {
        return Err(ExportError::GlbTooLarge(total));
    }
    Ok(total)
}

/// The glTF JSON document describing the BIN chunk [`write_glb`] writes.
fn gltf_document(mesh: &SurfaceMesh) -> gltf_json::Root {
    use gltf_json as json;
    use json::accessor::{ComponentType, GenericComponentType, Type};
    use json::validation::Checked::Valid;
    use json::validation::USize64;

    let v = mesh.positions.len() as u64;
    let bin = glb_bin_length(mesh);
    let mut root = json::Root {
        asset: json::Asset {
            generator: Some(format!("ntori {}", env!("CARGO_PKG_VERSION"))),
            extras: json::extras::RawValue::from_string(
                serde_json::json!({
                    "ntori": {
                        "genus": mesh.genus,
                        "te": mesh.te,
                        "tr": mesh.tr,
                        "TEXCOORD_0": "home chart coordinates + 0.5, v flipped (glTF's convention)",
                        "_CHART": "home chart id",
                    }
                })
                .to_string(),
            )
            .ok(),
            ..Default::default()
        },
        ..Default::default()
    };
    let buffer = root.push(json::Buffer {
        byte_length: USize64(bin),
        name: None,
        uri: None,
        extensions: None,
        extras: Default::default(),
    });
    let mut offset = 0u64;
    let mut view = |root: &mut json::Root, length: u64, stride: Option<usize>, indices: bool| {
        let target = if indices {
            json::buffer::Target::ElementArrayBuffer
        } else {
            json::buffer::Target::ArrayBuffer
        };
        let index = root.push(json::buffer::View {
            buffer,
            byte_length: USize64(length),
            byte_offset: Some(USize64(offset)),
            byte_stride: stride.map(json::buffer::Stride),
            name: None,
            target: Some(Valid(target)),
            extensions: None,
            extras: Default::default(),
        });
        offset += length;
        index
    };
    let positions_view = view(&mut root, 12 * v, None, false);
    let normals_view = view(&mut root, 12 * v, None, false);
    let uvs_view = view(&mut root, 8 * v, None, false);
    let charts_view = view(&mut root, 4 * v, Some(4), false);
    let indices_view = view(&mut root, 12 * mesh.triangles.len() as u64, None, true);

    let accessor = |root: &mut json::Root,
                    view,
                    count: u64,
                    component: ComponentType,
                    type_: Type,
                    bounds: Option<([f32; 3], [f32; 3])>,
                    name: &str| {
        root.push(json::Accessor {
            buffer_view: Some(view),
            byte_offset: Some(USize64(0)),
            count: USize64(count),
            component_type: Valid(GenericComponentType(component)),
            type_: Valid(type_),
            min: bounds.map(|b| json::Value::from(b.0.to_vec())),
            max: bounds.map(|b| json::Value::from(b.1.to_vec())),
            name: Some(name.into()),
            normalized: false,
            sparse: None,
            extensions: None,
            extras: Default::default(),
        })
    };
    let mut min = [f32::INFINITY; 3];
    let mut max = [f32::NEG_INFINITY; 3];
    for i in 0..mesh.positions.len() {
        let p = mesh.position_f32(i);
        for k in 0..3 {
            min[k] = min[k].min(p[k]);
            max[k] = max[k].max(p[k]);
        }
    }
    let bounds = (!mesh.positions.is_empty()).then_some((min, max));
    let positions = accessor(
        &mut root,
        positions_view,
        v,
        ComponentType::F32,
        Type::Vec3,
        bounds,
        "positions",
    );
    let normals = accessor(
        &mut root,
        normals_view,
        v,
        ComponentType::F32,
        Type::Vec3,
        None,
        "normals",
    );
    let uvs = accessor(
        &mut root,
        uvs_view,
        v,
        ComponentType::F32,
        Type::Vec2,
        None,
        "home chart coordinates",
    );
    let charts = accessor(
        &mut root,
        charts_view,
        v,
        ComponentType::U16,
        Type::Scalar,
        None,
        "home charts",
    );
    let indices = accessor(
        &mut root,
        indices_view,
        3 * mesh.triangles.len() as u64,
        ComponentType::U32,
        Type::Scalar,
        None,
        "triangles",
    );
    let primitive = json::mesh::Primitive {
        attributes: [
            (json::mesh::Semantic::Positions, positions),
            (json::mesh::Semantic::Normals, normals),
            (json::mesh::Semantic::TexCoords(0), uvs),
            (json::mesh::Semantic::Extras("CHART".into()), charts),
        ]
        .into_iter()
        .map(|(s, a)| (Valid(s), a))
        .collect(),
        indices: Some(indices),
        material: None,
        mode: Valid(json::mesh::Mode::Triangles),
        targets: None,
        extensions: None,
        extras: Default::default(),
    };
    let name = format!("ntori genus {}", mesh.genus);
    let gltf_mesh = root.push(json::Mesh {
        name: Some(name.clone()),
        primitives: vec![primitive],
        weights: None,
        extensions: None,
        extras: Default::default(),
    });
    let node = root.push(json::Node {
        mesh: Some(gltf_mesh),
        name: Some(name),
        ..Default::default()
    });
    let scene = root.push(json::Scene {
        nodes: vec![node],
        name: None,
        extensions: None,
        extras: Default::default(),
    });
    root.scene = Some(scene);
    root
}

/// Binary glTF 2.0: one mesh, one triangle primitive with `POSITION`, `NORMAL`, `TEXCOORD_0`
/// (f32; v flipped as glTF's texture origin is the top left), `_CHART` (u16) and u32 indices.
pub fn write_glb(mesh: &SurfaceMesh, out: &mut dyn Write) -> std::io::Result<()> {
    let too_large = |_| std::io::Error::other("the mesh is too large for GLB (4 GiB)");
    let mut json = serde_json::to_vec(&gltf_document(mesh)).map_err(std::io::Error::other)?;
    while json.len() % 4 != 0 {
        json.push(b' ');
    }
    let bin = glb_bin_length(mesh);
    let total = 12 + 8 + json.len() as u64 + 8 + bin;
    let total = u32::try_from(total).map_err(too_large)?;
    let json_len = u32::try_from(json.len()).map_err(too_large)?;
    let bin_len = u32::try_from(bin).map_err(too_large)?;
    out.write_all(b"glTF")?;
    out.write_all(&2u32.to_le_bytes())?;
    out.write_all(&total.to_le_bytes())?;
    out.write_all(&json_len.to_le_bytes())?;
    out.write_all(b"JSON")?;
    out.write_all(&json)?;
    out.write_all(&bin_len.to_le_bytes())?;
    out.write_all(b"BIN\0")?;
    // Every section is a multiple of 4 bytes long, so the chunk needs no padding.
    fn floats(out: &mut dyn Write, values: impl Iterator<Item = f32>) -> std::io::Result<()> {
        for x in values {
            out.write_all(&x.to_le_bytes())?;
        }
        Ok(())
    }
    floats(
        out,
        (0..mesh.positions.len()).flat_map(|i| mesh.position_f32(i)),
    )?;
    floats(
        out,
        (0..mesh.normals.len()).flat_map(|i| mesh.normal_f32(i)),
    )?;
    floats(
        out,
        mesh.uvs
            .iter()
            .flat_map(|[u, v]| [*u as f32, (1.0 - v) as f32]),
    )?;
    for &c in &mesh.charts {
        let c = u16::try_from(c).map_err(|_| std::io::Error::other("chart id over 65535"))?;
        out.write_all(&c.to_le_bytes())?;
        out.write_all(&[0, 0])?;
    }
    for &i in mesh.triangles.iter().flatten() {
        out.write_all(&i.to_le_bytes())?;
    }
    Ok(())
}
