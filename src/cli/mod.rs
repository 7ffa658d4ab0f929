//! The `ntori` command line: the parser, one module per subcommand, and what they share.

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod bench;
mod edit;
mod export;
mod figures;
mod info;
mod new;
mod render;
mod report;
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
    Edit(edit::Args),
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
        Command::Edit(args) => edit::run(args),
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
