//! Calibration files: ROS `camera_info` YAML, OpenCV FileStorage YAML and
//! XML, Kalibr camchain YAML in; ROS YAML out.

use std::path::Path;

use crate::error::{refuse, FileKind, LoadError, LoadProblem};
use serde_yaml::Value;

use super::Camera;

/// An image whose aspect ratio differs from the calibration's: another
/// camera or a crop, for which no rescaled calibration is right.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "image is {}x{} but the camera calibration is for {}x{}",
    image[0],
    image[1],
    calibration[0],
    calibration[1]
)]
pub struct OtherCamera {
    /// The image's width and height, pixels.
    pub image: [u32; 2],
    /// The width and height the calibration was made for, pixels.
    pub calibration: [u32; 2],
}

/// A calibration no real lens gives (see [`Camera::check_plausible`]).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ImplausibleCamera {
    /// A focal length that gives a field of view outside 0.1-175°.
    #[error(
        "camera_matrix: {axis} = {} gives a {fov:.3}° field of view across {side} pixels; \
         a real lens gives 0.1-175°",
        short_number(*focal)
    )]
    FieldOfView {
        /// "fx" or "fy".
        axis: &'static str,
        /// The focal length, pixels.
        focal: f64,
        /// The field of view it gives, degrees.
        fov: f64,
        /// The image side it spans, pixels.
        side: f64,
    },
    /// Pixels far from square.
    #[error("camera_matrix: fx/fy = {aspect:.3}; real pixels are not that far from square")]
    NotSquare {
        /// fx / fy.
        aspect: f64,
    },
    /// A principal point far outside the image.
    #[error(
        "camera_matrix: principal point {axis} = {} lies far outside the {width}x{height} image",
        short_number(*value)
    )]
    PrincipalPoint {
        /// "cx" or "cy".
        axis: &'static str,
        /// Its value, pixels.
        value: f64,
        /// The image's width, pixels.
        width: u32,
        /// The image's height, pixels.
        height: u32,
    },
    /// Distortion no lens gives.
    #[error(
        "distortion_coefficients [{}] are not a real lens: {problem}",
        coefficients.map(short_number).join(", ")
    )]
    Distortion {
        /// k1, k2, p1, p2, k3.
        coefficients: [f64; 5],
        /// What it does to the image.
        problem: LensProblem,
    },
}

/// What implausible distortion does to the image, walking from the
/// principal point towards `pixel` (an image corner or edge middle).
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum LensProblem {
    /// Distortion that cannot be inverted at a pixel on the way.
    #[error("pixel ({:.0}, {:.0}) has no undistorted position", pixel[0], pixel[1])]
    NoInverse {
        /// The pixel without one.
        pixel: [f64; 2],
    },
    /// Distortion that folds the image over.
    #[error("the image folds over itself towards pixel ({:.0}, {:.0})", pixel[0], pixel[1])]
    FoldsOver {
        /// The corner or edge middle it folds towards.
        pixel: [f64; 2],
    },
    /// Distortion that shrinks or stretches the edge more than four times.
    #[error(
        "pixel ({:.0}, {:.0}) would lie at {:.3}% of its distance from the centre without \
         distortion (a real lens: 25-400%)",
        pixel[0],
        pixel[1],
        ratio * 100.0
    )]
    Stretched {
        /// The corner or edge middle.
        pixel: [f64; 2],
        /// Its distance from the centre without distortion over that with.
        ratio: f64,
    },
}

impl Camera {
    /// Read a calibration file: a ROS `camera_info` YAML (as written by
    /// `camera_calibration`, or the message form with `K`/`D` or `k`/`d`),
    /// an OpenCV FileStorage YAML (`%YAML:1.0`, `!!opencv-matrix`) or XML,
    /// or a Kalibr camchain YAML (first camera, pinhole/radtan).
    /// Errors carry the file name as context and say what is missing.
    pub fn load(path: impl AsRef<Path>) -> Result<Camera, LoadError> {
        let path = path.as_ref();
        let text = crate::input::read_text(path, FileKind::Camera)?;
        Camera::parse(&text).map_err(|err| err.in_file(path))
    }

