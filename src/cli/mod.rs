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
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(err) => return usage_error(err),
    };
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

/// Help and version go out as clap writes them; a usage error becomes one
/// line like every other error, since clap's own message spans a usage block
/// and tips, which scripts and people scanning a log both read badly.
fn usage_error(err: clap::Error) -> ExitCode {
    use clap::error::ErrorKind;
    if matches!(
        err.kind(),
        ErrorKind::DisplayHelp
            | ErrorKind::DisplayVersion
            | ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand
    ) {
        err.exit();
    }
    let rendered = err.render().to_string();
    let first = rendered.lines().next().unwrap_or("invalid arguments");
    let message = first.strip_prefix("error: ").unwrap_or(first);
    let subcommand = std::env::args()
        .nth(1)
        .filter(|a| Cli::command_names().iter().any(|name| name == a));
    let help = match subcommand {
        Some(name) => format!("whycode {name} --help"),
        None => "whycode --help".to_string(),
    };
    eprintln!("whycode: error: {message} (see '{help}')");
    // Not clap's usual 2: `validate` exits 2 for "markers missing or
    // misread", and a mistyped option must not read as a verdict.
    ExitCode::FAILURE
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

/// Most IDs one list may name: a sheet or scene of this many is already far
/// beyond any swarm, and the bound keeps `1-4000000000` from filling memory.
pub(crate) const MAX_LISTED_IDS: usize = 100_000;

/// Parses `--ids` lists like "1-5,9, 12-14" in the order written. An ID
/// named twice is refused: a sheet printing it twice would make the
/// manifest's marker-to-ID match, and so validation, ambiguous.
pub(crate) fn parse_id_list(text: &str) -> anyhow::Result<Vec<u32>> {
    use anyhow::bail;
    let mut ids = Vec::new();
    for part in text.split(',').map(str::trim).filter(|p| !p.is_empty()) {
        let parse = |s: &str| -> anyhow::Result<u32> {
            match s.trim().parse::<u32>() {
                Ok(0) => {
                    bail!("--ids: '{part}' names ID 0, which means \"unknown\"; IDs start at 1")
                }
                Ok(id) => Ok(id),
                Err(_) => bail!("--ids: '{part}' is not an ID or a range like 3-7"),
            }
        };
        match part.split_once('-') {
            Some((a, b)) => {
                let (a, b) = (parse(a)?, parse(b)?);
                if a > b {
                    bail!("--ids: range '{part}' runs backwards");
                }
                if (b - a) as usize >= MAX_LISTED_IDS {
                    bail!("--ids: range '{part}' names more than {MAX_LISTED_IDS} IDs");
                }
                ids.extend(a..=b);
            }
            None => ids.push(parse(part)?),
        }
        if ids.len() > MAX_LISTED_IDS {
            bail!("--ids: the list names more than {MAX_LISTED_IDS} IDs");
        }
    }
    if ids.is_empty() {
        bail!("--ids: no IDs given");
    }
    let mut sorted = ids.clone();
    sorted.sort_unstable();
    if let Some(pair) = sorted.windows(2).find(|w| w[0] == w[1]) {
        bail!("--ids: ID {} is listed more than once", pair[0]);
    }
    Ok(ids)
}

/// The error's context chain joined with ": " on one line. Causes whose text
/// their parent already quotes (image decoding errors do) are left out.
pub(crate) fn one_line(err: &anyhow::Error) -> String {
    let mut parts: Vec<String> = Vec::new();
    for cause in err.chain() {
        let text = cause
            .to_string()
            .split_whitespace()
            .collect::<Vec<_>>()
            .join(" ");
        if text.is_empty() || parts.last().is_some_and(|p| p.contains(&text)) {
            continue;
        }
        parts.push(text);
    }
    parts.join(": ")
}

#[cfg(test)]
mod tests {
    use super::parse_id_list;

    #[test]
    fn id_lists_take_ranges_and_single_ids_in_order() {
        assert_eq!(
            parse_id_list("1-5,9, 12-14").unwrap(),
            [1, 2, 3, 4, 5, 9, 12, 13, 14]
        );
        assert_eq!(parse_id_list("7,2").unwrap(), [7, 2]);
    }

    #[test]
    fn bad_id_lists_get_plain_messages() {
        let error = |text: &str| format!("{:#}", parse_id_list(text).unwrap_err());
        assert!(error("5-3").contains("backwards"));
        assert_eq!(error("1,x"), "--ids: 'x' is not an ID or a range like 3-7");
        assert!(error("-3").contains("'-3' is not an ID"));
        assert!(error("0").contains("IDs start at 1"));
        assert!(error("1-3,2").contains("ID 2 is listed more than once"));
        assert!(error("1-4000000000").contains("more than 100000 IDs"));
        assert!(error(" , ").contains("no IDs given"));
    }
}
