//! `ntori figures`: the paper's figures, regenerated from the project's own code.
//!
//! The 2D figures (1, 2 left, 3, 4, 5, 7) are SVG written here by hand; the 3D ones (2 right, 6 and
//! the gallery) are PNG images from the offscreen renderer. Every figure is deterministic: the same
//! build writes the same bytes (fixed number formatting, no maps iterated in hash order, no dates).
//! Every figure's caption, with the command and the parameters that made it, goes to `CAPTIONS.md`.
//!
//! Conventions shared by all figures: genus 2 unless a figure says otherwise; a white background; one
//! colour per chart kind and per edge pair ([`palette`]); SVG pages whose `viewBox` is their size in
//! pixels, so font sizes are the drawn sizes (never below 13).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use charts::{Atlas, ChartsError};

use crate::io::atomic::{FileError, write_atomically};

mod charts_figs;
pub mod drawing;
mod geometry;
pub use crate::render::palette;
mod polygons;
pub mod renderings;
mod svg;
mod tessellation_fig;

pub use charts_figs::overlap_regions;

/// The genus the 2D figures are drawn for (the paper's running example).
pub const GENUS: u32 = 2;

/// Tessellation levels of figure 7: the coarsest, and the subdivided one.
pub const COARSE: (u32, u32) = (1, 1);
pub const SUBDIVIDED: (u32, u32) = (4, 3);

/// One finished figure.
#[derive(Clone, Debug)]
pub struct Figure {
    /// The file name inside the output directory.
    pub file: String,
    /// What the figure shows (Markdown).
    pub caption: String,
    /// The parameters that made it (Markdown), beyond `ntori figures` itself.
    pub parameters: String,
    pub bytes: Vec<u8>,
}

/// Why the figures could not be made or written. Every message names the path or the figure.
#[derive(Debug, thiserror::Error)]
pub enum FiguresError {
    #[error("cannot create the figure directory {}: {source}", .path.display())]
    CreateDir {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(transparent)]
    Write(#[from] FileError),
    #[error("cannot build the charts for figure {figure}: {source}")]
    Charts { figure: String, source: ChartsError },
    #[error("cannot make the surface for figure {figure}: {source}")]
    Embedding {
        figure: String,
        source: embedding::EmbeddingError,
    },
    #[error("cannot render figure {figure}: {source}")]
    Render {
        figure: String,
        source: crate::render::RenderError,
    },
}

/// What [`generate`] makes.
#[derive(Clone, Copy, Debug)]
pub struct Options {
    /// Also the PNG figures (2 right, 6, the gallery), which need a graphics adapter. Without one
    /// they are left out and [`Summary::notes`] says so.
    pub render: bool,
}

impl Default for Options {
    fn default() -> Self {
        Options { render: true }
    }
}

fn charts_error(figure: &str) -> impl FnOnce(ChartsError) -> FiguresError + '_ {
    move |source| FiguresError::Charts {
        figure: figure.to_owned(),
        source,
    }
}

/// What [`generate`] reports as it goes.
#[derive(Clone, Debug)]
pub enum Progress {
    /// About to make this many figures.
    Total(u64),
    /// Making the figure written to this file.
    Making(String),
    /// Finished one more.
    Done,
}

/// What [`generate`] wrote.
#[derive(Clone, Debug, Default)]
pub struct Summary {
    /// Every file written (figures, then `CAPTIONS.md`), in order.
    pub written: Vec<PathBuf>,
    /// What was left out and why (e.g. the PNG figures, when no GPU adapter could be had).
    pub notes: Vec<String>,
}

/// The 2D figures, in order (figures 1, 2 left, 3, 4, 5, 7), each made by `make` and returned.
pub fn figures_2d() -> Result<Vec<Figure>, FiguresError> {
    jobs_2d().into_iter().map(|job| (job.make)()).collect()
}

/// A figure to make.
struct Job {
    file: &'static str,
    make: Box<dyn FnOnce() -> Result<Figure, FiguresError>>,
}