    /// Parse the text of a calibration file (see [`Camera::load`]).
    pub fn parse(text: &str) -> Result<Camera, LoadError> {
        parse_calibration(text).map_err(|problem| {
            LoadError::invalid_text(
                FileKind::Camera,
                crate::error::shorten_words(&problem.to_string()),
            )
        })
    }

    /// Refuses calibrations no real lens gives, which would otherwise turn
    /// into poses kilometres away or silently empty pose columns: a field of
    /// view outside 0.1-175°, pixels far from square, a principal point far
    /// outside the image, or distortion that folds the image over, cannot
    /// be inverted, or shrinks or stretches the image's edge by more than
    /// four times.
    pub fn check_plausible(&self) -> Result<(), ImplausibleCamera> {
        let (w, h) = (f64::from(self.width), f64::from(self.height));
        for (axis, focal, side) in [("fx", self.fx, w), ("fy", self.fy, h)] {
            let fov = 2.0 * (0.5 * side / focal).atan().to_degrees();
            if !(fov.is_finite() && (0.1..=175.0).contains(&fov)) {
                return Err(ImplausibleCamera::FieldOfView {
                    axis,
                    focal,
                    fov,
                    side,
                });
            }
        }
        let aspect = self.fx / self.fy;
        if !(0.25..=4.0).contains(&aspect) {
            return Err(ImplausibleCamera::NotSquare { aspect });
        }
        for (axis, value, side) in [("cx", self.cx, w), ("cy", self.cy, h)] {
            if !(-0.5 * side..=1.5 * side).contains(&value) {
                return Err(ImplausibleCamera::PrincipalPoint {
                    axis,
                    value,
                    width: self.width,
                    height: self.height,
                });
            }
        }
        if !self.has_distortion() {
            return Ok(());
        }
        let bad = |problem: LensProblem| {
            Err(ImplausibleCamera::Distortion {
                coefficients: self.distortion,
                problem,
            })
        };
        // Walk from the principal point to every corner and edge middle.
        let (x0, x1, y0, y1) = (-0.5, w - 0.5, -0.5, h - 0.5);
        let (xm, ym) = ((x0 + x1) / 2.0, (y0 + y1) / 2.0);
        for (u, v) in [
            (x0, y0),
            (x1, y0),
            (x1, y1),
            (x0, y1),
            (xm, y0),
            (xm, y1),
            (x0, ym),
            (x1, ym),
        ] {
            let mut last = 0.0;
            const STEPS: usize = 32;
            for k in 1..=STEPS {
                let t = k as f64 / STEPS as f64;
                let (pu, pv) = (self.cx + (u - self.cx) * t, self.cy + (v - self.cy) * t);
                let (x, y) = self.undistort(pu, pv);
                let (bu, bv) = self.distort_normalized(x, y);
                let miss = (bu - pu).hypot(bv - pv);
                if miss.is_nan() || miss >= 0.01 {
                    return bad(LensProblem::NoInverse { pixel: [pu, pv] });
                }
                let radius = x.hypot(y);
                if radius <= last {
                    return bad(LensProblem::FoldsOver { pixel: [u, v] });
                }
                last = radius;
            }
            let distorted = ((u - self.cx) / self.fx).hypot((v - self.cy) / self.fy);
            let ratio = last / distorted;
            if !(0.25..=4.0).contains(&ratio) {
                return bad(LensProblem::Stretched {
                    pixel: [u, v],
                    ratio,
                });
            }
        }
        Ok(())
    }
}

/// Deeper than any calibration file nests; a hostile file nested 100,000
/// deep took the YAML parser 42 s to refuse.
const MAX_NESTING: usize = 32;

/// How deeply `text` nests, by flow brackets and by block indentation
/// (each `- ` opening a sequence entry on a line counts one level).
fn nesting(text: &str) -> usize {
    let (mut depth, mut deepest) = (0usize, 0usize);
    for line in text.lines() {
        let indent = line.len() - line.trim_start_matches([' ', '-']).len();
        deepest = deepest.max(indent / 2 + line.trim_start().matches("- ").count());
        for c in line.chars() {
            match c {
                '[' | '{' | '<' => {
                    depth += 1;
                    deepest = deepest.max(depth);
                }
                ']' | '}' | '>' => depth = depth.saturating_sub(1),
                _ => {}
            }
        }
    }
    deepest
}

