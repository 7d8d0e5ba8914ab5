//! `Detector` and `Marker`.

use crate::camera::PyCamera;
use crate::family::PyFamily;
use crate::{guard, Error};
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::Mutex;
use whycode::arena::ArenaPosition;
use whycode::board::{Board, BoardPose};
use whycode::detect::{Detection, Detector, StageTimings, Target};
use whycode::session::{Frame, FrameError, FrameReport, Session, SessionConfig};
use whycode::spec::{DetectSpec, TargetSpec};

/// Finds WhyCode markers (or legacy WhyCon circles) in frames.
///
/// Without tracking every call stands alone and a shared detector serves
/// several threads at once (each borrows a worker); with tracking, frames
/// are a sequence and calls take turns.
#[pyclass(name = "Detector", module = "whycode", frozen)]
pub struct PyDetector {
    config: SessionConfig,
    /// A session that has seen no frame, cloned for new workers.
    fresh: Session,
    /// Idle workers (without tracking), or the one tracking session.
    idle: Mutex<Vec<Session>>,
    tracking_state: Mutex<Option<Session>>,
    /// The stage timings of the frame detected last (with `timings=True`).
    last_timings: Mutex<Option<StageTimings>>,
}

/// Measures `view` in `session` as `whycode detect` measures an image:
/// the markers, their places on the arena, the boards' poses. A camera of
/// another aspect ratio is another camera, refused rather than left
/// without pose.
fn process(
    session: &mut Session,
    view: &crate::pixels::GrayView<'_>,
) -> Result<FrameReport, Error> {
    session
        .process(Frame::new(view, ""))
        .map_err(|problem| match problem {
            FrameError::Camera { problem, .. } => problem.into(),
            FrameError::Arena(problem) => Error::value(problem),
        })
}

impl PyDetector {
    fn run(&self, view: &crate::pixels::GrayView<'_>) -> Result<FrameReport, Error> {
        if self.config.detector.tracking {
            let mut state = self
                .tracking_state
                .lock()
                .unwrap_or_else(|poisoned| poisoned.into_inner());
            let detector = state.get_or_insert_with(|| self.fresh.clone());
            // A panic below leaves `state` empty, never half-updated.
            let mut taken = std::mem::replace(detector, self.fresh.clone());
            let found = process(&mut taken, view);
            self.keep_timings(&taken);
            *detector = taken;
            found
        } else {
            let worker = self.idle.lock().unwrap_or_else(|p| p.into_inner()).pop();
            let mut worker = worker.unwrap_or_else(|| self.fresh.clone());
            let found = process(&mut worker, view);
            self.keep_timings(&worker);
            self.idle
                .lock()
                .unwrap_or_else(|p| p.into_inner())
                .push(worker);
            found
        }
    }

    fn keep_timings(&self, session: &Session) {
        if self.config.detector.timings {
            *self.last_timings.lock().unwrap_or_else(|p| p.into_inner()) =
                session.detector().last_timings();
        }
    }
}

