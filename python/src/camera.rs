//! `Camera`: calibration files and OpenCV's arrays.

use crate::{guard, Error};
use numpy::PyReadonlyArrayDyn;
use pyo3::prelude::*;
use std::path::PathBuf;
use whycode::camera::Camera;

/// A calibrated pinhole camera with plumb_bob (k1 k2 p1 p2 k3) distortion.
#[pyclass(name = "Camera", module = "whycode", frozen)]
#[derive(Clone)]
pub struct PyCamera {
    pub(crate) camera: Camera,
    /// The files it was found from (a calibration's manifest, the pages
    /// that lists, the photos), which `save` must not write over.
    pub(crate) sources: Vec<PathBuf>,
}

impl PyCamera {
    /// A camera that was not made from files.
    pub(crate) fn new(camera: Camera) -> PyCamera {
        PyCamera {
            camera,
            sources: Vec::new(),
        }
    }
}

fn values(array: &Bound<'_, PyAny>, what: &str) -> PyResult<Vec<f64>> {
    let converted = array
        .py()
        .import("numpy")?
        .call_method1("asarray", (array, "float64"))
        .map_err(|_| Error::value(format!("{what}: expected an array of numbers")))?;
    let array: PyReadonlyArrayDyn<'_, f64> = converted.extract()?;
    Ok(array.as_array().iter().copied().collect())
}

fn format_list(values: &[f64]) -> String {
    let items: Vec<String> = values.iter().map(|v| format!("{v:?}")).collect();
    format!("[{}]", items.join(", "))
}

#[pymethods]
impl PyCamera {
    /// Reads a calibration: ROS camera_info YAML, OpenCV YAML/XML or Kalibr.
    #[staticmethod]
    fn load(path: PathBuf) -> PyResult<PyCamera> {
        Ok(guard(|| Ok(PyCamera::new(Camera::load(&path)?)))?)
    }

    /// From OpenCV's calibration results: the 3x3 camera matrix, the
    /// distortion coefficients (4, 5 or more with zeros beyond k3) and the
    /// image size (width, height) the calibration was made at.
    #[staticmethod]
    #[pyo3(signature = (camera_matrix, dist_coeffs, image_size))]
    fn from_opencv(
        camera_matrix: &Bound<'_, PyAny>,
        dist_coeffs: &Bound<'_, PyAny>,
        image_size: (i64, i64),
    ) -> PyResult<PyCamera> {
        let k = values(camera_matrix, "camera_matrix")?;
        let d = if dist_coeffs.is_none() {
            Vec::new()
        } else {
            values(dist_coeffs, "dist_coeffs")?
        };
        if k.iter().chain(&d).any(|v| !v.is_finite()) {
            return Err(Error::value("camera_matrix and dist_coeffs must be finite").into());
        }
        let (w, h) = image_size;
        if w <= 0 || h <= 0 || w > u32::MAX as i64 || h > u32::MAX as i64 {
            return Err(Error::value(format!(
                "image_size ({w}, {h}) is not an image size (width, height)"
            ))
            .into());
        }
        // Through the calibration parser, so an array is checked exactly as
        // a file with the same numbers would be.
        let text = format!(
            "camera_matrix:\n  rows: 3\n  cols: 3\n  data: {}\ndistortion_coefficients:\n  data: {}\nimage_width: {w}\nimage_height: {h}\n",
            format_list(&k),
            format_list(&d)
        );
        Ok(guard(|| Ok(PyCamera::new(Camera::parse(&text)?)))?)
    }

    /// An ideal camera (no distortion) with a horizontal field of view.
    #[staticmethod]
    #[pyo3(signature = (width, height, fov_deg = 60.0))]
    fn ideal(width: u32, height: u32, fov_deg: f64) -> PyResult<PyCamera> {
        if width == 0 || height == 0 || !(1.0..=170.0).contains(&fov_deg) {
            return Err(Error::value(
                "ideal camera: size must be positive and fov_deg between 1 and 170",
            )
            .into());
        }
        Ok(PyCamera::new(Camera::ideal(width, height, fov_deg)))
    }

    #[getter]
    fn fx(&self) -> f64 {
        self.camera.fx
    }
    #[getter]
    fn fy(&self) -> f64 {
        self.camera.fy
    }
    #[getter]
    fn cx(&self) -> f64 {
        self.camera.cx
    }
    #[getter]
    fn cy(&self) -> f64 {
        self.camera.cy
    }
    #[getter]
    fn width(&self) -> u32 {
        self.camera.width
    }
    #[getter]
    fn height(&self) -> u32 {
        self.camera.height
    }
    /// k1, k2, p1, p2, k3.
    #[getter]
    fn distortion(&self) -> (f64, f64, f64, f64, f64) {
        let d = self.camera.distortion;
        (d[0], d[1], d[2], d[3], d[4])
    }

    /// The 3x3 camera matrix as OpenCV writes it.
    #[getter]
    fn camera_matrix<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, numpy::PyArray2<f64>>> {
        let c = &self.camera;
        let k = vec![
            vec![c.fx, 0.0, c.cx],
            vec![0.0, c.fy, c.cy],
            vec![0.0, 0.0, 1.0],
        ];
        Ok(numpy::PyArray2::from_vec2(py, &k).expect("3x3"))
    }

    /// The calibration as ROS camera_info YAML.
    #[pyo3(signature = (camera_name = "camera"))]
    fn to_ros_yaml(&self, camera_name: &str) -> String {
        self.camera.to_ros_yaml(camera_name)
    }

    /// Writes the calibration in the format `whycode calibrate` picks for
    /// the same name: `.xml` OpenCV XML, `.yml` OpenCV YAML, anything else
    /// ROS camera_info YAML; or `format` ("ros", "opencv-yaml",
    /// "opencv-xml", the CLI's `--output-format`). Written whole or not at
    /// all; `whycode detect --camera` and `Camera.load` read it back.
    #[pyo3(signature = (path, *, format = None, camera_name = "camera"))]
    fn save(
        &self,
        py: Python<'_>,
        path: PathBuf,
        format: Option<&str>,
        camera_name: &str,
    ) -> PyResult<()> {
        use whycode::camera::CalibrationFormat;
        let format = match format {
            None => CalibrationFormat::for_path(&path),
            Some("ros") => CalibrationFormat::RosYaml,
            Some("opencv-yaml") => CalibrationFormat::OpenCvYaml,
            Some("opencv-xml") => CalibrationFormat::OpenCvXml,
            Some(other) => {
                return Err(Error::value(format!(
                    "format '{other}' is not 'ros', 'opencv-yaml' or 'opencv-xml'"
                ))
                .into())
            }
        };
        let text = self.camera.to_file_text(format, camera_name);
        let sources: Vec<&std::path::Path> = self.sources.iter().map(PathBuf::as_path).collect();
        Ok(py.detach(|| {
            guard(|| {
                whycode::io::check_outputs(&sources, &[&path])?;
                Ok(whycode::io::write_atomic(&path, text.as_bytes())?)
            })
        })?)
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<PyCamera>()
            .is_ok_and(|o| o.get().camera == self.camera)
    }

    fn __repr__(&self) -> String {
        let c = &self.camera;
        format!(
            "Camera(fx={}, fy={}, cx={}, cy={}, size=({}, {}), distortion={:?})",
            c.fx, c.fy, c.cx, c.cy, c.width, c.height, c.distortion
        )
    }
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyCamera>()
}
