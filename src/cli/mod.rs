//! The `whycode` command line: argument parsing only; the work is done by
//! the library modules.

use clap::{Parser, Subcommand};
use std::process::ExitCode;

mod arena;
mod args;
mod calibrate;
mod detect;
mod ids;
mod marker;
mod output;
mod outputs;
mod sheet;
mod simulate;
mod stream;
mod validate;

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
    /// Calibrate a camera (intrinsics, lens distortion) from photos of a printed sheet
    Calibrate(calibrate::CalibrateArgs),
    /// Measure an arena's floor frame from four corner markers in one photo
    Arena(arena::ArenaArgs),
}

/// An interrupted run (Ctrl-C, `kill`, a closed terminal) removes the
/// temporary files its writes had staged before it ends: a signal does not
/// unwind, so their own clean-up would never run. Installed as the first
/// file is staged ([`whycode::io::before_first_staging`]): a command that
/// writes no file (a photo detected to the terminal) starts no thread for
/// it.
fn clean_up_on_signals() {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let Ok(mut signals) = signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) else {
        return;
    };
    std::thread::spawn(move || {
        if let Some(signal) = signals.forever().next() {
            whycode::io::remove_staged();
            std::process::exit(128 + signal);
        }
    });
}

/// Parses the command line and runs the subcommand.
pub fn main() -> ExitCode {
    whycode::io::before_first_staging(clean_up_on_signals);
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(err) => return usage_error(err),
    };
    // Every file the command reads is an input no output may replace,
    // the pages a manifest lists included, not only those its flags name.
    let _inputs = whycode::input::Recording::start();
    let result = match cli.command {
        Command::Ids(args) => ids::run(args),
        Command::Marker(args) => marker::run(args),
        Command::Sheet(args) => sheet::run(args),
        Command::Detect(args) => detect::run(args),
        Command::Validate(args) => validate::run(args),
        Command::Simulate(args) => simulate::run(args),
        Command::Calibrate(args) => calibrate::run(args),
        Command::Arena(args) => arena::run(args),
    };
    if whycode::io::stopping() {
        // A signal is ending the run: its handler removes the staged files
        // and exits with the signal's status; an error its clean-up caused
        // would only mislead.
        loop {
            std::thread::park();
        }
    }
    match result {
        Ok(code) => code,
        // The reader had what it wanted (`| head`): not a failure.
        Err(err) if err.is::<output::ReaderGone>() => ExitCode::SUCCESS,
        Err(err) => {
            output::error(one_line(&err));
            ExitCode::FAILURE
        }
    }
}

/// Help and version go out as clap writes them; a usage error becomes one
/// line like every other error, since clap's own message spans a usage block
/// and tips, which scripts and people scanning a log both read badly.
fn usage_error(err: clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    match err.kind() {
        ErrorKind::DisplayHelp | ErrorKind::DisplayVersion => err.exit(),
        // `whycode` alone: the help, as a failure. Not clap's usual 2:
        // `validate` exits 2 for "markers missing or misread", and a
        // mistyped command line must not read as a verdict.
        ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            let _ = err.print();
            return ExitCode::FAILURE;
        }
        _ => {}
    }
    let subcommand = std::env::args()
        .nth(1)
        .filter(|a| Cli::command_names().iter().any(|name| name == a));
    let help = match subcommand {
        Some(name) => format!("whycode {name} --help"),
        None => "whycode --help".to_string(),
    };
    output::error(format_args!(
        "{} (see '{help}')",
        one_line_usage(&err.render().to_string())
    ));
    ExitCode::FAILURE
}

/// Clap's message on one line: its first paragraph (the problem and the
/// arguments it names: missing, conflicting, or the possible values), joined
/// with ", ", plus a "did you mean" tip if there is one. The usage block and
/// the pointer to --help are left out.
fn one_line_usage(rendered: &str) -> String {
    let mut paragraphs = rendered.split("\n\n");
    let first: Vec<&str> = paragraphs
        .next()
        .unwrap_or_default()
        .lines()
        .map(str::trim)
        .filter(|line| !line.is_empty())
        .collect();
    let mut message = match first.split_first() {
        Some((head, rest)) => {
            let head = head.strip_prefix("error: ").unwrap_or(head);
            let rest = rest.join(", ");
            if rest.is_empty() {
                head.to_string()
            } else if rest.starts_with('[') || head.ends_with(':') {
                format!("{head} {rest}")
            } else {
                format!("{head}: {rest}")
            }
        }
        None => "invalid arguments".to_string(),
    };
    // Clap suggests "-- -5" for values that look like flags; every option
    // that takes a number already accepts a leading '-', so that tip only
    // misleads. "a similar argument exists" is worth keeping.
    for line in paragraphs.flat_map(str::lines).map(str::trim) {
        if let Some(tip) = line.strip_prefix("tip: ") {
            if tip.contains("similar") {
                message.push_str("; ");
                message.push_str(tip);
            }
        }
    }
    message
}

impl Cli {
    fn command_names() -> Vec<String> {
        use clap::CommandFactory;
        Cli::command()
            .get_subcommands()
            .map(|c| c.get_name().to_string())
            .collect()
    }
}

/// The one line the command line prints for an error: its causes joined.
/// A sheet manifest, with a warning when the page files beside it come
/// from another run than it does (`whycode::fileset`).
fn load_manifest(path: &std::path::Path) -> anyhow::Result<whycode::manifest::Manifest> {
    let manifest = whycode::manifest::Manifest::load(path)?;
    warn_if_mixed(&manifest, path);
    Ok(manifest)
}

fn warn_if_mixed(manifest: &whycode::manifest::Manifest, path: &std::path::Path) {
    if let Some(note) = manifest.mixed_set_note(path) {
        output::say(format_args!("warning: {note}"));
    }
}

pub fn one_line(err: &anyhow::Error) -> String {
    whycode::error::one_line(err.as_ref())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_subcommand_is_a_consistent_clap_definition() {
        use clap::CommandFactory;
        Cli::command().debug_assert();
    }

    #[test]
    fn clap_messages_keep_their_names_on_one_line() {
        let missing = "error: the following required arguments were not provided:\n  \
--diameter <DIAMETER>\n  --id <ID>\n\nUsage: whycode marker --diameter <DIAMETER>\n\n\
For more information, try '--help'.\n";
        assert_eq!(
            one_line_usage(missing),
            "the following required arguments were not provided: --diameter <DIAMETER>, --id <ID>"
        );
        let value = "error: invalid value 'xml' for '--format <FORMAT>'\n  \
[possible values: table, csv, json]\n\n  tip: a similar value exists: 'csv'\n\n\
For more information, try '--help'.\n";
        assert_eq!(
            one_line_usage(value),
            "invalid value 'xml' for '--format <FORMAT>' [possible values: table, csv, json]; \
a similar value exists: 'csv'"
        );
    }
}
