//! Following a tracked marker from frame to frame: where it should be
//! now, found by its edges (or, failing that, by a flood fill from a point
//! on its disc).

use super::track::Track;
#[cfg(feature = "parallel")]
use crate::detect::scan::Walker;
use crate::detect::scan::{Passed, Rules};
use crate::detect::segment::Gray;
#[cfg(feature = "parallel")]
use crate::detect::segment::Marks;
use crate::detect::threshold::ThresholdMap;
use crate::detect::{ellipse, Candidate, Detector};
use crate::math::Ellipse;

/// How far past its predicted outline a tracked marker's edge is looked
/// for, pixels (`a`: the predicted semi-major axis).
pub(super) fn edge_window(a: f64) -> f64 {
    (3.5 + 0.03 * a).min(23.0)
}

impl Detector {
    /// Looks for a tracked marker where it should be now. First the cheap
    /// way: edge points around the predicted outline, a conic fit, and a
    /// check that the centre is white and the annulus black (a few hundred
    /// pixels). If that fails, the paper's way: from a point on the
    /// marker's disc along the row to the first dark pixel, which starts
    /// the marker's dark segment and the full tests.
    pub(super) fn follow(&mut self, gray: Gray<'_>, index: usize) -> Option<Candidate> {
        let mut edge = std::mem::take(&mut self.walker.edge);
        let by_edges = self.follow_edges(gray, &self.tracks[index], &mut edge);
        self.walker.edge = edge;
        by_edges.or_else(|| self.follow_by_fill(gray, index))
    }

    /// The paper's way to follow a marker, when its edges were not found
    /// where its track predicted them (see [`Detector::follow`]); the fill
    /// labels what it reaches.
    pub(super) fn follow_by_fill(&mut self, gray: Gray<'_>, index: usize) -> Option<Candidate> {
        let passed = self.fill_tracked(gray, index)?;
        let c = self.walker.fit_outline(gray, &passed)?;
        self.where_expected(index, c)
    }

    /// The flood fill of [`Detector::follow_by_fill`]: from [`fill_seed`],
    /// the segment there and its tests. The only part of the
    /// fill's way that writes (the labels), so the rest may be done on
    /// other threads.
    pub(super) fn fill_tracked(&mut self, gray: Gray<'_>, index: usize) -> Option<Passed> {
        let track = &self.tracks[index];
        let (x, y) = fill_seed(gray, track)?;
        if self
            .walker
            .labels
            .is_dark_visited(y as usize * gray.width + x as usize)
        {
            return None;
        }
        let map = ThresholdMap::constant(track.threshold);
        self.follow_filled = true;
        Rules::new(&self.config, &self.tolerances, &self.occupied).evaluate(
            &mut self.walker,
            gray,
            &map,
            (x, y),
            &[],
        )
    }

    /// Candidate `c`, filled and fitted for track `index`, if it lies where
    /// the track expects its marker (within its radius of one of the
    /// track's guesses) and is of its size.
    pub(super) fn where_expected(&self, index: usize, c: Candidate) -> Option<Candidate> {
        let track = &self.tracks[index];
        let near = track.matches_a_guess(c.outer.u, c.outer.v);
        let same_size = (c.outer.semi_major / track.a - 1.0).abs() < 0.3;
        (near && same_size).then_some(c)
    }

    /// The cheap way of [`Detector::follow`], tried at each of the track's
    /// guesses in turn ([`Track::guesses`]): a flood fill and an outline
    /// fit cost many times a look at the edges. Reads the pixels only
    /// (`edge` is scratch), so the tracks of a frame can be followed on
    /// several threads.
    pub(super) fn follow_edges(
        &self,
        gray: Gray<'_>,
        track: &Track,
        edge: &mut Vec<(f64, f64)>,
    ) -> Option<Candidate> {
        track
            .guesses()
            .find_map(|guess| self.edges_at(gray, track, guess, edge))
    }

