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

/// A genus: a whole number 0 or more. (Above 64 the charts say "not supported" with the limit;
/// clap's own u32 parser would answer -1 with the range 0..=4294967295.)
fn parse_genus(s: &str) -> Result<u32, String> {
    let max = charts::MAX_GENUS;
    match s.trim().parse::<i64>() {
        Ok(n) if n < 0 => Err(format!("a genus is 0 or more (0 to {max}), got {n}")),
        Ok(n) => u32::try_from(n).map_err(|_| format!("genus {n} is not supported (0 to {max})")),
        Err(_) => Err(format!(
            "a genus is a whole number from 0 to {max}, got {s:?}"
        )),
    }
}

/// The spline and the fit's weight, as `new` and `fit` take them.
#[derive(clap::Args, Debug, Clone, Copy)]
struct FitArgs {
    /// Control points per side of each chart's grid [default: 32 for new and fit --cage, 20 for fit: a user's
    /// mesh is often coarser than the plates, and a grid finer than the data overfits it]
    #[arg(long, value_name = "G", value_parser = clap::value_parser!(u64).range(4..=64))]
    grid: Option<u64>,
    /// Spline degree.
    #[arg(long, default_value_t = SplineSettings::default().degree as u64, value_name = "P",
          value_parser = clap::value_parser!(u64).range(1..=7))]
    degree: u64,
    /// Continuity order of the blend functions (1 to 4).
    #[arg(long, default_value_t = SplineSettings::default().continuity as u64, value_name = "K",
          value_parser = clap::value_parser!(u64).range(1..=4))]
    continuity: u64,
    /// Weight λ of the control grids' smoothness energy in the fit (relative to the data term).
    #[arg(long, default_value_t = FitSettings::default().smoothness, value_name = "λ",
          value_parser = parse_smoothness)]
    smoothness: f64,
}

impl FitArgs {
    /// The settings asked for; the grid is `default_grid` where none was given.
    fn settings(&self, default_grid: usize) -> (SplineSettings, FitSettings) {
        let spline = SplineSettings {
            degree: self.degree as usize,
            continuity: self.continuity as usize,
            grid: self.grid.map_or(default_grid, |g| g as usize),
        };
        let fit = FitSettings {
            smoothness: self.smoothness,
            ..FitSettings::default()
        };
        (spline, fit)
    }
}

/// The largest smoothness weight accepted: beyond it the least-squares system is the smoothness
/// term alone to f64 precision (λ = 1e308 overflowed into non-finite control points).
const MAX_SMOOTHNESS: f64 = 1e6;

/// λ: a number in (0, 1e6].
fn parse_smoothness(s: &str) -> Result<f64, String> {
    let v: f64 = s
        .trim()
        .parse()
        .map_err(|_| format!("{s:?} is not a number"))?;
    if v.is_finite() && v > 0.0 && v <= MAX_SMOOTHNESS {
        Ok(v)
    } else {
        Err(format!(
            "the smoothness weight must lie in (0, {MAX_SMOOTHNESS:e}], got {v}"
        ))
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
