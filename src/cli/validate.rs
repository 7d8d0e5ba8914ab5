//! `whycode validate`: check photos of printed sheets against the manifest.

use super::output;
use anyhow::{Context, Result};
use clap::ValueEnum;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use whycode::camera::Camera;
use whycode::validate::{self, annotate};

/// Exit status when the check ran but the sheet has problems.
const PROBLEMS: u8 = 2;

#[derive(Debug, clap::Args)]
#[command(
    after_help = "Exit status: 0 when every printed marker was found reading as its \
own ID and no page is printed at a wrong scale; 2 when a marker is missing, misread or \
unidentified, or a page's scale is off by more than 1 %; 1 on errors. The printed scale is \
measured against the paper's edges: keep the whole sheet, with some background around it, \
in the photo (otherwise the scale is reported as unknown)."
)]
pub struct ValidateArgs {
    /// The manifest written with the sheet
    #[arg(long, value_name = "FILE")]
    manifest: PathBuf,
    /// Photos of the printed pages (PNG, JPEG, PGM, BMP)
    #[arg(required = true, value_name = "PHOTO")]
    photos: Vec<PathBuf>,
    /// Camera calibration (ROS camera_info or OpenCV YAML): removes lens distortion
    #[arg(long, value_name = "FILE")]
    camera: Option<PathBuf>,
    /// Write an annotated copy of each photo into this folder
    #[arg(long, value_name = "DIR")]
    annotate: Option<PathBuf>,
    /// Report format on standard output
    #[arg(long, short = 'f', value_enum, default_value_t = Format::Table)]
    format: Format,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum Format {
    Table,
    Json,
}

pub fn run(args: ValidateArgs) -> Result<ExitCode> {
    let manifest = super::load_manifest(&args.manifest)?;
    let mut detector =
        validate::detector_for(&manifest).with_context(|| args.manifest.display().to_string())?;
    let camera = args.camera.as_deref().map(Camera::load).transpose()?;
    if let Some(dir) = &args.annotate {
        std::fs::create_dir_all(dir)
            .with_context(|| format!("cannot create folder {}", dir.display()))?;
    }
    let mut photos = Vec::new();
    let annotation_names: std::collections::HashMap<PathBuf, PathBuf> = match &args.annotate {
        Some(dir) => whycode::io::annotation_paths(dir, &args.photos)
            .into_iter()
            .collect(),
        None => Default::default(),
    };
    for path in &args.photos {
        let image = whycode::image_io::load_gray(path)?;
        let cam = camera
            .as_ref()
            .map(|c| c.for_image(image.width(), image.height()))
            .transpose()
            .map_err(|problem| anyhow::anyhow!("{}: {problem}", path.display()))?;
        let name = path.display().to_string();
        let report = validate::check_image(&name, &manifest, &image, cam.as_ref(), &mut detector);
        if let Some(out) = annotation_names.get(path) {
            save_rgb(out, &annotate::annotate(&image, &report))?;
        }
        photos.push(report);
    }
    let report = validate::summarise(&manifest, photos);
    match args.format {
        Format::Table => output::print(&report.to_table())?,
        Format::Json => output::print(&report.to_json())?,
    }
    Ok(if report.ok {
        ExitCode::SUCCESS
    } else {
        ExitCode::from(PROBLEMS)
    })
}

fn save_rgb(path: &Path, picture: &image::RgbImage) -> Result<()> {
    let bytes = whycode::image_io::encode_rgb_png(picture)
        .map_err(|e| anyhow::anyhow!("cannot encode {}: {e}", path.display()))?;
    Ok(whycode::io::write_atomic(path, &bytes)?)
}
