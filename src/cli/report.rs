//! What the checking subcommands (`info`, `tessellate`, `new`) share: print the report as JSON or
//! text, and exit 3 if one of its checks failed.

use std::process::ExitCode;

use serde::Serialize;

use super::write_stdout;

/// The exit status of a command that ran but whose check failed.
pub const CHECK_FAILED: u8 = 3;

/// A subcommand's findings: serialised for `--json`, written out as text otherwise.
pub trait Report: Serialize {
    /// Whether every check passed.
    fn passed(&self) -> bool;
    /// The human-readable form.
    fn to_text(&self) -> String;
}

/// Prints `report` to stdout (pretty JSON if `json`, else its text) and gives the exit status:
/// success if it passed, [`CHECK_FAILED`] if not.
pub fn emit(report: &impl Report, json: bool) -> anyhow::Result<ExitCode> {
    let text = if json {
        serde_json::to_string_pretty(report)? + "\n"
    } else {
        report.to_text()
    };
    write_stdout(&text)?;
    Ok(if report.passed() {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(CHECK_FAILED)
    })
}