fn parse_calibration(text: &str) -> Result<Camera, LoadProblem> {
    if nesting(text) > MAX_NESTING {
        refuse!("nested more than {MAX_NESTING} levels deep: not a camera calibration");
    }
    let doc = if text.trim_start().starts_with("<?xml") || text.contains("<opencv_storage>") {
        opencv_xml_to_value(text)?
    } else {
        let cleaned = strip_opencv_yaml(text);
        serde_yaml::from_str(&cleaned).map_err(|e| {
            LoadProblem::Invalid(format!("not a readable calibration YAML: {}", one_line(&e)))
        })?
    };
    let Value::Mapping(_) = doc else {
        refuse!("not a camera calibration (expected a YAML mapping)");
    };
    // Kalibr camchain files nest each camera under cam0, cam1, ...
    let doc = match field(&doc, &["cam0"]) {
        Some(cam0) if field(&doc, CAMERA_MATRIX_KEYS).is_none() => cam0.clone(),
        _ => doc,
    };

    let k = matrix_field(&doc, CAMERA_MATRIX_KEYS)?
        .ok_or_else(|| LoadProblem::Invalid("missing camera_matrix (or K)".into()))?;
    let k = match k.len() {
        9 => k,
        // Kalibr: [fu, fv, pu, pv].
        4 => vec![k[0], 0.0, k[2], 0.0, k[1], k[3], 0.0, 0.0, 1.0],
        n => refuse!("camera_matrix has {n} values, expected 9 (3x3)"),
    };
    let (fx, skew, cx, fy, cy) = (k[0], k[1], k[2], k[4], k[5]);
    if !(fx > 0.0 && fy > 0.0 && fx.is_finite() && fy.is_finite()) {
        refuse!("camera_matrix has invalid focal lengths fx={fx}, fy={fy}");
    }
    if !cx.is_finite() || !cy.is_finite() {
        refuse!("camera_matrix has an invalid principal point");
    }
    if skew.abs() > 1e-6 * fx || k[3] != 0.0 || k[6] != 0.0 || k[7] != 0.0 || k[8] != 1.0 {
        refuse!("camera_matrix is not of the form [fx 0 cx; 0 fy cy; 0 0 1]");
    }

    if let Some(model) = field(&doc, &["distortion_model"]) {
        let model = model.as_str().unwrap_or_default();
        let supported = ["plumb_bob", "rational_polynomial", "radtan", "none", ""];
        if !supported.contains(&model) {
            refuse!("unsupported distortion_model {model:?} (only plumb_bob)");
        }
    }
    if let Some(model) = field(&doc, &["camera_model"]).and_then(Value::as_str) {
        if model != "pinhole" {
            refuse!("unsupported camera_model {model:?} (only pinhole)");
        }
    }
    let coefficients = matrix_field(
        &doc,
        &[
            "distortion_coefficients",
            "distortionCoefficients",
            "dist_coeffs",
            "distCoeffs",
            "distortion_coeffs",
            "D",
            "d",
        ],
    )?
    .unwrap_or_default();
    let mut distortion = [0.0; 5];
    for (slot, &value) in distortion.iter_mut().zip(&coefficients) {
        *slot = value;
    }
    if coefficients.len() > 5 && coefficients[5..].iter().any(|&c| c != 0.0) {
        refuse!(
            "distortion_coefficients has {} terms with non-zero k4.. ; only the 5-term \
                 plumb_bob model (k1 k2 p1 p2 k3) is supported",
            coefficients.len()
        );
    }
    if distortion.iter().any(|c| !c.is_finite()) {
        refuse!("distortion_coefficients contains a non-finite value");
    }

    // Kalibr gives `resolution: [width, height]` instead.
    let resolution = matrix_field(&doc, &["resolution"])?;
    let from_resolution = |index: usize, name: &str| -> Result<Option<u32>, LoadProblem> {
        match &resolution {
            Some(r) if r.len() == 2 => image_size(r[index], name).map(Some),
            Some(_) => refuse!("resolution must be [width, height]"),
            None => Ok(None),
        }
    };
    let width = match size_field(&doc, &["image_width", "imageWidth", "width"])? {
        Some(w) => w,
        None => from_resolution(0, "image_width")?
            .ok_or_else(|| LoadProblem::Invalid("missing image_width".into()))?,
    };
    let height = match size_field(&doc, &["image_height", "imageHeight", "height"])? {
        Some(h) => h,
        None => from_resolution(1, "image_height")?
            .ok_or_else(|| LoadProblem::Invalid("missing image_height".into()))?,
    };

    let camera = Camera {
        fx,
        fy,
        cx,
        cy,
        distortion,
        width,
        height,
    };
    camera
        .check_plausible()
        .map_err(|e| LoadProblem::Invalid(e.to_string()))?;
    Ok(camera)
}

