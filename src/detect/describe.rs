//! Describing a candidate disc: who it is (`identity.rs`), then its pose
//! (`pose.rs`).

use std::ops::Deref;

use image::{ImageBuffer, Luma};

use super::ring::RingRead;
use super::segment::Gray;
use super::tracking::track::PoseMemory;
use super::{Candidate, Detection, Detector, Stage};

impl Detector {
    /// The detection of a candidate, and what its pose tells the track: who
    /// it is ([`Detector::identity`]), then where it is.
    pub(super) fn describe<C: Deref<Target = [u8]>>(
        &mut self,
        image: &ImageBuffer<Luma<u8>, C>,
        gray: Gray<'_>,
        c: &Candidate,
    ) -> (Detection, PoseMemory) {
        let (mut d, read, posed) = self.identity(image, gray, c);
        self.stopwatch.lap(Stage::Describe);
        let memory = self.measure_pose(gray, c, &mut d, &read, posed);
        self.stopwatch.lap(Stage::Pose);
        (d, memory)
    }
}

/// A candidate's detection as its outline and `read` describe it, before
/// the ID filter and the pose.
pub(super) fn detection(c: &Candidate, read: &RingRead, unreadable: bool) -> Detection {
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
