//! `calibrate`: a camera's intrinsics and lens distortion from photos of a
//! printed sheet, as `whycode calibrate` finds them.

use crate::camera::PyCamera;
use crate::{guard, spec_error, Error};
use pyo3::prelude::*;
use std::path::PathBuf;
use whycode::calibrate::CalibrationError;
use whycode::manifest::Manifest;
use whycode::spec::CalibrateSpec;

impl From<CalibrationError> for Error {
    fn from(err: CalibrationError) -> Error {
        Error::Value(whycode::error::one_line(&err))
    }
}

/// Calibrates a camera from photos of the sheet `manifest` describes, as
/// `whycode calibrate` does with the same options. `images` holds paths
/// (read by the CLI's loader) or numpy arrays (named "image1", "image2",
/// ... in the report), all from one camera at one resolution. Returns
/// `(camera, report)`: the report is a dict of the overall and per-view
/// RMS, each parameter's standard deviation, the markers per ninth of the
/// image and the advice. A calibration the photos cannot support raises
/// ValueError with the command line's one-line reason.
#[pyfunction(name = "calibrate")]
#[pyo3(signature = (manifest, images, *, fix_principal_point = false, fix_aspect = false,
    no_tangential = false, no_k3 = false, print_scale = None))]
#[allow(clippy::too_many_arguments)]
fn calibrate_photos<'py>(
    py: Python<'py>,
    manifest: PathBuf,
    images: Vec<Bound<'py, PyAny>>,
    fix_principal_point: bool,
    fix_aspect: bool,
    no_tangential: bool,
    no_k3: bool,
    print_scale: Option<&Bound<'py, PyAny>>,
) -> PyResult<(PyCamera, Bound<'py, PyAny>)> {
    let print_scale = print_scale
        .map(|s| crate::quantity(s, "print_scale", whycode::units::parse_scale))
        .transpose()?;
    let options = guard(|| {
        CalibrateSpec {
            fix_principal_point,
            fix_aspect,
            no_tangential,
            no_k3,
            print_scale,
        }
        .build()
        .map_err(spec_error)
    })?;
    if images.is_empty() {
        return Err(Error::value("calibrate: no images given").into());
    }
    // The manifest, the pages it lists and the photos: what the camera is
    // found from, and what its `save` must never write over.
    let read = whycode::input::Recording::start();
    let manifest = py.detach(|| guard(|| Ok(Manifest::load(&manifest)?)))?;
    let mut photos = Vec::with_capacity(images.len());
    for (k, item) in images.iter().enumerate() {
        if let Ok(path) = item.extract::<PathBuf>() {
            let image = py.detach(|| guard(|| Ok(whycode::image_io::load_gray(&path)?)))?;
            photos.push((path.display().to_string(), image));
        } else {
            photos.push((
                format!("image{}", k + 1),
                crate::pixels::gray_image(py, item)?,
            ));
        }
    }
    let sources = read.files();
    drop(read);
    let (camera, report) = py.detach(|| {
        guard(|| {
            let calibration = whycode::calibrate::calibrate(&manifest, &photos, &options)?;
            Ok((calibration.camera, calibration.to_json()))
        })
    })?;
    Ok((
        PyCamera { camera, sources },
        crate::json_to_py(py, &report)?,
    ))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(calibrate_photos, m)?)
}