/// A number as a person writes it: 1e308 rather than 309 digits.
fn short_number(x: f64) -> String {
    if x == 0.0 || (1e-4..1e7).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

const CAMERA_MATRIX_KEYS: &[&str] = &["camera_matrix", "cameraMatrix", "K", "k", "intrinsics"];

/// The subset of OpenCV's FileStorage XML a calibration uses: top-level
/// scalars (`<image_width>640</image_width>`) and matrices
/// (`<camera_matrix type_id="opencv-matrix"><rows>..<data>..</data>`),
/// turned into the same structure the YAML reader produces.
fn opencv_xml_to_value(text: &str) -> Result<Value, LoadProblem> {
    let body = inner_xml(text, "opencv_storage").ok_or_else(|| {
        LoadProblem::Invalid(
            "not an OpenCV calibration XML (no complete <opencv_storage> element)".into(),
        )
    })?;
    let mut map = serde_yaml::Mapping::new();
    let mut rest = body;
    while let Some(open) = rest.find('<') {
        let after = &rest[open + 1..];
        if after.starts_with('!') || after.starts_with('?') || after.starts_with('/') {
            rest = &after[after.find('>').map_or(after.len(), |i| i + 1)..];
            continue;
        }
        let name_end = after
            .find(|c: char| c.is_whitespace() || c == '>' || c == '/')
            .ok_or_else(|| LoadProblem::Invalid("malformed XML element".into()))?;
        let name = &after[..name_end];
        let not_closed = || LoadProblem::Invalid(format!("malformed XML: <{name}> is not closed"));
        let content = inner_xml(rest, name).ok_or_else(not_closed)?;
        // A matrix keeps its declared rows and cols, so that the YAML
        // reader's check (rows x cols values) holds XML files to the same.
        let value = match inner_xml(content, "data") {
            Some(data) => {
                let mut matrix = serde_yaml::Mapping::new();
                for dimension in ["rows", "cols"] {
                    if let Some(n) = inner_xml(content, dimension) {
                        matrix.insert(dimension.into(), n.trim().into());
                    }
                }
                let values = data.split_whitespace().map(|t| t.into()).collect();
                matrix.insert("data".into(), Value::Sequence(values));
                Value::Mapping(matrix)
            }
            None => content.trim().trim_matches('"').into(),
        };
        map.insert(name.into(), value);
        let close = format!("</{name}>");
        let end = rest.find(&close).ok_or_else(not_closed)?;
        rest = &rest[end + close.len()..];
    }
    Ok(Value::Mapping(map))
}

/// Text between the first `<tag ...>` and its `</tag>`.
fn inner_xml<'a>(text: &'a str, tag: &str) -> Option<&'a str> {
    let mut search = 0;
    let start = loop {
        let found = search + text[search..].find(&format!("<{tag}"))?;
        let next = text[found + 1 + tag.len()..].chars().next()?;
        if next == '>' || next.is_whitespace() {
            break found + text[found..].find('>')? + 1;
        }
        search = found + 1;
    };
    let end = start + text[start..].find(&format!("</{tag}>"))?;
    Some(&text[start..end])
}

