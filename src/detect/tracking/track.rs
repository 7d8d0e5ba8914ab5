//! Tracking across frames (paper 4.1-4.2): each marker's next position is
//! predicted from its last position and velocity, so that the search of
//! the next frame starts inside the marker and touches only its pixels; the
//! test tolerances follow the values the detector actually measures,
//! slowly (x ← 0.99 x + 0.01 x_measured).

use crate::pose::CirclePose;

/// What the detector remembers about one marker between frames.
#[derive(Debug, Clone)]
pub struct Track {
    /// The number its detections carry (`Detection::track`).
    pub number: u32,
    pub u: f64,
    pub v: f64,
    /// Image velocity, pixels per frame, smoothed over past frames.
    pub du: f64,
    pub dv: f64,
    /// How far the marker moved between the last two frames it was seen
    /// in, pixels: the velocity not smoothed.
    pub moved: (f64, f64),
    /// Semi-axes of the last outer ellipse.
    pub a: f64,
    pub b: f64,
    /// The threshold that separated this marker's black from its white.
    pub threshold: u8,
    /// Frames in a row this marker was seen.
    pub hits: u32,
    /// Direction of the outer ellipse's major axis.
    pub angle: f64,
    /// Grey levels of the black disc and the white inside.
    pub black: f64,
    pub white: f64,
    /// What the ring said last: ID (0 unknown), member code, yaw, and for
    /// how many frames in a row the same ID was read.
    pub id: u32,
    pub code: Option<u32>,
    pub yaw: Option<f64>,
    pub confidence: f64,
    pub status: Option<crate::family::MatchStatus>,
    /// The ring's bit count as the ring showed it last.
    pub bits: Option<u32>,
    pub id_streak: u32,
    /// Belief over the marker's ID from all its ring readings so far
    /// (paper 5.1), with a family.
    pub ids: Option<super::idfilter::IdFilter>,
    /// The marker's normal (camera frame) once the pose stage told it apart
    /// from the other candidate with confidence; later frames keep to it.
    pub normal: Option<nalgebra::Vector3<f64>>,
    /// The circle pose fitted to the marker's edges last frame: this
    /// frame's fit starts from it.
    pub fitted: Option<Fitted>,
}

/// A circle pose fitted to a marker's edges, and the closed-form
/// candidate's centre it was fitted from: the next frame's fit starts from
/// it moved by as much as that candidate's centre moved.
#[derive(Debug, Clone, Copy)]
pub struct Fitted {
    pub circle: CirclePose,
    pub closed_form_centre: nalgebra::Vector3<f64>,
}

/// What the pose stage learnt about a marker in this frame, for the next.
#[derive(Debug, Clone, Copy, Default)]
pub struct PoseMemory {
    /// The normal, when it was told apart from the other candidate with
    /// confidence.
    pub settled_normal: Option<nalgebra::Vector3<f64>>,
    /// The circle pose fitted to this frame's edges.
    pub fitted: Option<Fitted>,
}

impl Track {
    pub fn new(u: f64, v: f64, a: f64, b: f64, threshold: u8) -> Track {
        Track {
            number: 0,
            u,
            v,
            du: 0.0,
            dv: 0.0,
            moved: (0.0, 0.0),
            a,
            b,
            threshold,
            hits: 1,
            angle: 0.0,
            black: f64::from(threshold) / 2.0,
            white: f64::from(threshold) * 1.5,
            id: 0,
            code: None,
            yaw: None,
            confidence: 0.0,
            status: None,
            bits: None,
            id_streak: 0,
            ids: None,
            normal: None,
            fitted: None,
        }
    }

    /// Where the marker should be in the next frame.
    pub fn predicted(&self) -> (f64, f64) {
        (self.u + self.du, self.v + self.dv)
    }

    /// Where the marker may be in the next frame, most likely first: as
    /// [`Track::predicted`]; moved on by as much as it moved last (its
    /// velocity just changed: a robot sped up, braked or turned back); and
    /// where it was (it stopped). A place within a pixel of one before it
    /// is left out.
    pub fn guesses(&self) -> impl Iterator<Item = (f64, f64)> {
        let places = [
            self.predicted(),
            (self.u + self.moved.0, self.v + self.moved.1),
            (self.u, self.v),
        ];
        (0..places.len()).filter_map(move |k| {
            let (u, v) = places[k];
            let new = places[..k]
                .iter()
                .all(|&(pu, pv)| (u - pu).hypot(v - pv) >= 1.0);
            new.then_some((u, v))
        })
    }

    /// Where a flood fill looking for the marker starts: where it was, if it
    /// moves less than most of its semi-minor axis a frame (that point then
    /// lies on its disc, however seen, whether it moved on, stopped or
    /// turned back), else where it should be now.
    pub fn fill_origin(&self) -> (f64, f64) {
        if self.du.hypot(self.dv) < FILL_FROM_LAST * self.b {
            (self.u, self.v)
        } else {
            self.predicted()
        }
    }

