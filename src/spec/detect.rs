//! A detector as the front ends ask for it: `whycode detect`'s options,
//! Python's `Detector(...)` keywords, the page's live view and the ROS 2
//! node's parameters, checked once and built into a [`DetectorConfig`].

use super::{limits, within, Problem, SpecError, TargetSpec};
use crate::camera::Camera;
use crate::detect::{DetectorConfig, Target};
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
    /// diameter without `camera` waits in the configuration for it.
    pub camera_later: bool,
}

impl DetectSpec {
    /// Checks every option and builds the detector's configuration.
    pub fn build(&self) -> Result<DetectorConfig, SpecError> {
        let target = self.target.resolve()?;
        let mut diameter_m = self
            .diameter
            .map(|d| within("diameter", d.mm(), limits::MARKER_DIAMETER_MM).map(|mm| mm / 1000.0))
            .transpose()?;
        if !self.boards.is_empty() {
            if self.camera.is_none() {
                return Err(SpecError::of(
                    "board",
                    Problem::Conflict("a board's pose needs the camera: give camera too".into()),
                ));
            }
            diameter_m = diameter_m.or_else(|| {
                self.boards
                    .iter()
                    .flat_map(|b| b.markers.first())
                    .map(|m| m.diameter_m)
                    .next()
            });
        }
        match (diameter_m.is_some(), self.camera.is_some()) {
            (true, false) if !self.camera_later => {
                return Err(pose_needs_both("diameter", "camera"))
            }
            (false, true) => return Err(pose_needs_both("camera", "diameter")),
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
            camera: self.camera,
            tracking: self.tracking,
            report_unreadable: self.unreadable,
            boards: self.boards.clone(),
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
        Ok(config)
    }
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
        assert_eq!(both.build().unwrap().diameter_m, Some(0.04));
    }
}
