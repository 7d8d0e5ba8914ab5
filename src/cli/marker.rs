use crate::detect::Target;
use crate::family::Family;
use crate::geometry::Marker;
use crate::render::check::check_marker_page;
use crate::render::marker::{marker_label, marker_page, MarkerOptions, DEFAULT_LABEL_PT};
use crate::render::sheet::id_range_error;
use crate::render::{encode_pages, write_all, Format};
use crate::units::Length;
use anyhow::{bail, Result};
use std::path::PathBuf;
use std::process::ExitCode;

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
    /// Code length of the family, in bits
    #[arg(long, required_unless_present = "legacy")]
    bits: Option<u32>,
    /// Minimum Hamming distance of the family
    #[arg(long, default_value_t = 2)]
    distance: u32,
    /// Marker ID within the family (from 1)
    #[arg(long, required_unless_present = "legacy", conflicts_with = "legacy")]
    id: Option<u32>,
    /// Legacy WhyCon circle without an ID ring
    #[arg(long, conflicts_with = "bits")]
    legacy: bool,
    /// Outer diameter of the black disc, with a unit (50mm, 5cm, 2in)
    #[arg(long)]
    diameter: Length,
    /// White margin around the black disc (default and minimum: 0.3 x radius)
    #[arg(long)]
    margin: Option<Length>,
    /// Resolution of PNG output, in dots per inch
    #[arg(long, default_value_t = 300.0)]
    dpi: f64,
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
    #[arg(short, long)]
    output: PathBuf,
}

pub fn run(args: MarkerArgs) -> Result<ExitCode> {
    let format = Format::from_path(&args.output)?;
    if format == Format::Png && !(args.dpi.is_finite() && (10.0..=4800.0).contains(&args.dpi)) {
        bail!("--dpi must be between 10 and 4800, got {}", args.dpi);
    }
    crate::render::check_output_dir(&args.output)?;
    let diameter = args.diameter.mm();
    let mut target = Target::WhyCon;
    let (marker, title) = if args.legacy {
        (Marker::whycon(diameter), "WhyCon marker".to_string())
    } else {
        let bits = args.bits.expect("clap requires --bits without --legacy");
        let id = args.id.expect("clap requires --id without --legacy");
        let family_of_id = Family::generate(bits, args.distance)?;
        let Some(code) = family_of_id.code(id) else {
            bail!("{}", id_range_error(&family_of_id, id));
        };
        target = Target::WhyCode(family_of_id);
        (
            Marker::whycode(bits, code, diameter),
            format!("WhyCode {bits}-bit d{} ID {id}", args.distance),
        )
    };
    let label = args.label.then(|| {
        if args.legacy {
            marker_label(&marker, None, None)
        } else {
            marker_label(&marker, args.id, Some(args.distance))
        }
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
        let png_dpi = (format == Format::Png).then_some(args.dpi);
        check_marker_page(&page, &marker, args.id.unwrap_or(0), &target, png_dpi)?;
    }
    let files = encode_pages(std::slice::from_ref(&page), &args.output, &title, args.dpi)?;
    write_all(&files)?;
    Ok(ExitCode::SUCCESS)
}
