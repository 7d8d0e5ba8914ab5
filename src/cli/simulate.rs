//! `whycode simulate`: render a synthetic camera view with ground truth.

use super::args::{
    parse_plain_number, parse_scale, spec_error, whole_number, DistanceArg, FamilyArgs,
};
use super::output;
use anyhow::{bail, Context, Result};
use clap::ValueEnum;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use whycode::camera::Camera;
use whycode::family::parse_id_list;
use whycode::fileset::FileDigest;
use whycode::image_io::ImageFormat;
use whycode::simulate;
use whycode::spec::{BackgroundKind, Layout, SceneSpec};
use whycode::units::{Angle, Length};

#[derive(Debug, clap::Args)]
#[command(
    after_help = "Without --camera the camera is ideal (no distortion): --size (default \
1920x1080) and --fov (default 60deg, horizontal). Writes the image (format from the \
extension: .png, .jpg, .pgm, .bmp) and the ground truth as JSON next to it (view.png -> \
view.json): every marker's ID, code, pixel centre, yaw, size and pose.\n\n\
Lengths need a unit (mm, cm, m, in) and angles one too (deg, rad). --distance is the \
family's Hamming distance, as in every command; the camera's distance is --camera-distance. \
For one more release the old spellings still work, with a note: --hamming N, and \
--distance with a length (0.8m) for the camera distance.\n\nExamples:\n  \
whycode simulate --manifest swarm.json --camera-distance 0.8m --tilt 30deg -o view.png\n  \
whycode simulate --bits 12 --distance 2 --ids 1-20 --diameter 50mm -o scene.png"
)]
pub struct SimulateArgs {
    // Boxed: the options are many, and the CLI's subcommand enum stays small.
    #[command(flatten)]
    options: Box<SimulateOptions>,
}

