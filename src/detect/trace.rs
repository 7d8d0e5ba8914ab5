//! Where the scan lost each segment it tested (feature `trace`, off in
//! every build that detects for real): the detector's candidate tests
//! record the last test each dark segment reached, so that a tool
//! (`examples/defocus_losses`) can tell, for every marker a detector
//! missed, the stage that lost it. Compiled out without the feature: the
//! scan's code is the same as without this module.

/// The last test a dark segment reached in the scan, in the scan's order.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Reached {
    /// The dark fill ran into the image border or grew too large.
    Escaped,
    /// Fewer dark pixels, or a narrower box, than the smallest marker.
    Size,
    /// The dark pixels do not fill their box's ellipse (eq. 1).
    Roundness,
    /// No light region enclosed by the dark one near its centre.
    WhiteInside,
    /// The light region's share, its centre or the disc's size is off.
    RatioOrConcentricity,
    /// The moment ellipse's area is off (eq. 4).
    Area,
    /// Too little contrast between the dark and the light region.
    Contrast,
    /// The edge does not support a tight sub-pixel ellipse.
    EllipseFit,
    /// Passed every test: a candidate for the describe stage.
    Candidate,
}

/// One segment's end in the scan: the last test it reached and where
/// (the dark segment's centroid and its box's larger half side).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Loss {
    /// The last test reached.
    pub reached: Reached,
    /// Column of the dark segment's centroid.
    pub u: f64,
    /// Row of the dark segment's centroid.
    pub v: f64,
    /// Half the larger side of the dark segment's box, pixels.
    pub half_size: f64,
}

impl super::Detector {
    /// What the scans of the frames so far recorded, emptied.
    pub fn take_trace(&mut self) -> Vec<Loss> {
        std::mem::take(&mut self.walker.trace)
    }
}

impl super::scan::Walker {
    /// Records that the segment of `stats` reached `reached` and no further.
    pub(super) fn note_loss(&mut self, reached: Reached, stats: &super::segment::Stats) {
        if stats.count == 0 {
            return;
        }
        let (u, v) = stats.centroid();
        self.trace.push(Loss {
            reached,
            u,
            v,
            half_size: 0.5 * f64::from(stats.width().max(stats.height())),
        });
    }
}
