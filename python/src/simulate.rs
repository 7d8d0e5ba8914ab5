//! `simulate`: what a camera would see, with ground truth.

use crate::camera::PyCamera;
use crate::family::PyFamily;
use crate::{guard, spec_error, Error};
use pyo3::prelude::*;
use std::path::PathBuf;
use whycode::spec::{BackgroundKind, Layout, SceneSpec, TargetSpec};
use whycode::units::Angle;

fn degrees(value: f64) -> Angle {
    Angle::from_degrees(value)
}

/// Renders a synthetic camera view, as `whycode simulate` does: one page of
/// a printed sheet (`manifest`), or loose markers of `family` (`ids`).
/// Angles are in degrees, lengths in metres or text with a unit.
/// Returns (HxW uint8 image, ground truth as a dict).
#[pyfunction(name = "simulate")]
#[pyo3(signature = (*, manifest = None, page = None, print_scale = None, family = None, ids = None,
    diameter = None, layout = None, camera = None, size = None, fov = None,
    camera_distance = None, tilt = 0.0, pan = 0.0, roll = 0.0, background = None,
    gradient = 1.0, gradient_angle = 0.0, exposure = None, dark = false, blur = 0.0,
    motion_blur = 0.0, motion_angle = 0.0, noise = 0.0, jpeg = None, blot = Vec::new(), seed = 1))]
#[allow(clippy::too_many_arguments)]
fn simulate_scene<'py>(
    py: Python<'py>,
    manifest: Option<PathBuf>,
    page: Option<u32>,
    print_scale: Option<f64>,
    family: Option<PyRef<'py, PyFamily>>,
    ids: Option<Vec<u32>>,
    diameter: Option<&Bound<'py, PyAny>>,
    layout: Option<&str>,
    camera: Option<PyRef<'py, PyCamera>>,
    size: Option<(u32, u32)>,
    fov: Option<f64>,
    camera_distance: Option<&Bound<'py, PyAny>>,
    tilt: f64,
    pan: f64,
    roll: f64,
    background: Option<&str>,
    gradient: f64,
    gradient_angle: f64,
    exposure: Option<f64>,
    dark: bool,
    blur: f64,
    motion_blur: f64,
    motion_angle: f64,
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
        print_scale,
        target: match family {
            Some(f) => TargetSpec::of_family(Some(&f.family)),
            None => TargetSpec::default(),
        },
        ids,
        diameter: diameter.map(|d| crate::length(d, "diameter")).transpose()?,
        layout,
        camera: camera.map(|c| c.camera),
        size,
        fov: fov.map(degrees),
        camera_distance: camera_distance
            .map(|d| crate::length(d, "camera_distance"))
            .transpose()?,
        tilt: degrees(tilt),
        pan: degrees(pan),
        roll: degrees(roll),
        background,
        gradient,
        gradient_angle: degrees(gradient_angle),
        exposure,
        dark,
        blur_px: blur,
        motion_blur_px: motion_blur,
        motion_angle: degrees(motion_angle),
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
