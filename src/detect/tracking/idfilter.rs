//! Per-track Bayesian filter over marker IDs (paper section 5.1), which the
//! reference implementation describes but never switches on.
//!
//! Hypotheses: every ID of the family, plus "not a member" (a marker whose
//! ring carries no family code, e.g. a periodic code, reported as ID 0).
//! Families can hold thousands of IDs, so the distribution is sparse: IDs
//! that were ever observed carry their own probability, all others share
//! one value (every update treats them alike, so they stay equal).
//!
//! Observation model: a reading names ID k with confidence c. With
//! probability c it is right; otherwise it is a misread, and misreads land
//! on one of a few plausible neighbours (codes one bit away), not uniformly
//! on thousands of IDs, so the likelihood ratio of one reading is bounded:
//! a single confident misread cannot overturn a track that several
//! readings agree on. A clearly read ring that is no member is weak
//! evidence for "not a member"; an unreadable ring is no evidence.
//! The posterior is mixed with a little of the prior at every step so that
//! a track can still change its mind (a tracker mix-up) in a few frames.

use crate::detect::ring::RingReading;
use crate::family::MatchStatus;

/// How many IDs a misread typically confuses a marker with.
const CONFUSABLE_IDS: f64 = 8.0;
/// Readings are never trusted beyond this.
const MAX_CONFIDENCE: f64 = 0.95;
/// Prior probability that a tracked marker carries no member code.
const NON_MEMBER_PRIOR: f64 = 0.05;
/// Likelihood ratio of a clear "no member" reading for the non-member
/// hypothesis: weak evidence, since misreads of members also fall outside
/// the family.
const MAX_NON_MEMBER_RATIO: f64 = 3.0;
/// Share of the prior mixed back in at every update.
const FORGETTING: f64 = 1e-4;
/// Most IDs kept with their own probability; the least likely beyond this
/// rejoin the shared remainder.
const MAX_TRACKED_IDS: usize = 32;

/// The filter's current belief.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IdEstimate {
    /// The most probable ID, 0 for "not a member" (or nothing known yet).
    pub id: u32,
    /// Its posterior probability.
    pub probability: f64,
}

/// Bayesian ID filter for one tracked marker.
#[derive(Debug, Clone)]
pub struct IdFilter {
    members: usize,
    /// Observed IDs with their probabilities.
    known: Vec<(u32, f64)>,
    /// Probability of each member ID not in `known`.
    rest: f64,
    non_member: f64,
    observations: u32,
}

impl IdFilter {
    /// A filter over a family of `members` IDs (1..=members).
    pub fn new(members: usize) -> IdFilter {
        let members = members.max(1);
        IdFilter {
            members,
            known: Vec::new(),
            rest: (1.0 - NON_MEMBER_PRIOR) / members as f64,
            non_member: NON_MEMBER_PRIOR,
            observations: 0,
        }
    }

    /// Number of readings that carried evidence.
    pub fn observations(&self) -> u32 {
        self.observations
    }

    /// Folds one ring reading in. Unreadable and ambiguous rings carry no
    /// evidence and leave the belief unchanged.
    pub fn update(&mut self, reading: &RingReading) {
        match reading.decoded {
            Some(d) if d.is_member() => self.observe_member(d.id, reading.confidence),
            Some(d) if d.status == MatchStatus::Rejected => {
                self.observe_non_member(reading.confidence)
            }
            _ => {}
        }
    }

    /// A reading that named member `id` with confidence `confidence`.
    pub fn observe_member(&mut self, id: u32, confidence: f64) {
        if id == 0 || id as usize > self.members || confidence.is_nan() || confidence <= 0.0 {
            return;
        }
        let c = confidence.min(MAX_CONFIDENCE);
        let alternatives = CONFUSABLE_IDS.min(self.members as f64);
        // L(k) / L(other) for the named ID against every other hypothesis.
        let ratio = 1.0 + c * alternatives / (1.0 - c);
        self.forget();
        self.entry(id);
        for (k, p) in &mut self.known {
            if *k == id {
                *p *= ratio;
            }
        }
        self.finish_update();
    }

    /// A clear reading of a ring that is no family member, with the
    /// reading's confidence that it is indeed none.
    pub fn observe_non_member(&mut self, confidence: f64) {
        if confidence.is_nan() || confidence <= 0.0 {
            return;
        }
        let ratio = 1.0 + (MAX_NON_MEMBER_RATIO - 1.0) * confidence.min(1.0);
        self.forget();
        self.non_member *= ratio;
        self.finish_update();
    }

    /// The most probable hypothesis.
    pub fn estimate(&self) -> IdEstimate {
        let mut best = IdEstimate {
            id: 0,
            probability: self.non_member,
        };
        for &(id, p) in &self.known {
            if p > best.probability {
                best = IdEstimate { id, probability: p };
            }
        }
        if self.rest > best.probability {
            // Nothing observed stands out: no ID can be named.
            return IdEstimate {
                id: 0,
                probability: self.rest,
            };
        }
        best
    }

    /// The confidence to report with `estimate` on a frame whose own
    /// reading contradicts it (names another member, or clearly no member)
    /// with `reading_confidence`. The posterior treats readings as
    /// independent and so may stay at 0.999 after one contradiction; but a
    /// glint or a tracker swap lasts several frames, and the belief is
    /// right on this frame only if this frame's reading is the misread:
    /// the report is capped at that reading's own chance of being wrong.
    pub fn contradicted(estimate: IdEstimate, reading_confidence: f64) -> f64 {
        if reading_confidence.is_nan() {
            return estimate.probability;
        }
        let c = reading_confidence.clamp(0.0, MAX_CONFIDENCE);
        estimate.probability.min(1.0 - c)
    }

