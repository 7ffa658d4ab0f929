//! `ntori export`: a model's surface as a triangle mesh file.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use ntori::io::export::{
    self, DEFAULT_UNITS, Encoding, ExportError, ExportOptions, Format, Meshing, Units, Up, UvLayout,
};

use embedding::remesh::QualitySettings;

use super::write_stdout;

/// Export a model's surface as a triangle (or quad) mesh: OBJ, PLY, STL, GLB, 3MF or OFF.
///
/// The surface is tessellated with the quality tessellation: well-shaped triangles sized by the
/// surface's curvature, each flat triangle within --tolerance (0.001 of the surface's diagonal
/// unless given) of the surface. --te and --tr choose the paper's t_e/t_r scheme instead (see
/// `ntori tessellate --help`; 4n·t_e² + 8n·t_e·(2t_r − 1) triangles at genus 1 ≤ n ≤ 13, regular in
/// the charts, with slivers where a chart is stretched). Every vertex is a surface point, evaluated
/// exactly: the position, the analytic unit normal (outward; triangles wind counter-clockwise seen
/// from outside), and the vertex's home chart and its coordinates there. The format comes from the
/// output's extension unless --format names it. What each format carries:
///   .obj  positions, normals, texture coordinates (text; OBJ cannot carry the chart id)
///   .ply  positions, normals, texture coordinates `s t`, the chart id as `chart`
///         (binary little endian, or text with --ascii)
///   .stl  triangles with one face normal each; no shared vertices, no texture coordinates
///         (binary, or text with --ascii)
///   .glb  binary glTF 2.0: POSITION, NORMAL, TEXCOORD_0 (f32; v flipped, as glTF's textures
///         start at the top), the chart id as the custom attribute _CHART (u8), u32 indices,
///         and a PBR material whose base colour is a checker texture drawn through TEXCOORD_0
///   .3mf  3MF, for slicers: one object of vertices and triangles, in millimetres
///   .off  positions and triangles only (text)
/// The object is named after the model file (its name without the extension): OBJ's `o`, the
/// GLB node and mesh, the 3MF object, STL's `solid` (the binary header), a PLY or OFF comment.
///
/// Size: one model unit becomes S U (--scale S, --units U), by default 1 cm, so the default
/// genus-2 model (about 6 units across) is a 6 cm object whatever the format. Formats with
/// a unit are written in it: GLB in metres (glTF's unit), 3MF in millimetres (it declares
/// them), STL in millimetres (it has no field for a unit; slicers read millimetres). OBJ, PLY
/// and OFF have no unit: their numbers are S times the model's, meaning U (a comment says so).
///
/// Up: z is the model's up (its plates lie in the xy plane). Each format gets what its readers
/// expect unless --up says otherwise: +y for GLB (glTF's specification) and OBJ (Blender and
/// most viewers), +z for PLY, STL, 3MF and OFF. +y up turns the model by −90° about x,
/// (x, y, z) → (x, z, −y): a rotation, so triangles and normals still face outward.
///
/// Texture coordinates (--uv): `chart`, the default, moves each vertex's home chart
/// coordinates into [0, 1]²; they are continuous within one chart only, so every chart covers
/// the same square and triangles whose corners have different home charts span a seam.
/// `atlas` packs each chart's region into its own tile of a grid in [0, 1]² and splits the
/// mesh along the seams (a vertex on triangles of two charts is written twice, at the same
/// position, with the chart id of its tile), so a texture can be painted and baked; for OBJ,
/// PLY and GLB, the formats with texture coordinates.
///
/// Coordinates are stored as 32-bit floats. The file is written whole or not at all, and an
/// existing file is replaced only with --force (it may be the mesh the model was fitted to).
///
/// Examples:
///   ntori export model.json -o surface.obj
///   ntori export model.json -o fine.ply --tolerance 0.0003 --ascii
///   ntori export model.json -o quads.obj --quads                 (all quads)
///   ntori export model.json -o regular.obj --te 32 --tr 32      (the t_e/t_r scheme)
///   ntori export model.json -o print.3mf --scale 2      (the default model, 120 mm across)
///   ntori export model.json -o paint.glb --uv atlas
#[derive(clap::Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct Args {
    /// The model file (as written by `ntori new`).
    #[arg(value_name = "MODEL")]
    model: PathBuf,
    /// Where to write the mesh; its extension picks the format unless --format is given.
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
    /// The file format, overriding the output's extension.
    #[arg(long, value_enum)]
    format: Option<Format>,
    /// Use the t_e/t_r tessellation with A divisions of each edge chart's square (and each
    /// arc), 1 to 512 (t_r is 16 unless --tr is given). 1 is refused at genus ≥ 1: there two
    /// different edges would join the same two vertices, which mesh readers take for a
    /// non-manifold mesh. Too coarse a tessellation folds (a warning says so).
    #[arg(long, value_name = "A", allow_negative_numbers = true,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(export::MAX_RESOLUTION)))]
    te: Option<u32>,
    /// Use the t_e/t_r tessellation with B divisions of each wheel spoke, 1 to 512 (t_e is 16
    /// unless --te is given).
    #[arg(long, value_name = "B", allow_negative_numbers = true,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(export::MAX_RESOLUTION)))]
    tr: Option<u32>,
    /// The quality tessellation's chordal tolerance: the distance between each flat triangle
    /// and the surface is at most T times the surface's diagonal (1e-5 to 0.1) [default: 0.001].
    /// On the example models of genus 0 to 10 at least 99.99% of triangles have every angle
    /// ≥ 20°, none has one of 150° or more, and neighbours bend by at most 18°; should a surface
    /// defeat it, a warning says how many triangles face away.
    #[arg(long, value_name = "T", conflicts_with_all = ["te", "tr"], allow_negative_numbers = true,
          value_parser = parse_tolerance)]
    tolerance: Option<f64>,
    /// Write quads (OBJ, PLY and OFF): the quality tessellation's triangles paired into quads
    /// where the pair makes a good one, then every face split at its centre and edge midpoints
    /// (on the surface), so the mesh is all quads; made from triangles at 1.4 times the
    /// tolerance: the split divides a triangle's chordal error by about four, but a quad is not
    /// flat, and at 1.4 its halves stay within the tolerance.
    #[arg(long, conflicts_with_all = ["te", "tr"])]
    quads: bool,
    /// Write PLY or STL as text instead of binary.
    #[arg(long)]
    ascii: bool,
    /// The file's up axis [default: y for GLB and OBJ, z for the others].
    #[arg(long, value_enum, value_name = "AXIS")]
    up: Option<Up>,
    /// One model unit becomes S units (--units): a finite number above 0.
    #[arg(long, default_value_t = 1.0, value_name = "S", allow_negative_numbers = true,
          value_parser = parse_scale)]
    scale: f64,
    /// The unit a model unit (times --scale) is measured in; GLB, STL and 3MF are converted to
    /// their own unit, OBJ, PLY and OFF store numbers in this one.
    #[arg(long, value_enum, default_value_t = DEFAULT_UNITS, value_name = "U")]
    units: Units,
    /// Texture coordinates: each vertex's home chart's, or a packed atlas split at seams.
    #[arg(long, value_enum, default_value_t = UvLayout::Chart, value_name = "LAYOUT")]
    uv: UvLayout,
    /// Print nothing on success.
    #[arg(short, long)]
    quiet: bool,
    /// Replace the output file if it exists.
    #[arg(long)]
    force: bool,
}

