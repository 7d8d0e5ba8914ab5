use super::args::{print_error, whole_number, DpiArg, MarkerKindArgs};
use super::output;
use anyhow::{Context, Result};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use whycode::family::parse_id_list;
use whycode::render::job::SheetJob;
use whycode::render::template::Template;
use whycode::render::write_all;
use whycode::units::Length;

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
    #[command(flatten)]
    kind: MarkerKindArgs,
    /// IDs to print: a list of IDs and ranges, e.g. 1-5,9,12-14 [default: every ID]
    #[arg(long, conflicts_with_all = ["all", "legacy"])]
    ids: Option<String>,
    /// Print every ID of the family (what happens without --ids)
    #[arg(long, conflicts_with_all = ["legacy", "ids"])]
    all: bool,
    /// Number of legacy WhyCon circles (with --legacy)
    #[arg(
        long,
        requires = "legacy",
        required_if_eq("legacy", "true"),
        value_parser = whole_number,
        allow_hyphen_values = true
    )]
    count: Option<u32>,
    /// Outer diameter of the black disc, with a unit (40mm, 4cm, 1.5in)
    #[arg(long, default_value = "40mm", allow_hyphen_values = true)]
    diameter: Length,
    /// Page template: a built-in name (see --list-templates) or a .toml file
    #[arg(long, default_value = "a4")]
    template: String,
    #[command(flatten)]
    dpi: DpiArg,
    /// Skip the self-check that renders each page and reads every marker back
    #[arg(long)]
    no_check: bool,
    /// List the built-in templates and exit
    #[arg(long)]
    list_templates: bool,
    /// Output file: .pdf, .svg or .png
    #[arg(short, long, value_name = "FILE", default_value = "swarm.pdf")]
    output: PathBuf,
}

/// Page files beside `output` that an earlier run of the same sheet wrote
/// and this run does not: the pages past the new count, as the manifest
/// about to be replaced lists them (and only those: nothing is guessed
/// from names alone). Where that manifest kept its pages' digests, a page
/// someone has since replaced with a file of their own is left alone.
fn stale_pages(output: &Path, files: &[(PathBuf, Vec<u8>)]) -> Vec<PathBuf> {
    let manifest = output.with_extension("json");
    // The old manifest is an output about to be replaced, not an input.
    let Ok(old) = whycode::input::unrecorded(|| whycode::manifest::Manifest::load(&manifest))
    else {
        return Vec::new();
    };
    let new: Vec<&PathBuf> = files.iter().map(|(p, _)| p).collect();
    let changed = whycode::fileset::mismatched(&manifest, &old.files);
    whycode::render::page_paths(output, old.pages as usize)
        .into_iter()
        .filter(|page| !new.contains(&page) && page.is_file())
        .filter(|page| {
            let name = page.file_name().map(|n| n.to_string_lossy().into_owned());
            !changed.iter().any(|c| Some(c) == name.as_ref())
        })
        .collect()
}

pub fn run(args: SheetArgs) -> Result<ExitCode> {
    if args.list_templates {
        let mut list = String::new();
        for t in Template::all_builtin() {
            list.push_str(&format!(
                "{:<8} {:>6} x {:<6} mm  margin {} mm  {}\n",
                t.name,
                whycode::units::trim_float(t.page_width_mm),
                whycode::units::trim_float(t.page_height_mm),
                whycode::units::trim_float(t.margin_mm),
                t.description
            ));
        }
        output::print(&list)?;
        return Ok(ExitCode::SUCCESS);
    }
    whycode::render::check_output_dir(&args.output)?;
    let inputs: Vec<&Path> = args.kind.family.family.as_deref().into_iter().collect();
    // Checked before the work with the names known now, and again with every
    // page's name once the pages are counted.
    whycode::io::check_outputs(
        &inputs,
        &[&args.output, &args.output.with_extension("json")],
    )?;
    let target = args.kind.resolve()?;
    let ids = args
        .ids
        .as_deref()
        .map(parse_id_list)
        .transpose()
        .context("--ids")?;
    let job = SheetJob {
        family: target.family(),
        ids,
        count: args.count.map(|c| c as usize),
        diameter_mm: args.diameter.mm(),
        template: Template::resolve(&args.template)?,
        name: args
            .output
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        dpi: args.dpi.dpi,
        self_check: !args.no_check,
    };
    let printed = job.print(&args.output).map_err(print_error)?;
    match &printed.check {
        Some(report) => output::say(format_args!("self-check passed: {}", report.summary())),
        None => output::note(
            "self-check skipped (--no-check): the markers were not read back before writing",
        ),
    }
    let summary = printed.summary();
    let files = printed.into_files();
    let outputs: Vec<&Path> = files.iter().map(|(p, _)| p.as_path()).collect();
    whycode::io::check_outputs(&inputs, &outputs)?;
    let stale = stale_pages(&args.output, &files);
    write_all(&files)?;
    // Pages of an earlier, longer run of this sheet would read as part of
    // the new one; the new manifest is in place, so they go.
    for page in stale {
        std::fs::remove_file(&page)
            .with_context(|| format!("{}: cannot remove the stale page", page.display()))?;
    }
    let written: Vec<String> = files.iter().map(|(p, _)| p.display().to_string()).collect();
    output::say(format_args!("{summary}: {}", written.join(", ")));
    Ok(ExitCode::SUCCESS)
}