    /// Posterior probability of one ID (0: not a member).
    pub fn probability(&self, id: u32) -> f64 {
        if id == 0 {
            return self.non_member;
        }
        if id as usize > self.members {
            return 0.0;
        }
        self.known
            .iter()
            .find(|(k, _)| *k == id)
            .map_or(self.rest, |&(_, p)| p)
    }

    fn entry(&mut self, id: u32) {
        if !self.known.iter().any(|(k, _)| *k == id) {
            self.known.push((id, self.rest));
        }
    }

    fn forget(&mut self) {
        let prior_member = (1.0 - NON_MEMBER_PRIOR) / self.members as f64;
        for (_, p) in &mut self.known {
            *p = (1.0 - FORGETTING) * *p + FORGETTING * prior_member;
        }
        self.rest = (1.0 - FORGETTING) * self.rest + FORGETTING * prior_member;
        self.non_member = (1.0 - FORGETTING) * self.non_member + FORGETTING * NON_MEMBER_PRIOR;
    }

    fn finish_update(&mut self) {
        self.observations += 1;
        if self.known.len() > MAX_TRACKED_IDS {
            self.known.sort_by(|a, b| b.1.total_cmp(&a.1));
            self.known.truncate(MAX_TRACKED_IDS);
        }
        let unlisted = (self.members - self.known.len()) as f64;
        let total =
            self.non_member + self.rest * unlisted + self.known.iter().map(|e| e.1).sum::<f64>();
        self.non_member /= total;
        self.rest /= total;
        for (_, p) in &mut self.known {
            *p /= total;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    struct Lcg(u64);
    impl Lcg {
        fn uniform(&mut self) -> f64 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            (self.0 >> 11) as f64 / (1u64 << 53) as f64
        }
    }

    #[test]
    fn noisy_sequence_converges_to_the_true_id() {
        // 40 % of readings are misreads spread over other IDs, each with a
        // middling confidence: the truth must still win within 15 readings.
        let mut rng = Lcg(7);
        for members in [16usize, 2048] {
            let mut filter = IdFilter::new(members);
            let truth = 5;
            for _ in 0..15 {
                let id = if rng.uniform() < 0.6 {
                    truth
                } else {
                    1 + (rng.uniform() * members as f64) as u32 % members as u32
                };
                filter.observe_member(id, 0.4 + 0.3 * rng.uniform());
            }
            let est = filter.estimate();
            assert_eq!(est.id, truth, "members {members}: {est:?}");
            assert!(est.probability > 0.9, "{est:?}");
        }
    }

    #[test]
    fn one_confident_misread_does_not_flip_a_track() {
        let mut filter = IdFilter::new(4080);
        for _ in 0..5 {
            filter.observe_member(17, 0.9);
        }
        filter.observe_member(18, 0.95);
        assert_eq!(filter.estimate().id, 17);
        assert!(filter.estimate().probability > 0.99);
        // A new marker under the same track takes over after a few reads.
        for _ in 0..4 {
            filter.observe_member(18, 0.95);
        }
        assert_eq!(filter.estimate().id, 18);
    }

    #[test]
    fn a_single_reading_names_the_id_but_not_with_certainty() {
        let mut filter = IdFilter::new(30);
        assert_eq!(filter.estimate().id, 0);
        filter.observe_member(3, 0.9);
        let est = filter.estimate();
        assert_eq!(est.id, 3);
        assert!(est.probability > 0.5 && est.probability < 0.99, "{est:?}");
        // Readings with no confidence change nothing.
        let before = filter.probability(3);
        filter.observe_member(4, 0.0);
        assert_eq!(filter.probability(3), before);
    }

    #[test]
    fn a_contradicted_belief_is_reported_with_the_doubt_of_the_contradiction() {
        let mut filter = IdFilter::new(30);
        for _ in 0..5 {
            filter.observe_member(7, 0.9);
        }
        filter.observe_member(8, 0.9);
        let belief = filter.estimate();
        assert_eq!(belief.id, 7);
        assert!(belief.probability > 0.99, "{belief:?}");
        let reported = IdFilter::contradicted(belief, 0.9);
        assert!((reported - 0.1).abs() < 1e-9, "{reported}");
        // A faint contradiction dents the report a little; a reading with
        // no confidence none at all.
        assert!((IdFilter::contradicted(belief, 0.2) - 0.8).abs() < 1e-9);
        assert_eq!(IdFilter::contradicted(belief, 0.0), belief.probability);
        // The filter never trusts a reading fully, nor doubts fully.
        assert!(IdFilter::contradicted(belief, 1.0) > 0.0);
    }

    #[test]
    fn repeated_non_member_readings_settle_on_unknown() {
        let mut filter = IdFilter::new(30);
        filter.observe_member(12, 0.3);
        for _ in 0..8 {
            filter.observe_non_member(0.95);
        }
        let est = filter.estimate();
        assert_eq!(est.id, 0);
        assert!(est.probability > 0.9, "{est:?}");
        // ...while one rejected reading barely dents a confident member.
        let mut filter = IdFilter::new(30);
        for _ in 0..4 {
            filter.observe_member(9, 0.9);
        }
        filter.observe_non_member(1.0);
        assert_eq!(filter.estimate().id, 9);
    }

    #[test]
    fn probabilities_stay_normalised_with_many_distinct_readings() {
        let mut filter = IdFilter::new(500);
        for k in 0..200u32 {
            filter.observe_member(1 + k * 7 % 500, 0.5);
        }
        let listed: f64 = filter.known.iter().map(|e| e.1).sum();
        let total = listed + filter.rest * (500 - filter.known.len()) as f64 + filter.non_member;
        assert!((total - 1.0).abs() < 1e-9, "{total}");
        assert!(filter.known.len() <= MAX_TRACKED_IDS);
    }
}
