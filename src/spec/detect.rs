//! A detector as the front ends ask for it: `whycode detect`'s options,
//! Python's `Detector(...)` keywords, the page's live view and the ROS 2
//! node's parameters, checked once and built into a [`SessionConfig`].

use super::{limits, within, Problem, SpecError, TargetSpec};
use crate::camera::Camera;
use crate::detect::{DetectorConfig, Target};
use crate::session::SessionConfig;
use crate::units::Length;

/// What to look for and what to report. `Default` is the command line's
/// `whycode detect` without options: the default family, no pose, no
/// tracking.
#[derive(Debug, Clone, Default)]
pub struct DetectSpec {
    /// Which markers.
    pub target: TargetSpec,
    /// The printed outer diameter of the black disc, for pose (with `camera`).
    pub diameter: Option<Length>,
    /// The calibrated camera, for pose (with `diameter`).
    pub camera: Option<Camera>,
    /// Most markers to report per frame (default 1024).
    pub max_markers: Option<usize>,
    /// Follow markers from frame to frame (calls are then one sequence).
    pub tracking: bool,
    /// Also report round candidates whose ring shows no code structure.
    pub unreadable: bool,
    /// Smallest black ring of a legacy marker worth reporting, pixels
    /// (legacy only; default the original WhyCon's 100).
    pub min_ink: Option<f64>,
    /// Boards and bundles whose poses each frame reports (with `camera`;
    /// without `diameter` the first board's first marker gives it).
    pub boards: Vec<crate::board::Board>,
    /// Time each stage of every frame (read with
    /// [`Detector::last_timings`](crate::Detector::last_timings)).
    pub timings: bool,
    /// Look for new markers over the whole frame in every tracked frame
    /// (a recording read offline): a marker is found in the frame it comes.
    pub scan_every_frame: bool,
    /// The camera comes with the frames (a bag's camera_info), so a
    /// diameter or boards without `camera` wait in the configuration for it.
    pub camera_later: bool,
    /// A floor frame (`whycode arena`) every marker is placed in. One
    /// measured with a camera brings that camera (`camera`, if given, must
    /// be the same) and places markers without `diameter` too (each
    /// outline is read on the arena's plane).
    pub arena: Option<crate::arena::Arena>,
    /// Height above the arena's floor of the markers located, in place of
    /// the arena file's (with an arena measured with a camera).
    pub marker_height: Option<Length>,
}

/// Boards a detector can locate and report: each name a /tf frame of its
/// own, and each sheet printed in the family detected (in another, its IDs
/// would be read as other markers, or as none, and the pose come from the
/// wrong places).
fn check_boards(boards: &[crate::board::Board], target: &Target) -> Result<(), SpecError> {
    let mut names = std::collections::HashSet::new();
    for board in boards {
        if let Some(problem) = crate::board::name_problem(&board.name) {
            return Err(SpecError::invalid("board", problem));
        }
        if !names.insert(board.name.as_str()) {
            return Err(SpecError::invalid(
                "board",
                format!(
                    "two boards are named {:?}: each board's name is its own /tf frame",
                    board.name
                ),
            ));
        }
        let Some(family) = target.family() else {
            continue;
        };
        for marker in &board.markers {
            let Some((bits, code)) = marker.ring else {
                continue;
            };
            if bits != family.bits() || family.code(marker.id) != Some(code) {
                let reads = match family.id_of(code) {
                    _ if bits != family.bits() => format!("has {} bits", family.bits()),
                    Some(other) => format!("reads as ID {other}"),
                    None => "does not hold".to_string(),
                };
                return Err(SpecError::invalid(
                    "board",
                    format!(
                        "{}: ID {} is printed as the {bits}-bit code {code}, which the family \
                         detected ({} bits, distance {}) {reads}: detect with the family the \
                         sheet was printed in",
                        board.name,
                        marker.id,
                        family.bits(),
                        family.distance(),
                    ),
                ));
            }
        }
    }
    Ok(())
}

