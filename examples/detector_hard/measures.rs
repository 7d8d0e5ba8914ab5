//! Rows 1 and 2 measure angles rather than count markers: yaw against the
//! true image direction of +x, and the pose's normal, roll and centre
//! against the true marker.

use nalgebra::Vector3;
use whycode::family::Family;
use whycode::simulate::TrueMarker;

use crate::scenario::{
    detector, match_truth, wrap, Counts, Errors, Families, Scenario, Spread, DEG,
};

/// Row 1: yaw of markers read with their own ID, `frames_per_bits` frames
/// of 800x600 per code length. Errors in degrees, and the ID counts.
pub fn yaw_errors(
    families: &mut Families,
    bits: &[u32],
    frames_per_bits: usize,
    spread: Spread,
    seed0: u64,
) -> (Errors, Counts) {
    let mut errors = Errors::default();
    let mut counts = Counts::default();
    for (b, &n) in bits.iter().enumerate() {
        let family = families.get(n, 2);
        let scenario = Scenario::new(
            Some(&family),
            spread,
            frames_per_bits,
            seed0 + 1000 * b as u64,
        );
        let mut det = detector(Some(&family), &scenario.camera(), false);
        scenario.run(&mut det, &mut counts, |frame, found| {
            let truth = &frame.truth;
            for (t, d) in match_truth(truth, found).pairs {
                let Some(d) = d else { continue };
                let (m, d) = (&truth.markers[t], &found[d]);
                if let (true, Some(yaw)) = (d.id == m.id, d.yaw) {
                    errors.add(wrap(yaw - m.yaw) / DEG, (frame.seed, t));
                }
            }
        });
    }
    (errors, counts)
}

/// Row 2: angle between the estimated and the true marker normal, in
/// degrees, per 10° band of the true viewing angle (between the normal and
/// the line of sight); and how many exceed `wrong_deg` (the wrong one of
/// the two candidate normals picked). Also the in-plane rotation error of
/// the full pose (its +x axis against the true one, degrees) and the centre
/// errors (px) of `Detection::u, v` and of the pose's projected position.
pub struct NormalResult {
    pub per_view: Vec<(f64, Errors)>,
    pub all: Errors,
    pub wrong_picks: usize,
    pub first_wrong: Option<(u64, usize, f64)>,
    pub pose_roll: Errors,
    pub centre: Errors,
    pub pose_centre: Errors,
    pub counts: Counts,
}

/// View angle of a true marker: between its normal and the direction to
/// the camera, degrees.
fn view_angle(m: &TrueMarker) -> f64 {
    let n = Vector3::from(m.normal);
    let to_camera = -Vector3::from(m.position).normalize();
    n.dot(&to_camera).clamp(-1.0, 1.0).acos() / DEG
}

pub fn normal_errors(
    family: &Family,
    tilts_deg: &[f64],
    frames_per_tilt: usize,
    markers_per_frame: usize,
    diameter_px: (f64, f64),
    wrong_deg: f64,
    seed0: u64,
) -> NormalResult {
    let cam = crate::scenario::camera(800, 600);
    // One detector for every tilt: its adaptive state carries over.
    let mut det = detector(Some(family), &cam, false);
    let mut bands = vec![Errors::default(); 9];
    let mut result = NormalResult {
        per_view: Vec::new(),
        all: Errors::default(),
        wrong_picks: 0,
        first_wrong: None,
        pose_roll: Errors::default(),
        centre: Errors::default(),
        pose_centre: Errors::default(),
        counts: Counts::default(),
    };
    for (k, &tilt) in tilts_deg.iter().enumerate() {
        let spread = Spread::fixed_tilt(markers_per_frame, diameter_px, tilt);
        let scenario = Scenario::new(
            Some(family),
            spread,
            frames_per_tilt,
            seed0 + 1000 * k as u64,
        );
        let mut counts = std::mem::take(&mut result.counts);
        scenario.run(&mut det, &mut counts, |frame, found| {
            let (seed, truth) = (frame.seed, &frame.truth);
            for (t, d) in match_truth(truth, found).pairs {
                let Some(d) = d.map(|d| &found[d]) else {
                    continue;
                };
                let m = &truth.markers[t];
                result.centre.add((d.u - m.u).hypot(d.v - m.v), (seed, t));
                let Some(pose) = d.pose.as_ref() else {
                    continue;
                };
                if let Some((pu, pv)) = cam.project(&pose.position) {
                    result
                        .pose_centre
                        .add((pu - m.u).hypot(pv - m.v), (seed, t));
                }
                let n = pose.rotation.column(2).into_owned();
                let want = Vector3::from(m.normal);
                let angle = n.normalize().dot(&want).clamp(-1.0, 1.0).acos() / DEG;
                let band = ((view_angle(m) / 10.0) as usize).min(bands.len() - 1);
                bands[band].add(angle, (seed, t));
                result.all.add(angle, (seed, t));
                if angle > wrong_deg {
                    result.wrong_picks += 1;
                    result.first_wrong.get_or_insert((seed, t, angle));
                }
                if d.id == m.id {
                    // Rotation about the normal: the estimated +x axis
                    // against the true one, both projected onto the true
                    // marker plane.
                    let rot = nalgebra::Matrix3::from_fn(|i, j| m.rotation[i][j]);
                    let x_est = rot.transpose() * pose.rotation.column(0).into_owned();
                    result
                        .pose_roll
                        .add(x_est.y.atan2(x_est.x) / DEG, (seed, t));
                }
            }
        });
        result.counts = counts;
    }
    result.per_view = bands
        .into_iter()
        .enumerate()
        .filter(|(_, e)| e.n > 0)
        .map(|(k, e)| (10.0 * k as f64, e))
        .collect();
    result
}