    /// [`Detector::follow_edges`] with the marker's centre guessed at
    /// (`pu`, `pv`).
    fn edges_at(
        &self,
        gray: Gray<'_>,
        track: &Track,
        (pu, pv): (f64, f64),
        edge: &mut Vec<(f64, f64)>,
    ) -> Option<Candidate> {
        let guess = Ellipse {
            u: pu,
            v: pv,
            semi_major: track.a,
            semi_minor: track.b,
            angle: track.angle,
        };
        let mid = (track.black + track.white) / 2.0;
        let window = edge_window(track.a);
        let rays = ellipse::scanline_edge_points(
            gray,
            &guess,
            mid,
            track.white - track.black,
            window,
            edge,
        );
        if edge.len() * 5 < rays * 4 {
            return None;
        }
        let fitted = Ellipse::fit_near(edge, (pu, pv), track.a)?;
        let rms = (fitted
            .radial_distances(edge)
            .map(|d| d.powi(2))
            .sum::<f64>()
            / edge.len() as f64)
            .sqrt();
        let consistent = rms < 0.3 + 0.01 * track.a
            && (fitted.semi_major / track.a - 1.0).abs() < 0.1
            && (fitted.semi_minor / track.b - 1.0).abs() < 0.1
            && (fitted.u - pu).hypot(fitted.v - pv) < window;
        if !consistent {
            return None;
        }
        // Inside: white at the centre, black across the annulus.
        let white_ratio = self.config.target.design().centre_white_ratio();
        let (mut white_sum, mut black_sum) = (0.0, 0.0);
        const PROBES: usize = 8;
        for k in 0..PROBES {
            let t = std::f64::consts::TAU * k as f64 / PROBES as f64;
            let inner = fitted.scaled(0.6 * white_ratio).point_at(t);
            let annulus = fitted.scaled(0.8).point_at(t);
            let w = ellipse::sample(gray, inner.0, inner.1)?;
            let b = ellipse::sample(gray, annulus.0, annulus.1)?;
            if w < mid || b >= mid {
                return None;
            }
            white_sum += w;
            black_sum += b;
        }
        let (white, black) = (white_sum / PROBES as f64, black_sum / PROBES as f64);
        Some(Candidate {
            outer: fitted,
            edge: edge.clone(),
            black,
            white,
            ratio: self.tolerances.ratio.expected,
            roundness: 0.0,
            area_error: 0.0,
            tested: false,
            track: None,
            #[cfg(feature = "parallel")]
            described: None,
        })
    }
}

/// Where the flood fill of a tracked marker starts: from the track's
/// [`Track::fill_origin`] along the row to the first pixel darker than its
/// threshold, within one and a half of its radii.
fn fill_seed(gray: Gray<'_>, track: &Track) -> Option<(u32, u32)> {
    let (pu, pv) = track.fill_origin();
    let (x, y) = (pu.round(), pv.round());
    if !(x >= 0.0 && y >= 0.0 && (x as usize) < gray.width && (y as usize) < gray.height) {
        return None;
    }
    let (x, y) = (x as usize, y as usize);
    let reach = (1.5 * track.a + 2.0) as usize;
    let row = y * gray.width;
    let end = (x + reach).min(gray.width - 1);
    let seed = (x..=end).find(|&xx| gray.pixels[row + xx] < track.threshold)?;
    Some((seed as u32, y as u32))
}

/// A tracked marker's flood fill made apart from the others' (on another
/// thread, in labels of its own), and the labels it left.
#[cfg(feature = "parallel")]
pub(super) struct FilledApart {
    pub(super) passed: Option<Passed>,
    /// The box of every pixel the fill read the labels of, but for the
    /// pixels round it.
    pub(super) reach: [u32; 4],
    pub(super) marks: Vec<Marks>,
}

/// The flood fill of [`Detector::fill_tracked`] for `track` in `walker`,
/// whose labels must be clear; leaves them clear. None where no fill
/// starts.
#[cfg(feature = "parallel")]
pub(super) fn fill_apart(
    rules: &Rules<'_>,
    walker: &mut Walker,
    gray: Gray<'_>,
    track: &Track,
) -> Option<FilledApart> {
    let seed = fill_seed(gray, track)?;
    let map = ThresholdMap::constant(track.threshold);
    walker.take_reach();
    let passed = rules.evaluate(walker, gray, &map, seed, &[]);
    // The seed is dark under the track's threshold, so the fill took it.
    let reach = walker.take_reach()?;
    let mut marks = Vec::new();
    walker.labels.marks_in(reach, true, &mut marks);
    Some(FilledApart {
        passed,
        reach,
        marks,
    })
}
