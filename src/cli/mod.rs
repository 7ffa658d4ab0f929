//! The `ntori` command line: the parser, one module per subcommand, and what they share.

use std::process::ExitCode;

use clap::{Parser, Subcommand};
use embedding::SplineSettings;
use embedding::fit::FitSettings;

mod bench;
mod edit;
mod export;
mod figures;
mod fit;
mod info;
mod new;
mod render;
mod report;
mod sculpt;
mod tessellate;

/// ntori: smooth closed surfaces of any genus, built from charts glued by linear fractional maps.
///
/// A surface of genus n (a sphere with n handles) is the regular hyperbolic 4n-gon with its edges
/// glued in pairs (a₁ b₁ a₁⁻¹ b₁⁻¹ … aₙ bₙ aₙ⁻¹ bₙ⁻¹), following Grimm and Hughes, "Parameterizing
/// n-holed tori". Genus 1 uses the flat square, genus 0 the round sphere.
#[derive(Parser, Debug)]
#[command(name = "ntori", version, about, long_about, propagate_version = true)]
pub struct Cli {
    /// Log more (-v: info, -vv: debug); RUST_LOG overrides.
    #[arg(short, long, action = clap::ArgAction::Count, global = true)]
    pub verbose: u8,
    #[command(subcommand)]
    command: Command,
}

/// The subcommands; each one's arguments, help and work are in its own module.
#[derive(Subcommand, Debug)]
enum Command {
    Info(info::Args),
    Tessellate(tessellate::Args),
    New(new::Args),
    Fit(fit::Args),
    Edit(edit::Args),
    Sculpt(sculpt::Args),
    Export(export::Args),
    Render(render::Args),
    Figures(figures::Args),
    Bench(bench::Args),
}

/// Runs the subcommand: its exit status, or the error to print.
pub fn run(cli: Cli) -> anyhow::Result<ExitCode> {
    match cli.command {
        Command::Info(args) => info::run(args),
        Command::Tessellate(args) => tessellate::run(args),
        Command::New(args) => new::run(args),
        Command::Fit(args) => fit::run(args),
        Command::Edit(args) => edit::run(args),
        Command::Sculpt(args) => sculpt::run(args),
        Command::Export(args) => export::run(args),
        Command::Render(args) => render::run(args),
        Command::Figures(args) => figures::run(args),
        Command::Bench(args) => bench::run(args),
    }
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
        allow_negative_numbers = true,
        value_parser = parse_genus
    )]
    genus: u32,
}

/// A genus: a whole number from 0 to 64, refused as a usage error (exit status 2) either way out
/// of range, as -1 and 65 alike are mistakes on the command line. (clap's own u32 parser would
/// answer -1 with the range 0..=4294967295.)
fn parse_genus(s: &str) -> Result<u32, String> {
    let max = charts::MAX_GENUS;
    match s.trim().parse::<i64>() {
        Ok(n) if n < 0 => Err(format!("a genus is 0 or more (0 to {max}), got {n}")),
        Ok(n) if n > i64::from(max) => Err(format!(
            "genus {n} is not supported: the charts are built and validated for genus 0 to {max}"
        )),
        Ok(n) => Ok(n as u32),
        Err(_) => Err(format!(
            "a genus is a whole number from 0 to {max}, got {s:?}"
        )),
    }
}

