//! TEMPORARY: the command line as it was before the split, to compare help and errors.
#![allow(dead_code, clippy::all)]
use clap::{CommandFactory, Parser, Subcommand};
use embedding::SplineSettings;
use embedding::fit::FitSettings;

/// ntori: smooth closed surfaces of any genus, built from charts glued by linear fractional maps.
///
/// A surface of genus n (a sphere with n handles) is the regular hyperbolic 4n-gon with its edges
/// glued in pairs (a₁ b₁ a₁⁻¹ b₁⁻¹ … aₙ bₙ aₙ⁻¹ bₙ⁻¹), following Grimm and Hughes, "Parameterizing
/// n-holed tori". Genus 1 uses the flat square, genus 0 the round sphere.
#[derive(Parser, Debug)]
#[command(name = "ntori", version, about, long_about, propagate_version = true)]
struct Cli {
    /// Log more (-v: info, -vv: debug); RUST_LOG overrides.
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    verbose: u8,
    #[command(subcommand)]
    command: Command,
}

/// The surface's genus, as every subcommand takes it.
#[derive(clap::Args, Debug, Clone, Copy)]
struct GenusArg {
    /// Genus of the surface: 0 (sphere), 1 (torus), 2 … 64.
    #[arg(
        short,
        long,
        default_value_t = 2,
        value_name = "N",
        allow_negative_numbers = true
    )]
    genus: u32,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Show the chart structure for one genus, and check it.
    ///
    /// Prints the fundamental polygon's constants (for genus n ≥ 2, the regular hyperbolic 4n-gon in
    /// the Poincaré disk):
    ///   ω  the angle 2π/4n between neighbouring edge directions, also each corner's angle;
    ///   h, r  the centre distance and radius of the circles the edges lie on (r² = h² − 1);
    ///   γ  the distance from the centre to an edge midpoint; α the distance to a corner;
    ///   β  where the corners of neighbouring edge charts' tessellation squares meet;
    ///   δ  the paper's vertex-chart scale (its boundary passes through β).
    ///
    /// Then the 2n + 2 charts (inside, vertex, one edge chart per glued pair a_k, b_k), each mapped
    /// into the disk by one linear fractional transformation; the overlaps U_ij between charts, split
    /// into connected components, each with its own transition function ψ_ij.
    ///
    /// The self-check spreads points over the surface and reports: the largest error of ψ_ii = id, of
    /// ψ_ji ∘ ψ_ij = id (inverse) and of ψ_jk ∘ ψ_ij = ψ_ik (cocycle), in chart-coordinate units; and
    /// the coverage margin: over all points, the smallest distance to a chart boundary from the chart
    /// holding the point deepest. The blend functions divide by their sum, and the margin keeps that
    /// sum away from zero. Exit status 3 if the self-check fails.
    ///
    /// Examples:
    ///   ntori info                       genus 2, as text
    ///   ntori info --genus 1 --json      the flat torus, as JSON
    #[command(verbatim_doc_comment)]
    Info {
        #[command(flatten)]
        genus: GenusArg,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
        /// How many points the self-check spreads over the surface.
        #[arg(long, default_value_t = 20_000, value_name = "K",
              value_parser = clap::value_parser!(u64).range(1..=10_000_000))]
        points: u64,
    },
    /// Tessellate the surface (the paper's t_e/t_r scheme) and check the mesh.
    ///
    /// The coarsest level (t_e = t_r = 1) cuts the surface into 2n + 2 regions, one per chart: a
    /// square in each edge chart, sized so that neighbouring squares' corners meet at the point β, and
    /// two "wheels" (about the inside chart's centre and about the vertex) bounded by the 4n arcs the
    /// squares leave. t_e divides each square into a t_e × t_e grid and each arc into t_e pieces; t_r
    /// divides the wheels' spokes. Genus 0 uses two wheels, the caps, meeting at the equator.
    ///
    /// Prints V, E, F, the Euler characteristic χ = V − E + F (2 − 2n for genus n), the genus read off
    /// the mesh, components, and checks: closed, manifold, orientable, consistently oriented; no
    /// degenerate triangle; vertex coordinates agreeing across charts; and the triangles' areas, with
    /// geodesic sides, adding up to the surface's area (4π(n − 1) for n ≥ 2). Exit status 3 if a check
    /// fails.
    ///
    /// Examples:
    ///   ntori tessellate --genus 2 --te 4 --tr 3
    ///   ntori tessellate --genus 3 --te 1 --tr 1 --svg coarsest.svg   (the paper's figure 7)
    #[command(verbatim_doc_comment)]
    Tessellate {
        #[command(flatten)]
        genus: GenusArg,
        /// Divisions of each square (and each arc).
        #[arg(
            long,
            default_value_t = 4,
            value_name = "A",
            allow_negative_numbers = true
        )]
        te: u32,
        /// Divisions of each wheel spoke.
        #[arg(
            long,
            default_value_t = 4,
            value_name = "B",
            allow_negative_numbers = true
        )]
        tr: u32,
        /// Print JSON instead of text.
        #[arg(long)]
        json: bool,
        /// Also draw the tessellation in the fundamental polygon, charts coloured, to this SVG file.
        #[arg(long, value_name = "FILE")]
        svg: Option<std::path::PathBuf>,
    },
    /// Make a new model: a smooth genus-n surface fitted to an n-holed mesh, written as a model file.
    ///
    /// The paper's section 5.1. A genus-n mesh (a round plate with n holes, rims rounded; the sphere for
    /// n = 0, the round torus for n = 1) is cut along 2n loops through one vertex into a disk whose
    /// boundary reads a₁ b₁ a₁⁻¹ b₁⁻¹ …; Floater's mean value map flattens the disk onto the polygon
    /// (in the Klein model, where it is convex), the map is relaxed on the closed surface so it has no
    /// seams, and every chart's control points are fitted at once by regularised least squares.
    ///
    /// Prints the fit's checks: folded triangles in the parameterization (0: a bijection), the
    /// residual |S(p_i) − P_i| at the mesh vertices as a fraction of the mesh's size, and Gauss–Bonnet
    /// (∫K dA from the analytic curvature against 2π(2 − 2n)). Exit status 3 if a check fails. An
    /// existing file is not replaced unless --force is given.
    ///
    /// Examples:
    ///   ntori new                                 genus 2, written to model.json
    ///   ntori new --genus 5 -o five.json --grid 16
    #[command(verbatim_doc_comment)]
    New {
        #[command(flatten)]
        genus: GenusArg,
        /// Where to write the model.
        #[arg(short, long, default_value = "model.json", value_name = "FILE")]
        output: std::path::PathBuf,
        /// Replace the output file if it exists.
        #[arg(long)]
        force: bool,
        /// Input mesh resolution: points around each hole (around the equator for the sphere).
        #[arg(long, default_value_t = 32, value_name = "R",
              value_parser = clap::value_parser!(u64).range(8..=1024))]
        resolution: u64,
        /// Control points per side of each chart's grid.
        #[arg(long, default_value_t = SplineSettings::default().grid as u64, value_name = "G",
              value_parser = clap::value_parser!(u64).range(4..=64))]
        grid: u64,
        /// Spline degree.
        #[arg(long, default_value_t = SplineSettings::default().degree as u64, value_name = "P",
              value_parser = clap::value_parser!(u64).range(1..=7))]
        degree: u64,
        /// Continuity order of the blend functions (1 to 4).
        #[arg(long, default_value_t = SplineSettings::default().continuity as u64, value_name = "K",
              value_parser = clap::value_parser!(u64).range(1..=4))]
        continuity: u64,
        /// Weight λ of the control grids' smoothness energy in the fit (relative to the data term).
        #[arg(long, default_value_t = FitSettings::default().smoothness, value_name = "λ")]
        smoothness: f64,
        /// Print the report as JSON.
        #[arg(long)]
        json: bool,
        /// No progress messages on stderr.
        #[arg(short, long)]
        quiet: bool,
    },
    /// Open the editor: a window to sculpt the surface by dragging its points.
    ///
    /// Opens MODEL (as written by `ntori new`), or fits the default genus-2 model when none is
    /// given. Drag a point of the surface and the smallest change to the control points moves it
    /// under the cursor (the paper's minimum-norm least squares); Ctrl + click pins points so they
    /// stay put. Orbit with a left drag off the surface, pan with a right or middle drag, zoom with
    /// the wheel; F frames the model, F1 lists every shortcut. Undo and redo, open, save, mesh
    /// export and screenshots are in the menus. Unsaved work is autosaved to
    /// $XDG_STATE_HOME/ntori (or ~/.local/state/ntori) and offered back after a crash.
    ///
    /// Needs a display and a GPU (or Mesa's software Vulkan, lavapipe).
    ///
    /// Examples:
    ///   ntori edit                         the default genus-2 model
    ///   ntori edit model.json --te 48 --tr 48
    #[command(verbatim_doc_comment)]
    Edit {
        /// The model file to open.
        #[arg(value_name = "MODEL")]
        model: Option<std::path::PathBuf>,
        /// Divisions of each edge chart's square (and each arc) in the viewport, 1 to 256.
        #[arg(long, default_value_t = ntori::editor::state::DEFAULT_T, value_name = "A",
              value_parser = clap::value_parser!(u32).range(1..=i64::from(ntori::editor::state::MAX_T)))]
        te: u32,
        /// Divisions of each wheel spoke in the viewport, 1 to 256.
        #[arg(long, default_value_t = ntori::editor::state::DEFAULT_T, value_name = "B",
              value_parser = clap::value_parser!(u32).range(1..=i64::from(ntori::editor::state::MAX_T)))]
        tr: u32,
        /// For smoke tests: close after this many frames.
        #[arg(long, hide = true, value_name = "N")]
        exit_after_frames: Option<u32>,
        /// For smoke tests: write the viewport's picture here before closing.
        #[arg(long, hide = true, value_name = "PNG")]
        screenshot_on_exit: Option<std::path::PathBuf>,
    },
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
    #[command(verbatim_doc_comment)]
    Export {
        /// The model file (as written by `ntori new`).
        #[arg(value_name = "MODEL")]
        model: std::path::PathBuf,
        /// Where to write the mesh; its extension picks the format unless --format is given.
        #[arg(short, long, value_name = "FILE")]
        output: std::path::PathBuf,
        /// The file format, overriding the output's extension.
        #[arg(long, value_enum)]
        format: Option<ntori::io::export::Format>,
        /// Divisions of each edge chart's square (and each arc), 1 to 512. At 1 two different edges
        /// can join the same two vertices, which tools that know edges by their endpoints take for
        /// a non-manifold mesh. Too coarse a tessellation folds (a warning says so).
        #[arg(long, default_value_t = 16, value_name = "A", allow_negative_numbers = true,
              value_parser = clap::value_parser!(u32).range(1..=i64::from(ntori::io::export::MAX_RESOLUTION)))]
        te: u32,
        /// Divisions of each wheel spoke, 1 to 512.
        #[arg(long, default_value_t = 16, value_name = "B", allow_negative_numbers = true,
              value_parser = clap::value_parser!(u32).range(1..=i64::from(ntori::io::export::MAX_RESOLUTION)))]
        tr: u32,
        /// Write PLY or STL as text instead of binary.
        #[arg(long)]
        ascii: bool,
        /// Print nothing on success.
        #[arg(short, long)]
        quiet: bool,
    },
    /// Render a model to a PNG picture, without a window.
    ///
    /// Uses the GPU if there is one, and otherwise Mesa's software Vulkan (lavapipe; on Debian or
    /// Ubuntu: apt-get install mesa-vulkan-drivers). The surface is tessellated at t_e = t_r = T and
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
    #[command(verbatim_doc_comment)]
    Render {
        /// The model file (as written by `ntori new`).
        #[arg(value_name = "MODEL")]
        model: std::path::PathBuf,
        /// Where to write the PNG.
        #[arg(short, long, value_name = "FILE")]
        output: std::path::PathBuf,
        /// Picture size in pixels, WIDTHxHEIGHT (1 to 8192 each).
        #[arg(long, default_value = "1024x768", value_name = "WxH", value_parser = parse_size)]
        size: (u32, u32),
        /// Camera: azimuth,elevation,distance (degrees, degrees, bounding radii).
        #[arg(long, default_value = "30,35,3.6", value_name = "AZ,EL,DIST", value_parser = parse_view,
              allow_hyphen_values = true)]
        view: ntori::render::View,
        /// How to colour the surface.
        #[arg(long, value_enum, default_value_t = StyleArg::Shaded)]
        style: StyleArg,
        /// Which curvature the curvature style shows.
        #[arg(long, value_enum, default_value_t = CurvatureArg::Gaussian)]
        curvature: CurvatureArg,
        /// Tessellation t_e = t_r (1 to 256).
        #[arg(long, default_value_t = 32, value_name = "T",
              value_parser = clap::value_parser!(u32).range(1..=256))]
        tessellation: u32,
        /// Print nothing on success.
        #[arg(short, long)]
        quiet: bool,
    },
    /// Regenerate the paper's figures: SVG drawings, PNG renderings, and a caption file.
    ///
    /// Writes into DIR (created if needed): figure 1 (the abstract 4n-gon with its edge pairing),
    /// figure 2 (left: the corners in their order around the surface's vertex, SVG; right: the loops
    /// a₁ b₁ a₂ b₂ on the surface, PNG), figure 3 (the hyperbolic polygon with ω, h, r, γ, α, β),
    /// figure 4 (the three chart kinds, in their coordinates and in the polygon), figure 5 (the
    /// overlap regions), figure 6 (the input mesh, the fitted surface, two edited surfaces; PNG),
    /// figure 7 (the tessellation), a gallery (genus 0 to 6, and genus 2 in the chart and curvature
    /// styles; PNG), and CAPTIONS.md listing every file with what it shows and the parameters that
    /// made it. The 2D figures are for genus 2, like the paper's.
    ///
    /// The PNG figures need a GPU (or a software adapter); without one they are left out with a
    /// warning, and the caption file says so. Running the command again writes the same bytes.
    ///
    /// Examples:
    ///   ntori figures                       into ./figures
    ///   ntori figures --out paper --quiet
    #[command(verbatim_doc_comment)]
    Figures {
        /// The directory to write the figures into.
        #[arg(long, default_value = "figures", value_name = "DIR")]
        out: std::path::PathBuf,
        /// No progress bar on stderr.
        #[arg(short, long)]
        quiet: bool,
    },
    /// Measure throughput and print it as JSON.
    ///
    /// Figures for tessellation, point location, stencil building, re-embedding (also as a fraction
    /// of memory copy bandwidth) and drag events. Baselines (copy bandwidth, a chain of scalar
    /// multiply-adds) are measured in the same run, and every figure is also given per baseline
    /// operation, since this machine is shared and noisy.
    ///
    /// For statistics and history use `cargo bench`; this is the quick look.
    Bench {
        #[command(flatten)]
        genus: GenusArg,
        /// About how many vertices to measure with.
        #[arg(long, default_value_t = 100_000, value_name = "V",
              value_parser = clap::value_parser!(u64).range(10..=5_000_000))]
        vertices: u64,
        /// No progress messages on stderr.
        #[arg(short, long)]
        quiet: bool,
    },
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

