//! The `ntori` command line: see [`cli`] for the subcommands.

use std::process::ExitCode;

use clap::Parser as _;

mod cli;

fn main() -> ExitCode {
    quiet_wayland_probe();
    let cli = cli::Cli::parse();
    init_logging(cli.verbose);
    match cli::run(cli) {
        Ok(code) => code,
        Err(err) => {
            eprintln!("ntori: error: {}", message(&err));
            ExitCode::FAILURE
        }
    }
}

/// Mesa's Vulkan device-select layer probes for a Wayland compositor whenever an adapter is
/// requested, and libwayland prints "error: XDG_RUNTIME_DIR is invalid or not set" to stderr
/// where there is no runtime directory (even under `-q`, since it is C code writing directly).
/// Without a runtime directory (and no absolute WAYLAND_DISPLAY) that probe cannot succeed, so the
/// layer is switched off with its documented variable, NODEVICE_SELECT; wgpu picks the adapter
/// itself either way.
fn quiet_wayland_probe() {
    let runtime_dir_usable = std::env::var_os("XDG_RUNTIME_DIR").is_some_and(|d| {
        std::path::Path::new(&d).is_absolute() && std::path::Path::new(&d).is_dir()
    });
    let absolute_display =
        std::env::var_os("WAYLAND_DISPLAY").is_some_and(|d| std::path::Path::new(&d).is_absolute());
    if !runtime_dir_usable && !absolute_display && std::env::var_os("NODEVICE_SELECT").is_none() {
        // SAFETY: the first thing main does, before any thread exists, so nothing reads the
        // environment concurrently.
        unsafe { std::env::set_var("NODEVICE_SELECT", "1") };
    }
}

/// The error and its causes on one line, each cause said once: many errors quote their source in
/// their own message (so a library error reads well alone), and anyhow's `{:#}` would repeat it.
fn message(err: &anyhow::Error) -> String {
    let mut text = err.to_string();
    for cause in err.chain().skip(1) {
        let cause = cause.to_string();
        if !text.contains(&cause) {
            text.push_str(": ");
            text.push_str(&cause);
        }
    }
    text
}

/// Logs to stderr: warnings by default, more with -v or -vv; RUST_LOG overrides.
fn init_logging(verbose: u8) {
    let default = match verbose {
        0 => "warn",
        1 => "info",
        _ => "debug",
    };
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new(default));
    // Colour codes only for a terminal: in a log file or a pipe they are noise.
    let ansi = std::io::IsTerminal::is_terminal(&std::io::stderr());
    tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .with_ansi(ansi)
        .init();
}