/// The spline and the fit's weight, as `new` and `fit` take them.
#[derive(clap::Args, Debug, Clone, Copy)]
struct FitArgs {
    /// Control points per side of each chart's grid [default: for new 32 for the sphere and the
    /// torus and 48 from genus 2 (a coarser grid ripples there), but 40 from genus 5 to 16 (whose
    /// disk charts take the finer grids) and 64 at genus 30 to 32; for fit 40, and for a genus-0 mesh (its two
    /// charts carry the whole surface) 80, raised to at most 128 until there is a control point per
    /// vertex; 32 for fit --cage]
    #[arg(long, value_name = "G", allow_negative_numbers = true, value_parser = clap::value_parser!(u64).range(4..=MAX_GRID))]
    grid: Option<u64>,
    /// Control points per side of the disk charts' grids (the inside and vertex charts, which
    /// carry most of a high-genus surface and are coarse at their rims) [default: for new twice
    /// the grid at genus 3 and 4 (96 at 48), three times from genus 5 (120 at 40), four times
    /// from genus 11 (160 at 40), five times at 16 (200), 16/3 from genus 17 (256 at 48) and 8 times from genus 34
    /// (384), the grid below genus 3; for fit twice the grid from genus
    /// 2 (80 at 40), the grid below; the grid for fit --cage]
    #[arg(long, value_name = "G", allow_negative_numbers = true, value_parser = clap::value_parser!(u64).range(4..=512))]
    disk_grid: Option<u64>,
    /// Spline degree.
    #[arg(long, default_value_t = SplineSettings::default().degree as u64, value_name = "P",
          value_parser = clap::value_parser!(u64).range(1..=7))]
    degree: u64,
    /// Continuity order of the blend functions (1 to 4).
    #[arg(long, default_value_t = SplineSettings::default().continuity as u64, value_name = "K",
          value_parser = clap::value_parser!(u64).range(1..=4))]
    continuity: u64,
    /// Weight λ of the control grids' smoothness energy in the fit (relative to the data term;
    /// `fit` measures that energy in the surface's arc length, from a first fit)
    /// [default: 1e-4 for grids up to 32, 2e-3 for finer ones, whose second differences are
    /// smaller for the same shape, and 1e-2 for new's plates of genus 2 to 40 on those (3e-2 at genus
    /// 27 to 32); `fit` raises
    /// it where that leaves the surface rough]
    #[arg(long, value_name = "λ", allow_negative_numbers = true, value_parser = parse_smoothness)]
    smoothness: Option<f64>,
    /// Weight of the rows that make overlapping charts' patches agree with each other between the
    /// input's points, where both blends are at least 0.05 (0: none; relative to the data term)
    /// [default: 0.3 for new's plates from genus 17, whose charts barely overlap, with disk grids
    /// at least five times the grid; 0 otherwise; `fit` raises it to 3, then 30, where the
    /// surface crosses itself or only its patches are too far apart, unless λ is given with
    /// `--smoothness`: the fit's roughness, which that judges by, is then not measured]
    #[arg(long, value_name = "W", allow_negative_numbers = true, value_parser = parse_agreement)]
    agreement: Option<f64>,
}

impl FitArgs {
    /// The settings asked for at `genus`; the grid is `default_grid` where none was given, the
    /// disk charts' grid `default_disk_grid` of the grid (`None`: the grid), the smoothness
    /// weight `default_smoothness` of the grid and the agreement weight `default_agreement` of
    /// the grids. Grids too large for a fit are refused here
    /// ([`check_grid_size`]), before any work.
    fn settings(
        &self,
        genus: u32,
        default_grid: usize,
        default_disk_grid: impl Fn(usize) -> Option<usize>,
        default_smoothness: impl Fn(usize) -> f64,
        default_agreement: impl Fn(SplineSettings) -> f64,
    ) -> anyhow::Result<(SplineSettings, FitSettings)> {
        let grid = self.grid.map_or(default_grid, |g| g as usize);
        let disk_grid = self
            .disk_grid
            .map(|g| g as usize)
            .or_else(|| default_disk_grid(grid))
            .filter(|&d| d != grid);
        let spline = SplineSettings {
            degree: self.degree as usize,
            continuity: self.continuity as usize,
            grid,
            disk_grid,
        };
        check_grid_size(genus, &spline)?;
        let fit = FitSettings {
            smoothness: self
                .smoothness
                .unwrap_or_else(|| default_smoothness(spline.grid)),
            agreement: self.agreement.unwrap_or_else(|| default_agreement(spline)),
            ..FitSettings::default()
        };
        Ok((spline, fit))
    }
}

