//! Describing a candidate disc: what it is (a followed marker's identity
//! from its track, what its ring says, or for legacy markers whether its
//! inside is WhyCon's), the ID filter of tracked markers, then its pose
//! (`pose.rs`).

use std::ops::Deref;

use image::{ImageBuffer, Luma};

use super::identity::{self, Unnamed};
use super::ring::{RingRead, RingVerdict};
use super::segment::Gray;
use super::tracking::track::PoseMemory;
use super::{legacy, Candidate, Detection, Detector, Stage};
use crate::geometry::Design;

impl Detector {
    /// The detection of a candidate, and what its pose tells the track.
    pub(super) fn describe<C: Deref<Target = [u8]>>(
        &mut self,
        image: &ImageBuffer<Luma<u8>, C>,
        gray: Gray<'_>,
        c: &Candidate,
    ) -> (Detection, PoseMemory) {
        let quality = 1.0 - (c.area_error / self.area.tolerance()).min(1.0);
        let outline = (0.5 + 0.5 * quality).clamp(0.0, 1.0);
        let followed = c.track.and_then(|i| self.follow_code(gray, c, i));
        let (mut d, read) = match followed {
            Some(followed) => (detection(c, &followed.read, false), followed.read),
            None if self.config.target.design() == Design::WhyCode => {
                // A followed ring is tested for the bit count it showed
                // last first: passing that surely spares testing every
                // other count (each frame's cost on rings of another
                // family, or without one).
                let remembered = c.track.and_then(|i| self.tracks[i].bits);
                let verdict = self.rings.identify(image, gray, c, outline, remembered);
                // A settled track whose ring blurs is still the marker.
                let settled = c.track.is_some_and(|i| self.settled(i));
                let mut marker = !matches!(verdict, RingVerdict::NotAMarker(_)) || settled;
                if !marker {
                    // No code ring shows: a marker still, when its geometry
                    // says so (a legacy WhyCon circle, a ring blurred past
                    // reading), reported without an ID.
                    let large = 2.0 * c.outer.semi_minor >= identity::MIN_NO_RING_DIAMETER_PX;
                    let sharp = legacy::is_marker(image, gray, c, self.config.legacy_min_ink_px);
                    if sharp && c.track.is_none() {
                        self.legacy_looking += 1;
                    }
                    marker = (sharp && large) || legacy::is_blurred_marker(gray, c);
                }
                let family = self.config.target.family().is_some();
                let mut d = detection(c, verdict.read(), !marker);
                d.unnamed = Unnamed::of_verdict(&verdict, family);
                (d, *verdict.read())
            }
            None => {
                // A marker followed for a while stays one when its inside
                // blurs, so its inside need not be looked at (the ray test
                // costs more than following it).
                let followed = c.track.is_some_and(|i| self.tracks[i].hits >= 3);
                let marker = followed
                    || legacy::is_marker(image, gray, c, self.config.legacy_min_ink_px)
                    || legacy::is_blurred_marker(gray, c);
                let read = RingRead::nothing(outline);
                (detection(c, &read, !marker), read)
            }
        };
        if let Some(i) = c.track {
            self.filter_identity(gray, c, i, &mut d, followed.is_some());
        }
        if d.id != 0 {
            d.unnamed = None;
        } else if d.unnamed.is_none() && self.config.target.design() == Design::WhyCode {
            // A followed marker whose ring this frame did not name.
            d.unnamed = Some(Unnamed::Unread);
        }
        self.stopwatch.lap(Stage::Describe);
        let memory = self.measure_pose(gray, c, &mut d, &read, followed.and_then(|f| f.posed));
        self.stopwatch.lap(Stage::Pose);
        (d, memory)
    }
}

/// A candidate's detection as its outline and `read` describe it, before
/// the ID filter and the pose.
fn detection(c: &Candidate, read: &RingRead, unreadable: bool) -> Detection {
    Detection {
        id: read.id,
        code: read.code,
        u: c.outer.u,
        v: c.outer.v,
        yaw: read.yaw,
        axes: [c.outer.semi_major, c.outer.semi_minor],
        angle: c.outer.angle,
        confidence: read.confidence,
        status: read.status,
        pose: None,
        bits: read.bits,
        unreadable,
        unnamed: None,
        track: None,
    }
}
