//! A board's pose across the frames of a tracked stream. Each frame's fit
//! stands on its own, so its noise shows as jitter of a board that does
//! not move. An alpha-beta filter (position and rotation each with a
//! velocity) averages that noise away without lagging behind a board that
//! moves steadily; a change the filter cannot explain (a jump, a board
//! picked up) restarts it from the measurement instead of dragging the
//! old pose along.

use nalgebra::{Rotation3, Vector3};

use super::BoardPose;
use crate::pose::Pose;

/// Share of each frame's surprise taken into the pose: about halves the
/// jitter of a still board.
const ALPHA: f64 = 0.5;
/// Share taken into the velocity: small, so that noise does not read as
/// motion, yet a steady motion is followed without lag once learned.
const BETA: f64 = 0.1;
/// A surprise larger than this restarts the filter: metres, as a share of
/// the board's distance, with a floor.
const GATE_DISTANCE_SHARE: f64 = 0.02;
const GATE_MIN_M: f64 = 0.005;
/// The same for the rotation, radians.
const GATE_ANGLE: f64 = 3.0 * std::f64::consts::PI / 180.0;

/// One board's filter state.
#[derive(Debug, Clone, Default)]
struct BoardFilter {
    state: Option<State>,
}

#[derive(Debug, Clone)]
struct State {
    position: Vector3<f64>,
    /// Metres per frame.
    velocity: Vector3<f64>,
    rotation: Rotation3<f64>,
    /// Rotation vector per frame, in the camera frame.
    spin: Vector3<f64>,
}

impl BoardFilter {
    /// The smoothed pose for this frame's measurement; `None` (the board
    /// not seen) forgets the board, so it starts afresh when seen again.
    pub fn update(&mut self, measured: Option<BoardPose>) -> Option<BoardPose> {
        let Some(mut pose) = measured else {
            self.state = None;
            return None;
        };
        let rotation = Rotation3::from_matrix(&pose.rotation);
        let fresh = State {
            position: pose.position,
            velocity: Vector3::zeros(),
            rotation,
            spin: Vector3::zeros(),
        };
        let next = match self.state.take() {
            None => fresh,
            Some(s) => {
                let predicted_position = s.position + s.velocity;
                let predicted_rotation = Rotation3::new(s.spin) * s.rotation;
                let moved = pose.position - predicted_position;
                let turned = (rotation * predicted_rotation.inverse()).scaled_axis();
                let gate = (GATE_DISTANCE_SHARE * pose.position.norm()).max(GATE_MIN_M);
                if moved.norm() > gate || turned.norm() > GATE_ANGLE {
                    fresh
                } else {
                    State {
                        position: predicted_position + ALPHA * moved,
                        velocity: s.velocity + BETA * moved,
                        rotation: Rotation3::new(ALPHA * turned) * predicted_rotation,
                        spin: s.spin + BETA * turned,
                    }
                }
            }
        };
        let smoothed = Pose::new(next.position, *next.rotation.matrix());
        pose.position = smoothed.position;
        pose.rotation = smoothed.rotation;
        pose.quaternion = smoothed.quaternion;
        self.state = Some(next);
        Some(pose)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Matrix3;

    fn pose(position: Vector3<f64>, angle: f64) -> BoardPose {
        let rotation = *Rotation3::from_axis_angle(&Vector3::z_axis(), angle).matrix();
        BoardPose {
            name: "b".into(),
            position,
            rotation,
            quaternion: Pose::new(position, rotation).quaternion,
            used: vec![1],
            seen: vec![1],
            rejected: Vec::new(),
            rms_px: 0.1,
        }
    }

    /// A small deterministic noise sequence.
    fn noise(k: usize) -> f64 {
        ((k as f64 * 12.9898).sin() * 43758.5453).rem_euclid(1.0) - 0.5
    }

    #[test]
    fn a_still_board_jitters_less_a_moving_one_is_not_left_behind_and_a_jump_restarts() {
        let mut filter = BoardFilter::default();
        let truth = |k: usize| Vector3::new(0.001 * k as f64, 0.0, 1.0);
        let (mut raw, mut smooth) = (0.0, 0.0);
        for k in 0..200 {
            let measured = truth(k) + Vector3::new(noise(k), noise(k + 500), 0.0) * 0.002;
            let out = filter
                .update(Some(pose(measured, 0.3 + 0.001 * noise(k + 900))))
                .unwrap();
            if k >= 50 {
                raw += (measured - truth(k)).norm_squared();
                smooth += (out.position - truth(k)).norm_squared();
            }
        }
        // Steady motion of 1 mm a frame: the filter's error is its
        // smoothed noise, not a lag.
        assert!(smooth < 0.6 * raw, "smoothed {smooth} vs raw {raw}");
        // A jump beyond the gate is taken as it is.
        let jumped = filter
            .update(Some(pose(Vector3::new(0.5, 0.0, 1.0), 0.3)))
            .unwrap();
        assert_eq!(jumped.position, Vector3::new(0.5, 0.0, 1.0));
        assert!(
            (jumped.rotation - Matrix3::from(Rotation3::from_axis_angle(&Vector3::z_axis(), 0.3)))
                .norm()
                < 1e-12
        );
        // Unseen, then seen: no memory of before.
        assert!(filter.update(None).is_none());
        let again = filter
            .update(Some(pose(Vector3::new(0.2, 0.0, 1.0), 0.0)))
            .unwrap();
        assert_eq!(again.position, Vector3::new(0.2, 0.0, 1.0));
    }
}

/// The configured boards of a stream and each one's filter: every frame's
/// markers in, the boards' poses out (what a session reports beside the
/// markers).
#[derive(Debug, Clone, Default)]
pub struct BoardTracker {
    boards: Vec<super::Board>,
    filters: Vec<BoardFilter>,
    /// Frames are one sequence: each board's pose is smoothed over the
    /// frames it was seen in. Off, each frame stands alone.
    smooth: bool,
}

impl BoardTracker {
    /// A tracker of `boards`, smoothing across frames with `smooth`.
    pub fn new(boards: Vec<super::Board>, smooth: bool) -> BoardTracker {
        BoardTracker {
            filters: vec![BoardFilter::default(); boards.len()],
            boards,
            smooth,
        }
    }

    /// The pose of every board seen in `detections` (one frame's markers)
    /// through `camera`, the markers' poses computed for `diameter_m`;
    /// none without a camera or a diameter.
    pub fn update(
        &mut self,
        detections: &[crate::detect::Detection],
        camera: Option<&crate::camera::Camera>,
        diameter_m: Option<f64>,
    ) -> Vec<BoardPose> {
        let (Some(camera), Some(diameter)) = (camera, diameter_m) else {
            return Vec::new();
        };
        let smooth = self.smooth;
        self.boards
            .iter()
            .zip(&mut self.filters)
            .filter_map(|(board, filter)| {
                let measured = super::locate(board, detections, camera, diameter);
                if smooth {
                    filter.update(measured)
                } else {
                    measured
                }
            })
            .collect()
    }

    /// Forgets every board's past poses.
    pub fn reset(&mut self) {
        self.filters = vec![BoardFilter::default(); self.boards.len()];
    }
}