/// "30,35,4" → the view; checked like [`ntori::render::View::validate`].
fn parse_view(s: &str) -> Result<ntori::render::View, String> {
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
    let view = ntori::render::View {
        azimuth_deg: num(az)?,
        elevation_deg: num(el)?,
        distance: num(d)?,
    };
    view.validate().map_err(|e| e.to_string())?;
    Ok(view)
}

fn all_helps(mut cmd: clap::Command) -> Vec<(String, String)> {
    fn walk(cmd: &mut clap::Command, path: String, out: &mut Vec<(String, String)>) {
        out.push((format!("{path} short"), cmd.render_help().to_string()));
        out.push((format!("{path} long"), cmd.render_long_help().to_string()));
        out.push((
            format!("{path} ansi"),
            cmd.render_long_help().ansi().to_string(),
        ));
        out.push((format!("{path} usage"), cmd.render_usage().to_string()));
        out.push((format!("{path} version"), cmd.render_long_version()));
        for sub in cmd.get_subcommands_mut() {
            let name = format!("{path} {}", sub.get_name());
            walk(sub, name, out);
        }
    }
    cmd.build();
    let mut out = Vec::new();
    walk(&mut cmd, "ntori".into(), &mut out);
    out
}

#[test]
fn help_is_unchanged() {
    let old = all_helps(Cli::command());
    let new = all_helps(super::Cli::command());
    assert_eq!(old.len(), new.len());
    for ((on, ot), (nn, nt)) in old.iter().zip(&new) {
        assert_eq!(on, nn);
        assert_eq!(ot, nt, "{on}");
    }
    eprintln!("compared {} help texts", old.len());
}

