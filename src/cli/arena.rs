//! `whycode arena`: a floor frame from four corner markers in one photo.

use super::args::{spec_error, whole_number, MarkerKindArgs};
use super::output;
use anyhow::{Context, Result};
use std::path::PathBuf;
use std::process::ExitCode;
use whycode::arena::Mapping;
use whycode::camera::Camera;
use whycode::spec::ArenaSpec;
use whycode::units::Length;

const AFTER_HELP: &str = "\
Lay four markers at the corners of a rectangle on the floor and photograph \
them with the camera that will watch the arena. The corners, in --ids order: \
the origin, the corner along +x, the far corner, the corner along +y (z is \
up, so seen from above they run counter-clockwise). Without --ids the four \
outermost markers are the corners, as the original WhyCon picks them: the \
lowest-left in the image is the origin, x runs right and y up the image.

With --camera (a calibration, e.g. from `whycode calibrate`) the arena file \
holds the floor's pose in that camera's frame: lens distortion is removed and \
markers above the floor (--marker-height) are placed in 3D. Without it, a \
plane-to-image map of the floor that ignores the lens.

Examples:
  whycode arena --ids 1,2,3,4 --size 2m,1.5m --camera camera.yaml floor.png -o arena.yaml
  whycode detect --arena arena.yaml --diameter 8cm --format json frames/";

#[derive(Debug, clap::Args)]
#[command(after_help = AFTER_HELP)]
pub struct ArenaArgs {
    /// A photo of the four corner markers, from the camera's working place
    #[arg(value_name = "PHOTO")]
    photo: PathBuf,
    /// The arena file to write (YAML)
    #[arg(long, short = 'o', value_name = "FILE")]
    output: PathBuf,
    /// The corners' IDs: origin, +x corner, far corner, +y corner
    /// [default: the four outermost markers]
    #[arg(long, value_name = "A,B,C,D", value_parser = whole_number, value_delimiter = ',')]
    ids: Option<Vec<u32>>,
    /// The rectangle's sides along x and along y: 2m,1.5m (bare numbers
    /// are metres)
    #[arg(long, value_name = "X,Y", value_parser = Length::parse_metres, value_delimiter = ',', required = true)]
    size: Vec<Length>,
    /// The calibrated camera that took the photo (ROS or OpenCV YAML/XML)
    #[arg(long, value_name = "FILE")]
    camera: Option<PathBuf>,
    /// Height above the floor of the markers `detect` will locate (on
    /// robots): 0.12 (metres), 12cm [default: 0, on the floor]; needs
    /// --camera
    #[arg(long, value_name = "LENGTH", value_parser = Length::parse_height, allow_hyphen_values = true)]
    marker_height: Option<Length>,
    #[command(flatten)]
    kind: MarkerKindArgs,
}

pub fn run(args: ArenaArgs) -> Result<ExitCode> {
    let size = match args.size.as_slice() {
        &[x, y] => [x, y],
        other => anyhow::bail!(
            "--size: give two sides, along x and along y (2m,1.5m), not {}",
            other.len()
        ),
    };
    let options = ArenaSpec {
        target: args.kind.spec()?,
        ids: args.ids.clone(),
        size: Some(size),
        camera: args.camera.as_deref().map(Camera::load).transpose()?,
        marker_height: args.marker_height,
    }
    .build()
    .map_err(spec_error)?;
    let mut inputs = vec![args.photo.as_path()];
    inputs.extend(args.camera.as_deref());
    whycode::io::check_outputs(&inputs, &[&args.output])?;
    let image = whycode::image_io::load_gray(&args.photo)?;
    let arena = options
        .measure(&image)
        .with_context(|| args.photo.display().to_string())?;
    whycode::io::write_atomic(&args.output, arena.to_yaml().as_bytes())?;
    let ids = arena.ids.map(|id| id.to_string()).join(", ");
    let how = match &arena.mapping {
        Mapping::Floor { translation, .. } => format!(
            "floor origin {:.3} m from the camera; worst corner {:.2} mm off the rectangle",
            translation.norm(),
            arena.corner_error_m * 1000.0
        ),
        Mapping::Homography { .. } => {
            "no camera: a plane-to-image map of the floor, lens ignored".to_string()
        }
    };
    output::say(format_args!(
        "arena {} m x {} m, corners {ids} (origin, +x, far, +y); {how}; wrote {}",
        arena.size_m[0],
        arena.size_m[1],
        args.output.display()
    ));
    Ok(ExitCode::SUCCESS)
}
