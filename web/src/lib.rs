//! The whycode library for the browser page in `web/`: thin wasm-bindgen
//! wrappers that take the CLI's options, call the same library functions
//! the CLI calls, and hand back the same bytes. Nothing here draws, decodes
//! or lays out on its own; argument checks mirror the CLI's so that the page
//! refuses what `whycode` refuses, with the same words.

use std::path::Path;

use anyhow::{Context, Result};
use image::GrayImage;
use serde::Deserialize;
use wasm_bindgen::prelude::*;
use whycode::arena::Arena;
use whycode::board::Board;
use whycode::calibrate;
use whycode::camera::Camera;
use whycode::detect::{Detector, Target};
use whycode::family::{parse_id_list, CountTable, Family};
use whycode::image_io;
use whycode::manifest::Manifest;
use whycode::render::job::{MarkerJob, PrintError, SheetJob};
use whycode::render::template::{builtin_names, Template};
use whycode::session::{Frame, FrameReport, Session, SessionConfig};
use whycode::spec::{cli_option, Bits, CalibrateSpec, DetectSpec, SpecError, TargetSpec};
use whycode::units::{trim_float, Length};
use whycode::validate::{self, annotate, PhotoReport};

/// Largest photo the page decodes: a phone's 50 MP still fits, and the
/// decoded copies stay well inside a tab's memory.
const PHOTO_LIMIT: image_io::SizeLimit = image_io::SizeLimit {
    max_side: 12_000,
    max_pixels: 60_000_000,
};

fn js_error(err: anyhow::Error) -> JsError {
    JsError::new(&one_line(err.as_ref()))
}

/// A library spec's error in the page's words, which are the command
/// line's (`--diameter: ...`).
fn spec_error(err: SpecError) -> anyhow::Error {
    anyhow::anyhow!(err.message_with(cli_option))
}

fn print_error(err: PrintError) -> anyhow::Error {
    match err {
        PrintError::Option(err) => spec_error(err),
        PrintError::Render(err @ whycode::render::RenderError::SelfCheck { .. }) => {
            anyhow::anyhow!("{err} (nothing written)")
        }
        PrintError::Render(err) => err.into(),
    }
}

use whycode::error::one_line;

/// The library version, shown in the page footer.
#[wasm_bindgen]
pub fn version() -> String {
    env!("CARGO_PKG_VERSION").to_string()
}

/// The built-in page templates as JSON: name, description and size.
#[wasm_bindgen]
pub fn templates() -> String {
    let list: Vec<serde_json::Value> = Template::all_builtin()
        .iter()
        .map(|t| {
            serde_json::json!({
                "name": t.name,
                "description": t.description,
                "width_mm": t.page_width_mm,
                "height_mm": t.page_height_mm,
                "margin_mm": t.margin_mm,
                "gap_mm": t.gap_mm,
                "label_size_pt": t.label_size_pt,
                "cut_guides": t.cut_guides,
                "scale_bar_mm": t.scale_bar_mm,
            })
        })
        .collect();
    serde_json::Value::Array(list).to_string()
}

fn generate(bits: u32, distance: u32) -> Result<Family> {
    Ok(Family::generate(bits, distance)?)
}

/// The family file, byte for byte what `whycode ids --format json` writes.
#[wasm_bindgen(js_name = familyJson)]
pub fn family_json(bits: u32, distance: u32) -> Result<String, JsError> {
    Ok(generate(bits, distance).map_err(js_error)?.to_json())
}

/// The family's ID table as JSON for display: the first `limit` rows of
/// ID, code, binary and self-distance, plus the family's size and minimum
/// distance.
#[wasm_bindgen(js_name = familyTable)]
pub fn family_table(bits: u32, distance: u32, limit: usize) -> Result<String, JsError> {
    let family = generate(bits, distance).map_err(js_error)?;
    let width = family.bits() as usize;
    let self_distances = family.self_distances();
    let rows: Vec<serde_json::Value> = family
        .codes()
        .iter()
        .zip(&self_distances)
        .take(limit)
        .enumerate()
        .map(|(k, (&code, sd))| serde_json::json!([k + 1, code, format!("{code:0width$b}"), sd]))
        .collect();
    Ok(serde_json::json!({
        "bits": family.bits(),
        "distance": family.distance(),
        "len": family.len(),
        "min_distance": family.min_distance(),
        "worst_self_distance": self_distances.iter().min(),
        "rows": rows,
    })
    .to_string())
}