impl Camera {
    /// The calibration as a ROS `camera_info` YAML file (the format
    /// `camera_calibration` writes), which [`Camera::load`] reads back
    /// exactly.
    pub fn to_ros_yaml(&self, camera_name: &str) -> String {
        let list = |values: &[f64]| {
            values
                .iter()
                .map(|v| format!("{v:?}"))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let (fx, fy, cx, cy) = (self.fx, self.fy, self.cx, self.cy);
        format!(
            "image_width: {}\nimage_height: {}\ncamera_name: {}\n\
             camera_matrix:\n  rows: 3\n  cols: 3\n  data: [{}]\n\
             distortion_model: plumb_bob\n\
             distortion_coefficients:\n  rows: 1\n  cols: 5\n  data: [{}]\n\
             rectification_matrix:\n  rows: 3\n  cols: 3\n  data: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]\n\
             projection_matrix:\n  rows: 3\n  cols: 4\n  data: [{}]\n",
            self.width,
            self.height,
            serde_yaml::to_string(camera_name)
                .map(|s| s.trim_end().to_string())
                .unwrap_or_default(),
            list(&[fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0]),
            list(&self.distortion),
            list(&[fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0]),
        )
    }
}

/// The calibration file formats [`Camera::to_file_text`] writes, all of
/// which [`Camera::load`] reads back exactly.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CalibrationFormat {
    /// ROS `camera_info` YAML, as `camera_calibration` writes it.
    RosYaml,
    /// OpenCV FileStorage YAML (`%YAML:1.0`, `!!opencv-matrix`).
    OpenCvYaml,
    /// OpenCV FileStorage XML.
    OpenCvXml,
}

impl CalibrationFormat {
    /// The format a file name asks for: `.xml` OpenCV XML, `.yml` OpenCV
    /// YAML (the extension OpenCV's samples write), anything else ROS YAML.
    pub fn for_path(path: &Path) -> CalibrationFormat {
        match path
            .extension()
            .and_then(|e| e.to_str())
            .map(str::to_ascii_lowercase)
            .as_deref()
        {
            Some("xml") => CalibrationFormat::OpenCvXml,
            Some("yml") => CalibrationFormat::OpenCvYaml,
            _ => CalibrationFormat::RosYaml,
        }
    }
}

impl Camera {
    /// The calibration in `format`; `camera_name` goes where the format
    /// has a place for it (ROS YAML).
    pub fn to_file_text(&self, format: CalibrationFormat, camera_name: &str) -> String {
        match format {
            CalibrationFormat::RosYaml => self.to_ros_yaml(camera_name),
            CalibrationFormat::OpenCvYaml => self.to_opencv_yaml(),
            CalibrationFormat::OpenCvXml => self.to_opencv_xml(),
        }
    }

    fn camera_matrix(&self) -> [f64; 9] {
        [self.fx, 0.0, self.cx, 0.0, self.fy, self.cy, 0.0, 0.0, 1.0]
    }

    /// The calibration as OpenCV FileStorage YAML (what
    /// `cv::FileStorage` and the calibration sample write).
    pub fn to_opencv_yaml(&self) -> String {
        let matrix = |rows: usize, cols: usize, values: &[f64]| {
            format!(
                "!!opencv-matrix\n   rows: {rows}\n   cols: {cols}\n   dt: d\n   data: [ {} ]\n",
                exact_list(values, ", ")
            )
        };
        format!(
            "%YAML:1.0\n---\nimage_width: {}\nimage_height: {}\ncamera_matrix: {}\
             distortion_coefficients: {}",
            self.width,
            self.height,
            matrix(3, 3, &self.camera_matrix()),
            matrix(5, 1, &self.distortion),
        )
    }

    /// The calibration as OpenCV FileStorage XML.
    pub fn to_opencv_xml(&self) -> String {
        let matrix = |name: &str, rows: usize, cols: usize, values: &[f64]| {
            format!(
                "<{name} type_id=\"opencv-matrix\">\n  <rows>{rows}</rows>\n  <cols>{cols}</cols>\n  \
                 <dt>d</dt>\n  <data>\n    {}</data></{name}>\n",
                exact_list(values, " ")
            )
        };
        format!(
            "<?xml version=\"1.0\"?>\n<opencv_storage>\n<image_width>{}</image_width>\n\
             <image_height>{}</image_height>\n{}{}</opencv_storage>\n",
            self.width,
            self.height,
            matrix("camera_matrix", 3, 3, &self.camera_matrix()),
            matrix("distortion_coefficients", 5, 1, &self.distortion),
        )
    }
}

/// Numbers in their shortest form that reads back to the same bits.
fn exact_list(values: &[f64], separator: &str) -> String {
    values
        .iter()
        .map(|v| format!("{v:?}"))
        .collect::<Vec<_>>()
        .join(separator)
}

