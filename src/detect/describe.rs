//! Describing a candidate disc: who it is (`identity.rs`), then its pose
//! (`pose.rs`).

use std::ops::Deref;

use image::{ImageBuffer, Luma};

use super::ring::RingRead;
use super::segment::Gray;
use super::timings::Stopwatch;
use super::tracking::track::PoseMemory;
use super::{Candidate, Detection, Detector, Stage, Workspace};

impl Detector {
    /// The detection of a followed candidate, and what its pose tells the
    /// track: who it is ([`Detector::identity`]), then where it is.
    pub(super) fn describe<C: Deref<Target = [u8]>>(
        &mut self,
        image: &ImageBuffer<Luma<u8>, C>,
        gray: Gray<'_>,
        c: &Candidate,
    ) -> (Detection, PoseMemory) {
        let mut ws = std::mem::take(&mut self.workspace);
        let (mut d, read, posed) = self.identity(&mut ws, image, gray, c);
        self.stopwatch.lap(Stage::Describe);
        let memory = self.measure_pose(&mut ws, gray, c, &mut d, &read, posed);
        self.stopwatch.lap(Stage::Pose);
        self.legacy_looking += std::mem::take(&mut ws.legacy_looking);
        self.workspace = ws;
        (d, memory)
    }

    /// [`Detector::describe`] for a candidate a scan found (it has no track
    /// yet): reads the detector's state only, so that the frame's new
    /// candidates can be described on several threads, each in its own
    /// workspace and stopwatch.
    pub(super) fn describe_found<C: Deref<Target = [u8]>>(
        &self,
        ws: &mut Workspace,
        stopwatch: &mut Stopwatch,
        image: &ImageBuffer<Luma<u8>, C>,
        gray: Gray<'_>,
        c: &Candidate,
    ) -> (Detection, PoseMemory) {
        debug_assert!(c.track.is_none());
        let (mut d, read) = self.found_identity(ws, image, gray, c);
        stopwatch.lap(Stage::Describe);
        let memory = self.measure_pose(ws, gray, c, &mut d, &read, None);
        stopwatch.lap(Stage::Pose);
        (d, memory)
    }
}

impl Detector {
    /// Describes candidate `c`, found by a scan on several threads, as
    /// [`Detector::describe_found`] will, and keeps what that gives on it.
    #[cfg(feature = "parallel")]
    pub(super) fn describe_early<C: Deref<Target = [u8]>>(
        &self,
        stopwatch: &mut Stopwatch,
        image: &ImageBuffer<Luma<u8>, C>,
        gray: Gray<'_>,
        c: &mut Candidate,
    ) {
        let mut ws = Workspace::default();
        let (detection, memory) = self.describe_found(&mut ws, stopwatch, image, gray, c);
        c.described = Some(Box::new(super::Described {
            detection,
            memory,
            legacy_looking: ws.legacy_looking,
        }));
    }

    /// Without threads nothing is done beside the scan (and the page's
    /// build stays as small as it was).
    #[cfg(not(feature = "parallel"))]
    pub(super) fn describe_early<C: Deref<Target = [u8]>>(
        &self,
        _: &mut Stopwatch,
        _: &ImageBuffer<Luma<u8>, C>,
        _: Gray<'_>,
        _: &mut Candidate,
    ) {
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
