//! `whycode simulate`: render a synthetic camera view with ground truth.

use super::args::{parse_plain_number, whole_number, DistanceArg, FamilyArgs};
use anyhow::{bail, Context, Result};
use clap::ValueEnum;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use whycode::camera::Camera;
use whycode::family::parse_id_list;
use whycode::geometry::Marker;
use whycode::manifest::Manifest;
use whycode::simulate::{self, layout, Background, MotionBlur, Scene, SceneObject, SheetPage};
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
    #[arg(long, default_value_t = 1, value_parser = whole_number, allow_hyphen_values = true)]
    page: u32,
    /// Scale the printer applied to the content, e.g. 0.97 or 97%
    #[arg(long, default_value = "1", value_parser = parse_scale, allow_hyphen_values = true)]
    print_scale: f64,
    #[command(flatten)]
    family: FamilyArgs,
    /// Old name of --distance (the Hamming distance), kept for one release
    #[arg(long, hide = true, value_parser = whole_number)]
    hamming: Option<u32>,
    /// Loose markers: IDs, e.g. 1-20 or 1,4,9-12
    #[arg(long)]
    ids: Option<String>,
    /// Loose markers: diameter of the black disc
    #[arg(long, default_value = "50mm", allow_hyphen_values = true)]
    diameter: Length,
    /// Loose markers: arrangement
    #[arg(long, value_enum, default_value_t = Layout::Grid)]
    layout: Layout,
    /// Camera calibration (ROS camera_info or OpenCV YAML)
    #[arg(long, value_name = "FILE")]
    camera: Option<PathBuf>,
    /// Image size of the ideal camera, WIDTHxHEIGHT
    #[arg(long, default_value = "1920x1080", conflicts_with = "camera")]
    size: String,
    /// Horizontal field of view of the ideal camera
    #[arg(long, default_value = "60deg", conflicts_with = "camera")]
    fov: Angle,
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
    #[arg(long, default_value = "0px", value_parser = parse_pixels, allow_hyphen_values = true)]
    blur: f64,
    /// Motion blur: length of the smear in pixels, e.g. 6px
    #[arg(long, default_value = "0px", value_parser = parse_pixels, allow_hyphen_values = true)]
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
enum Layout {
    Grid,
    Scatter,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
enum BackgroundArg {
    Grey,
    Table,
    Clutter,
}

fn parse_scale(text: &str) -> Result<f64, String> {
    let t = text.trim();
    let value = match t.strip_suffix('%') {
        Some(p) => p.trim().parse::<f64>().map(|p| p / 100.0),
        None => t.parse::<f64>(),
    }
    .map_err(|_| format!("'{text}' is not a scale (write e.g. 0.97 or 97%)"))?;
    if !(value > 0.1 && value < 10.0) {
        return Err(format!("'{text}' is not a plausible print scale"));
    }
    Ok(value)
}

fn parse_pixels(text: &str) -> Result<f64, String> {
    let t = text.trim();
    let number = t.strip_suffix("px").unwrap_or(t).trim();
    // Blur cost grows with its length; beyond a few hundred pixels nothing
    // is left to see anyway, and an unbounded value runs for hours.
    const MAX_BLUR_PX: f64 = 500.0;
    match number.parse::<f64>() {
        Ok(v) if v.is_finite() && (0.0..=MAX_BLUR_PX).contains(&v) => Ok(v),
        Ok(v) if v.is_finite() && v > MAX_BLUR_PX => Err(format!(
            "'{text}' is more blur than this simulates (at most {MAX_BLUR_PX}px)"
        )),
        _ => Err(format!(
            "'{text}' is not a length in pixels (write e.g. 2px)"
        )),
    }
}

fn parse_size(text: &str) -> Result<(u32, u32)> {
    let (w, h) = text
        .split_once(['x', 'X'])
        .with_context(|| format!("--size '{text}': write WIDTHxHEIGHT, e.g. 1920x1080"))?;
    let parse = |s: &str| {
        s.trim()
            .parse::<u32>()
            .ok()
            .filter(|&v| (16..=20000).contains(&v))
    };
    match (parse(w), parse(h)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => bail!("--size '{text}': width and height must be 16..20000 pixels"),
    }
}

pub fn run(args: SimulateArgs) -> Result<ExitCode> {
    let mut args = *args.options;
    let camera_distance = take_old_spellings(&mut args)?;
    let camera = match &args.camera {
        Some(path) => Camera::load(path)?,
        None => {
            let (w, h) = parse_size(&args.size)?;
            let fov = args.fov.degrees();
            if !(1.0..=170.0).contains(&fov) {
                bail!("--fov must be between 1 and 170 degrees");
            }
            Camera::ideal(w, h, fov)
        }
    };
    if !(args.gradient.is_finite() && args.gradient >= 1.0) {
        bail!("--gradient must be a ratio of at least 1 (e.g. 3 for 3:1)");
    }
    if !(args.noise.is_finite() && args.noise >= 0.0) {
        bail!("--noise must be a grey-level sigma of at least 0");
    }
    let mut scene = Scene::new(camera);
    let (tilt, pan, roll) = (args.tilt.radians(), args.pan.radians(), args.roll.radians());
    if let Some(path) = &args.manifest {
        let manifest = Manifest::load(path)?;
        if args.page == 0 || args.page > manifest.pages.max(1) {
            bail!("{}: has no page {}", path.display(), args.page);
        }
        let [w, h] = manifest.page_size_mm;
        if args.family.distance.is_some() {
            bail!("--distance: the manifest names the family; the camera's distance is --camera-distance");
        }
        let distance = match camera_distance {
            Some(d) => d.m(),
            None => layout::distance_to_fill(&camera, w, h, 0.8),
        };
        let sheet_name = path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let mut page = SheetPage::new(
            manifest.clone(),
            args.page,
            layout::centred(distance, tilt, pan, roll),
        )
        .with_printed_text(&sheet_name);
        page.print_scale = args.print_scale;
        for &id in &args.blot {
            let entry = manifest
                .markers
                .iter()
                .find(|m| m.id == id && m.page == args.page)
                .with_context(|| format!("--blot {id}: no marker {id} on page {}", args.page))?;
            let marker = SheetPage::marker_of(&manifest, entry);
            page.blots
                .extend(layout::ring_blots(&marker, entry.x_mm, entry.y_mm, false));
        }
        scene.objects.push(SceneObject::Page(page));
        scene.background = Background::Table;
    } else {
        let Some(ids) = &args.ids else {
            bail!("say what to show: --manifest FILE, or --ids LIST (with --bits and --distance, or --family) for loose markers");
        };
        let family = args
            .family
            .resolve()
            .with_context(|| args.family.describe())?;
        let bits = family.bits();
        let ids = parse_id_list(ids).context("--ids")?;
        let diameter = args.diameter.mm();
        let markers = ids
            .iter()
            .map(|&id| {
                let code = family.code(id).with_context(|| {
                    format!(
                        "--ids: ID {id} is not in the {bits}-bit family with distance {} ({} IDs)",
                        family.distance(),
                        family.len()
                    )
                })?;
                Ok((Marker::whycode(bits, code, diameter), id))
            })
            .collect::<Result<Vec<_>>>()?;
        let distance = camera_distance.map_or(1.0, Length::m);
        let mut loose = match args.layout {
            Layout::Grid => {
                layout::marker_grid(&markers, &layout::centred(distance, tilt, pan, roll))
            }
            Layout::Scatter => {
                let max_tilt = if tilt != 0.0 {
                    tilt.abs()
                } else {
                    40f64.to_radians()
                };
                layout::marker_scatter(&camera, &markers, distance, max_tilt, args.seed)
            }
        };
        for &id in &args.blot {
            let m = loose
                .iter_mut()
                .find(|m| m.id == id)
                .with_context(|| format!("--blot {id}: no marker {id} in the scene"))?;
            let blots = layout::ring_blots(&m.marker, 0.0, 0.0, true);
            m.blots.extend(blots);
        }
        scene
            .objects
            .extend(loose.into_iter().map(SceneObject::Marker));
        scene.background = Background::Uniform(0.45);
    }
    if let Some(bg) = args.background {
        scene.background = match bg {
            BackgroundArg::Grey => Background::Uniform(0.45),
            BackgroundArg::Table => Background::Table,
            BackgroundArg::Clutter => Background::Clutter { density: 1.5 },
        };
    }
    scene.gradient = args.gradient;
    scene.gradient_angle = args.gradient_angle.radians();
    scene.exposure = match (args.exposure, args.dark) {
        (Some(e), _) if e > 0.0 && e.is_finite() => e,
        (Some(_), _) => bail!("--exposure must be positive"),
        (None, true) => 0.25,
        (None, false) => 1.0,
    };
    scene.focus_blur_px = args.blur;
    if args.motion_blur > 0.0 {
        scene.motion_blur = Some(MotionBlur {
            length_px: args.motion_blur,
            angle: args.motion_angle.radians(),
        });
    }
    scene.noise = args.noise;
    scene.seed = args.seed;
    let format = whycode::image_io::ImageFormat::from_path(&args.output)?;
    // A JPEG output file is itself the compression step: do it once.
    scene.jpeg_quality = if format == whycode::image_io::ImageFormat::Jpeg {
        None
    } else {
        args.jpeg
    };

    let (image, truth) = simulate::render(&scene);
    let truth_path = args
        .truth
        .clone()
        .unwrap_or_else(|| args.output.with_extension("json"));
    if truth_path == args.output {
        bail!(
            "{}: the ground truth would overwrite the image",
            truth_path.display()
        );
    }
    // `-o swarm.png` next to the sheet's own swarm.json is the natural thing
    // to type, and would silently replace the record of what was printed.
    if is_sheet_manifest(&truth_path) {
        bail!(
            "{}: is a sheet manifest, which the ground truth would overwrite; name the image differently or pass --truth FILE",
            truth_path.display()
        );
    }
    whycode::image_io::save_image(&args.output, &image, args.jpeg.unwrap_or(92))?;
    whycode::io::write_atomic(&truth_path, truth.to_json().as_bytes())?;
    let visible = truth.markers.iter().filter(|m| m.visible).count();
    println!(
        "wrote {} ({}x{}) and {}: {} markers, {} wholly in view",
        display(&args.output),
        image.width(),
        image.height(),
        display(&truth_path),
        truth.markers.len(),
        visible
    );
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
        eprintln!(
            "whycode: note: --distance {text} reads as the camera distance for one more release; write --camera-distance {text} (--distance is now the Hamming distance)"
        );
        camera_distance = Some(*length);
        args.family.distance = None;
    }
    if let Some(hamming) = args.hamming {
        if args.family.distance.is_some() || args.family.family.is_some() {
            bail!("--hamming is the old name of --distance; give the family once, as --distance (or --family)");
        }
        eprintln!(
            "whycode: note: --hamming is now --distance; --hamming {hamming} still works for one more release"
        );
        args.family.distance = Some(DistanceArg::Hamming(hamming));
    }
    Ok(camera_distance)
}

fn display(path: &Path) -> String {
    path.display().to_string()
}

fn is_sheet_manifest(path: &std::path::Path) -> bool {
    let Ok(text) = std::fs::read_to_string(path) else {
        return false;
    };
    serde_json::from_str::<serde_json::Value>(&text)
        .is_ok_and(|v| v.get("format").and_then(|f| f.as_str()) == Some("whycode-sheet"))
}
