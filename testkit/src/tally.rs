//! Tallies over many frames: what happened to the true targets
//! ([`Counts`], from `whycode::simulate`'s matching) and running
//! statistics of signed errors ([`Errors`]). Every entry keeps where it
//! came from (the frame's seed and the target's index in its truth), so a
//! figure can be traced to the scene that made it.

use whycode::simulate::{match_reports, IdRead, Reach, Sighting, TrueTarget};

/// Running statistics of signed errors.
#[derive(Debug, Clone, Copy, Default)]
pub struct Errors {
    /// How many errors were added.
    pub n: usize,
    /// Their sum.
    pub sum: f64,
    /// The sum of their sizes.
    pub sum_abs: f64,
    /// The largest size.
    pub max_abs: f64,
    /// Where the largest error was: (seed, target index in the truth).
    pub worst: Option<(u64, usize)>,
}

impl Errors {
    /// Adds error `e` made at `at` (seed, target index).
    pub fn add(&mut self, e: f64, at: (u64, usize)) {
        self.n += 1;
        self.sum += e;
        self.sum_abs += e.abs();
        if e.abs() >= self.max_abs {
            self.max_abs = e.abs();
            self.worst = Some(at);
        }
    }

    /// The mean signed error (the bias); NaN without errors.
    pub fn mean(&self) -> f64 {
        if self.n == 0 {
            f64::NAN
        } else {
            self.sum / self.n as f64
        }
    }

    /// The mean size of the errors; NaN without errors.
    pub fn mean_abs(&self) -> f64 {
        if self.n == 0 {
            f64::NAN
        } else {
            self.sum_abs / self.n as f64
        }
    }
}

/// What happened to the visible true targets of a set of frames.
#[derive(Debug, Clone, Copy, Default)]
pub struct Counts {
    /// Visible targets.
    pub markers: usize,
    /// Targets some report was paired with.
    pub detected: usize,
    /// Detected with their own ID.
    pub correct_id: usize,
    /// Detected without an ID.
    pub unknown_id: usize,
    /// Detected with another member's ID: a guess that went wrong.
    pub wrong_id: usize,
    /// Reports about no target.
    pub false_detections: usize,
    /// False detections that even carry a member ID.
    pub false_with_id: usize,
    /// Frames added.
    pub frames: usize,
    /// First (seed, target) missed.
    pub first_miss: Option<(u64, usize)>,
    /// First (seed, target) read with a wrong ID.
    pub first_wrong: Option<(u64, usize)>,
    /// First (seed, position) of a false detection.
    pub first_false: Option<(u64, (f64, f64))>,
}

impl Counts {
    /// Adds one frame (seeded `seed`): its targets and what a detector
    /// reported, paired within the default [`Reach`].
    pub fn add(&mut self, seed: u64, targets: &[TrueTarget], found: &[Sighting]) {
        self.add_within(seed, targets, found, Reach::default());
    }

    /// [`Counts::add`] with reports paired within `reach`.
    pub fn add_within(
        &mut self,
        seed: u64,
        targets: &[TrueTarget],
        found: &[Sighting],
        reach: Reach,
    ) {
        let matched = match_reports(targets, found, reach);
        self.frames += 1;
        for &(t, d) in &matched.pairs {
            self.markers += 1;
            let Some(d) = d else {
                self.first_miss.get_or_insert((seed, t));
                continue;
            };
            self.detected += 1;
            match targets[t].id_read(found[d].id) {
                IdRead::Unknown => self.unknown_id += 1,
                IdRead::Right => self.correct_id += 1,
                IdRead::Wrong => {
                    self.wrong_id += 1;
                    self.first_wrong.get_or_insert((seed, t));
                }
            }
        }
        for &k in &matched.false_reports {
            self.false_detections += 1;
            if found[k].id.is_some() {
                self.false_with_id += 1;
            }
            self.first_false
                .get_or_insert((seed, (found[k].u, found[k].v)));
        }
    }

    /// Adds another set of frames' counts (the first misses, wrong IDs and
    /// false reports kept where these had none).
    pub fn merge(&mut self, other: &Counts) {
        self.markers += other.markers;
        self.detected += other.detected;
        self.correct_id += other.correct_id;
        self.unknown_id += other.unknown_id;
        self.wrong_id += other.wrong_id;
        self.false_detections += other.false_detections;
        self.false_with_id += other.false_with_id;
        self.frames += other.frames;
        self.first_miss = self.first_miss.or(other.first_miss);
        self.first_wrong = self.first_wrong.or(other.first_wrong);
        self.first_false = self.first_false.or(other.first_false);
    }

    /// Share of the targets detected.
    pub fn detection_rate(&self) -> f64 {
        self.detected as f64 / self.markers.max(1) as f64
    }

    /// Share of the targets read with their own ID.
    pub fn id_rate(&self) -> f64 {
        self.correct_id as f64 / self.markers.max(1) as f64
    }

    /// False detections per frame.
    pub fn false_per_frame(&self) -> f64 {
        self.false_detections as f64 / self.frames.max(1) as f64
    }

    /// `n` of the targets, in percent.
    pub fn percent(&self, n: usize) -> f64 {
        100.0 * n as f64 / self.markers.max(1) as f64
    }
}
