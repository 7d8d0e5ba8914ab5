//! Rows 1 and 2 measure angles rather than count markers: yaw against the
//! true image direction of +x, and the pose's normal, roll and centre
//! against the true target. The same scoring reads our reports and the
//! rivals' on the same scenes.

use whycode::camera::Camera;
use whycode::detect::Detector;
use whycode::family::Family;
use whycode::simulate::{match_reports, Reach, Sighting};
use whycode_testkit::scenario::{camera, detector, Families, Frame, Scenario, Spread, DEG};
use whycode_testkit::tally::{Counts, Errors};

use crate::rival::{self, Rival};

/// Yaw errors (degrees) and the ID counts of one detector.
#[derive(Default)]
pub struct YawResult {
    pub errors: Errors,
    pub counts: Counts,
}

impl YawResult {
    fn add(&mut self, frame: &Frame, found: &[Sighting]) {
        for (t, d) in match_reports(&frame.targets, found, Reach::default()).pairs {
            let Some(d) = d else { continue };
            let (m, d) = (&frame.targets[t], &found[d]);
            if let (true, Some(yaw)) = (d.id == Some(m.id), d.yaw) {
                self.errors.add(m.yaw_error(yaw) / DEG, (frame.seed, t));
            }
        }
    }
}

/// Row 1: yaw of markers read with their own ID, `frames_per_bits` frames
/// of 800x600 per code length; ours, and each rival's on the same scenes
/// (`None` where a rival is missing or failed).
pub fn yaw_errors(
    families: &mut Families,
    bits: &[u32],
    frames_per_bits: usize,
    spread: Spread,
    seed0: u64,
    rivals: &[Option<&dyn Rival>],
) -> (YawResult, Vec<Option<YawResult>>) {
    let mut ours = YawResult::default();
    let mut theirs: Vec<Option<YawResult>> = rivals
        .iter()
        .map(|r| r.map(|_| YawResult::default()))
        .collect();
    for (b, &n) in bits.iter().enumerate() {
        let family = families.get(n, 2);
        let scenario = Scenario::new(
            Some(&family),
            spread,
            frames_per_bits,
            seed0 + 1000 * b as u64,
        );
        let mut det = detector(Some(&family), &scenario.camera(), false);
        let results = (&mut ours, theirs.as_mut_slice());
        run_all(
            &scenario,
            &mut det,
            results,
            rivals,
            |r| &mut r.counts,
            |r, frame, found| r.add(frame, found),
        );
    }
    (ours, theirs)
}

/// Adds `scenario`'s frames as read by ours (`det`) to `ours`, and as read
/// by each rival to its slot in `theirs` (a rival that fails drops out):
/// `add` scores one frame's reports into a result, whose `Counts`
/// `counts` picks.
fn run_all<R>(
    scenario: &Scenario,
    det: &mut Detector,
    (ours, theirs): (&mut R, &mut [Option<R>]),
    rivals: &[Option<&dyn Rival>],
    counts: fn(&mut R) -> &mut Counts,
    add: impl Fn(&mut R, &Frame, &[Sighting]),
) {
    let mut tally = std::mem::take(counts(ours));
    scenario.run(det, &mut tally, |frame, found| add(ours, frame, found));
    *counts(ours) = tally;
    for (rival, slot) in rivals.iter().zip(theirs.iter_mut()) {
        let (Some(rival), Some(result)) = (rival, slot.as_mut()) else {
            continue;
        };
        let mut tally = std::mem::take(counts(result));
        let run = rival::run(scenario, *rival, &mut tally, |frame, found| {
            add(result, frame, found)
        });
        *counts(result) = tally;
        if let Err(e) = run {
            eprintln!("{} failed: {e}", rival.name());
            *slot = None;
        }
    }
}

