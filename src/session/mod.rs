//! A stream of frames measured the same way by every front end: the
//! measuring twin of [`crate::render::job`].
//!
//! A front end fills a [`SessionConfig`] (most often through
//! [`crate::spec::DetectSpec::build`]), makes a [`Session`] and hands it
//! its frames one at a time: image files, a folder, a bag or a video on
//! the command line, numpy arrays in Python, canvas pixels in the page,
//! ROS image messages in the node. [`Session::process`] fits the camera
//! to the frame, detects, places the markers on the arena and the boards
//! in the camera frame, and returns one [`FrameReport`]. Sinks are
//! functions of that report: [`report`] (JSON, CSV, table),
//! [`annotate`] (drawings), `ros::describe::frame_message` (messages and
//! transforms).
//!
//! Detection itself knows none of this: [`crate::detect`] finds markers;
//! boards ([`crate::board::BoardTracker`]) and the arena
//! ([`crate::arena::Arena::locate`]) consume its detections here.

pub mod annotate;
pub mod report;

use crate::arena::{Arena, ArenaPosition};
use crate::board::{Board, BoardTracker};
use crate::camera::{Camera, OtherCamera};
use crate::detect::{Detector, DetectorConfig};
pub use report::{FrameReport, StreamPosition};

/// What a session measures with: the detector, the boards whose poses
/// each frame reports and the arena every marker is placed on.
#[derive(Debug, Clone)]
pub struct SessionConfig {
    /// The detector; its camera is the one given (or the arena's).
    pub detector: DetectorConfig,
    /// Rigid sets of markers whose poses each frame reports (with a
    /// camera and a diameter).
    pub boards: Vec<Board>,
    /// A floor frame every marker is placed in.
    pub arena: Option<Arena>,
    /// A camera that comes with the frames (a bag's or a topic's
    /// camera_info) replaces the configured one: true unless the user gave
    /// a camera, which then wins.
    pub stream_cameras: bool,
}

impl SessionConfig {
    /// A session of the detector alone: no boards, no arena.
    pub fn detector(detector: DetectorConfig) -> SessionConfig {
        SessionConfig {
            detector,
            boards: Vec::new(),
            arena: None,
            stream_cameras: false,
        }
    }
}

/// One frame handed to a session.
pub struct Frame<'a, C: std::ops::Deref<Target = [u8]>> {
    /// The frame's grey pixels.
    pub image: &'a image::ImageBuffer<image::Luma<u8>, C>,
    /// How the frame is named in reports (a path, "camera", a topic).
    pub name: String,
    /// Where it sits in a recorded stream.
    pub stream: Option<StreamPosition>,
    /// The calibration that came with it (see
    /// [`SessionConfig::stream_cameras`]).
    pub camera: Option<Camera>,
}

impl<'a, C: std::ops::Deref<Target = [u8]>> Frame<'a, C> {
    /// A frame with a name and nothing else.
    pub fn new(image: &'a image::ImageBuffer<image::Luma<u8>, C>, name: impl Into<String>) -> Self {
        Frame {
            image,
            name: name.into(),
            stream: None,
            camera: None,
        }
    }
}

/// Why a frame could not be measured: the problem alone, which front ends
/// put after the frame's name in their own words.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum FrameError {
    /// The calibration is of another aspect ratio than the frame.
    #[error("{problem}")]
    Camera {
        /// The calibration came with the stream (not the configured one).
        from_stream: bool,
        /// What does not fit.
        problem: OtherCamera,
    },
    /// The arena was measured in a frame of another size or shape.
    #[error("{0}")]
    Arena(String),
}

/// A detector, the camera fitted to the frames, the boards' trackers and
/// the arena: one per stream of frames.
#[derive(Debug, Clone)]
pub struct Session {
    detector: Detector,
    /// The camera the configuration gave (fitted to each frame from here).
    configured: Option<Camera>,
    stream_cameras: bool,
    boards: BoardTracker,
    arena: Option<Arena>,
}

