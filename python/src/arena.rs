//! `Arena`: a floor frame from four corner markers (`whycode arena`).

use crate::camera::PyCamera;
use crate::family::PyFamily;
use crate::{guard, Error};
use pyo3::prelude::*;
use std::path::PathBuf;
use whycode::arena::{Arena, Mapping};
use whycode::spec::{ArenaSpec, TargetSpec};

/// A floor frame: four corner markers of a rectangle of known size, and
/// how the image maps to the floor (through a calibrated camera, or a
/// plane-to-image map that ignores the lens). Pass it, or its file's path,
/// to `Detector(arena=...)`.
#[pyclass(name = "Arena", module = "whycode", frozen)]
#[derive(Clone)]
pub struct PyArena {
    pub(crate) arena: Arena,
}

#[pymethods]
impl PyArena {
    /// Reads an arena file (written by `whycode arena` or `save`).
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<PyArena> {
        Ok(guard(|| {
            Ok(PyArena {
                arena: Arena::load(&path)?,
            })
        })?)
    }

    /// An arena file's text.
    #[staticmethod]
    fn from_yaml(text: &str) -> PyResult<PyArena> {
        Ok(guard(|| {
            Ok(PyArena {
                arena: Arena::parse(text)?,
            })
        })?)
    }

    /// Measures the arena in one photo, as `whycode arena` does: `size` is
    /// (along x, along y) in metres or text with units; `ids` the corners
    /// (origin, +x corner, far corner, +y corner), default the four
    /// outermost markers; `camera` the calibrated camera that took it;
    /// `marker_height` the height above the floor of the markers to locate.
    #[staticmethod]
    #[pyo3(signature = (image, size, *, ids = None, camera = None, marker_height = None, family = None, legacy = false))]
    #[allow(clippy::too_many_arguments)]
    fn measure(
        py: Python<'_>,
        image: &Bound<'_, PyAny>,
        size: (Bound<'_, PyAny>, Bound<'_, PyAny>),
        ids: Option<Vec<u32>>,
        camera: Option<PyRef<'_, PyCamera>>,
        marker_height: Option<&Bound<'_, PyAny>>,
        family: Option<PyRef<'_, PyFamily>>,
        legacy: bool,
    ) -> PyResult<PyArena> {
        let spec = ArenaSpec {
            target: match family {
                Some(f) => TargetSpec::of_family(Some(&f.family)),
                None if legacy => TargetSpec::legacy(),
                None => TargetSpec::default(),
            },
            ids,
            size: Some([
                crate::metres(&size.0, "size")?,
                crate::metres(&size.1, "size")?,
            ]),
            camera: camera.map(|c| c.camera),
            marker_height: marker_height.map(height).transpose()?,
        };
        let options = guard(|| spec.build().map_err(crate::spec_error))?;
        let arena = crate::pixels::with_gray(py, image, |view| {
            options
                .measure(view)
                .map_err(|e| Error::value(e.to_string()))
        })?;
        Ok(PyArena { arena })
    }

    /// The arena file's text (YAML), as `whycode arena` writes it.
    fn to_yaml(&self) -> String {
        self.arena.to_yaml()
    }

    /// Writes the arena file (whole or not at all).
    fn save(&self, path: PathBuf) -> PyResult<()> {
        Ok(guard(|| {
            Ok(whycode::io::write_atomic(
                &path,
                self.arena.to_yaml().as_bytes(),
            )?)
        })?)
    }

    /// The corners' IDs: origin, +x corner, far corner, +y corner.
    #[getter]
    fn ids(&self) -> (u32, u32, u32, u32) {
        let [a, b, c, d] = self.arena.ids;
        (a, b, c, d)
    }

    /// The rectangle's sides along x and y, metres.
    #[getter]
    fn size(&self) -> (f64, f64) {
        (self.arena.size_m[0], self.arena.size_m[1])
    }

    /// Height above the floor of the markers located, metres.
    #[getter]
    fn marker_height(&self) -> f64 {
        self.arena.marker_height_m
    }

    /// The camera it was measured with; None for a plane-to-image map.
    #[getter]
    fn camera(&self) -> Option<PyCamera> {
        self.arena.camera().map(|camera| PyCamera::new(*camera))
    }

    fn __repr__(&self) -> String {
        let [w, h] = self.arena.size_m;
        let how = match &self.arena.mapping {
            Mapping::Floor { .. } => "camera",
            Mapping::Homography { .. } => "plane map, no camera",
        };
        format!(
            "Arena(ids={:?}, size=({w}, {h}), marker_height={}, {how})",
            self.arena.ids, self.arena.marker_height_m
        )
    }
}

/// A height: like a length in metres, but 0 (on the floor) is fine.
fn height(value: &Bound<'_, PyAny>) -> PyResult<whycode::units::Length> {
    crate::quantity(value, "marker_height", whycode::units::Length::parse_height)
}

/// `arena=` as `Detector` takes it: an `Arena` or an arena file's path.
pub(crate) fn arena_of(value: &Bound<'_, PyAny>) -> PyResult<Arena> {
    if let Ok(arena) = value.extract::<PyRef<'_, PyArena>>() {
        return Ok(arena.arena.clone());
    }
    let path: PathBuf = value
        .extract()
        .map_err(|_| Error::value("arena: expected an Arena or an arena file's path"))?;
    Ok(guard(|| Ok(Arena::load(&path)?))?)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyArena>()
}