    /// Takes a new observation; the velocity is smoothed because single
    /// frame differences carry the centre's measurement noise.
    pub fn update(&mut self, u: f64, v: f64, a: f64, b: f64, threshold: u8) {
        let (mu, mv) = (u - self.u, v - self.v);
        self.moved = (mu, mv);
        let k = if self.hits == 1 { 1.0 } else { 0.6 };
        self.du += k * (mu - self.du);
        self.dv += k * (mv - self.dv);
        self.u = u;
        self.v = v;
        self.a = a;
        self.b = b;
        self.threshold = threshold;
        self.hits += 1;
    }

    /// Remembers how the marker looked, for the next frame's edge search.
    pub fn observe_appearance(&mut self, angle: f64, black: f64, white: f64) {
        self.angle = angle;
        self.black = black;
        self.white = white;
    }

    /// Folds this frame's ring reading into the ID belief; returns the
    /// belief afterwards.
    pub fn observe_reading(
        &mut self,
        members: usize,
        d: &crate::detect::Detection,
    ) -> super::idfilter::IdEstimate {
        let filter = self
            .ids
            .get_or_insert_with(|| super::idfilter::IdFilter::new(members));
        match d.status {
            Some(crate::family::MatchStatus::Rejected) => filter.observe_non_member(d.confidence),
            Some(_) if d.id != 0 => filter.observe_member(d.id, d.confidence),
            _ => {}
        }
        filter.estimate()
    }

    /// Remembers what the ring said this frame.
    pub fn observe_identity(&mut self, d: &crate::detect::Detection) {
        if d.id != 0 && d.id == self.id {
            self.id_streak += 1;
        } else {
            self.id_streak = u32::from(d.id != 0);
        }
        self.id = d.id;
        self.code = d.code;
        self.yaw = d.yaw;
        self.confidence = d.confidence;
        self.status = d.status;
        self.bits = d.bits.or(self.bits);
    }

    /// True when an observation at (u, v) is this marker moved on.
    pub fn matches(&self, u: f64, v: f64) -> bool {
        self.reaches(self.predicted(), u, v)
    }

    /// True when an observation at (u, v) lies where one of the track's
    /// [`Track::guesses`] puts the marker.
    pub fn matches_a_guess(&self, u: f64, v: f64) -> bool {
        self.guesses().any(|place| self.reaches(place, u, v))
    }

    /// Whether (u, v) lies within the marker's radius of `place`.
    fn reaches(&self, (pu, pv): (f64, f64), u: f64, v: f64) -> bool {
        (u - pu).hypot(v - pv) < self.a.max(4.0)
    }
}

/// Speed, in semi-minor axes of the outline a frame, under which a missed
/// marker's flood fill starts where it was last seen (see
/// [`Track::fill_origin`]).
const FILL_FROM_LAST: f64 = 0.8;

/// The candidate tests' tolerances, each following what the candidates
/// that passed the tests measured (paper 4.2): the white share, the
/// roundness (eq. 1) and the area (eq. 4).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tolerances {
    pub ratio: Adaptive,
    pub roundness: Adaptive,
    pub area: Adaptive,
}

/// A test value that follows what is measured: `expected` is the mean the
/// test is centred on (or the typical error, for error-only tests) and the
/// tolerance shrinks towards a multiple of the typical error but never
/// below half, nor above, the configured tolerance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Adaptive {
    pub expected: f64,
    pub typical_error: f64,
    pub configured_tolerance: f64,
}

/// Weight of a new measurement in the running values (paper 4.2).
pub const ADAPTATION_RATE: f64 = 0.01;

impl Adaptive {
    pub fn new(expected: f64, tolerance: f64) -> Adaptive {
        Adaptive {
            expected,
            typical_error: tolerance / 4.0,
            configured_tolerance: tolerance,
        }
    }

    pub fn tolerance(&self) -> f64 {
        (4.0 * self.typical_error).clamp(0.5 * self.configured_tolerance, self.configured_tolerance)
    }

    /// Relative deviation of a measurement from the expected value.
    pub fn relative_error(&self, measured: f64) -> f64 {
        if self.expected == 0.0 {
            measured.abs()
        } else {
            (measured / self.expected - 1.0).abs()
        }
    }

    pub fn accepts(&self, measured: f64) -> bool {
        self.relative_error(measured) < self.tolerance()
    }

    pub fn learn(&mut self, measured: f64) {
        let error = self.relative_error(measured);
        if self.expected != 0.0 {
            self.expected += ADAPTATION_RATE * (measured - self.expected);
        }
        self.typical_error += ADAPTATION_RATE * (error - self.typical_error);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn prediction_follows_constant_motion() {
        let mut t = Track::new(10.0, 20.0, 5.0, 5.0, 100);
        for k in 1..6 {
            t.update(10.0 + 3.0 * k as f64, 20.0 - 2.0 * k as f64, 5.0, 5.0, 100);
        }
        let (u, v) = t.predicted();
        assert!((u - 28.0).abs() < 0.1 && (v - 8.0).abs() < 0.1, "{u} {v}");
    }

    #[test]
    fn expectation_moves_slowly_towards_measurements() {
        let mut a = Adaptive::new(0.2, 0.5);
        a.learn(0.3);
        assert!((a.expected - 0.201).abs() < 1e-12);
        for _ in 0..1000 {
            a.learn(0.25);
        }
        assert!((a.expected - 0.25).abs() < 1e-3);
        assert!(a.tolerance() >= 0.25 && a.tolerance() <= 0.5);
    }
}