/// OpenCV writes `%YAML:1.0` (not valid YAML 1.1/1.2 syntax) and tags its
/// matrices `!!opencv-matrix`; neither carries information we need.
fn strip_opencv_yaml(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    for line in text.lines() {
        if line.trim_start().starts_with("%YAML") {
            continue;
        }
        out.push_str(&line.replace("!!opencv-matrix", ""));
        out.push('\n');
    }
    out
}

fn one_line(e: &impl std::fmt::Display) -> String {
    e.to_string().lines().collect::<Vec<_>>().join(" ")
}

/// Look a key up case-sensitively first (ROS message `K` vs `k` differ only
/// in case), then case-insensitively (OpenCV samples write `Camera_Matrix`).
fn field<'a>(doc: &'a Value, names: &[&str]) -> Option<&'a Value> {
    let map = doc.as_mapping()?;
    for name in names {
        if let Some(v) = map.get(*name) {
            return Some(v);
        }
    }
    for name in names {
        for (key, value) in map {
            if key.as_str().is_some_and(|k| k.eq_ignore_ascii_case(name)) {
                return Some(value);
            }
        }
    }
    None
}

/// A matrix either as `{rows, cols, data: [...]}` or as a flat list.
fn matrix_field(doc: &Value, names: &[&str]) -> Result<Option<Vec<f64>>, LoadProblem> {
    let Some(value) = field(doc, names) else {
        return Ok(None);
    };
    let value = untag(value);
    let name = names[0];
    let data = match value {
        Value::Sequence(_) => value,
        Value::Mapping(_) => {
            let Some(data) = field(value, &["data"]) else {
                refuse!("{name} has no data list");
            };
            data
        }
        _ => refuse!("{name} is neither a list nor a matrix with data"),
    };
    let Value::Sequence(items) = untag(data) else {
        refuse!("{name} data is not a list");
    };
    let values = items
        .iter()
        .map(number)
        .collect::<Option<Vec<f64>>>()
        .ok_or_else(|| LoadProblem::Invalid(format!("{name} contains a non-numeric value")))?;
    if let Value::Mapping(_) = value {
        let rows = field(value, &["rows"]).and_then(number);
        let cols = field(value, &["cols"]).and_then(number);
        if let (Some(rows), Some(cols)) = (rows, cols) {
            if (rows * cols) as usize != values.len() {
                refuse!(
                    "{name} declares {rows}x{cols} but has {} values",
                    values.len()
                );
            }
        }
    }
    Ok(Some(values))
}

fn size_field(doc: &Value, names: &[&str]) -> Result<Option<u32>, LoadProblem> {
    let Some(value) = field(doc, names) else {
        return Ok(None);
    };
    let Some(n) = number(value) else {
        refuse!("{} is not a number", names[0]);
    };
    image_size(n, names[0]).map(Some)
}

fn image_size(n: f64, name: &str) -> Result<u32, LoadProblem> {
    if !((1.0..=1_000_000.0).contains(&n) && n.fract() == 0.0) {
        refuse!("{name} = {n} is not a valid image size");
    }
    Ok(n as u32)
}

fn untag(value: &Value) -> &Value {
    match value {
        Value::Tagged(tagged) => untag(&tagged.value),
        other => other,
    }
}

