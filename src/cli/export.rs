//! `ntori export`: a model's surface as a triangle mesh file.

use std::path::{Path, PathBuf};
use std::process::ExitCode;

use ntori::io::export::{self, Encoding, ExportError, Format};

use super::write_stdout;

/// Export a model's surface as a triangle mesh: OBJ, PLY, STL, GLB or OFF.
///
/// The surface is tessellated with the t_e/t_r scheme (see `ntori tessellate --help`; about
/// 4n·t_e² + 8n·t_e·(2t_r − 1) triangles at genus n ≥ 1) and evaluated at every vertex: the
/// position, the analytic unit normal (outward; triangles wind counter-clockwise seen from
/// outside), and the vertex's home chart and its coordinates there. The format comes from the
/// output's extension unless --format names it. What each format carries:
///   .obj  positions, normals, texture coordinates (text; OBJ cannot carry the chart id)
///   .ply  positions, normals, texture coordinates u v, the chart id as `chart`
///         (binary little endian, or text with --ascii)
///   .stl  triangles with one face normal each; no shared vertices, no texture coordinates
///         (binary, or text with --ascii)
///   .glb  binary glTF 2.0: POSITION, NORMAL, TEXCOORD_0 (f32; v flipped, as glTF's textures
///         start at the top), the chart id as the custom attribute _CHART (u16), u32 indices
///   .off  positions and triangles only (text)
/// Texture coordinates are the home chart's coordinates moved into [0, 1]²; they are continuous
/// within one chart, so triangles whose corners have different home charts span a texture seam.
/// Coordinates are stored as 32-bit floats. The file is written whole or not at all; an existing
/// file is replaced.
///
/// Examples:
///   ntori export model.json -o surface.obj
///   ntori export model.json -o surface.ply --te 32 --tr 32 --ascii
///   ntori export model.json -o print.stl
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
    /// Divisions of each edge chart's square (and each arc), 1 to 512. At 1 two different edges
    /// can join the same two vertices, which tools that know edges by their endpoints take for
    /// a non-manifold mesh. Too coarse a tessellation folds (a warning says so).
    #[arg(long, default_value_t = 16, value_name = "A", allow_negative_numbers = true,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(export::MAX_RESOLUTION)))]
    te: u32,
    /// Divisions of each wheel spoke, 1 to 512.
    #[arg(long, default_value_t = 16, value_name = "B", allow_negative_numbers = true,
          value_parser = clap::value_parser!(u32).range(1..=i64::from(export::MAX_RESOLUTION)))]
    tr: u32,
    /// Write PLY or STL as text instead of binary.
    #[arg(long)]
    ascii: bool,
    /// Print nothing on success.
    #[arg(short, long)]
    quiet: bool,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let Args {
        model: model_path,
        output,
        format,
        te,
        tr,
        ascii,
        quiet,
    } = args;
    let output: &Path = &output;
    let format = match format {
        Some(f) => f,
        None => Format::from_path(output)?,
    };
    if ascii && !format.has_encodings() {
        return Err(ExportError::NoEncodings(format).into());
    }
    let encoding = if ascii {
        Encoding::Ascii
    } else {
        Encoding::Binary
    };
    ntori::io::atomic::check_output(output, &[&model_path])?;
    let model = ntori::io::model_file::load(&model_path)?;
    export::check_resolution(model.genus(), te, tr)?;
    let exported = export::export_surface(&model, (te, tr), output, format, encoding).map_err(
        |e| match e {
            // Writing failed: the file error says which file and why.
            ExportError::File(_) | ExportError::GlbTooLarge(_) => anyhow::Error::new(e),
            other => anyhow::Error::new(other).context(format!(
                "cannot export {}: cannot mesh its surface",
                model_path.display()
            )),
        },
    )?;
    if exported.folded > 0 {
        eprintln!(
            "ntori: warning: {} of {} triangles face against the surface's normals: \
             t_e = {te}, t_r = {tr} is too coarse for this surface (raise them)",
            exported.folded, exported.triangles
        );
    }
    if !quiet {
        let kind = match (format.has_encodings(), encoding) {
            (false, _) => String::new(),
            (true, Encoding::Binary) => " (binary)".into(),
            (true, Encoding::Ascii) => " (text)".into(),
        };
        write_stdout(&format!(
            "wrote {}: {format}{kind}, genus {}, t_e = {te}, t_r = {tr}, {} vertices, {} triangles\n",
            output.display(),
            model.genus(),
            exported.vertices,
            exported.triangles
        ))?;
    }
    Ok(ExitCode::SUCCESS)
}
