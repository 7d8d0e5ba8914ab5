//! `validate`: photos of a printed sheet checked against its manifest.

use crate::camera::PyCamera;
use crate::{guard, Error};
use pyo3::prelude::*;
use std::path::PathBuf;
use whycode::manifest::Manifest;

/// Checks photos of a printed sheet against the manifest written with it.
/// `images` holds paths (read by the CLI's loader) or numpy arrays (named
/// "image1", "image2", ... in the report). Returns the report as
/// `whycode validate --format json` prints it; with `annotate=True`,
/// `(report, [annotated BGR array per photo])` (OpenCV's order, as the
/// arrays taken).
#[pyfunction(name = "validate")]
#[pyo3(signature = (manifest, images, camera = None, *, annotate = false))]
fn validate_photos<'py>(
    py: Python<'py>,
    manifest: PathBuf,
    images: Vec<Bound<'py, PyAny>>,
    camera: Option<PyRef<'py, PyCamera>>,
    annotate: bool,
) -> PyResult<Bound<'py, PyAny>> {
    if images.is_empty() {
        return Err(Error::value("validate: no images given").into());
    }
    let camera = camera.map(|c| c.camera);
    let (manifest_data, mut detector) = py.detach(|| {
        guard(|| {
            let data = Manifest::load(&manifest)?;
            let detector = whycode::validate::detector_for(&data)
                .map_err(|e| Error::value(format!("{}: {e}", manifest.display())))?;
            Ok((data, detector))
        })
    })?;
    let mut photos = Vec::new();
    let mut pictures = Vec::new();
    for (k, item) in images.iter().enumerate() {
        let (name, image) = if let Ok(path) = item.extract::<PathBuf>() {
            let image = py.detach(|| guard(|| Ok(whycode::image_io::load_gray(&path)?)))?;
            (path.display().to_string(), image)
        } else {
            (
                format!("image{}", k + 1),
                crate::pixels::gray_image(py, item)?,
            )
        };
        let report = py.detach(|| {
            guard(|| {
                let cam = camera
                    .as_ref()
                    .map(|c| c.for_image(image.width(), image.height()))
                    .transpose()
                    .map_err(|problem| Error::value(format!("{name}: {problem}")))?;
                let report = whycode::validate::check_image(
                    &name,
                    &manifest_data,
                    &image,
                    cam.as_ref(),
                    &mut detector,
                );
                let picture =
                    annotate.then(|| whycode::validate::annotate::annotate(&image, &report));
                Ok((report, picture))
            })
        })?;
        photos.push(report.0);
        if let Some(p) = report.1 {
            pictures.push(p);
        }
    }
    let json =
        py.detach(|| guard(|| Ok(whycode::validate::summarise(&manifest_data, photos).to_json())))?;
    let report = crate::json_to_py(py, &json)?;
    if annotate {
        let arrays = pictures
            .into_iter()
            .map(|p| crate::pixels::bgr_to_array(py, p).map(Bound::into_any))
            .collect::<PyResult<Vec<_>>>()?;
        Ok((report, arrays).into_pyobject(py)?.into_any())
    } else {
        Ok(report)
    }
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(validate_photos, m)?)
}
