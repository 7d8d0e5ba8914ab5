//! An arena as the front ends ask for it: `whycode arena`'s options (and
//! Python's), checked once and built into [`ArenaOptions`].

use super::{limits, within, Problem, SpecError, TargetSpec};
use crate::arena::{ArenaOptions, Corners};
use crate::camera::Camera;
use crate::detect::{DetectorConfig, Target};
use crate::units::Length;

/// Which markers are the corners, how far apart, and the camera. `size`
/// is required; the rest defaults to the command line's: the default
/// family, the four outermost markers, no camera, markers on the floor.
#[derive(Debug, Clone, Default)]
pub struct ArenaSpec {
    /// Which markers.
    pub target: TargetSpec,
    /// The corners' IDs: origin, +x corner, far corner, +y corner; `None`
    /// for the four outermost markers.
    pub ids: Option<Vec<u32>>,
    /// The rectangle's sides along x and y.
    pub size: Option<[Length; 2]>,
    /// The calibrated camera that took the photo.
    pub camera: Option<Camera>,
    /// Height above the floor of the markers `detect` will locate (with a
    /// camera).
    pub marker_height: Option<Length>,
}

/// A marker diameter for measuring the arena with a camera: the detector
/// needs one for the poses whose projected centres the corners are, but
/// a centre's direction does not depend on the size assumed.
const ANY_DIAMETER_M: f64 = 0.1;

impl ArenaSpec {
    /// Checks every option and builds what measures the arena.
    pub fn build(&self) -> Result<ArenaOptions, SpecError> {
        let target = self.target.resolve()?;
        let Some(size) = self.size else {
            return Err(SpecError::invalid(
                "size",
                "give the rectangle's two sides (along x, along y)",
            ));
        };
        let size_m = [
            within("size", size[0].m(), limits::ARENA_SIDE_M)?,
            within("size", size[1].m(), limits::ARENA_SIDE_M)?,
        ];
        let corners = match &self.ids {
            None => Corners::Outermost,
            Some(_) if target == Target::WhyCon => {
                return Err(SpecError::of(
                    "ids",
                    Problem::Conflict(
                        "legacy circles carry no IDs: leave the IDs out and the four outermost markers are the corners".into(),
                    ),
                ))
            }
            Some(ids) => match ids.as_slice() {
                &[a, b, c, d] => Corners::Ids([a, b, c, d]),
                _ => {
                    return Err(SpecError::invalid(
                        "ids",
                        format!(
                            "give four IDs (origin, +x corner, far corner, +y corner), not {}",
                            ids.len()
                        ),
                    ))
                }
            },
        };
        let marker_height_m = self
            .marker_height
            .map(|h| within("marker_height", h.m(), limits::MARKER_HEIGHT_M))
            .transpose()?
            .unwrap_or(0.0);
        if marker_height_m != 0.0 && self.camera.is_none() {
            return Err(SpecError::of(
                "marker_height",
                Problem::Conflict(
                    "without a camera the arena maps the floor only: give the camera for markers above it".into(),
                ),
            ));
        }
        let config = DetectorConfig {
            target,
            camera: self.camera,
            diameter_m: self.camera.map(|_| ANY_DIAMETER_M),
            ..DetectorConfig::default()
        };
        Ok(ArenaOptions {
            config,
            corners,
            size_m,
            marker_height_m,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_ids_and_heights_are_checked() {
        let spec = ArenaSpec {
            size: Some([Length::from_m(2.0), Length::from_mm(1.5)]),
            ..ArenaSpec::default()
        };
        assert_eq!(
            spec.build()
                .unwrap_err()
                .message_with(super::super::cli_option),
            "--size: 0.0015 m is outside 0.05 to 500 m"
        );
        let three = ArenaSpec {
            size: Some([Length::from_m(2.0), Length::from_m(1.5)]),
            ids: Some(vec![1, 2, 3]),
            ..ArenaSpec::default()
        };
        assert_eq!(three.build().unwrap_err().option, Some("ids"));
        let raised = ArenaSpec {
            ids: None,
            marker_height: Some(Length::from_mm(120.0)),
            ..three
        };
        assert_eq!(raised.build().unwrap_err().option, Some("marker_height"));
    }
}
