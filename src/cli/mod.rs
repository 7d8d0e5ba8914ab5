//! The `whycode` command line: argument parsing only; the work is done by
//! the library modules.

use clap::{Parser, Subcommand};
use std::process::ExitCode;

pub mod detect;
pub mod ids;
pub mod marker;
pub mod sheet;
pub mod simulate;
pub mod validate;

#[derive(Debug, Parser)]
#[command(
    name = "whycode",
    version,
    about = "WhyCode circular fiducial markers: ID tables, print sheets, detection and validation"
)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// List a family's IDs and codes, or the count matrix over bit lengths and distances
    Ids(ids::IdsArgs),
    /// Render one marker as SVG, PDF or PNG at an exact physical size
    Marker(marker::MarkerArgs),
    /// Lay out many markers on print pages (PDF, SVG or PNG) with a manifest
    Sheet(sheet::SheetArgs),
    /// Find markers in images, decode IDs and yaw, estimate pose
    Detect(detect::DetectArgs),
    /// Check photos of printed sheets against the sheet manifest
    Validate(validate::ValidateArgs),
    /// Render what a camera would see of markers or sheets, with ground truth
    Simulate(simulate::SimulateArgs),
}

/// Parses the command line and runs the subcommand.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Ids(args) => ids::run(args),
        Command::Marker(args) => marker::run(args),
        Command::Sheet(args) => sheet::run(args),
        Command::Detect(args) => detect::run(args),
        Command::Validate(args) => validate::run(args),
        Command::Simulate(args) => simulate::run(args),
    };
    match result {
        Ok(code) => code,
        Err(err) => {
            eprintln!("whycode: error: {}", one_line(&err));
            ExitCode::FAILURE
        }
    }
}

/// The error's context chain joined with ": " on one line. Causes whose text
/// their parent already quotes (image decoding errors do) are left out.
pub(crate) fn one_line(err: &anyhow::Error) -> String {
    let mut parts: Vec<String> = Vec::new();
    for cause in err.chain() {
        let text = cause.to_string().split_whitespace().collect::<Vec<_>>().join(" ");
        if text.is_empty() || parts.last().is_some_and(|p| p.contains(&text)) {
            continue;
        }
        parts.push(text);
    }
    parts.join(": ")
}