/// Numbers may come as YAML floats/ints or, from some writers, as strings
/// (e.g. OpenCV's `1.` or `.5`).
fn number(value: &Value) -> Option<f64> {
    match untag(value) {
        Value::Number(n) => n.as_f64(),
        Value::String(s) => s.trim().parse().ok(),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::tests::distorted;

    const ROS_YAML: &str = "\
image_width: 640
image_height: 480
camera_name: narrow_stereo
camera_matrix:
  rows: 3
  cols: 3
  data: [610.0, 0.0, 318.4, 0.0, 612.0, 243.1, 0.0, 0.0, 1.0]
distortion_model: plumb_bob
distortion_coefficients:
  rows: 1
  cols: 5
  data: [-0.28, 0.09, 0.0012, -0.0008, -0.012]
rectification_matrix:
  rows: 3
  cols: 3
  data: [1, 0, 0, 0, 1, 0, 0, 0, 1]
projection_matrix:
  rows: 3
  cols: 4
  data: [500, 0, 320, 0, 0, 500, 240, 0, 0, 0, 1, 0]
";

    const ROS_MESSAGE: &str = "\
header:
  seq: 0
  stamp: {secs: 0, nsecs: 0}
  frame_id: camera
height: 480
width: 640
distortion_model: \"plumb_bob\"
D: [-0.28, 0.09, 0.0012, -0.0008, -0.012]
K: [610.0, 0.0, 318.4, 0.0, 612.0, 243.1, 0.0, 0.0, 1.0]
R: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0]
P: [500.0, 0.0, 320.0, 0.0, 0.0, 500.0, 240.0, 0.0, 0.0, 0.0, 1.0, 0.0]
binning_x: 0
binning_y: 0
roi: {x_offset: 0, y_offset: 0, height: 0, width: 0, do_rectify: False}
";

    const OPENCV_YAML: &str = "%YAML:1.0
---
calibration_time: \"Mon 01 Jan 2024 10:00:00 CET\"
image_width: 640
image_height: 480
flags: 0
camera_matrix: !!opencv-matrix
   rows: 3
   cols: 3
   dt: d
   data: [ 6.1e+02, 0., 3.184e+02, 0., 6.12e+02, 2.431e+02, 0., 0.,
       1. ]
distortion_coefficients: !!opencv-matrix
   rows: 5
   cols: 1
   dt: d
   data: [ -2.8e-01, 9.0000000000000000e-02, 1.2e-03, -8.0e-04,
       -1.2e-02 ]
avg_reprojection_error: 2.1e-01
";

    #[test]
    fn parses_all_calibration_formats() {
        for text in [ROS_YAML, ROS_MESSAGE, OPENCV_YAML] {
            let cam = Camera::parse(text).unwrap_or_else(|e| panic!("{e:#}\n{text}"));
            assert_eq!(cam, distorted(), "{text}");
        }
    }

    const OPENCV_XML: &str = r#"<?xml version="1.0"?>
<opencv_storage>
<calibration_time>"Mon 01 Jan 2024"</calibration_time>
<!-- written by the calibration sample -->
<image_width>640</image_width>
<image_height>480</image_height>
<camera_matrix type_id="opencv-matrix">
  <rows>3</rows>
  <cols>3</cols>
  <dt>d</dt>
  <data>
    6.1e+02 0. 3.184e+02 0. 6.12e+02 2.431e+02 0. 0. 1.</data></camera_matrix>
<distortion_coefficients type_id="opencv-matrix">
  <rows>5</rows>
  <cols>1</cols>
  <dt>d</dt>
  <data>
    -2.8e-01 9.0e-02 1.2e-03 -8.0e-04 -1.2e-02</data></distortion_coefficients>
<avg_reprojection_error>2.1e-01</avg_reprojection_error>
</opencv_storage>
"#;

    const KALIBR: &str = "\
cam0:
  camera_model: pinhole
  intrinsics: [610.0, 612.0, 318.4, 243.1]
  distortion_model: radtan
  distortion_coeffs: [-0.28, 0.09, 0.0012, -0.0008]
  resolution: [640, 480]
  rostopic: /cam0/image_raw
";

    #[test]
    fn opencv_xml_matrices_must_hold_what_they_declare() {
        let five = "-2.8e-01 9.0e-02 1.2e-03 -8.0e-04 -1.2e-02";
        for data in ["", "-2.8e-01", &"0.1 ".repeat(100)] {
            let text = OPENCV_XML.replace(five, data);
            let err = Camera::parse(&text).unwrap_err().to_string();
            assert!(
                err.starts_with("distortion_coefficients declares 5x1 but has"),
                "{err}"
            );
        }
    }

    #[test]
    fn parses_opencv_xml_and_kalibr() {
        assert_eq!(Camera::parse(OPENCV_XML).unwrap(), distorted());
        let kalibr = Camera::parse(KALIBR).unwrap();
        assert_eq!(
            kalibr,
            Camera {
                distortion: [-0.28, 0.09, 0.0012, -0.0008, 0.0],
                ..distorted()
            }
        );
    }

    #[test]
    fn ros_yaml_writer_round_trips() {
        let cam = Camera {
            fx: 1234.5678901234,
            cx: 0.1 + 0.2,
            ..distorted()
        };
        let text = cam.to_ros_yaml("front: camera");
        assert_eq!(Camera::parse(&text).unwrap(), cam, "{text}");
    }

    #[test]
    fn every_writer_round_trips_and_the_extension_picks_it() {
        let cam = Camera {
            fx: 1234.5678901234,
            distortion: [-0.28, 0.09, 1.2e-5, -0.0008, -0.012],
            ..distorted()
        };
        for (name, format) in [
            ("cam.yaml", CalibrationFormat::RosYaml),
            ("cam.yml", CalibrationFormat::OpenCvYaml),
            ("cam.XML", CalibrationFormat::OpenCvXml),
            ("cam", CalibrationFormat::RosYaml),
        ] {
            assert_eq!(CalibrationFormat::for_path(Path::new(name)), format);
            let text = cam.to_file_text(format, "cam");
            assert_eq!(Camera::parse(&text).unwrap(), cam, "{text}");
        }
    }

    #[test]
    fn parses_opencv_tutorial_key_spelling_and_four_coefficients() {
        let text = "%YAML:1.0\nimage_Width: 800\nimage_Height: 600\n\
            Camera_Matrix: !!opencv-matrix\n   rows: 3\n   cols: 3\n   dt: d\n   \
            data: [ 700., 0., 399.5, 0., 700., 299.5, 0., 0., 1. ]\n\
            Distortion_Coefficients: !!opencv-matrix\n   rows: 4\n   cols: 1\n   dt: d\n   \
            data: [ -0.1, 0.01, 0., 0. ]\n";
        let cam = Camera::parse(text).unwrap();
        assert_eq!((cam.width, cam.height), (800, 600));
        assert_eq!(cam.distortion, [-0.1, 0.01, 0.0, 0.0, 0.0]);
        assert_eq!((cam.fx, cam.cx), (700.0, 399.5));
    }

    #[test]
    fn deeply_nested_text_is_refused_before_parsing() {
        for text in [
            "[".repeat(100_000),
            "- ".repeat(100_000),
            (0..1000)
                .map(|k| format!("{}a{k}:\n", " ".repeat(2 * k)))
                .collect(),
        ] {
            let err = Camera::parse(&text).unwrap_err().to_string();
            assert!(err.contains("nested more than"), "{err}");
        }
    }

    #[test]
    fn load_reports_file_and_problem_on_one_line() {
        let dir = tempfile::tempdir().unwrap();
        let good = dir.path().join("cam.yaml");
        std::fs::write(&good, OPENCV_YAML).unwrap();
        assert_eq!(Camera::load(&good).unwrap(), distorted());

        let cases = [
            (
                "nok.yaml",
                "image_width: 640\nimage_height: 480\n",
                "camera_matrix",
            ),
            (
                "nosize.yaml",
                "K: [1, 0, 1, 0, 1, 1, 0, 0, 1]\n",
                "image_width",
            ),
            ("short.yaml", "width: 4\nheight: 4\nK: [1, 0, 1]\n", "9"),
            (
                "fisheye.yaml",
                "width: 4\nheight: 4\nK: [1,0,1,0,1,1,0,0,1]\ndistortion_model: equidistant\n",
                "equidistant",
            ),
            ("garbage.yaml", "{ this is: [not yaml\n", "YAML"),
            ("list.yaml", "- 1\n- 2\n", "mapping"),
            (
                "open.xml",
                "<?xml version=\"1.0\"?>\n<opencv_storage>\n<camera_matrix><data>1 0\n</opencv_storage>",
                "not closed",
            ),
            (
                "other.xml",
                "<?xml version=\"1.0\"?>\n<svg></svg>\n",
                "opencv_storage",
            ),
            (
                "wide.yaml",
                "width: 4\nheight: 4\nK: [1,0,1,0,1,1,0,0,1]\nD: [0, 0, 0, 0, 0, 0.3, 0, 0]\n",
                "plumb_bob",
            ),
        ];
        for (name, text, expected) in cases {
            let path = dir.path().join(name);
            std::fs::write(&path, text).unwrap();
            let message = format!("{:#}", Camera::load(&path).unwrap_err());
            assert!(message.contains(name), "{message}");
            assert!(message.contains(expected), "{message}");
            assert!(!message.contains('\n'), "{message}");
        }
        let missing = dir.path().join("absent.yaml");
        let message = format!("{:#}", Camera::load(&missing).unwrap_err());
        assert!(message.contains("absent.yaml") && !message.contains('\n'));
    }
}