#[test]
fn parse_errors_are_unchanged() {
    let cases: &[&[&str]] = &[
        &[],
        &["bogus"],
        &["info", "--genus", "-3"],
        &["info", "--points", "0"],
        &["info", "--help"],
        &["info", "-h"],
        &["help"],
        &["help", "new"],
        &["--version"],
        &["new", "--version"],
        &["new", "--grid", "2"],
        &["new", "--degree", "9"],
        &["new", "--smoothness", "x"],
        &["tessellate", "--te", "-1"],
        &["tessellate", "--te", "x"],
        &["export"],
        &["export", "m.json"],
        &["export", "m.json", "-o", "x.obj", "--te", "0"],
        &["export", "m.json", "-o", "x.obj", "--format", "dxf"],
        &["render", "m", "-o", "p", "--size", "0x5"],
        &["render", "m", "-o", "p", "--size", "abc"],
        &["render", "m", "-o", "p", "--view", "1,2"],
        &["render", "m", "-o", "p", "--view", "-30,100,4"],
        &["render", "m", "-o", "p", "--style", "nope"],
        &["render", "m", "-o", "p", "--tessellation", "300"],
        &["edit", "--te", "0"],
        &["edit", "a", "b"],
        &["bench", "--vertices", "1"],
        &["figures", "--out"],
        &["info", "--jsn"],
        &["-vv", "info", "-g", "x"],
    ];
    for args in cases {
        let argv = std::iter::once("ntori").chain(args.iter().copied());
        let old = Cli::try_parse_from(argv.clone())
            .map(|c| format!("{c:?}"))
            .map_err(|e| (e.kind(), e.render().ansi().to_string(), e.exit_code()));
        let new = super::Cli::try_parse_from(argv)
            .map(|c| format!("{c:?}"))
            .map_err(|e| (e.kind(), e.render().ansi().to_string(), e.exit_code()));
        match (old, new) {
            (Err(o), Err(n)) => assert_eq!(o, n, "{args:?}"),
            (Ok(_), Ok(_)) => {}
            (o, n) => panic!("{args:?}: {o:?} vs {n:?}"),
        }
    }
}