/// The most control points a fit is given: what the grids' old limits (64, and 512 for the disk
/// charts) made at genus 64. `--grid` now goes further for the few charts of low genus, not for
/// the 130 charts of genus 64, whose fit would take hours and many gigabytes.
const MAX_CONTROL_POINTS: usize = 1 << 20;

/// Refuses spline settings whose grids at `genus` hold more than [`MAX_CONTROL_POINTS`]: every
/// genus has two disk charts and 2·genus square ones.
fn check_grid_size(genus: u32, settings: &SplineSettings) -> anyhow::Result<()> {
    let disk = settings.disk_grid.unwrap_or(settings.grid);
    let count = 2 * disk * disk + 2 * genus as usize * settings.grid * settings.grid;
    if count > MAX_CONTROL_POINTS {
        anyhow::bail!(
            "a grid of {} ({} in the disk charts) at genus {genus} makes {count} control points, \
             more than the {MAX_CONTROL_POINTS} a fit takes; choose a coarser --grid or --disk-grid",
            settings.grid,
            disk
        );
    }
    Ok(())
}

/// The largest `--grid`: twice what `fit` gives a genus-0 mesh by default (a finer grid is what
/// brings a sphere's two charts closer to a detailed mesh), and beyond any grid the other genera
/// need (their disk charts have a grid of their own).
const MAX_GRID: u64 = 160;

/// The largest smoothness weight accepted: beyond it the least-squares system is the smoothness
/// term alone to f64 precision (λ = 1e308 overflowed into non-finite control points).
const MAX_SMOOTHNESS: f64 = 1e6;

/// A number as a weight option takes it (surrounding spaces allowed), or what it is not.
fn parse_number(s: &str) -> Result<f64, String> {
    s.trim()
        .parse()
        .map_err(|_| format!("{s:?} is not a number"))
}

/// λ: a number in (0, 1e6].
fn parse_smoothness(s: &str) -> Result<f64, String> {
    let v = parse_number(s)?;
    if v.is_finite() && v > 0.0 && v <= MAX_SMOOTHNESS {
        Ok(v)
    } else {
        Err(format!(
            "the smoothness weight must lie in (0, {MAX_SMOOTHNESS:e}], got {v}"
        ))
    }
}

/// The largest agreement weight `--agreement` takes: far past where it helps (at 10 genus 31's
/// peak curvature was worse than at 0.3), but still a well-posed system.
const MAX_AGREEMENT: f64 = 1e3;

fn parse_agreement(s: &str) -> Result<f64, String> {
    parse_weight(s, "the agreement weight", MAX_AGREEMENT)
}

/// A weight in [0, `max`] (0 turning its rows off), or why `s` is not one, naming `what`.
fn parse_weight(s: &str, what: &str, max: f64) -> Result<f64, String> {
    let v = parse_number(s)?;
    if v.is_finite() && (0.0..=max).contains(&v) {
        Ok(v)
    } else {
        Err(format!("{what} must lie in [0, {max:e}], got {v}"))
    }
}

/// Writes to stdout; a closed pipe (`ntori info | head`) is not an error.
fn write_stdout(text: &str) -> anyhow::Result<()> {
    use std::io::Write as _;
    let mut out = std::io::stdout().lock();
    match out.write_all(text.as_bytes()).and_then(|()| out.flush()) {
        Err(e) if e.kind() != std::io::ErrorKind::BrokenPipe => Err(e.into()),
        _ => Ok(()),
    }
}

/// A fit's progress on stderr: the stage and the time so far, and once the input's size is known
/// (the mesh is being flattened), an estimate of the whole fit where it is a long one.
pub struct FitProgress {
    bar: indicatif::ProgressBar,
    estimate: std::cell::Cell<Option<f64>>,
    /// The stage under way and when it began, so that `-v` logs how long each took.
    current: std::cell::RefCell<Option<(String, std::time::Instant)>>,
}

/// Fits estimated to take less than this (seconds) get no estimate: they are done before it helps.
const LONG_FIT_SECONDS: f64 = 10.0;