/// Number of IDs for every bit length and distance, as JSON rows (one per
/// distance, `null` where the distance exceeds the bit count): the matrix of
/// `whycode ids --counts`.
#[wasm_bindgen]
pub fn counts(bits: &[u32], distances: &[u32]) -> Result<String, JsError> {
    let inner = || -> Result<String> {
        let table = CountTable::new(bits, distances).map_err(|e| spec_error(e.into()))?;
        Ok(
            serde_json::json!({ "bits": bits, "distances": distances, "counts": table.counts })
                .to_string(),
        )
    };
    inner().map_err(js_error)
}

/// Files made by one call: names as the CLI would write them, bytes, and
/// the lines the CLI prints on standard error.
#[wasm_bindgen]
pub struct Files {
    files: Vec<(String, Vec<u8>)>,
    notes: Vec<String>,
}

#[wasm_bindgen]
impl Files {
    pub fn count(&self) -> usize {
        self.files.len()
    }

    pub fn name(&self, index: usize) -> String {
        self.files
            .get(index)
            .map(|f| f.0.clone())
            .unwrap_or_default()
    }

    pub fn bytes(&self, index: usize) -> Vec<u8> {
        self.files
            .get(index)
            .map(|f| f.1.clone())
            .unwrap_or_default()
    }

    pub fn notes(&self) -> String {
        self.notes.join("\n")
    }
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default()
}

fn length(option: &str, text: &str) -> Result<f64> {
    text.parse::<Length>()
        .map(Length::mm)
        .map_err(|e| anyhow::anyhow!("{option}: {e}"))
}

/// The options of `whycode sheet`, as the page's form sends them.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SheetOptions {
    bits: Option<u32>,
    distance: Option<u32>,
    ids: Option<String>,
    #[serde(default)]
    legacy: bool,
    count: Option<usize>,
    diameter: String,
    /// A built-in template's name, or the name a custom template is saved
    /// under (with `template_toml` holding its text).
    template: String,
    template_toml: Option<String>,
    dpi: Option<f64>,
    /// Output file name with extension: "swarm.pdf", "swarm.svg" or "swarm.png".
    output: String,
    #[serde(default)]
    no_check: bool,
}

/// What a sheet or a marker prints, from the form's kind fields as the
/// command line resolves `--legacy`, `--bits` and `--distance`.
fn chosen_target(legacy: bool, bits: Option<u32>, distance: Option<u32>) -> Result<Target> {
    TargetSpec {
        legacy,
        bits: bits.map(Bits::Count),
        distance,
        ..TargetSpec::default()
    }
    .resolve()
    .map_err(spec_error)
}

/// `whycode sheet`: the page files and the manifest, as the CLI writes them
/// for the same options. `options` is JSON (see [`SheetOptions`]).
#[wasm_bindgen]
pub fn sheet(options: &str) -> Result<Files, JsError> {
    sheet_files(options).map_err(js_error)
}

