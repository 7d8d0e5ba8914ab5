//! `simulate`: what a camera would see, with ground truth.

use crate::camera::PyCamera;
use crate::family::PyFamily;
use crate::{guard, Error};
use pyo3::prelude::*;
use std::path::PathBuf;
use whycode::camera::Camera;
use whycode::family::Family;
use whycode::geometry::Marker;
use whycode::manifest::Manifest;
use whycode::simulate::{layout, Background, MotionBlur, Scene, SceneObject, SheetPage};
use whycode::units::Angle;

fn radians(degrees: f64, what: &str) -> crate::Result<f64> {
    if !degrees.is_finite() {
        return Err(Error::value(format!("{what}: not a finite angle")));
    }
    Ok(Angle::from_degrees(degrees).radians())
}

fn pixels(value: f64, what: &str) -> crate::Result<f64> {
    const MAX_BLUR_PX: f64 = 500.0;
    if !(value.is_finite() && (0.0..=MAX_BLUR_PX).contains(&value)) {
        return Err(Error::value(format!(
            "{what}: {value} is not a blur length between 0 and {MAX_BLUR_PX} pixels"
        )));
    }
    Ok(value)
}

/// Renders a synthetic camera view, as `whycode simulate` does: one page of
/// a printed sheet (`manifest`), or loose markers of `family` (`ids`).
/// Angles are in degrees, lengths in metres or text with a unit.
/// Returns (HxW uint8 image, ground truth as a dict).
#[pyfunction(name = "simulate")]
#[pyo3(signature = (*, manifest = None, page = 1, print_scale = 1.0, family = None, ids = None,
    diameter = None, layout = "grid", camera = None, size = (1920, 1080), fov = 60.0,
    camera_distance = None, tilt = 0.0, pan = 0.0, roll = 0.0, background = None,
    gradient = 1.0, gradient_angle = 0.0, exposure = None, dark = false, blur = 0.0,
    motion_blur = 0.0, motion_angle = 0.0, noise = 0.0, jpeg = None, blot = Vec::new(), seed = 1))]
