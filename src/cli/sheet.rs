use crate::detect::Target;
use crate::family::Family;
use crate::manifest::FamilyRef;
use crate::render::check::{check_sheet, check_sheet_png};
use crate::render::sheet::{family_markers, layout, legacy_markers, SheetSpec};
use crate::render::template::Template;
use crate::render::{encode_pages, write_all, Format};
use crate::units::Length;
use anyhow::{bail, Result};
use std::path::PathBuf;
use std::process::ExitCode;

/// Lay out markers on print pages; PDF gives one file, SVG and PNG one file
/// per page (name-1.svg, name-2.svg, ... when there is more than one page).
/// A manifest (name.json) records where each marker is.
#[derive(Debug, clap::Args)]
#[command(
    after_help = "Output: PDF is one file; SVG and PNG are one file per page, named NAME-1.svg, \
NAME-2.svg, ... when there is more than one page. NAME.json next to the output records every \
marker's ID, code, page and centre (mm from the page's top-left corner). Before writing, every \
page is rendered at 300 dpi and at a coarse resolution and each marker must read back as its \
own ID (--no-check skips this).\n\nExamples:\n  \
whycode sheet --bits 8 --distance 2 --ids 1-16 --diameter 40mm --template a4 -o swarm.pdf\n  \
whycode sheet --bits 12 --distance 3 --all --diameter 30mm --template letter -o set.svg\n  \
whycode sheet --legacy --count 6 --diameter 80mm -o whycon.pdf\n\n\
Without options: every ID of the 8-bit distance-2 family, 40 mm, on A4, written to swarm.pdf."
)]
pub struct SheetArgs {
    /// Code length of the family, in bits [default: 8]
    #[arg(long)]
    bits: Option<u32>,
    /// Minimum Hamming distance of the family
    #[arg(long, default_value_t = 2)]
    distance: u32,
    /// IDs to print: a list of IDs and ranges, e.g. 1-5,9,12-14 [default: every ID]
    #[arg(long, conflicts_with_all = ["all", "legacy"])]
    ids: Option<String>,
    /// Print every ID of the family (what happens without --ids)
    #[arg(long, conflicts_with_all = ["legacy", "ids"])]
    all: bool,
    /// Legacy WhyCon circles without IDs (with --count)
    #[arg(long, conflicts_with = "bits", requires = "count")]
    legacy: bool,
    /// Number of legacy WhyCon circles
    #[arg(long, requires = "legacy")]
    count: Option<usize>,
    /// Outer diameter of the black disc, with a unit (40mm, 4cm, 1.5in)
    #[arg(long, default_value = "40mm")]
    diameter: Length,
    /// Page template: a built-in name (see --list-templates) or a .toml file
    #[arg(long, default_value = "a4")]
    template: String,
    /// Resolution of PNG output, in dots per inch
    #[arg(long, default_value_t = 300.0)]
    dpi: f64,
    /// Skip the self-check that renders each page and reads every marker back
    #[arg(long)]
    no_check: bool,
    /// List the built-in templates and exit
    #[arg(long)]
    list_templates: bool,
    /// Output file: .pdf, .svg or .png
    #[arg(short, long, default_value = "swarm.pdf")]
    output: PathBuf,
}

pub fn run(args: SheetArgs) -> Result<ExitCode> {
    if args.list_templates {
        for t in Template::all_builtin() {
            println!(
                "{:<8} {:>6} x {:<6} mm  margin {} mm  {}",
                t.name,
                crate::units::trim_float(t.page_width_mm),
                crate::units::trim_float(t.page_height_mm),
                crate::units::trim_float(t.margin_mm),
                t.description
            );
        }
        return Ok(ExitCode::SUCCESS);
    }
    let output = args.output;
    let diameter = args.diameter.mm();
    let format = Format::from_path(&output)?;
    if format == Format::Png && !(args.dpi.is_finite() && (10.0..=1200.0).contains(&args.dpi)) {
        bail!("--dpi must be between 10 and 1200, got {}", args.dpi);
    }
    crate::render::check_output_dir(&output)?;
    let template = Template::resolve(&args.template)?;
    let mut target = Target::WhyCon;
    let (markers, family) = if args.legacy {
        let count = args.count.expect("clap requires --count with --legacy");
        if count == 0 || count > 100_000 {
            bail!("--count must be between 1 and 100000, got {count}");
        }
        (legacy_markers(count, diameter), None)
    } else {
        let bits = args.bits.unwrap_or(crate::family::DEFAULT_BITS);
        let family = Family::generate(bits, args.distance)?;
        let ids: Vec<u32> = match &args.ids {
            Some(list) => super::parse_id_list(list)?,
            None if family.len() > super::MAX_LISTED_IDS => bail!(
                "the {bits}-bit family with distance {} has {} IDs, too many to print at once; choose some with --ids (at most {})",
                args.distance,
                family.len(),
                super::MAX_LISTED_IDS
            ),
            None => (1..=family.len() as u32).collect(),
        };
        let markers = family_markers(&family, &ids, diameter)?;
        target = Target::WhyCode(family);
        (
            markers,
            Some(FamilyRef {
                bits,
                distance: args.distance,
            }),
        )
    };
    let name = output
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let spec = SheetSpec {
        markers,
        template,
        name: name.clone(),
        family,
        legacy: args.legacy,
    };
    let sheet = layout(&spec)?;
    if args.no_check {
        eprintln!("whycode: note: self-check skipped (--no-check): the markers were not read back before writing");
    } else {
        let report = if format == Format::Png {
            check_sheet_png(&sheet, &target, args.dpi)?
        } else {
            check_sheet(&sheet, &target)?
        };
        let dpis: Vec<String> = report.resolutions.iter().map(|d| format!("{d}")).collect();
        let what = if args.legacy {
            "found in place"
        } else {
            "read back as its own ID, upright,"
        };
        eprintln!(
            "whycode: self-check passed: every marker {what} at {} dpi",
            match dpis.split_last() {
                Some((last, rest)) if !rest.is_empty() => format!("{} and {last}", rest.join(", ")),
                _ => dpis.join(""),
            }
        );
    }
    let mut files = encode_pages(&sheet.pages, &output, &name, args.dpi)?;
    files.push((
        output.with_extension("json"),
        sheet.manifest.to_json().into_bytes(),
    ));
    write_all(&files)?;
    let written: Vec<String> = files.iter().map(|(p, _)| p.display().to_string()).collect();
    eprintln!(
        "whycode: {} markers on {} page{}: {}",
        sheet.manifest.markers.len(),
        sheet.pages.len(),
        if sheet.pages.len() == 1 { "" } else { "s" },
        written.join(", ")
    );
    Ok(ExitCode::SUCCESS)
}