#[derive(Debug, clap::Args)]
struct SimulateOptions {
    /// Sheet manifest: show one page of the printed sheet
    #[arg(long, value_name = "FILE", conflicts_with_all = ["bits", "family", "ids"])]
    manifest: Option<PathBuf>,
    /// Page of the sheet to show
    /// [default: 1]
    #[arg(long, value_parser = whole_number, allow_hyphen_values = true)]
    page: Option<u32>,
    /// Scale the printer applied to the content, e.g. 0.97 or 97% [default: 1]
    #[arg(long, value_parser = parse_scale, allow_hyphen_values = true)]
    print_scale: Option<f64>,
    #[command(flatten)]
    family: FamilyArgs,
    /// Old name of --distance (the Hamming distance), kept for one release
    #[arg(long, hide = true, value_parser = whole_number)]
    hamming: Option<u32>,
    /// Loose markers: IDs, e.g. 1-20 or 1,4,9-12
    #[arg(long)]
    ids: Option<String>,
    /// Loose markers: diameter of the black disc [default: 50mm]
    #[arg(long, allow_hyphen_values = true)]
    diameter: Option<Length>,
    /// Loose markers: arrangement [default: grid]
    #[arg(long, value_enum)]
    layout: Option<LayoutArg>,
    /// Camera calibration (ROS camera_info or OpenCV YAML)
    #[arg(long, value_name = "FILE")]
    camera: Option<PathBuf>,
    /// Image size of the ideal camera, WIDTHxHEIGHT [default: 1920x1080]
    #[arg(long, value_parser = parse_size, conflicts_with = "camera")]
    size: Option<(u32, u32)>,
    /// Horizontal field of view of the ideal camera [default: 60deg]
    #[arg(long, conflicts_with = "camera")]
    fov: Option<Angle>,
    /// Distance from the camera to the page centre / marker board, with a
    /// unit (default: a page fills 80 % of the frame; loose markers 1 m)
    #[arg(long, value_name = "LENGTH", allow_hyphen_values = true)]
    camera_distance: Option<Length>,
    /// Rotation about the horizontal axis (positive: top edge towards the camera)
    #[arg(long, default_value = "0deg", allow_hyphen_values = true)]
    tilt: Angle,
    /// Rotation about the vertical axis (positive: right edge towards the camera)
    #[arg(long, default_value = "0deg", allow_hyphen_values = true)]
    pan: Angle,
    /// Rotation in the paper's plane, counter-clockwise as seen
    #[arg(long, default_value = "0deg", allow_hyphen_values = true)]
    roll: Angle,
    /// What is behind the paper
    #[arg(long, value_enum)]
    background: Option<BackgroundArg>,
    /// Illumination ratio brightest:darkest across the frame, e.g. 3
    #[arg(long, default_value = "1", value_parser = parse_plain_number, allow_hyphen_values = true)]
    gradient: f64,
    /// Direction in which the light falls off (image angle, 0 = to the right)
    #[arg(long, default_value = "0deg", allow_hyphen_values = true)]
    gradient_angle: Angle,
    /// A dark frame (exposure 0.25)
    #[arg(long, conflicts_with = "exposure")]
    dark: bool,
    /// Exposure: 1 puts white paper near grey 220
    #[arg(long, value_parser = parse_plain_number, allow_hyphen_values = true)]
    exposure: Option<f64>,
    /// Focus blur: Gaussian sigma in pixels, e.g. 2px
    #[arg(long, default_value = "0px", value_parser = whycode::units::parse_pixels, allow_hyphen_values = true)]
    blur: f64,
    /// Motion blur: length of the smear in pixels, e.g. 6px
    #[arg(long, default_value = "0px", value_parser = whycode::units::parse_pixels, allow_hyphen_values = true)]
    motion_blur: f64,
    /// Direction of the motion blur (image angle)
    #[arg(long, default_value = "0deg", allow_hyphen_values = true)]
    motion_angle: Angle,
    /// Sensor noise: Gaussian sigma in grey levels
    #[arg(long, default_value = "0", value_parser = parse_plain_number, allow_hyphen_values = true)]
    noise: f64,
    /// JPEG quality (1-100): compress the image (a .jpg output is written at this quality)
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=100))]
    jpeg: Option<u8>,
    /// Put an ink blot over one ring sector of the marker with this ID (repeatable)
    #[arg(long, value_name = "ID")]
    blot: Vec<u32>,
    /// Random seed (noise, clutter, scattered layout)
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output image
    #[arg(short, long, value_name = "FILE")]
    output: PathBuf,
    /// Ground-truth JSON (default: the output path with .json)
    #[arg(long, value_name = "FILE")]
    truth: Option<PathBuf>,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum LayoutArg {
    /// A flat board of markers in rows, centred in the view
    Grid,
    /// Markers scattered at random through the view, none overlapping; an
    /// error when they do not all fit
    Scatter,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum BackgroundArg {
    Grey,
    Table,
    Clutter,
}

fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let (w, h) = text
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("'{text}': write WIDTHxHEIGHT, e.g. 1920x1080"))?;
    let side = |s: &str| {
        s.trim()
            .parse::<u32>()
            .map_err(|_| format!("'{text}': width and height are whole numbers of pixels"))
    };
    Ok((side(w)?, side(h)?))
}