impl Session {
    /// A session that has seen no frame.
    pub fn new(config: SessionConfig) -> Session {
        let boards = BoardTracker::new(config.boards, config.detector.tracking);
        Session {
            configured: config.detector.camera,
            detector: Detector::new(config.detector),
            stream_cameras: config.stream_cameras,
            boards,
            arena: config.arena,
        }
    }

    /// Starts over as [`Session::new`] with `config` would, keeping the
    /// detector's pixel buffers (a worker reading unrelated images one
    /// after another).
    pub fn restart(&mut self, config: SessionConfig) {
        self.configured = config.detector.camera;
        self.stream_cameras = config.stream_cameras;
        self.boards = BoardTracker::new(config.boards, config.detector.tracking);
        self.arena = config.arena;
        self.detector.restart(config.detector);
    }

    /// The detector's configuration (its camera fitted to the last frame).
    pub fn detector_config(&self) -> &DetectorConfig {
        self.detector.config()
    }

    /// The detector, for what it keeps across frames (the family check,
    /// the last frame's timings).
    pub fn detector(&self) -> &Detector {
        &self.detector
    }

    /// The arena markers are placed on.
    pub fn arena(&self) -> Option<&Arena> {
        self.arena.as_ref()
    }

    /// Forgets tracked markers and boards (a pause, a camera switch).
    pub fn reset(&mut self) {
        self.detector.reset();
        self.boards.reset();
    }

    /// The camera for a frame of `width` x `height` (the stream's, the
    /// configured one or none), fitted to its size.
    fn camera_for(
        &self,
        width: u32,
        height: u32,
        stream: Option<Camera>,
    ) -> Result<Option<Camera>, FrameError> {
        let (camera, from_stream) = match stream {
            Some(camera) if self.stream_cameras => (Some(camera), true),
            _ => (self.configured, false),
        };
        camera
            .map(|c| c.for_image(width, height))
            .transpose()
            .map_err(|problem| FrameError::Camera {
                from_stream,
                problem,
            })
    }

    /// Measures one frame: nothing is detected in a frame the camera or
    /// the arena does not fit.
    pub fn process<C: std::ops::Deref<Target = [u8]>>(
        &mut self,
        frame: Frame<'_, C>,
    ) -> Result<FrameReport, FrameError> {
        let (width, height) = frame.image.dimensions();
        let camera = self.camera_for(width, height, frame.camera)?;
        if let Some(problem) = self
            .arena
            .as_ref()
            .and_then(|arena| arena.frame_problem(width, height))
        {
            return Err(FrameError::Arena(problem));
        }
        if self.detector.config().camera != camera {
            // Another calibration: poses and tracks start over with it.
            let mut config = self.detector.config().clone();
            config.camera = camera;
            self.detector.restart(config);
        }
        let clock = Clock::start();
        let markers = self.detector.detect(frame.image);
        let elapsed_ms = clock.elapsed_ms();
        let places: Vec<Option<ArenaPosition>> = match &self.arena {
            Some(arena) => markers
                .iter()
                .map(|d| arena.locate(d, camera.as_ref(), (width, height)))
                .collect(),
            None => vec![None; markers.len()],
        };
        let boards =
            self.boards
                .update(&markers, camera.as_ref(), self.detector.config().diameter_m);
        Ok(FrameReport {
            image: frame.name,
            width,
            height,
            elapsed_ms,
            markers,
            places,
            boards,
            timings: self.detector.last_timings(),
            stream: frame.stream,
            legacy_looking: self.detector.last_legacy_looking(),
        })
    }
}

/// The detection's wall time where the platform has a clock (not in the
/// browser's WebAssembly, where the page times frames itself).
struct Clock {
    #[cfg(not(all(target_arch = "wasm32", target_os = "unknown")))]
    start: std::time::Instant,
}

impl Clock {
    fn start() -> Clock {
        Clock {
            #[cfg(not(all(target_arch = "wasm32", target_os = "unknown")))]
            start: std::time::Instant::now(),
        }
    }

    fn elapsed_ms(&self) -> f64 {
        #[cfg(not(all(target_arch = "wasm32", target_os = "unknown")))]
        return self.start.elapsed().as_secs_f64() * 1000.0;
        #[cfg(all(target_arch = "wasm32", target_os = "unknown"))]
        return 0.0;
    }
}