/// t_e or t_r where only the other is given.
const DEFAULT_T: u32 = 16;

/// A chordal tolerance within the quality tessellation's range.
pub(super) fn parse_tolerance(s: &str) -> Result<f64, String> {
    use embedding::remesh::QualitySettings as Q;
    match s.parse::<f64>() {
        Ok(t) if (Q::MIN_TOLERANCE..=Q::MAX_TOLERANCE).contains(&t) => Ok(t),
        Ok(t) => Err(format!(
            "the tolerance is a fraction of the diagonal from {} to {}, got {t}",
            Q::MIN_TOLERANCE,
            Q::MAX_TOLERANCE
        )),
        Err(e) => Err(e.to_string()),
    }
}

/// A scale: a finite number above 0 (0 would collapse the mesh, a negative one turn it inside
/// out).
fn parse_scale(s: &str) -> Result<f64, String> {
    match s.trim().parse::<f64>() {
        Ok(x) if x.is_finite() && x > 0.0 => Ok(x),
        Ok(x) => Err(format!(
            "the scale must be a finite number above 0, got {x}"
        )),
        Err(_) => Err(format!("the scale must be a number, got {s:?}")),
    }
}

/// `x` with about four significant digits.
fn significant(x: f64) -> String {
    let decimals = if x > 0.0 {
        (3 - x.log10().floor() as i32).clamp(0, 12) as usize
    } else {
        0
    };
    format!("{x:.decimals$}")
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let Args {
        model: model_path,
        output,
        format,
        te,
        tr,
        tolerance,
        quads,
        ascii,
        up,
        scale,
        units,
        uv,
        quiet,
        force,
    } = args;
    let output: &Path = &output;
    // A directory has no extension to read a format from: say what it is first.
    if output.is_dir() {
        ntori::io::atomic::check_new_output(output, &[&model_path], force)?;
    }
    let format = match format {
        Some(f) => f,
        None => Format::from_path(output)?,
    };
    let encoding = if ascii {
        Encoding::Ascii
    } else {
        Encoding::Binary
    };
    let options = ExportOptions {
        encoding,
        up,
        scale,
        units,
        uv,
        name: model_path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned()),
    };
    options.check(format)?;
    // Refused before the model is read.
    if quads && !format.has_quads() {
        return Err(ExportError::NoQuads(format).into());
    }
    ntori::io::atomic::check_new_output(output, &[&model_path], force)?;
    let model = ntori::io::model_file::load(&model_path)?;
    let meshing = match (te, tr, tolerance) {
        (None, None, tolerance) => {
            let tolerance = tolerance.unwrap_or(QualitySettings::default().tolerance);
            if quads {
                Meshing::Quads { tolerance }
            } else {
                Meshing::Quality { tolerance }
            }
        }
        (te, tr, _) => {
            let (te, tr) = (te.unwrap_or(DEFAULT_T), tr.unwrap_or(DEFAULT_T));
            export::check_resolution(model.genus(), te, tr)?;
            Meshing::TeTr { te, tr }
        }
    };
    let exported =
        export::export_surface(&model, meshing, output, format, &options).map_err(|e| match e {
            // Writing failed: the file error says which file and why.
            ExportError::File(_) | ExportError::GlbTooLarge(_) => anyhow::Error::new(e),
            other => anyhow::Error::new(other).context(format!(
                "cannot export {}: cannot mesh its surface",
                model_path.display()
            )),
        })?;
    if exported.folded > 0 {
        let advice = match meshing {
            Meshing::TeTr { .. } => {
                format!("{meshing} is too coarse for this surface (raise them)")
            }
            Meshing::Quality { .. } => {
                "the quality tessellation could not turn them (export with --te and --tr instead)"
                    .to_string()
            }
            Meshing::Quads { .. } => {
                "the quad tessellation could not turn them (export without --quads, or with a \
                 smaller --tolerance)"
                    .to_string()
            }
        };
        let (folded, all) = (exported.folded, exported.triangles);
        let what = if exported.quads {
            format!("{folded} of the {all} halves of the quads")
        } else {
            format!("{folded} of {all} triangles")
        };
        eprintln!("ntori: warning: {what} face against the surface's normals: {advice}");
    }
    if !quiet {
        let kind = match (format.has_encodings(), encoding) {
            (false, _) => String::new(),
            (true, Encoding::Binary) => " (binary)".into(),
            (true, Encoding::Ascii) => " (text)".into(),
        };
        let [x, y, z] = exported.size.map(significant);
        write_stdout(&format!(
            "wrote {}: {format}{kind}, genus {}, {meshing}, {} vertices, {}, \
             {x} × {y} × {z} {}\n",
            output.display(),
            model.genus(),
            exported.vertices,
            exported.face_count(),
            exported.unit.symbol()
        ))?;
    }
    Ok(ExitCode::SUCCESS)
}