pub fn run(args: SimulateArgs) -> Result<ExitCode> {
    let mut args = *args.options;
    let camera_distance = take_old_spellings(&mut args)?;
    let format = ImageFormat::from_path(&args.output)?;
    let truth_path = args
        .truth
        .clone()
        .unwrap_or_else(|| args.output.with_extension("json"));
    // `-o swarm.png` next to the sheet's own swarm.json is the natural thing
    // to type, and would silently replace the record of what was printed.
    if is_sheet_manifest(&truth_path) {
        bail!(
            "{}: is a sheet manifest, which the ground truth would overwrite; name the image differently or pass --truth FILE",
            truth_path.display()
        );
    }
    let inputs: Vec<&Path> = [&args.manifest, &args.family.family, &args.camera]
        .into_iter()
        .filter_map(|p| p.as_deref())
        .collect();
    whycode::io::check_outputs(&inputs, &[&args.output, &truth_path])?;
    let spec = SceneSpec {
        manifest: args.manifest.clone(),
        page: args.page,
        print_scale: args.print_scale,
        target: args.family.spec()?,
        ids: args
            .ids
            .as_deref()
            .map(|list| parse_id_list(list).context("--ids"))
            .transpose()?,
        diameter: args.diameter,
        layout: args.layout.map(|l| match l {
            LayoutArg::Grid => Layout::Grid,
            LayoutArg::Scatter => Layout::Scatter,
        }),
        camera: args.camera.as_deref().map(Camera::load).transpose()?,
        size: args.size,
        fov: args.fov,
        camera_distance,
        tilt: args.tilt,
        pan: args.pan,
        roll: args.roll,
        background: args.background.map(|b| match b {
            BackgroundArg::Grey => BackgroundKind::Grey,
            BackgroundArg::Table => BackgroundKind::Table,
            BackgroundArg::Clutter => BackgroundKind::Clutter,
        }),
        gradient: args.gradient,
        gradient_angle: args.gradient_angle,
        exposure: args.exposure,
        dark: args.dark,
        blur_px: args.blur,
        motion_blur_px: args.motion_blur,
        motion_angle: args.motion_angle,
        noise: args.noise,
        // A JPEG output file is itself the compression step: do it once.
        jpeg: args.jpeg.filter(|_| format != ImageFormat::Jpeg),
        blot: args.blot.clone(),
        seed: args.seed,
    };
    let scene = spec.build().map_err(spec_error)?;
    // Again now that the manifest is read: the pages it lists are inputs too.
    whycode::io::check_outputs(&inputs, &[&args.output, &truth_path])?;
    if let Some(path) = &args.manifest {
        // The scene read the manifest; its copy tells whether the pages
        // beside it are the ones it was written with.
        for object in &scene.objects {
            if let simulate::SceneObject::Page(page) = object {
                super::warn_if_mixed(&page.manifest, path);
            }
        }
    }

    let (image, mut truth) = simulate::render(&scene);
    let image_bytes =
        whycode::image_io::encode_image(&args.output, &image, args.jpeg.unwrap_or(92))?;
    truth.files = vec![FileDigest::of(&args.output, &image_bytes)];
    // The truth goes last: a reader that finds it finds its image beside it.
    whycode::io::write_all_atomic(&[
        (args.output.clone(), image_bytes),
        (truth_path.clone(), truth.to_json().into_bytes()),
    ])?;
    let visible = truth.markers.iter().filter(|m| m.visible).count();
    output::print(&format!(
        "wrote {} ({}x{}) and {}: {} markers, {} wholly in view\n",
        display(&args.output),
        image.width(),
        image.height(),
        display(&truth_path),
        truth.markers.len(),
        visible
    ))?;
    Ok(ExitCode::SUCCESS)
}

/// Accepts the spellings of the release before `--distance` meant the
/// Hamming distance everywhere, with a note: `--hamming N` and
/// `--distance LENGTH`. Returns the camera distance.
fn take_old_spellings(args: &mut SimulateOptions) -> Result<Option<Length>> {
    let mut camera_distance = args.camera_distance;
    if let Some(DistanceArg::Length { length, text }) = &args.family.distance {
        if camera_distance.is_some() {
            bail!("--distance '{text}' and --camera-distance both give the camera's distance; keep --camera-distance");
        }
        output::note(format_args!(
            "--distance {text} reads as the camera distance for one more release; write --camera-distance {text} (--distance is now the Hamming distance)"
        ));
        camera_distance = Some(*length);
        args.family.distance = None;
    }
    if let Some(hamming) = args.hamming {
        if args.family.distance.is_some() || args.family.family.is_some() {
            bail!("--hamming is the old name of --distance; give the family once, as --distance (or --family)");
        }
        output::note(format_args!(
            "--hamming is now --distance; --hamming {hamming} still works for one more release"
        ));
        args.family.distance = Some(DistanceArg::Hamming(hamming));
    }
    Ok(camera_distance)
}

fn display(path: &Path) -> String {
    path.display().to_string()
}

fn is_sheet_manifest(path: &std::path::Path) -> bool {
    // The truth's old content is an output's, not an input.
    let Ok(text) =
        whycode::input::unrecorded(|| whycode::input::read_text(path, whycode::FileKind::Manifest))
    else {
        return false;
    };
    serde_json::from_str::<serde_json::Value>(&text)
        .is_ok_and(|v| v.get("format").and_then(|f| f.as_str()) == Some("whycode-sheet"))
}
