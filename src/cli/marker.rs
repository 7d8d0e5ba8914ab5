use super::args::{print_error, whole_number, DpiArg, MarkerKindArgs};
use super::output;
use anyhow::Result;
use std::path::PathBuf;
use std::process::ExitCode;
use whycode::render::job::MarkerJob;
use whycode::render::write_all;
use whycode::units::Length;

/// Render one marker; the format follows the output's extension (.svg, .pdf, .png).
#[derive(Debug, clap::Args)]
#[command(
    after_help = "The page is the black disc plus its white margin, at exact size; the \
format follows the output's extension.\n\nExamples:\n  \
whycode marker --bits 8 --distance 2 --id 5 --diameter 50mm -o id5.pdf\n  \
whycode marker --bits 8 --id 5 --diameter 2in --dpi 600 -o id5.png\n  \
whycode marker --legacy --diameter 122mm -o whycon.svg"
)]
pub struct MarkerArgs {
    #[command(flatten)]
    kind: MarkerKindArgs,
    /// Marker ID within the family (from 1)
    #[arg(
        long,
        required_unless_present = "legacy",
        conflicts_with = "legacy",
        value_parser = whole_number,
        allow_hyphen_values = true
    )]
    id: Option<u32>,
    /// Outer diameter of the black disc, with a unit (50mm, 5cm, 2in)
    #[arg(long, allow_hyphen_values = true)]
    diameter: Length,
    /// White margin around the black disc (default and minimum: 0.3 x radius)
    #[arg(long, allow_hyphen_values = true)]
    margin: Option<Length>,
    #[command(flatten)]
    dpi: DpiArg,
    /// Thin grey cross in the white centre, for aligning the marker
    #[arg(long)]
    cross: bool,
    /// Thin dashed circle just outside the white margin, to cut along
    #[arg(long)]
    cut_guide: bool,
    /// Skip reading the marker back from a rendering before writing it
    #[arg(long)]
    no_check: bool,
    /// Print a label (ID, family, diameter) under the marker
    #[arg(long)]
    label: bool,
    /// Output file: .svg, .pdf or .png
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
}

pub fn run(args: MarkerArgs) -> Result<ExitCode> {
    whycode::render::check_output_dir(&args.output)?;
    let target = args.kind.resolve()?;
    let job = MarkerJob {
        family: target.family(),
        id: args.id,
        diameter_mm: args.diameter.mm(),
        margin_mm: args.margin.map(Length::mm),
        cross: args.cross,
        cut_guide: args.cut_guide,
        label: args.label,
        dpi: args.dpi.dpi,
        self_check: !args.no_check,
    };
    let (files, check) = job.print(&args.output).map_err(print_error)?;
    if check.is_none() {
        output::note(
            "self-check skipped (--no-check): the marker was not read back before writing",
        );
    }
    let inputs: Vec<&std::path::Path> = args.kind.family.family.as_deref().into_iter().collect();
    let outputs: Vec<&std::path::Path> = files.iter().map(|(p, _)| p.as_path()).collect();
    whycode::io::check_outputs(&inputs, &outputs)?;
    write_all(&files)?;
    output::say(format_args!(
        "wrote {}",
        outputs
            .iter()
            .map(|p| p.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    ));
    Ok(ExitCode::SUCCESS)
}