fn sheet_files(options: &str) -> Result<Files> {
    let args: SheetOptions = serde_json::from_str(options).context("sheet options")?;
    let output = Path::new(&args.output);
    let dpi = args.dpi.unwrap_or(300.0);
    let diameter_mm = length("--diameter", &args.diameter)?;
    let template = match &args.template_toml {
        Some(text) => Template::parse(&args.template, text)
            .with_context(|| format!("template {}", args.template))?,
        None => Template::builtin(&args.template)?,
    };
    let target = chosen_target(args.legacy, args.bits, args.distance)?;
    let ids = match args.ids.as_deref().map(str::trim) {
        Some(list) if !list.is_empty() => Some(parse_id_list(list).context("--ids")?),
        _ => None,
    };
    let job = SheetJob {
        family: target.family(),
        ids,
        count: args.count,
        diameter_mm,
        template,
        name: output
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default(),
        dpi,
        self_check: !args.no_check,
    };
    let printed = job.print(output).map_err(print_error)?;
    let mut notes = vec![match &printed.check {
        Some(report) => format!("self-check passed: {}", report.summary()),
        None => "self-check skipped: the markers were not read back".to_string(),
    }];
    notes.push(printed.summary());
    let files = printed
        .into_files()
        .into_iter()
        .map(|(path, bytes)| (file_name(&path), bytes))
        .collect();
    Ok(Files { files, notes })
}

/// The options of `whycode marker`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct MarkerArgs {
    bits: Option<u32>,
    distance: Option<u32>,
    id: Option<u32>,
    #[serde(default)]
    legacy: bool,
    diameter: String,
    margin: Option<String>,
    dpi: Option<f64>,
    #[serde(default)]
    cross: bool,
    #[serde(default)]
    cut_guide: bool,
    #[serde(default)]
    label: bool,
    #[serde(default)]
    no_check: bool,
    output: String,
}

/// `whycode marker`: one marker file, as the CLI writes it.
#[wasm_bindgen]
pub fn marker(options: &str) -> Result<Files, JsError> {
    marker_files(options).map_err(js_error)
}

fn marker_files(options: &str) -> Result<Files> {
    let args: MarkerArgs = serde_json::from_str(options).context("marker options")?;
    let output = Path::new(&args.output);
    let dpi = args.dpi.unwrap_or(300.0);
    let diameter_mm = length("--diameter", &args.diameter)?;
    let target = chosen_target(args.legacy, args.bits, args.distance)?;
    let margin_mm = match &args.margin {
        Some(text) if !text.trim().is_empty() => Some(length("--margin", text)?),
        _ => None,
    };
    let job = MarkerJob {
        family: target.family(),
        id: args.id,
        diameter_mm,
        margin_mm,
        cross: args.cross,
        cut_guide: args.cut_guide,
        label: args.label,
        dpi,
        self_check: !args.no_check,
    };
    let (files, check) = job.print(output).map_err(print_error)?;
    let notes = vec![match check {
        Some(_) => "self-check passed: the marker reads back as itself".to_string(),
        None => "self-check skipped: the marker was not read back".to_string(),
    }];
    let files = files
        .into_iter()
        .map(|(path, bytes)| (file_name(&path), bytes))
        .collect();
    Ok(Files { files, notes })
}

/// Decodes a photo's bytes to 8-bit grey with the CLI's loader, within
/// what a tab can hold.
fn decode_gray(name: &str, bytes: &[u8]) -> Result<GrayImage> {
    image_io::decode_gray(Path::new(name), bytes, PHOTO_LIMIT).map_err(|err| match err.problem {
        whycode::LoadProblem::TooLarge { .. } => anyhow::anyhow!(
            "{err}; scale it down, or check it with the whycode command (up to {} px a side)",
            image_io::MAX_SIDE
        ),
        _ => err.into(),
    })
}

/// `whycode validate`: a manifest, then photos one at a time (so the page
/// can show progress), then the report.
#[wasm_bindgen]
pub struct Validation {
    manifest: Manifest,
    detector: Detector,
    photos: Vec<PhotoReport>,
}

#[wasm_bindgen]
impl Validation {
    /// `name` is the manifest's file name, used in error messages.
    #[wasm_bindgen(constructor)]
    pub fn new(name: &str, text: &str) -> Result<Validation, JsError> {
        let manifest = Manifest::from_json(name, text).map_err(|e| js_error(e.into()))?;
        let detector = validate::detector_for(&manifest)
            .with_context(|| name.to_string())
            .map_err(js_error)?;
        Ok(Validation {
            manifest,
            detector,
            photos: Vec::new(),
        })
    }

