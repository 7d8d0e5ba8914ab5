//! Rows 1 and 2 measure angles rather than count markers: yaw against the
//! true image direction of +x, and the pose's normal, roll and centre
//! against the true target. The same scoring reads our reports and the
//! rivals' on the same scenes.

use whycode::camera::Camera;
use whycode::family::Family;

use crate::rival::Rival;
use crate::scenario::{
    detector, match_truth, wrap, Counts, Errors, Families, Frame, Scenario, Seen, Spread, Truth,
    DEG,
};

/// Yaw errors (degrees) and the ID counts of one detector.
#[derive(Default)]
pub struct YawResult {
    pub errors: Errors,
    pub counts: Counts,
}

impl YawResult {
    fn add(&mut self, frame: &Frame, found: &[Seen]) {
        for (t, d) in match_truth(&frame.targets, found).pairs {
            let Some(d) = d else { continue };
            let (m, d) = (&frame.targets[t], &found[d]);
            if let (true, Some(yaw)) = (d.id == Some(m.id), d.yaw) {
                self.errors.add(wrap(yaw - m.yaw) / DEG, (frame.seed, t));
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
        let mut counts = std::mem::take(&mut ours.counts);
        scenario.run(&mut det, &mut counts, |frame, found| ours.add(frame, found));
        ours.counts = counts;
        for (rival, slot) in rivals.iter().zip(theirs.iter_mut()) {
            let (Some(rival), Some(result)) = (rival, slot.as_mut()) else {
                continue;
            };
            let mut counts = std::mem::take(&mut result.counts);
            let run =
                scenario.run_rival(*rival, &mut counts, |frame, found| result.add(frame, found));
            result.counts = counts;
            if let Err(e) = run {
                eprintln!("{} failed: {e}", rival.name());
                *slot = None;
            }
        }
    }
    (ours, theirs)
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

/// View angle of a true target: between its normal and the direction to
/// the camera, degrees.
fn view_angle(m: &Truth) -> f64 {
    let to_camera = -m.position.normalize();
    m.normal().dot(&to_camera).clamp(-1.0, 1.0).acos() / DEG
}

impl NormalResult {
    fn add(&mut self, cam: &Camera, wrong_deg: f64, frame: &Frame, found: &[Seen]) {
        let (seed, truth) = (frame.seed, &frame.targets);
        if self.bands.is_empty() {
            self.bands = vec![Errors::default(); 9];
        }
        for (t, d) in match_truth(truth, found).pairs {
            let Some(d) = d.map(|d| &found[d]) else {
                continue;
            };
            let m = &truth[t];
            self.centre.add((d.u - m.u).hypot(d.v - m.v), (seed, t));
            if let Some((pu, pv)) = d.position.and_then(|p| cam.project(&p)) {
                self.pose_centre.add((pu - m.u).hypot(pv - m.v), (seed, t));
            }
            let Some(n) = d.normal else {
                continue;
            };
            let angle = n.normalize().dot(&m.normal()).clamp(-1.0, 1.0).acos() / DEG;
            let band = ((view_angle(m) / 10.0) as usize).min(self.bands.len() - 1);
            self.bands[band].add(angle, (seed, t));
            self.all.add(angle, (seed, t));
            if angle > wrong_deg {
                self.wrong_picks += 1;
                self.first_wrong.get_or_insert((seed, t, angle));
            }
            if let (Some(rotation), true) = (d.rotation, d.id == Some(m.id)) {
                // Rotation about the normal: the estimated +x axis against
                // the true one, both projected onto the true target plane.
                let x_est = m.rotation.transpose() * rotation.column(0).into_owned();
                self.pose_roll.add(x_est.y.atan2(x_est.x) / DEG, (seed, t));
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
    let cam = crate::scenario::camera(800, 600);
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
        let mut counts = std::mem::take(&mut ours.counts);
        scenario.run(&mut det, &mut counts, |frame, found| {
            ours.add(&cam, wrong_deg, frame, found)
        });
        ours.counts = counts;
        for (rival, slot) in rivals.iter().zip(theirs.iter_mut()) {
            let (Some(rival), Some(result)) = (rival, slot.as_mut()) else {
                continue;
            };
            let mut counts = std::mem::take(&mut result.counts);
            let run = scenario.run_rival(*rival, &mut counts, |frame, found| {
                result.add(&cam, wrong_deg, frame, found)
            });
            result.counts = counts;
            if let Err(e) = run {
                eprintln!("{} failed: {e}", rival.name());
                *slot = None;
            }
        }
    }
    ours.finish();
    for result in theirs.iter_mut().flatten() {
        result.finish();
    }
    (ours, theirs)
}