#[allow(clippy::too_many_arguments)]
fn simulate_scene<'py>(
    py: Python<'py>,
    manifest: Option<PathBuf>,
    page: u32,
    print_scale: f64,
    family: Option<PyRef<'py, PyFamily>>,
    ids: Option<Vec<u32>>,
    diameter: Option<&Bound<'py, PyAny>>,
    layout: &str,
    camera: Option<PyRef<'py, PyCamera>>,
    size: (u32, u32),
    fov: f64,
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
    let camera = match camera {
        Some(c) => c.camera,
        None => {
            let (w, h) = size;
            if !(16..=20000).contains(&w) || !(16..=20000).contains(&h) {
                return Err(Error::value("size: width and height must be 16..20000 pixels").into());
            }
            let fov = Angle::from_degrees(fov).degrees();
            if !(1.0..=170.0).contains(&fov) {
                return Err(Error::value("fov must be between 1 and 170 degrees").into());
            }
            Camera::ideal(w, h, fov)
        }
    };
    if !(gradient.is_finite() && gradient >= 1.0) {
        return Err(Error::value("gradient must be a ratio of at least 1 (e.g. 3 for 3:1)").into());
    }
    if !(noise.is_finite() && noise >= 0.0) {
        return Err(Error::value("noise must be a grey-level sigma of at least 0").into());
    }
    if !(print_scale > 0.1 && print_scale < 10.0) {
        return Err(Error::value(format!(
            "print_scale {print_scale} is not a plausible print scale"
        ))
        .into());
    }
    if jpeg.is_some_and(|q| !(1..=100).contains(&q)) {
        return Err(Error::value("jpeg quality must be between 1 and 100").into());
    }
    let diameter_mm = match diameter {
        Some(d) => crate::length(d, "diameter")?.mm(),
        None => 50.0,
    };
    let distance_m = camera_distance
        .map(|d| crate::length(d, "camera_distance").map(|l| l.m()))
        .transpose()?;
    let (tilt, pan, roll) = (
        radians(tilt, "tilt")?,
        radians(pan, "pan")?,
        radians(roll, "roll")?,
    );
    let scatter = match layout {
        "grid" => false,
        "scatter" => true,
        other => {
            return Err(Error::value(format!("layout '{other}' is not 'grid' or 'scatter'")).into())
        }
    };
    let background = match background {
        None => None,
        Some("grey") => Some(Background::Uniform(0.45)),
        Some("table") => Some(Background::Table),
        Some("clutter") => Some(Background::Clutter { density: 1.5 }),
        Some(other) => {
            return Err(Error::value(format!(
                "background '{other}' is not 'grey', 'table' or 'clutter'"
            ))
            .into())
        }
    };
    let exposure = match (exposure, dark) {
        (Some(_), true) => return Err(Error::value("give exposure or dark, not both").into()),
        (Some(e), _) if e > 0.0 && e.is_finite() => e,
        (Some(_), _) => return Err(Error::value("exposure must be positive").into()),
        (None, true) => 0.25,
        (None, false) => 1.0,
    };
    let blur = pixels(blur, "blur")?;
    let motion_blur = pixels(motion_blur, "motion_blur")?;
    let gradient_angle = radians(gradient_angle, "gradient_angle")?;
    let motion_angle = radians(motion_angle, "motion_angle")?;
    let family = family.map(|f| f.family.clone());

    let (image, truth) = py.detach(|| {
        guard(|| {
            let mut scene = Scene::new(camera);
            if let Some(path) = &manifest {
                if family.is_some() || ids.is_some() {
                    return Err(Error::value("show a manifest's page or loose markers (family, ids), not both"));
                }
                let manifest_data = Manifest::load(path)?;
                if page == 0 || page > manifest_data.pages.max(1) {
                    return Err(Error::value(format!("{}: has no page {page}", path.display())));
                }
                let [w, h] = manifest_data.page_size_mm;
                let distance = match distance_m {
                    Some(d) => d,
                    None => layout::distance_to_fill(&camera, w, h, 0.8),
                };
                let sheet_name = path
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default();
                let mut sheet_page = SheetPage::new(
                    manifest_data.clone(),
                    page,
                    layout::centred(distance, tilt, pan, roll),
                )
                .with_printed_text(&sheet_name);
                sheet_page.print_scale = print_scale;
                for &id in &blot {
                    let entry = manifest_data
                        .markers
                        .iter()
                        .find(|m| m.id == id && m.page == page)
                        .ok_or_else(|| Error::value(format!("blot {id}: no marker {id} on page {page}")))?;
                    let marker = SheetPage::marker_of(&manifest_data, entry);
                    sheet_page
                        .blots
                        .extend(layout::ring_blots(&marker, entry.x_mm, entry.y_mm, false));
                }
                scene.objects.push(SceneObject::Page(sheet_page));
                scene.background = Background::Table;
            } else {
                let Some(ids) = &ids else {
                    return Err(Error::value("say what to show: manifest=PATH, or ids=[...] (with family=) for loose markers"));
                };
                if ids.is_empty() || ids.len() > 100_000 {
                    return Err(Error::value("ids: give between 1 and 100000 IDs"));
                }
                let family = match family {
                    Some(f) => f,
                    None => Family::generate(
                        whycode::family::DEFAULT_BITS,
                        whycode::family::DEFAULT_DISTANCE,
                    )?,
                };
                let markers = ids
                    .iter()
                    .map(|&id| {
                        let code = family.code(id).ok_or_else(|| {
                            Error::value(whycode::render::sheet::id_range_error(&family, id))
                        })?;
                        Ok((Marker::whycode(family.bits(), code, diameter_mm), id))
                    })
                    .collect::<crate::Result<Vec<_>>>()?;
                let distance = distance_m.unwrap_or(1.0);
                let mut loose = if scatter {
                    let max_tilt = if tilt != 0.0 { tilt.abs() } else { 40f64.to_radians() };
                    layout::marker_scatter(&camera, &markers, distance, max_tilt, seed)
                } else {
                    layout::marker_grid(&markers, &layout::centred(distance, tilt, pan, roll))
                };
                for &id in &blot {
                    let m = loose
                        .iter_mut()
                        .find(|m| m.id == id)
                        .ok_or_else(|| Error::value(format!("blot {id}: no marker {id} in the scene")))?;
                    let blots = layout::ring_blots(&m.marker, 0.0, 0.0, true);
                    m.blots.extend(blots);
                }
                scene.objects.extend(loose.into_iter().map(SceneObject::Marker));
                scene.background = Background::Uniform(0.45);
            }
            if let Some(bg) = background {
                scene.background = bg;
            }
            scene.gradient = gradient;
            scene.gradient_angle = gradient_angle;
            scene.exposure = exposure;
            scene.focus_blur_px = blur;
            if motion_blur > 0.0 {
                scene.motion_blur = Some(MotionBlur {
                    length_px: motion_blur,
                    angle: motion_angle,
                });
            }
            scene.noise = noise;
            scene.seed = seed;
            scene.jpeg_quality = jpeg;
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