    /// Checks one photo and returns its annotated copy as PNG bytes.
    #[wasm_bindgen(js_name = addPhoto)]
    pub fn add_photo(&mut self, name: &str, bytes: &[u8]) -> Result<Vec<u8>, JsError> {
        let image = decode_gray(name, bytes).map_err(js_error)?;
        let report = validate::check_image(name, &self.manifest, &image, None, &mut self.detector);
        let picture = annotate::annotate(&image, &report);
        self.photos.push(report);
        image_io::encode_rgb_png(&picture)
            .map_err(|e| JsError::new(&format!("cannot encode the annotated photo: {e}")))
    }

    /// The report over the photos added so far, as `whycode validate --format json`.
    #[wasm_bindgen(js_name = reportJson)]
    pub fn report_json(&self) -> String {
        validate::summarise(&self.manifest, self.photos.clone()).to_json()
    }

    /// The same report as the CLI's table.
    #[wasm_bindgen(js_name = reportTable)]
    pub fn report_table(&self) -> String {
        validate::summarise(&self.manifest, self.photos.clone()).to_table()
    }
}

/// The options of `whycode calibrate`, as the page's form sends them.
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct CalibrateOptions {
    #[serde(default)]
    fix_principal_point: bool,
    #[serde(default)]
    fix_aspect: bool,
    #[serde(default)]
    no_tangential: bool,
    #[serde(default)]
    no_k3: bool,
    /// As typed: "0.97" or "97%"; empty for 100 %.
    print_scale: Option<String>,
}

impl CalibrateOptions {
    fn parse(options: &str) -> Result<calibrate::CalibrationOptions> {
        let args: CalibrateOptions =
            serde_json::from_str(options).context("calibration options")?;
        let print_scale = match args.print_scale.as_deref().map(str::trim) {
            Some(text) if !text.is_empty() => Some(
                whycode::units::parse_scale(text)
                    .map_err(|e| anyhow::anyhow!("--print-scale: {e}"))?,
            ),
            _ => None,
        };
        CalibrateSpec {
            fix_principal_point: args.fix_principal_point,
            fix_aspect: args.fix_aspect,
            no_tangential: args.no_tangential,
            no_k3: args.no_k3,
            print_scale,
        }
        .build()
        .map_err(spec_error)
    }
}

/// `whycode calibrate`: a manifest, then photos one at a time (each read at
/// once, so the page shows coverage and a first fit as they come), then
/// the calibration over all of them and its camera file.
#[wasm_bindgen]
pub struct Calibration {
    photos: calibrate::SheetPhotos,
    result: Option<calibrate::Calibration>,
}

#[wasm_bindgen]
impl Calibration {
    /// `name` is the manifest's file name, used in error messages.
    #[wasm_bindgen(constructor)]
    pub fn new(name: &str, text: &str) -> Result<Calibration, JsError> {
        let manifest = Manifest::from_json(name, text).map_err(|e| js_error(e.into()))?;
        let photos = calibrate::SheetPhotos::new(manifest)
            .with_context(|| name.to_string())
            .map_err(js_error)?;
        Ok(Calibration {
            photos,
            result: None,
        })
    }

    /// Reads one photo's markers; returns how many it has of the sheet.
    /// A photo of another size than the first is refused with the command
    /// line's words.
    #[wasm_bindgen(js_name = addPhoto)]
    pub fn add_photo(&mut self, name: &str, bytes: &[u8]) -> Result<usize, JsError> {
        let image = decode_gray(name, bytes).map_err(js_error)?;
        self.result = None;
        self.photos.add(name, image).map_err(|e| js_error(e.into()))
    }

    /// Forgets the photo added `index`-th (from 0).
    #[wasm_bindgen(js_name = removePhoto)]
    pub fn remove_photo(&mut self, index: usize) {
        self.photos.remove(index);
        self.result = None;
    }