impl DetectSpec {
    /// Checks every option and builds the session's configuration: the
    /// detector's, the boards and the arena.
    pub fn build(&self) -> Result<SessionConfig, SpecError> {
        let target = self.target.resolve()?;
        let mut diameter_m = self
            .diameter
            .map(|d| within("diameter", d.mm(), limits::MARKER_DIAMETER_MM).map(|mm| mm / 1000.0))
            .transpose()?;
        let mut camera = self.camera;
        let arena = self
            .arena
            .as_ref()
            .map(|arena| self.arena_with(arena, &mut camera))
            .transpose()?;
        if arena.is_none() && self.marker_height.is_some() {
            return Err(SpecError::of(
                "marker_height",
                Problem::Conflict("applies to markers located on an arena: give arena too".into()),
            ));
        }
        if !self.boards.is_empty() {
            if camera.is_none() && !self.camera_later {
                return Err(SpecError::of(
                    "board",
                    Problem::Conflict("a board's pose needs the camera: give camera too".into()),
                ));
            }
            check_boards(&self.boards, &target)?;
            diameter_m = diameter_m.or_else(|| {
                self.boards
                    .iter()
                    .flat_map(|b| b.markers.first())
                    .map(|m| m.diameter_m)
                    .next()
            });
        }
        match (diameter_m.is_some(), camera.is_some()) {
            (true, false) if !self.camera_later => {
                return Err(pose_needs_both("diameter", "camera"))
            }
            // The camera an arena brings places markers without a
            // diameter: each outline is read on the arena's known plane.
            (false, true) if self.camera.is_some() => {
                return Err(pose_needs_both(
                    "camera",
                    "diameter (or a board, whose markers give theirs)",
                ))
            }
            _ => {}
        }
        let legacy = target == Target::WhyCon;
        if self.unreadable && legacy {
            return Err(SpecError::of(
                "unreadable",
                Problem::Conflict("legacy circles have no ring to read".into()),
            ));
        }
        let mut config = DetectorConfig {
            target,
            diameter_m,
            camera,
            tracking: self.tracking,
            report_unreadable: self.unreadable,
            timings: self.timings,
            scan_every_frame: self.scan_every_frame,
            ..DetectorConfig::default()
        };
        if let Some(n) = self.max_markers {
            config.max_markers = n;
        }
        if let Some(pixels) = self.min_ink {
            if !legacy {
                return Err(SpecError::of(
                    "min_ink",
                    Problem::Conflict("applies to legacy circles only".into()),
                ));
            }
            config.legacy_min_ink_px = within("min_ink", pixels, limits::LEGACY_MIN_INK_PX)?;
        }
        Ok(SessionConfig {
            detector: config,
            boards: self.boards.clone(),
            arena,
            // A camera the user gave wins over one that comes with the
            // frames; the arena's does not.
            stream_cameras: self.camera.is_none(),
        })
    }
}

impl DetectSpec {
    /// The arena as the detector uses it (at the height asked for), the
    /// camera it was measured with put in `camera` or checked against it.
    fn arena_with(
        &self,
        arena: &crate::arena::Arena,
        camera: &mut Option<Camera>,
    ) -> Result<crate::arena::Arena, SpecError> {
        let mut arena = arena.clone();
        let Some(measured_with) = arena.camera().copied() else {
            if self.marker_height.is_some_and(|h| h.mm() != 0.0) {
                return Err(SpecError::of(
                    "marker_height",
                    Problem::Conflict(
                        "this arena was measured without a camera and maps the floor only: measure it with the camera for markers above the floor".into(),
                    ),
                ));
            }
            return Ok(arena);
        };
        if let Some(height) = self.marker_height {
            arena.marker_height_m = within("marker_height", height.m(), limits::MARKER_HEIGHT_M)?;
        }
        if let Some(problem) = arena.height_problem(arena.marker_height_m) {
            return Err(SpecError::invalid("marker_height", problem));
        }
        match *camera {
            None => *camera = Some(measured_with),
            Some(given) if !same_camera(&given, &measured_with) => {
                return Err(SpecError::of(
                    "arena",
                    Problem::Conflict(format!(
                        "was measured with another camera (fx {:.1} px at {}x{}): give that camera, or none to use the arena's",
                        measured_with.fx, measured_with.width, measured_with.height
                    )),
                ))
            }
            Some(_) => {}
        }
        Ok(arena)
    }
}

/// Whether `given` is the calibration `measured_with` (at that one's
/// resolution): focal lengths within 0.1 %, principal points within half
/// a pixel, distortion within 0.001.
fn same_camera(given: &Camera, measured_with: &Camera) -> bool {
    let Ok(given) = given.for_image(measured_with.width, measured_with.height) else {
        return false;
    };
    (given.fx / measured_with.fx - 1.0).abs() < 1e-3
        && (given.fy / measured_with.fy - 1.0).abs() < 1e-3
        && (given.cx - measured_with.cx).abs() < 0.5
        && (given.cy - measured_with.cy).abs() < 0.5
        && given
            .distortion
            .iter()
            .zip(&measured_with.distortion)
            .all(|(a, b)| (a - b).abs() < 1e-3)
}

fn pose_needs_both(given: &'static str, missing: &str) -> SpecError {
    SpecError::of(
        given,
        Problem::Conflict(format!(
            "a pose needs both the marker's diameter and the camera: give {missing} too, or neither"
        )),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_diameter_outside_the_plausible_range_is_refused() {
        let spec = DetectSpec {
            diameter: Some(Length::from_mm(1e-300)),
            camera: Some(Camera::ideal(640, 480, 60.0)),
            ..DetectSpec::default()
        };
        let err = spec.build().unwrap_err();
        assert_eq!(
            err.message_with(super::super::cli_option),
            "--diameter: 1e-300 mm is outside 0.5 to 10000 mm"
        );
        let huge = DetectSpec {
            diameter: Some(Length::from_m(50.0)),
            ..spec
        };
        assert!(huge.build().is_err());
    }

    #[test]
    fn pose_takes_a_diameter_and_a_camera_together() {
        let spec = DetectSpec {
            diameter: Some(Length::from_mm(40.0)),
            ..DetectSpec::default()
        };
        assert_eq!(spec.build().unwrap_err().option, Some("diameter"));
        let both = DetectSpec {
            camera: Some(Camera::ideal(640, 480, 60.0)),
            ..spec
        };
        assert_eq!(both.build().unwrap().detector.diameter_m, Some(0.04));
    }
}
