//! `simulate`: what a camera would see, with ground truth.

use crate::camera::PyCamera;
use crate::family::PyFamily;
use crate::{guard, spec_error, Error};
use pyo3::prelude::*;
use std::path::PathBuf;
use whycode::spec::{BackgroundKind, Layout, SceneSpec, TargetSpec};
use whycode::units::{parse_pixels, parse_scale, Angle};

/// An angle argument: text with its unit ("30deg", "0.5rad"), as on the
/// command line; `None` is 0.
fn angle(value: Option<&Bound<'_, PyAny>>, what: &str) -> PyResult<Angle> {
    value.map_or(Ok(Angle::from_degrees(0.0)), |v| {
        crate::quantity(v, what, str::parse)
    })
}

/// Pixels: a number, or text like "2px"; `None` is 0.
fn pixels(value: Option<&Bound<'_, PyAny>>, what: &str) -> PyResult<f64> {
    value.map_or(Ok(0.0), |v| crate::quantity(v, what, parse_pixels))
}

/// Renders a synthetic camera view, as `whycode simulate` does: one page of
/// a printed sheet (`manifest`), or loose markers of `family` (`ids`).
/// Quantities are given as on the command line: text with a unit
/// ("30deg", "50mm", "0.8m"; blur in pixels, "2px" or a number; a print
/// scale as 0.97 or "97%"), and a number means what it means typed there
/// without a unit.
/// Returns (HxW uint8 image, ground truth as a dict).
#[pyfunction(name = "simulate")]
#[pyo3(signature = (*, manifest = None, page = None, print_scale = None, family = None, ids = None,
    diameter = None, layout = None, camera = None, size = None, fov = None,
    camera_distance = None, tilt = None, pan = None, roll = None, background = None,
    gradient = 1.0, gradient_angle = None, exposure = None, dark = false, blur = None,
    motion_blur = None, motion_angle = None, noise = 0.0, jpeg = None, blot = Vec::new(), seed = 1))]
#[allow(clippy::too_many_arguments)]
fn simulate_scene<'py>(
    py: Python<'py>,
    manifest: Option<PathBuf>,
    page: Option<u32>,
    print_scale: Option<&Bound<'py, PyAny>>,
    family: Option<PyRef<'py, PyFamily>>,
    ids: Option<Vec<u32>>,
    diameter: Option<&Bound<'py, PyAny>>,
    layout: Option<&str>,
    camera: Option<PyRef<'py, PyCamera>>,
    size: Option<(u32, u32)>,
    fov: Option<&Bound<'py, PyAny>>,
    camera_distance: Option<&Bound<'py, PyAny>>,
    tilt: Option<&Bound<'py, PyAny>>,
    pan: Option<&Bound<'py, PyAny>>,
    roll: Option<&Bound<'py, PyAny>>,
    background: Option<&str>,
    gradient: f64,
    gradient_angle: Option<&Bound<'py, PyAny>>,
    exposure: Option<f64>,
    dark: bool,
    blur: Option<&Bound<'py, PyAny>>,
    motion_blur: Option<&Bound<'py, PyAny>>,
    motion_angle: Option<&Bound<'py, PyAny>>,
    noise: f64,
    jpeg: Option<u8>,
    blot: Vec<u32>,
    seed: u64,
) -> PyResult<(Bound<'py, numpy::PyArray2<u8>>, Bound<'py, PyAny>)> {
    let layout = match layout {
        None => None,
        Some("grid") => Some(Layout::Grid),
        Some("scatter") => Some(Layout::Scatter),
        Some(other) => {
            return Err(Error::value(format!("layout '{other}' is not 'grid' or 'scatter'")).into())
        }
    };
    let background = match background {
        None => None,
        Some("grey") => Some(BackgroundKind::Grey),
        Some("table") => Some(BackgroundKind::Table),
        Some("clutter") => Some(BackgroundKind::Clutter),
        Some(other) => {
            return Err(Error::value(format!(
                "background '{other}' is not 'grey', 'table' or 'clutter'"
            ))
            .into())
        }
    };
    let spec = SceneSpec {
        manifest,
        page,
        print_scale: print_scale
            .map(|s| crate::quantity(s, "print_scale", parse_scale))
            .transpose()?,
        target: match family {
            Some(f) => TargetSpec::of_family(Some(&f.family)),
            None => TargetSpec::default(),
        },
        ids,
        diameter: diameter.map(|d| crate::length(d, "diameter")).transpose()?,
        layout,
        camera: camera.map(|c| c.camera),
        size,
        fov: fov
            .map(|f| crate::quantity(f, "fov", str::parse))
            .transpose()?,
        camera_distance: camera_distance
            .map(|d| crate::length(d, "camera_distance"))
            .transpose()?,
        tilt: angle(tilt, "tilt")?,
        pan: angle(pan, "pan")?,
        roll: angle(roll, "roll")?,
        background,
        gradient,
        gradient_angle: angle(gradient_angle, "gradient_angle")?,
        exposure,
        dark,
        blur_px: pixels(blur, "blur")?,
        motion_blur_px: pixels(motion_blur, "motion_blur")?,
        motion_angle: angle(motion_angle, "motion_angle")?,
        noise,
        jpeg,
        blot,
        seed,
    };
    let (image, truth) = py.detach(|| {
        guard(|| {
            let scene = spec.build().map_err(spec_error)?;
            let (image, truth) = whycode::simulate::render(&scene);
            Ok((image, truth.to_json()))
        })
    })?;
    Ok((
        crate::pixels::to_array(py, image)?,
        crate::json_to_py(py, &truth)?,
    ))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(simulate_scene, m)?)
}