    /// What the photos so far show, as JSON: `coverage` (markers per ninth
    /// of the image, rows from the top), `views` ({label, markers}) and a
    /// first fit on the markers' ellipse centres (`rms_px`, `fx`, `fy`,
    /// `advice`) or the reason there is none yet (`refusal`, the command
    /// line's line).
    pub fn preview(&self, options: &str) -> Result<String, JsError> {
        let options = CalibrateOptions::parse(options).map_err(js_error)?;
        let preview = self.photos.preview(&options);
        let (Some((width, height)), Some(coverage)) = (preview.size, preview.coverage) else {
            return Ok(serde_json::json!({ "views": [], "coverage": null }).to_string());
        };
        let listed: Vec<serde_json::Value> = preview
            .views
            .iter()
            .map(|v| serde_json::json!({ "label": v.label, "markers": v.ids.len() }))
            .collect();
        let fit = match preview.fit {
            Ok(c) => serde_json::json!({
                "rms_px": c.rms,
                "fx": c.camera.fx,
                "fy": c.camera.fy,
                "advice": c.advice,
            }),
            Err(err) => serde_json::json!({ "refusal": err.to_string() }),
        };
        Ok(serde_json::json!({
            "width": width,
            "height": height,
            "views": listed,
            "coverage": coverage.counts,
            "fit": fit,
        })
        .to_string())
    }

    /// Calibrates from every photo added, as `whycode calibrate` with the
    /// same options; returns the report as JSON (see the library's
    /// `Calibration::to_json`). A calibration the photos cannot support is
    /// refused with the command line's one line.
    pub fn calibrate(&mut self, options: &str) -> Result<String, JsError> {
        let options = CalibrateOptions::parse(options).map_err(js_error)?;
        self.result = None;
        let result = self
            .photos
            .calibrate(&options)
            .map_err(|e| js_error(e.into()))?;
        let json = result.to_json();
        self.result = Some(result);
        Ok(json)
    }

    /// The last calibration's report as the command line prints it.
    #[wasm_bindgen(js_name = reportTable)]
    pub fn report_table(&self) -> String {
        self.result
            .as_ref()
            .map(calibrate::Calibration::to_table)
            .unwrap_or_default()
    }

    /// The last calibration's camera file, as `whycode calibrate -o
    /// <output>` writes it (the format follows the name's extension).
    #[wasm_bindgen(js_name = cameraFile)]
    pub fn camera_file(&self, output: &str) -> Result<String, JsError> {
        let result = self
            .result
            .as_ref()
            .ok_or_else(|| JsError::new("no calibration yet: calibrate first"))?;
        let format = whycode::camera::CalibrationFormat::for_path(Path::new(output));
        Ok(result.camera.to_file_text(format, "camera"))
    }
}

/// A file the page read from a file input: its name (which names boards
/// and errors, as a path does on the command line) and its text.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
// Read only where the files are (the `files` feature's module).
#[cfg_attr(not(feature = "files"), allow(dead_code))]
struct Upload {
    name: String,
    text: String,
}

/// The Live panel's options: `whycode detect`'s marker kind, and the
/// frames of reference `detect --diameter --camera --board --arena` take,
/// with the files' texts in place of their paths (the markers' height is
/// the arena file's).
#[derive(Debug, Default, Deserialize)]
#[serde(deny_unknown_fields)]
struct LiveOptions {
    bits: Option<u32>,
    distance: Option<u32>,
    #[serde(default)]
    legacy: bool,
    diameter: Option<String>,
    camera: Option<Upload>,
    #[serde(default)]
    boards: Vec<Upload>,
    arena: Option<Upload>,
}

/// `--diameter` as typed (a bare number is metres,
/// as there); empty means not given.
fn diameter(text: Option<&str>) -> Result<Option<Length>> {
    match text.map(str::trim) {
        Some(text) if !text.is_empty() => Length::parse_metres(text)
            .map(Some)
            .map_err(|e| anyhow::anyhow!("--diameter: {e}")),
        _ => Ok(None),
    }
}

