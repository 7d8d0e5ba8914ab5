use super::args::{whole_number, DpiArg, MarkerKindArgs};
use anyhow::{bail, Result};
use std::path::PathBuf;
use std::process::ExitCode;
use whycode::geometry::Marker;
use whycode::render::check::check_marker_page;
use whycode::render::marker::{marker_label, marker_page, MarkerOptions, DEFAULT_LABEL_PT};
use whycode::render::sheet::id_range_error;
use whycode::render::{encode_pages, write_all, Format};
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
    let format = Format::from_path(&args.output)?;
    let dpi = args.dpi.dpi;
    whycode::render::check_output_dir(&args.output)?;
    let diameter = args.diameter.mm();
    let target = args.kind.resolve()?;
    let family = target.family();
    let marker = match &family {
        None => Marker::whycon(diameter),
        Some(family) => {
            let id = args.id.expect("clap requires --id without --legacy");
            let Some(code) = family.code(id) else {
                bail!("{}", id_range_error(family, id));
            };
            Marker::whycode(family.bits(), code, diameter)
        }
    };
    let title = match &family {
        None => "WhyCon marker".to_string(),
        Some(family) => format!(
            "WhyCode {}-bit d{} ID {}",
            family.bits(),
            family.distance(),
            args.id.unwrap_or(0)
        ),
    };
    let label = args.label.then(|| match &family {
        None => marker_label(&marker, None, None),
        Some(family) => marker_label(&marker, args.id, Some(family.distance())),
    });
    let options = MarkerOptions {
        margin_mm: args.margin.map(Length::mm),
        cross: args.cross,
        cut_guide: args.cut_guide,
        label,
        // Larger markers are looked at from further away: grow the label with them.
        label_size_pt: (diameter / 8.0).clamp(DEFAULT_LABEL_PT, 14.0),
    };
    let page = marker_page(&marker, &options)?;
    if args.no_check {
        eprintln!("whycode: note: self-check skipped (--no-check): the marker was not read back before writing");
    } else {
        let png_dpi = (format == Format::Png).then_some(dpi);
        check_marker_page(&page, &marker, args.id.unwrap_or(0), &target, png_dpi)?;
    }
    let files = encode_pages(std::slice::from_ref(&page), &args.output, &title, dpi)?;
    write_all(&files)?;
    Ok(ExitCode::SUCCESS)
}
