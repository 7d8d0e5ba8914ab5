use crate::family::Family;
use crate::geometry::Marker;
use crate::render::marker::{marker_label, marker_page, MarkerOptions, DEFAULT_LABEL_PT};
use crate::render::sheet::id_range_error;
use crate::render::{encode_pages, write_all, Format};
use crate::units::Length;
use anyhow::{bail, Result};
use std::path::PathBuf;
use std::process::ExitCode;

/// Render one marker; the format follows the output's extension (.svg, .pdf, .png).
#[derive(Debug, clap::Args)]
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
    /// Thin dashed circle at the edge of the white margin, to cut along
    #[arg(long)]
    cut_guide: bool,
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
    let (marker, title) = if args.legacy {
        (Marker::whycon(diameter), "WhyCon marker".to_string())
    } else {
        let bits = args.bits.expect("clap requires --bits without --legacy");
        let id = args.id.expect("clap requires --id without --legacy");
        let family = Family::generate(bits, args.distance)?;
        let Some(code) = family.code(id) else {
            bail!("{}", id_range_error(&family, id));
        };
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
    let files = encode_pages(std::slice::from_ref(&page), &args.output, &title, args.dpi)?;
    write_all(&files)?;
    Ok(ExitCode::SUCCESS)
}