impl LiveOptions {
    /// The detector `whycode detect` builds from the same options (tracked
    /// frame to frame).
    fn parse(options: &str) -> Result<SessionConfig> {
        let args: LiveOptions = serde_json::from_str(options).context("live options")?;
        let target = if args.legacy {
            TargetSpec::legacy()
        } else {
            TargetSpec {
                bits: args.bits.map(Bits::Count),
                distance: args.distance,
                ..TargetSpec::default()
            }
        };
        let (camera, boards, arena) = args.files()?;
        DetectSpec {
            target,
            diameter: diameter(args.diameter.as_deref())?,
            camera,
            tracking: true,
            boards,
            arena,
            ..DetectSpec::default()
        }
        .build()
        .map_err(spec_error)
    }
}

impl LiveOptions {
    /// The camera, boards and arena the files give.
    #[cfg(feature = "files")]
    fn files(&self) -> Result<(Option<Camera>, Vec<Board>, Option<Arena>)> {
        let camera = self
            .camera
            .as_ref()
            .map(|file| Camera::parse(&file.text).map_err(|e| e.in_file(Path::new(&file.name))))
            .transpose()?;
        let mut boards = Vec::new();
        for file in &self.boards {
            boards.extend(Board::from_text(Path::new(&file.name), &file.text)?);
        }
        let arena = self
            .arena
            .as_ref()
            .map(|file| Arena::parse(&file.text).map_err(|err| err.in_file(Path::new(&file.name))))
            .transpose()?;
        Ok((camera, boards, arena))
    }

    /// This module reads no files: the page sends options with files to
    /// the module built with them (web/build.sh).
    #[cfg(not(feature = "files"))]
    fn files(&self) -> Result<(Option<Camera>, Vec<Board>, Option<Arena>)> {
        if self.camera.is_some() || !self.boards.is_empty() || self.arena.is_some() {
            anyhow::bail!("camera, board and arena files are read by the page's second module");
        }
        Ok((None, Vec::new(), None))
    }
}

/// Live detection on camera frames, with tracking between frames, and
/// single photos detected as `whycode detect` reads an image file.
#[wasm_bindgen]
pub struct Live {
    config: SessionConfig,
    session: Session,
    grey: GrayImage,
    /// The last camera frame's markers and board poses.
    last: FrameReport,
}

/// Numbers per detection in [`Live::detect_rgba`]'s result.
#[wasm_bindgen(js_name = liveStride)]
pub fn live_stride() -> usize {
    11
}

#[wasm_bindgen]
impl Live {
    /// A detector for the options (JSON, see [`LiveOptions`]): the marker
    /// kind, and optionally the diameter, camera file, boards and arena
    /// file, refused as the command line refuses them.
    #[wasm_bindgen(constructor)]
    pub fn new(options: &str) -> Result<Live, JsError> {
        let config = LiveOptions::parse(options).map_err(js_error)?;
        let grey = GrayImage::new(0, 0);
        Ok(Live {
            session: Session::new(config.clone()),
            config,
            last: FrameReport::empty("camera", 0, 0),
            grey,
        })
    }

