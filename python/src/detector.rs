//! `Detector` and `Marker`.

use crate::camera::PyCamera;
use crate::family::PyFamily;
use crate::{guard, Error};
use pyo3::prelude::*;
use std::sync::Mutex;
use whycode::detect::report::FrameReport;
use whycode::detect::{Detection, Detector, DetectorConfig, Target};
use whycode::spec::{DetectSpec, TargetSpec};

/// Finds WhyCode markers (or legacy WhyCon circles) in frames.
///
/// Without tracking every call stands alone and a shared detector serves
/// several threads at once (each borrows a worker); with tracking, frames
/// are a sequence and calls take turns.
#[pyclass(name = "Detector", module = "whycode", frozen)]
pub struct PyDetector {
    config: DetectorConfig,
    /// A detector that has seen no frame, cloned for new workers.
    fresh: Detector,
    /// Idle workers (without tracking), or the one tracking detector.
    idle: Mutex<Vec<Detector>>,
    tracking_state: Mutex<Option<Detector>>,
}

impl PyDetector {
    fn run(&self, view: &crate::pixels::GrayView<'_>) -> Vec<Detection> {
        if self.config.tracking {
            let mut state = self
                .tracking_state
                .lock()
                .unwrap_or_else(|poisoned| poisoned.into_inner());
            let detector = state.get_or_insert_with(|| self.fresh.clone());
            // A panic below leaves `state` empty, never half-updated.
            let mut taken = std::mem::replace(detector, self.fresh.clone());
            let found = taken.detect(view);
            *detector = taken;
            found
        } else {
            let worker = self.idle.lock().unwrap_or_else(|p| p.into_inner()).pop();
            let mut worker = worker.unwrap_or_else(|| self.fresh.clone());
            let found = worker.detect(view);
            self.idle
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .push(worker);
            found
        }
    }
}

#[pymethods]
impl PyDetector {
    /// `family`: a Family, or None for legacy WhyCon markers (no ID ring);
    /// default Family(8, 2). `diameter` (metres, or text like "122mm") and
    /// `camera` together give each marker a pose. `tracking` follows markers
    /// from frame to frame (calls are then one sequence).
    #[new]
    #[pyo3(signature = (family = None, *, legacy = false, diameter = None, camera = None, tracking = false, max_markers = None))]
    fn new(
        family: Option<PyRef<'_, PyFamily>>,
        legacy: bool,
        diameter: Option<&Bound<'_, PyAny>>,
        camera: Option<PyRef<'_, PyCamera>>,
        tracking: bool,
        max_markers: Option<usize>,
    ) -> PyResult<PyDetector> {
        let spec = DetectSpec {
            target: match family {
                Some(f) => TargetSpec::of_family(Some(&f.family)),
                None if legacy => TargetSpec::legacy(),
                None => TargetSpec::default(),
            },
            diameter: diameter.map(|d| crate::length(d, "diameter")).transpose()?,
            camera: camera.map(|c| c.camera),
            max_markers,
            tracking,
            ..DetectSpec::default()
        };
        if legacy && spec.target.family.is_some() {
            return Err(
                Error::value("legacy markers have no family: pass one or the other").into(),
            );
        }
        let config = guard(|| spec.build().map_err(crate::spec_error))?;
        let fresh = guard(|| Ok(Detector::new(config.clone())))?;
        Ok(PyDetector {
            config,
            fresh,
            idle: Mutex::new(Vec::new()),
            tracking_state: Mutex::new(None),
        })
    }

    /// Finds the markers in one frame: a numpy array, uint8 or uint16, HxW
    /// grey, HxWx3 BGR or HxWx4 BGRA. The GIL is released meanwhile.
    fn detect(&self, py: Python<'_>, image: &Bound<'_, PyAny>) -> PyResult<Vec<PyMarker>> {
        let found = crate::pixels::with_gray(py, image, |view| Ok(self.run(view)))?;
        Ok(found.into_iter().map(PyMarker::from).collect())
    }

    /// Benchmark baseline: median nanoseconds of the Rust `detect` alone on
    /// this frame over `repeats` calls (no conversion, no Python objects).
    fn _rust_detect_ns(
        &self,
        py: Python<'_>,
        image: &Bound<'_, PyAny>,
        repeats: usize,
    ) -> PyResult<f64> {
        crate::pixels::with_gray(py, image, |view| {
            let mut detector = self.fresh.clone();
            let mut times: Vec<f64> = (0..repeats.max(1))
                .map(|_| {
                    let start = std::time::Instant::now();
                    std::hint::black_box(detector.detect(view));
                    start.elapsed().as_nanos() as f64
                })
                .collect();
            times.sort_by(f64::total_cmp);
            Ok(times[times.len() / 2])
        })
    }

    /// Forgets tracks and adapted tolerances.
    fn reset(&self) {
        *self
            .tracking_state
            .lock()
            .unwrap_or_else(|p| p.into_inner()) = None;
        self.idle.lock().unwrap_or_else(|p| p.into_inner()).clear();
    }

