//! `whycode calibrate`: a camera's intrinsics and lens distortion from
//! photos of a printed sheet.

use super::args::{parse_scale, spec_error};
use super::output;
use anyhow::Result;
use clap::ValueEnum;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use whycode::calibrate::calibrate;
use whycode::camera::CalibrationFormat;
use whycode::spec::CalibrateSpec;

const AFTER_HELP: &str = "\
Photograph the printed sheet lying flat, 10-20 times: tilted 20-45° about \
different axes, from different sides, with the sheet reaching every corner of \
the image in some photo. Several pages of one manifest are fine (each is its \
own plane).

The output format follows the extension: .xml OpenCV XML, .yml OpenCV YAML, \
anything else ROS camera_info YAML (or --output-format). `whycode detect \
--camera` reads all three.

Example:
  whycode calibrate --manifest sheet.json photos/*.jpg -o camera.yaml";

#[derive(Debug, clap::Args)]
#[command(after_help = AFTER_HELP)]
pub struct CalibrateArgs {
    /// The manifest written with the sheet
    #[arg(long, value_name = "FILE")]
    manifest: PathBuf,
    /// Photos of the printed sheet, all from one camera at one resolution
    #[arg(required = true, value_name = "PHOTO")]
    photos: Vec<PathBuf>,
    /// The calibration file to write
    #[arg(long, short = 'o', value_name = "FILE")]
    output: PathBuf,
    /// Calibration file format [default: from the extension]
    #[arg(long, value_enum)]
    output_format: Option<FormatArg>,
    /// Camera name written into a ROS camera_info file
    #[arg(long, default_value = "camera")]
    camera_name: String,
    /// Hold the principal point at the image centre
    #[arg(long)]
    fix_principal_point: bool,
    /// Square pixels: fy = fx
    #[arg(long)]
    fix_aspect: bool,
    /// No tangential distortion (p1 = p2 = 0)
    #[arg(long)]
    no_tangential: bool,
    /// No sixth-order radial term (k3 = 0)
    #[arg(long)]
    no_k3: bool,
    /// The scale the printer applied, measured on the sheet's scale bar:
    /// 0.97 or 97% [default: 1]
    #[arg(long, value_parser = parse_scale, allow_hyphen_values = true)]
    print_scale: Option<f64>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum FormatArg {
    /// ROS camera_info YAML
    Ros,
    /// OpenCV FileStorage YAML
    OpencvYaml,
    /// OpenCV FileStorage XML
    OpencvXml,
}

pub fn run(args: CalibrateArgs) -> Result<ExitCode> {
    let options = CalibrateSpec {
        fix_principal_point: args.fix_principal_point,
        fix_aspect: args.fix_aspect,
        no_tangential: args.no_tangential,
        no_k3: args.no_k3,
        print_scale: args.print_scale,
    }
    .build()
    .map_err(spec_error)?;
    let manifest = super::load_manifest(&args.manifest)?;
    // After the manifest, so the pages it lists count as inputs too.
    let mut inputs: Vec<&Path> = args.photos.iter().map(PathBuf::as_path).collect();
    inputs.push(&args.manifest);
    whycode::io::check_outputs(&inputs, &[&args.output])?;
    let photos = args
        .photos
        .iter()
        .map(|path| {
            Ok((
                path.display().to_string(),
                whycode::image_io::load_gray(path)?,
            ))
        })
        .collect::<Result<Vec<_>>>()?;
    let calibration = calibrate(&manifest, &photos, &options)?;
    let format = match args.output_format {
        Some(FormatArg::Ros) => CalibrationFormat::RosYaml,
        Some(FormatArg::OpencvYaml) => CalibrationFormat::OpenCvYaml,
        Some(FormatArg::OpencvXml) => CalibrationFormat::OpenCvXml,
        None => CalibrationFormat::for_path(&args.output),
    };
    let text = calibration.camera.to_file_text(format, &args.camera_name);
    whycode::io::write_atomic(&args.output, text.as_bytes())?;
    output::print(&calibration.to_table())?;
    Ok(ExitCode::SUCCESS)
}