fn jobs_2d() -> Vec<Job> {
    fn svg(file: &str, caption: String, parameters: String, text: String) -> Figure {
        Figure {
            file: file.to_owned(),
            caption,
            parameters,
            bytes: text.into_bytes(),
        }
    }
    fn atlas(figure: &str) -> Result<Atlas, FiguresError> {
        Atlas::new(GENUS).map_err(charts_error(figure))
    }
    let genus = format!("genus {GENUS}");
    let mut jobs: Vec<Job> = Vec::new();
    let g = genus.clone();
    jobs.push(Job {
        file: "fig1-polygon.svg",
        make: Box::new(move || {
            let a = atlas("1")?;
            let poly = a.polygon().expect("genus ≥ 1 has a polygon");
            Ok(svg(
                "fig1-polygon.svg",
                "The abstract 4n-gon (n = 2: an octagon) with its edges labelled a₁ b₁ a₁⁻¹ b₁⁻¹ a₂ b₂ \
                 a₂⁻¹ b₂⁻¹ counter-clockwise from the right. Partner edges (a_k and a_k⁻¹, b_k and \
                 b_k⁻¹) share a colour and are glued arrow onto arrow; the arrows of a_k⁻¹ and b_k⁻¹ are \
                 read off the side pairings (`charts::Polygon::pairing`), not assumed."
                    .into(),
                format!("{g}; edge e = 4k + t is a_k, b_k, a_k⁻¹, b_k⁻¹ for t = 0, 1, 2, 3"),
                polygons::figure1(poly),
            ))
        }),
    });
    let g = genus.clone();
    jobs.push(Job {
        file: "fig2a-corners.svg",
        make: Box::new(move || {
            let a = atlas("2")?;
            let poly = a.polygon().expect("genus ≥ 1 has a polygon");
            let walk: Vec<String> = poly
                .vertex_cycle()
                .iter()
                .map(|s| s.corner.to_string())
                .collect();
            Ok(svg(
                "fig2a-corners.svg",
                format!(
                    "Left half of figure 2: the octagon with its corners numbered by the order in which \
                     a walk around the surface's single vertex meets them (`Polygon::vertex_cycle`, \
                     derived from the side pairings). Counting corners counter-clockwise from the one \
                     at angle ω/2, the walk visits corners {}. The right half is \
                     `fig2b-loops.png`: the loops a₁ b₁ a₂ b₂ drawn on the surface in the same colours.",
                    walk.join(", ")
                ),
                format!("{g}; the walk starts at corner 0 leaving by edge 1"),
                polygons::figure2_polygon(poly),
            ))
        }),
    });
    let g = genus.clone();
    jobs.push(Job {
        file: "fig3-hyperbolic-polygon.svg",
        make: Box::new(move || {
            let a = atlas("3")?;
            let poly = a.polygon().expect("genus ≥ 1 has a polygon");
            let c = poly.constants();
            Ok(svg(
                "fig3-hyperbolic-polygon.svg",
                format!(
                    "The regular hyperbolic octagon in the Poincaré disk (unit circle drawn), its sides \
                     arcs of the 4n dashed circles, each meeting the unit circle at right angles. \
                     ω = 2π/4n is the angle between neighbouring edge directions; h and r are the \
                     centre distance and radius of an edge's circle (r² = h² − 1); γ is the distance \
                     to an edge midpoint, α to a corner; β is where the tessellation squares of the \
                     neighbouring edge charts a₁ and b₁ (shaded) meet. Values: ω = {:.6}, h = {:.6}, \
                     r = {:.6}, γ = {:.6}, α = {:.6}, β = {:.6} + {:.6}i.",
                    c.omega,
                    c.h.unwrap_or(f64::NAN),
                    c.r.unwrap_or(f64::NAN),
                    c.gamma,
                    c.alpha,
                    c.beta.re,
                    c.beta.im
                ),
                format!("{g}; constants from `charts::Polygon::constants` (also `ntori info --genus 2`)"),
                polygons::figure3(&a, poly),
            ))
        }),
    });
    let g = genus.clone();
    jobs.push(Job {
        file: "fig4-charts.svg",
        make: Box::new(move || {
            let a = atlas("4")?;
            Ok(svg(
                "fig4-charts.svg",
                "The inside chart, edge chart a₁ and the vertex chart. Top: each in its own \
                 coordinates (disk |w| < ½, square (−½, ½)²) with a grid. Bottom: the image of that \
                 grid in the polygon: each chart is one linear fractional map into the disk (its raw \
                 image outlined dashed), and the parts that leave the polygon are brought back by the \
                 side-pairing group, so the edge chart's left half lies along a₁ and its right half \
                 along a₁⁻¹, and the vertex chart's 4n wedges sit in the 4n corners. The vertex \
                 chart's wedges carry the numbers of the corners they land in (as in figure 2)."
                    .into(),
                format!("{g}; default chart scales (`charts::ChartScales::default_for(2)`); grid step 0.1"),
                charts_figs::figure4(&a),
            ))
        }),
    });
    let g = genus.clone();
    jobs.push(Job {
        file: "fig5-overlaps.svg",
        make: Box::new(move || {
            let a = atlas("5")?;
            let (text, counts) = charts_figs::figure5(&a);
            Ok(svg(
                "fig5-overlaps.svg",
                format!(
                    "The overlap regions U_ij for each kind of chart pair, drawn in chart i's \
                     coordinates and shaded in chart j's colour: {}. Each shaded region is one \
                     connected component, with its own transition function; its outline is the exact \
                     preimage of chart j's domain boundary under that transition, and the tests check \
                     it against point location on a fine grid.",
                    counts
                ),
                format!("{g}; components from `charts::Atlas::transitions`"),
                text,
            ))
        }),
    });
    let g = genus.clone();
    jobs.push(Job {
        file: "fig7-tessellation.svg",
        make: Box::new(move || {
            let a = atlas("7")?;
            let text = tessellation_fig::figure7(&a).map_err(charts_error("7"))?;
            Ok(svg(
                "fig7-tessellation.svg",
                format!(
                    "The t_e/t_r tessellation. Top left: the coarsest level (t_e = t_r = {}) cuts the \
                     surface into 2n + 2 regions, one per chart: a square in each edge chart, the \
                     inside wheel and the vertex wheel (shown in the polygon, triangle sides the \
                     circular arcs they are, coloured by home chart). Top right: subdivided, \
                     t_e = {}, t_r = {}. Bottom: at t_e = {}, t_r = {}, the triangles of the inside \
                     chart, edge chart a₁ and the vertex chart in their own coordinates (domain \
                     outlined dashed).",
                    COARSE.0, SUBDIVIDED.0, SUBDIVIDED.1, SUBDIVIDED.0, SUBDIVIDED.1
                ),
                format!(
                    "{g}; top left as `ntori tessellate --genus 2 --te {} --tr {} --svg FILE`, top \
                     right as `--te {} --tr {}`",
                    COARSE.0, COARSE.1, SUBDIVIDED.0, SUBDIVIDED.1
                ),
                text,
            ))
        }),
    });
    jobs
}