    #[getter]
    fn tracking(&self) -> bool {
        self.config.tracking
    }

    #[getter]
    fn family(&self) -> Option<PyFamily> {
        match &self.config.target {
            Target::WhyCode(family) => Some(PyFamily::wrap(family.clone())),
            Target::WhyCon | Target::AnyBits { .. } => None,
        }
    }

    fn __repr__(&self) -> String {
        let family = match &self.config.target {
            Target::WhyCode(f) => format!("Family(bits={}, distance={})", f.bits(), f.distance()),
            Target::WhyCon => "None (legacy)".to_string(),
            Target::AnyBits { distance: None } => "None (any bit count)".to_string(),
            Target::AnyBits { distance: Some(d) } => {
                format!("None (any bit count, distance={d})")
            }
        };
        format!(
            "Detector(family={family}, diameter={:?}, camera={}, tracking={})",
            self.config.diameter_m,
            if self.config.camera.is_some() {
                "..."
            } else {
                "None"
            },
            if self.config.tracking {
                "True"
            } else {
                "False"
            }
        )
    }
}

/// One marker found in a frame. Attributes hold full precision; `as_dict()`
/// is the object `whycode detect --format json` prints (rounded as printed).
#[pyclass(name = "Marker", module = "whycode", frozen)]
pub struct PyMarker {
    detection: Detection,
}

impl From<Detection> for PyMarker {
    fn from(detection: Detection) -> PyMarker {
        PyMarker { detection }
    }
}

#[pymethods]
impl PyMarker {
    /// The marker's ID; 0 means "unknown" (a marker seen but not read).
    #[getter]
    fn id(&self) -> u32 {
        self.detection.id
    }
    /// The code as read, None for legacy markers or an unread ring.
    #[getter]
    fn code(&self) -> Option<u32> {
        self.detection.code
    }
    /// Centre, pixels.
    #[getter]
    fn u(&self) -> f64 {
        self.detection.u
    }
    #[getter]
    fn v(&self) -> f64 {
        self.detection.v
    }
    /// Direction of the marker's +x axis in the image (radians), None
    /// when unknown.
    #[getter]
    fn yaw(&self) -> Option<f64> {
        self.detection.yaw
    }
    /// Semi-axes of the outer ellipse (major, minor), pixels.
    #[getter]
    fn axes(&self) -> (f64, f64) {
        (self.detection.axes[0], self.detection.axes[1])
    }
    #[getter]
    fn confidence(&self) -> f64 {
        self.detection.confidence
    }
    /// Marker centre in the camera frame, metres (None without a pose).
    #[getter]
    fn position<'py>(&self, py: Python<'py>) -> Option<Bound<'py, numpy::PyArray1<f64>>> {
        self.detection
            .pose
            .as_ref()
            .map(|p| numpy::PyArray1::from_slice(py, &[p.position.x, p.position.y, p.position.z]))
    }
    /// Rotation from marker to camera frame, 3x3 (None without a pose).
    #[getter]
    fn rotation<'py>(&self, py: Python<'py>) -> Option<Bound<'py, numpy::PyArray2<f64>>> {
        self.detection.pose.as_ref().map(|p| {
            let rows: Vec<Vec<f64>> = (0..3)
                .map(|r| (0..3).map(|c| p.rotation[(r, c)]).collect())
                .collect();
            numpy::PyArray2::from_vec2(py, &rows).expect("3x3")
        })
    }
    /// The rotation as a quaternion (x, y, z, w) (None without a pose).
    #[getter]
    fn quaternion(&self) -> Option<(f64, f64, f64, f64)> {
        self.detection.pose.as_ref().map(|p| {
            (
                p.quaternion[0],
                p.quaternion[1],
                p.quaternion[2],
                p.quaternion[3],
            )
        })
    }

    /// The marker as `whycode detect --format json` prints it.
    fn as_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        // Through detect's own report writer: one source for fields,
        // order and rounding.
        let frame = FrameReport {
            image: String::new(),
            width: 0,
            height: 0,
            elapsed_ms: 0.0,
            markers: vec![self.detection.clone()],
            boards: Vec::new(),
        };
        crate::json_to_py(py, &frame.to_json())?
            .get_item("markers")?
            .get_item(0)
    }

    fn __repr__(&self) -> String {
        let d = &self.detection;
        let yaw = d
            .yaw
            .map_or("None".to_string(), |y| format!("{:.1}°", y.to_degrees()));
        format!(
            "Marker(id={}, u={:.2}, v={:.2}, yaw={yaw}, confidence={:.2}{})",
            d.id,
            d.u,
            d.v,
            d.confidence,
            if d.pose.is_some() { ", with pose" } else { "" }
        )
    }
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<PyDetector>()?;
    m.add_class::<PyMarker>()?;
    m.add_function(wrap_pyfunction!(crate::pixels::load_image, m)?)?;
    Ok(())
}