    /// Detects markers in an RGBA frame (a canvas's ImageData). Returns
    /// [`live_stride`] numbers per marker: id, u, v, semi-major, semi-minor,
    /// angle, yaw, confidence, then arena x, y (metres) and yaw (NaN when
    /// unknown or without an arena).
    #[wasm_bindgen(js_name = detectRgba)]
    pub fn detect_rgba(
        &mut self,
        rgba: &[u8],
        width: u32,
        height: u32,
    ) -> Result<Vec<f64>, JsError> {
        let pixels = width as usize * height as usize;
        if rgba.len() != pixels * 4 {
            return Err(JsError::new(&format!(
                "frame of {width}x{height} needs {} bytes, got {}",
                pixels * 4,
                rgba.len()
            )));
        }
        if self.grey.dimensions() != (width, height) {
            self.grey = GrayImage::new(width, height);
            self.session.reset();
        }
        // Rec. 709 weights, as the image crate's grey conversion of files.
        for (g, px) in self.grey.iter_mut().zip(rgba.chunks_exact(4)) {
            let sum = 2126 * u32::from(px[0]) + 7152 * u32::from(px[1]) + 722 * u32::from(px[2]);
            *g = ((sum + 5000) / 10_000) as u8;
        }
        let mut report = self
            .session
            .process(Frame::new(&self.grey, "camera"))
            .map_err(|problem| JsError::new(&format!("the camera's frames: {problem}")))?;
        // The library has no clock here; the page shows its own timing.
        report.elapsed_ms = 0.0;
        let mut out = Vec::with_capacity(report.markers.len() * live_stride());
        for (k, d) in report.markers.iter().enumerate() {
            let arena = report.place(k);
            out.extend_from_slice(&[
                f64::from(d.id),
                d.u,
                d.v,
                d.axes[0],
                d.axes[1],
                d.angle,
                d.yaw.unwrap_or(f64::NAN),
                d.confidence,
                arena.map_or(f64::NAN, |a| a.x),
                arena.map_or(f64::NAN, |a| a.y),
                arena.and_then(|a| a.yaw).unwrap_or(f64::NAN),
            ]);
        }
        self.last = report;
        Ok(out)
    }

    /// The last camera frame as `whycode detect --format json` writes a
    /// frame (markers with poses and arena places, the boards' poses).
    #[wasm_bindgen(js_name = frameJson)]
    pub fn frame_json(&self) -> String {
        self.last.to_json()
    }

    /// One photo, read as `whycode detect` reads an image file with the
    /// same options (its own untracked session: the camera's tracks are
    /// kept); returns the command's JSON line, with `elapsed_ms` 0.
    #[wasm_bindgen(js_name = detectPhoto)]
    pub fn detect_photo(&self, name: &str, bytes: &[u8]) -> Result<String, JsError> {
        let inner = || -> Result<String> {
            let grey = decode_gray(name, bytes)?;
            let mut config = self.config.clone();
            config.detector.tracking = false;
            let mut report = Session::new(config)
                .process(Frame::new(&grey, name))
                .map_err(|problem| anyhow::anyhow!("{name}: {problem}"))?;
            report.elapsed_ms = 0.0;
            Ok(report.to_json())
        };
        inner().map_err(js_error)
    }

    /// Forgets tracked markers (after a pause or a camera switch).
    pub fn reset(&mut self) {
        self.session.reset();
    }
}

/// Names of the built-in templates (for error messages in the page).
#[wasm_bindgen(js_name = templateNames)]
pub fn template_names() -> String {
    builtin_names().join(", ")
}

/// A length as the CLI prints it, e.g. "40 mm" (for labels in the page).
#[wasm_bindgen(js_name = lengthMm)]
pub fn length_mm(text: &str) -> Result<String, JsError> {
    let mm = length("diameter", text).map_err(js_error)?;
    Ok(trim_float(mm))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_text_file_is_not_a_photo() {
        let err = decode_gray("notes.txt", b"hello, not an image").unwrap_err();
        assert!(one_line(err.as_ref()).starts_with("notes.txt: not an image"));
    }

    #[test]
    fn a_photo_too_large_for_the_page_points_to_the_command() {
        let (width, height) = (13_000u32, 40u32);
        let mut bytes = Vec::new();
        image::ImageEncoder::write_image(
            image::codecs::png::PngEncoder::new(&mut bytes),
            &vec![255; (width * height) as usize],
            width,
            height,
            image::ExtendedColorType::L8,
        )
        .unwrap();
        let text = one_line(decode_gray("wide.png", &bytes).unwrap_err().as_ref());
        assert!(
            text.starts_with("wide.png: image of 13000x40 pixels is larger than the supported 12000 px a side and 60 megapixels; scale it down"),
            "{text}"
        );
    }
}