/// About how long a fit of `triangles` input triangles takes, in seconds: 1 s, 0.1 ms a triangle,
/// and a term in the square of the size (the map's sparse factorizations grow faster than the
/// mesh). Measured with release builds on the project's 2-core machine, `ntori new` with its
/// checks: genus 2, 10, 16 and 24 (11 k, 52 k, 115 k and 189 k triangles) took 1.8, 7.8, 29 and
/// 86 s (the rule: 2.3, 10.2, 32 and 73 s); `ntori fit` of a 20 k-triangle genus-4 mesh 7.0 s (3.7:
/// a user's mesh screens several markings); genus 64's 224 k triangles 308 s (98: it takes 23
/// factorizations where genus 2 takes 4). The rule is no closer than a factor of two or three.
pub fn estimated_fit_seconds(triangles: usize) -> f64 {
    let n = triangles as f64;
    1.0 + 1e-4 * n + 1.5e-9 * n * n
}

impl FitProgress {
    pub fn new(quiet: bool) -> FitProgress {
        let bar = spinner(quiet);
        if let Ok(style) = indicatif::ProgressStyle::with_template("{spinner} [{elapsed}] {msg}") {
            bar.set_style(style);
        }
        FitProgress {
            bar,
            estimate: std::cell::Cell::new(None),
            current: std::cell::RefCell::new(None),
        }
    }

    /// Shows what is being done (with the estimate, once there is one).
    pub fn stage(&self, stage: &str) {
        self.end_stage();
        *self.current.borrow_mut() = Some((stage.to_string(), std::time::Instant::now()));
        self.bar
            .set_message(stage_message(stage, self.estimate.get()));
        self.bar.tick();
    }

    /// A stage of the fit itself; flattening says how large the mesh is, which sets the estimate.
    pub fn fit_stage(&self, stage: embedding::fit::FitStage) {
        if let embedding::fit::FitStage::Flattening { triangles } = stage {
            let seconds = estimated_fit_seconds(triangles);
            self.estimate
                .set((seconds >= LONG_FIT_SECONDS).then_some(seconds));
        }
        self.stage(&stage.to_string());
    }

    pub fn finish(&self) {
        self.end_stage();
        self.bar.finish_and_clear();
    }

    /// Logs (at info, `-v`) how long the stage under way took.
    fn end_stage(&self) {
        if let Some((stage, began)) = self.current.borrow_mut().take() {
            let seconds = began.elapsed().as_secs_f64();
            tracing::info!(target: "ntori", "{stage}: {seconds:.2} s");
        }
    }
}

/// The progress line's text: the stage, and the estimate of the whole where there is one.
fn stage_message(stage: &str, estimate: Option<f64>) -> String {
    match estimate {
        Some(seconds) => format!("{stage} (the whole fit takes about {seconds:.0} s)"),
        None => stage.to_string(),
    }
}

/// A spinner on stderr, hidden when quiet or when stderr is not a terminal.
fn spinner(quiet: bool) -> indicatif::ProgressBar {
    if quiet || !std::io::IsTerminal::is_terminal(&std::io::stderr()) {
        indicatif::ProgressBar::hidden()
    } else {
        let bar = indicatif::ProgressBar::new_spinner();
        bar.enable_steady_tick(std::time::Duration::from_millis(120));
        bar
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_long_fit_shows_its_estimate_and_a_short_one_does_not() {
        assert_eq!(stage_message("fitting", None), "fitting");
        assert_eq!(
            stage_message("fitting", Some(36.4)),
            "fitting (the whole fit takes about 36 s)"
        );
        // The rule's own cut-off: genus 16's 115 384 triangles are long, the plate's 3170 are not.
        assert!(estimated_fit_seconds(115_384) >= LONG_FIT_SECONDS);
        assert!(estimated_fit_seconds(3170) < LONG_FIT_SECONDS);
        assert!(estimated_fit_seconds(2000) < estimated_fit_seconds(2001));
    }
}