#[pymethods]
impl PyDetector {
    /// `family`: a Family, or None for legacy WhyCon markers (no ID ring);
    /// default Family(8, 2). `diameter` (metres, or text like "122mm") and
    /// `camera` together give each marker a pose. `tracking` follows markers
    /// from frame to frame (calls are then one sequence). `timings` times
    /// each stage of every frame (see `last_timings()`). `arena` (an
    /// `Arena` or an arena file's path) gives each marker its place on the
    /// floor (`Marker.arena`); one measured with a camera brings that camera
    /// and places markers without `diameter`. `boards`: sheet manifests (each page a board)
    /// and bundle files whose poses every frame's result carries in
    /// `boards` (needs `camera`; without `diameter` the first board's first
    /// marker gives it).
    #[new]
    #[pyo3(signature = (family = None, *, legacy = false, diameter = None, camera = None, tracking = false, max_markers = None, timings = false, arena = None, boards = Vec::new()))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        py: Python<'_>,
        family: Option<PyRef<'_, PyFamily>>,
        legacy: bool,
        diameter: Option<&Bound<'_, PyAny>>,
        camera: Option<PyRef<'_, PyCamera>>,
        tracking: bool,
        max_markers: Option<usize>,
        timings: bool,
        arena: Option<&Bound<'_, PyAny>>,
        boards: Vec<PathBuf>,
    ) -> PyResult<PyDetector> {
        let boards = py.detach(|| {
            guard(|| {
                let mut all = Vec::new();
                for path in &boards {
                    all.extend(Board::load(path)?);
                }
                Ok(all)
            })
        })?;
        let spec = DetectSpec {
            target: match family {
                Some(f) => TargetSpec::of_family(Some(&f.family)),
                None if legacy => TargetSpec::legacy(),
                None => TargetSpec::default(),
            },
            diameter: diameter.map(|d| crate::metres(d, "diameter")).transpose()?,
            camera: camera.map(|c| c.camera),
            max_markers,
            tracking,
            timings,
            arena: arena.map(crate::arena::arena_of).transpose()?,
            boards,
            ..DetectSpec::default()
        };
        if legacy && spec.target.family.is_some() {
            return Err(
                Error::value("legacy markers have no family: pass one or the other").into(),
            );
        }
        let config = guard(|| {
            spec.build().map_err(|err| {
                // Spelled as the keyword is here: `boards`, not `board`.
                if err.option == Some("board") {
                    Error::value(err.message_with(|_| "boards".to_string()))
                } else {
                    crate::spec_error(err)
                }
            })
        })?;
        let fresh = guard(|| Ok(Session::new(config.clone())))?;
        Ok(PyDetector {
            config,
            fresh,
            idle: Mutex::new(Vec::new()),
            tracking_state: Mutex::new(None),
            last_timings: Mutex::new(None),
        })
    }

    /// Finds the markers in one frame: a numpy array, uint8 or uint16, HxW
    /// grey, HxWx3 BGR or HxWx4 BGRA. The GIL is released meanwhile.
    /// Returns a `Detections`: the list of markers, with the configured
    /// boards' poses in its `boards` attribute (dicts with the fields of
    /// `whycode detect --board`'s JSON `boards` list) and, in
    /// `legacy_looking`, how many discs looked like legacy WhyCon markers
    /// while WhyCode ones were looked for (`legacy=True` reads them).
    fn detect<'py>(
        &self,
        py: Python<'py>,
        image: &Bound<'py, PyAny>,
    ) -> PyResult<Bound<'py, PyAny>> {
        let found = crate::pixels::with_gray(py, image, |view| self.run(view))?;
        let markers: Vec<PyMarker> = found
            .markers
            .into_iter()
            .zip(found.places)
            .map(|(detection, arena)| PyMarker { detection, arena })
            .collect();
        let result = crate::detections_type(py)?.call1((markers,))?;
        result.setattr("boards", boards_to_py(py, found.boards)?)?;
        result.setattr("legacy_looking", found.legacy_looking)?;
        Ok(result)
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
            let mut detector = Detector::new(self.config.detector.clone());
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

    /// How long each stage of the detector took on the frame detected
    /// last, as `whycode detect --timings` prints it in JSON:
    /// `{"frames": 1, "total_ms": ..., "stages_ms": {"prepare": ..., ...}}`.
    /// None without `timings=True` or before the first frame.
    fn last_timings<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyAny>>> {
        let last = *self.last_timings.lock().unwrap_or_else(|p| p.into_inner());
        last.map(|t| {
            let text = serde_json::to_string(&t).expect("timings serialise");
            crate::json_to_py(py, &text)
        })
        .transpose()
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
        self.config.detector.tracking
    }

    #[getter]
    fn family(&self) -> Option<PyFamily> {
        match &self.config.detector.target {
            Target::WhyCode(family) => Some(PyFamily::wrap(family.clone())),
            Target::WhyCon | Target::AnyBits { .. } => None,
        }
    }

    fn __repr__(&self) -> String {
        let family = match &self.config.detector.target {
            Target::WhyCode(f) => format!("Family(bits={}, distance={})", f.bits(), f.distance()),
            Target::WhyCon => "None (legacy)".to_string(),
            Target::AnyBits { distance: None } => "None (any bit count)".to_string(),
            Target::AnyBits { distance: Some(d) } => {
                format!("None (any bit count, distance={d})")
            }
        };
        format!(
            "Detector(family={family}, diameter={:?}, camera={}, tracking={})",
            self.config.detector.diameter_m,
            if self.config.detector.camera.is_some() {
                "..."
            } else {
                "None"
            },
            if self.config.detector.tracking {
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
    /// Where it lies on the detector's arena.
    arena: Option<ArenaPosition>,
}

#[pymethods]
impl PyMarker {
    /// The marker's ID; 0 means "unknown" (a marker seen but not read).
    #[getter]
    fn id(&self) -> u32 {
        self.detection.id
    }
    /// With `tracking=True`, the marker's track number: the same in every
    /// frame while it is followed (legacy circles, all ID 0, are told apart
    /// by it); None without tracking.
    #[getter]
    fn track(&self) -> Option<u32> {
        self.detection.track
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
    /// Direction of the outer ellipse's major axis, radians, atan2(dv, du):
    /// with `u, v` and `axes`, what `cv2.ellipse` needs (in degrees).
    #[getter]
    fn angle(&self) -> f64 {
        self.detection.angle
    }
    /// The ring's bit count as the ring itself shows it (None where its
    /// sectors are too fine to count, or for a legacy circle).
    #[getter]
    fn bits(&self) -> Option<u32> {
        self.detection.bits
    }
    /// Why a WhyCode marker has ID 0, as detect's JSON says it
    /// ("no_code_ring", "ring_unread", "not_a_member", "ambiguous",
    /// "other_bit_count", "no_family"); None when it is named, and for
    /// legacy circles.
    #[getter]
    fn unknown(&self) -> Option<&'static str> {
        self.detection.unnamed.map(whycode::detect::Unnamed::key)
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
    /// The rotation as OpenCV's Rodrigues vector (axis times angle,
    /// radians), as `cv2.solvePnP` returns it (None without a pose).
    #[getter]
    fn rvec<'py>(&self, py: Python<'py>) -> Option<Bound<'py, numpy::PyArray1<f64>>> {
        self.detection
            .pose
            .as_ref()
            .map(|p| numpy::PyArray1::from_slice(py, p.rotation_vector().as_slice()))
    }
    /// The marker centre in the camera frame, metres: OpenCV's `tvec`, the
    /// same values as `position` (None without a pose).
    #[getter]
    fn tvec<'py>(&self, py: Python<'py>) -> Option<Bound<'py, numpy::PyArray1<f64>>> {
        self.position(py)
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

    /// With a `Detector(arena=...)`: where the marker lies on the arena, a
    /// dict of x, y, z (metres, floor frame) and yaw (radians, the marker's
    /// +x from the arena's +x, counter-clockwise; None for legacy circles).
    #[getter]
    fn arena<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, pyo3::types::PyDict>>> {
        self.arena
            .map(|a| {
                let dict = pyo3::types::PyDict::new(py);
                dict.set_item("x", a.x)?;
                dict.set_item("y", a.y)?;
                dict.set_item("z", a.z)?;
                dict.set_item("yaw", a.yaw)?;
                Ok(dict)
            })
            .transpose()
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
            places: vec![self.arena],
            boards: Vec::new(),
            timings: None,
            stream: None,
            legacy_looking: 0,
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

/// Board poses as `whycode detect --board` writes them in JSON: through
/// detect's own report writer, one source for fields and rounding.
fn boards_to_py(py: Python<'_>, boards: Vec<BoardPose>) -> PyResult<Bound<'_, PyAny>> {
    if boards.is_empty() {
        return Ok(pyo3::types::PyList::empty(py).into_any());
    }
    let frame = FrameReport {
        image: String::new(),
        width: 0,
        height: 0,
        elapsed_ms: 0.0,
        markers: Vec::new(),
        places: Vec::new(),
        boards,
        timings: None,
        stream: None,
        legacy_looking: 0,
    };
    crate::json_to_py(py, &frame.to_json())?.get_item("boards")
}

/// The markers drawn over the image as `whycode detect --annotate` draws
/// them (outer ellipse, ID, +x axis): a new HxWx3 uint8 array in BGR order,
/// OpenCV's. An 8-bit BGR or BGRA image keeps its colours; grey and 16-bit
/// images are drawn over their grey.
#[pyfunction]
fn draw<'py>(
    py: Python<'py>,
    image: &Bound<'py, PyAny>,
    markers: Vec<PyRef<'py, PyMarker>>,
) -> PyResult<Bound<'py, numpy::PyArray3<u8>>> {
    use whycode::session::annotate::{annotated_rgb, drawn_over};
    let detections: Vec<Detection> = markers.iter().map(|m| m.detection.clone()).collect();
    let picture = match crate::pixels::colour_image(image)? {
        Some(colour) => py.detach(|| guard(|| Ok(drawn_over(&colour, &detections)?)))?,
        None => {
            let grey = crate::pixels::gray_image(py, image)?;
            py.detach(|| guard(|| Ok(annotated_rgb(&grey, &detections)?)))?
        }
    };
    crate::pixels::bgr_to_array(py, picture)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(draw, m)?)?;
    m.add_class::<PyDetector>()?;
    m.add_class::<PyMarker>()?;
    m.add_function(wrap_pyfunction!(crate::pixels::load_image, m)?)?;
    Ok(())
}
