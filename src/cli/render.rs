//! `ntori render`: a model drawn to a PNG picture, without a window.

use std::path::PathBuf;
use std::process::ExitCode;

use anyhow::Context as _;
use ntori::render::{CurvatureKind, RenderOptions, Style, View};

use super::{spinner, write_stdout};

/// Render a model to a PNG picture, without a window.
///
/// Uses the GPU if there is one, and otherwise Mesa's software Vulkan (lavapipe; on Debian or
/// Ubuntu: apt-get install mesa-vulkan-drivers). The surface is tessellated at t_e = t_r = T (by
/// default 32, or 64 at genus 8 to 13, whose t = 32 triangles are coarse on the outer rim) and
/// evaluated exactly at the vertices, with analytic normals. Styles:
///   shaded      lit surface;
///   wireframe   the tessellation's edges over the shading (try a small T);
///   charts      each point coloured by its charts' blend weights, one colour per chart;
///   curvature   Gaussian (or, with --curvature mean, mean) curvature on a blue–white–red
///               scale symmetric about 0, ending at the 95th percentile of |value|, with a legend.
/// The view is azimuth and elevation in degrees (z is up) and the distance from the centre in
/// radii of the bounding sphere. The PNG is written atomically; the same inputs give the same
/// bytes on the same machine.
///
/// Examples:
///   ntori render model.json -o model.png
///   ntori render model.json -o top.png --view 0,90,4 --size 800x800
///   ntori render model.json -o k.png --style curvature --curvature gaussian
#[derive(clap::Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct Args {
    /// The model file (as written by `ntori new`).
    #[arg(value_name = "MODEL")]
    model: PathBuf,
    /// Where to write the PNG.
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
    /// Picture size in pixels, WIDTHxHEIGHT (1 to 8192 each).
    #[arg(long, default_value = "1024x768", value_name = "WxH", value_parser = parse_size)]
    size: (u32, u32),
    /// Camera: azimuth,elevation,distance (degrees, degrees, bounding radii).
    #[arg(long, default_value = "30,35,3.6", value_name = "AZ,EL,DIST", value_parser = parse_view,
          allow_hyphen_values = true)]
    view: View,
    /// How to colour the surface.
    #[arg(long, value_enum, default_value_t = StyleArg::Shaded)]
    style: StyleArg,
    /// Which curvature the curvature style shows.
    #[arg(long, value_enum, default_value_t = CurvatureArg::Gaussian)]
    curvature: CurvatureArg,
    /// Tessellation t_e = t_r (1 to 256) [default: 32, or 64 from genus 8 on where that makes at
    /// most 1.5 million triangles: genus 8 to 13]
    #[arg(long, value_name = "T", value_parser = clap::value_parser!(u32).range(1..=256))]
    tessellation: Option<u32>,
    /// Replace the output file if it exists.
    #[arg(long)]
    force: bool,
    /// Print nothing on success.
    #[arg(short, long)]
    quiet: bool,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum StyleArg {
    Shaded,
    Wireframe,
    Charts,
    Curvature,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug)]
enum CurvatureArg {
    Gaussian,
    Mean,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let Args {
        model,
        output,
        size,
        view,
        style,
        curvature,
        tessellation,
        quiet,
        force,
    } = args;
    let style = match style {
        StyleArg::Shaded => Style::Shaded,
        StyleArg::Wireframe => Style::Wireframe,
        StyleArg::Charts => Style::Charts,
        StyleArg::Curvature => Style::Curvature(match curvature {
            CurvatureArg::Gaussian => CurvatureKind::Gaussian,
            CurvatureArg::Mean => CurvatureKind::Mean,
        }),
    };
    ntori::io::atomic::check_new_output(&output, &[&model], force)?;
    let loaded = ntori::io::model_file::load(&model)?;
    let options = RenderOptions {
        width: size.0,
        height: size.1,
        view,
        style,
        tessellation: tessellation
            .unwrap_or_else(|| ntori::render::default_tessellation(loaded.genus())),
    };
    let bar = spinner(quiet);
    bar.set_message("opening the graphics adapter");
    let mut offscreen = ntori::render::Offscreen::new()?;
    bar.set_message(format!("rendering on {}", offscreen.adapter_name()));
    let png = offscreen
        .render_model_png(&loaded, &options, &[])
        .with_context(|| format!("cannot render {}", model.display()))?;
    bar.finish_and_clear();
    ntori::io::atomic::write_output(&output, &png, force)?;
    if !quiet {
        write_stdout(&format!(
            "wrote {} ({}×{}, {})\n",
            output.display(),
            options.width,
            options.height,
            offscreen.adapter_name()
        ))?;
    }
    Ok(ExitCode::SUCCESS)
}

/// "1024x768" → (1024, 768), each side 1 to 8192.
fn parse_size(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X', '×'])
        .ok_or_else(|| format!("expected WIDTHxHEIGHT, like 1024x768, got {s:?}"))?;
    let side = |v: &str| -> Result<u32, String> {
        let n: u32 = v
            .trim()
            .parse()
            .map_err(|_| format!("{v:?} is not a whole number of pixels"))?;
        if (1..=ntori::render::MAX_SIDE).contains(&n) {
            Ok(n)
        } else {
            Err(format!(
                "{n} pixels is not possible: each side must be 1 to {}",
                ntori::render::MAX_SIDE
            ))
        }
    };
    Ok((side(w)?, side(h)?))
}

/// "30,35,4" → the view; checked like [`View::validate`].
fn parse_view(s: &str) -> Result<View, String> {
    let parts: Vec<&str> = s.split(',').collect();
    let [az, el, d] = parts[..] else {
        return Err(format!(
            "expected AZIMUTH,ELEVATION,DISTANCE, like 30,35,4, got {s:?}"
        ));
    };
    let num = |v: &str| -> Result<f64, String> {
        v.trim()
            .parse()
            .map_err(|_| format!("{v:?} is not a number"))
    };
    let view = View {
        azimuth_deg: num(az)?,
        elevation_deg: num(el)?,
        distance: num(d)?,
    };
    view.validate().map_err(|e| e.to_string())?;
    Ok(view)
}
