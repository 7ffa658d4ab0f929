//! `ntori figures`: the paper's figures, regenerated.

use std::path::PathBuf;
use std::process::ExitCode;

use ntori::figures::Progress;

use super::write_stdout;

/// Regenerate the paper's figures: SVG drawings, PNG renderings, and a caption file.
///
/// Writes into DIR (created if needed): figure 1 (the abstract 4n-gon with its edge pairing),
/// figure 2 (left: the corners in their order around the surface's vertex, SVG; right: the loops
/// a₁ b₁ a₂ b₂ on the surface, PNG), figure 3 (the hyperbolic polygon with ω, h, r, γ, α, β),
/// figure 4 (the three chart kinds, in their coordinates and in the polygon), figure 5 (the
/// overlap regions), figure 6 (the input mesh, the fitted surface, two edited surfaces; PNG),
/// figure 7 (the tessellation), a gallery (genus 0 to 6, 8, 10, 16 and 32 shaded; genus 3, 5, 10,
/// 16 and 32 in mean curvature; genus 2 in the chart and curvature styles; PNG), and CAPTIONS.md
/// listing every file with what it shows and the parameters that made it. The 2D figures are for
/// genus 2, like the paper's. The whole command takes about two minutes on two cores, most of it
/// for genus 32's fit (on its grid of 64 and 372 392 triangles, and the points between them),
/// and 10 GB.
///
/// The PNG figures need a GPU (or a software adapter); without one they are left out with a
/// warning, and the caption file says so. Running the command again writes the same bytes.
///
/// Examples:
///   ntori figures                       into ./figures
///   ntori figures --out paper --quiet
#[derive(clap::Args, Debug)]
#[command(verbatim_doc_comment)]
pub struct Args {
    /// The directory to write the figures into.
    #[arg(long, default_value = "figures", value_name = "DIR")]
    out: PathBuf,
    /// No progress bar on stderr.
    #[arg(short, long)]
    quiet: bool,
}

pub fn run(args: Args) -> anyhow::Result<ExitCode> {
    let Args { out, quiet } = args;
    let bar = if quiet || !std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        indicatif::ProgressBar::hidden()
    } else {
        let bar = indicatif::ProgressBar::new(0);
        bar.set_style(
            indicatif::ProgressStyle::with_template("{bar:30} {pos}/{len} {msg}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        // The 3D figures fit surfaces for seconds at a time: keep the bar alive meanwhile.
        bar.enable_steady_tick(std::time::Duration::from_millis(200));
        bar
    };
    let options = ntori::figures::Options::default();
    let summary = ntori::figures::generate(&out, &options, &mut |p| match p {
        Progress::Total(n) => bar.set_length(n),
        Progress::Making(file) => bar.set_message(file),
        Progress::Done => bar.inc(1),
    });
    bar.finish_and_clear();
    let summary = summary?;
    for note in &summary.notes {
        eprintln!("ntori: warning: {note}");
    }
    if !quiet {
        write_stdout(&format!(
            "wrote {} files to {}\n",
            summary.written.len(),
            out.display()
        ))?;
    }
    Ok(ExitCode::SUCCESS)
}