/// The caption file: every figure's file, caption and parameters, in order.
pub fn captions(figures: &[Figure], notes: &[String]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Figures\n");
    let _ = writeln!(
        s,
        "Made by `ntori figures --out DIR` (this directory): the figures of Grimm and Hughes, \
         \"Parameterizing n-holed tori\", regenerated by ntori {}. Running the same command again \
         writes the same bytes.\n",
        env!("CARGO_PKG_VERSION")
    );
    for f in figures {
        let _ = writeln!(
            s,
            "## {}\n\n{}\n\nParameters: {}\n",
            f.file, f.caption, f.parameters
        );
    }
    for n in notes {
        let _ = writeln!(s, "Note: {n}\n");
    }
    s
}

/// Makes every figure and writes it to `dir` (created if needed), then `CAPTIONS.md`. Each file is
/// written as soon as it is made, whole or not at all.
pub fn generate(
    dir: &Path,
    options: &Options,
    progress: &mut dyn FnMut(Progress),
) -> Result<Summary, FiguresError> {
    std::fs::create_dir_all(dir).map_err(|source| FiguresError::CreateDir {
        path: dir.to_owned(),
        source,
    })?;
    let mut summary = Summary::default();
    let studio = if options.render {
        match crate::render::Offscreen::new() {
            Ok(offscreen) => Some(renderings::Studio::new(offscreen)),
            Err(e) => {
                let files: Vec<String> = renderings::jobs().into_iter().map(|j| j.file).collect();
                summary.notes.push(format!(
                    "the PNG figures ({}) were not made: {e}",
                    files.join(", ")
                ));
                None
            }
        }
    } else {
        None
    };
    let jobs = jobs_2d();
    let jobs_3d = if studio.is_some() {
        renderings::jobs()
    } else {
        Vec::new()
    };
    progress(Progress::Total((jobs.len() + jobs_3d.len()) as u64 + 1));
    let mut figures = Vec::new();
    let mut write = |figure: Figure, summary: &mut Summary| -> Result<(), FiguresError> {
        let path = dir.join(&figure.file);
        write_atomically(&path, &figure.bytes)?;
        summary.written.push(path);
        figures.push(Figure {
            bytes: Vec::new(),
            ..figure
        });
        Ok(())
    };
    for job in jobs {
        progress(Progress::Making(job.file.to_owned()));
        write((job.make)()?, &mut summary)?;
        progress(Progress::Done);
    }
    if let Some(mut studio) = studio {
        for job in jobs_3d {
            progress(Progress::Making(job.file.clone()));
            write((job.make)(&mut studio)?, &mut summary)?;
            progress(Progress::Done);
        }
    }
    progress(Progress::Making("CAPTIONS.md".into()));
    let path = dir.join("CAPTIONS.md");
    write_atomically(&path, captions(&figures, &summary.notes).as_bytes())?;
    summary.written.push(path);
    progress(Progress::Done);
    Ok(summary)
}