/// Row 2: angle between the estimated and the true normal, in degrees,
/// per 10° band of the true viewing angle (between the normal and the line
/// of sight); and how many exceed `wrong_deg` (the wrong one of the two
/// candidate normals picked). Also the in-plane rotation error of the full
/// pose (its +x axis against the true one, degrees) and the centre errors
/// (px) of the reported (u, v) and of the pose's projected position.
#[derive(Default)]
pub struct NormalResult {
    pub per_view: Vec<(f64, Errors)>,
    bands: Vec<Errors>,
    pub all: Errors,
    pub wrong_picks: usize,
    pub first_wrong: Option<(u64, usize, f64)>,
    pub pose_roll: Errors,
    pub centre: Errors,
    pub pose_centre: Errors,
    pub counts: Counts,
}

impl NormalResult {
    fn add(&mut self, cam: &Camera, wrong_deg: f64, frame: &Frame, found: &[Sighting]) {
        let (seed, truth) = (frame.seed, &frame.targets);
        if self.bands.is_empty() {
            self.bands = vec![Errors::default(); 9];
        }
        for (t, d) in match_reports(truth, found, Reach::default()).pairs {
            let Some(d) = d.map(|d| &found[d]) else {
                continue;
            };
            let m = &truth[t];
            self.centre.add(m.centre_error((d.u, d.v)), (seed, t));
            if let Some(p) = d.position.and_then(|p| cam.project(&p)) {
                self.pose_centre.add(m.centre_error(p), (seed, t));
            }
            let Some(n) = d.normal else {
                continue;
            };
            let angle = m.normal_error(&n) / DEG;
            let band = ((m.view_angle() / DEG / 10.0) as usize).min(self.bands.len() - 1);
            self.bands[band].add(angle, (seed, t));
            self.all.add(angle, (seed, t));
            if angle > wrong_deg {
                self.wrong_picks += 1;
                self.first_wrong.get_or_insert((seed, t, angle));
            }
            if let (Some(rotation), true) = (d.rotation, d.id == Some(m.id)) {
                // Rotation about the normal: the estimated +x axis against
                // the true one, both projected onto the true target plane.
                self.pose_roll.add(m.roll_error(&rotation) / DEG, (seed, t));
            }
        }
    }

    fn finish(&mut self) {
        self.per_view = std::mem::take(&mut self.bands)
            .into_iter()
            .enumerate()
            .filter(|(_, e)| e.n > 0)
            .map(|(k, e)| (10.0 * k as f64, e))
            .collect();
    }

    /// The normal's errors at view angles below 10°.
    pub fn face_on(&self) -> Errors {
        self.per_view
            .iter()
            .find(|(view, _)| *view == 0.0)
            .map_or_else(Errors::default, |(_, e)| *e)
    }
}

#[allow(clippy::too_many_arguments)]
pub fn normal_errors(
    family: &Family,
    tilts_deg: &[f64],
    frames_per_tilt: usize,
    markers_per_frame: usize,
    diameter_px: (f64, f64),
    wrong_deg: f64,
    seed0: u64,
    rivals: &[Option<&dyn Rival>],
) -> (NormalResult, Vec<Option<NormalResult>>) {
    let cam = camera(800, 600);
    // One detector for every tilt: its adaptive state carries over.
    let mut det = detector(Some(family), &cam, false);
    let mut ours = NormalResult::default();
    let mut theirs: Vec<Option<NormalResult>> = rivals
        .iter()
        .map(|r| r.map(|_| NormalResult::default()))
        .collect();
    for (k, &tilt) in tilts_deg.iter().enumerate() {
        let spread = Spread::fixed_tilt(markers_per_frame, diameter_px, tilt);
        let scenario = Scenario::new(
            Some(family),
            spread,
            frames_per_tilt,
            seed0 + 1000 * k as u64,
        );
        let results = (&mut ours, theirs.as_mut_slice());
        run_all(
            &scenario,
            &mut det,
            results,
            rivals,
            |r| &mut r.counts,
            |r, frame, found| r.add(&cam, wrong_deg, frame, found),
        );
    }
    ours.finish();
    for result in theirs.iter_mut().flatten() {
        result.finish();
    }
    (ours, theirs)
}
