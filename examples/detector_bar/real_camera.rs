//! Row 10: realistic cameras. Each cell (`whycode_testkit::scenario::
//! real_camera`: 1280x720, f = 1000 px, 8-bit markers tilted up to 30°)
//! spoils the picture one way a photograph taken by someone else does
//! (paper in shade of a bright frame, grey ink, video upscaled from half
//! the resolution, sharpening halos, a Bayer sensor, discs at the frame's
//! border, and all of them at once). Every rival reads the same scenes
//! with its own tags at the same printed footprint, in the same run.

use whycode::family::Family;
use whycode_testkit::scenario::{detector, real_camera, Print, RealCamera};
use whycode_testkit::tally::Counts;

use crate::rival;
use crate::table::{beats, cells, pct, Table};
use crate::Rivals;

pub fn rows(table: &mut Table, fam8: &Family, scale: usize, rivals: &Rivals) {
    let mut ours_total = Counts::default();
    let mut theirs_total: [Option<Counts>; 3] = rivals.map(|r| r.map(|_| Counts::default()));
    let show = |c: &Counts| {
        format!(
            "found {}, named {}, {} wrong, {} false",
            pct(c.detection_rate()),
            pct(c.id_rate()),
            c.wrong_id,
            c.false_detections
        )
    };
    let mut every_cell = true;
    for (k, camera) in RealCamera::ALL.into_iter().enumerate() {
        let scenario = real_camera(Some(fam8), camera, 2 * scale, 2_000_000 + 100 * k as u64);
        let mut det = detector(Some(fam8), &scenario.camera(), false);
        let mut ours = Counts::default();
        for f in 0..scenario.frames {
            let frame = scenario.frame(f, Print::WhyCode);
            let seen: Vec<_> = det
                .detect(&frame.image)
                .iter()
                .map(whycode::simulate::Sighting::from)
                .collect();
            ours.add(frame.seed, &frame.targets, &seen);
        }
        let theirs: [Option<Counts>; 3] = rivals.map(|r| rival::counts(&scenario, r));
        ours_total.merge(&ours);
        for (total, cell) in theirs_total.iter_mut().zip(&theirs) {
            if let (Some(t), Some(c)) = (total.as_mut(), cell) {
                t.merge(c);
            }
        }
        // At least every rival's share found and named, never a wrong ID
        // nor a false report.
        let pass = ours.wrong_id == 0
            && ours.false_detections == 0
            && beats(&ours, &theirs, |o, t| {
                o.detected >= t.detected && o.correct_id >= t.correct_id
            });
        every_cell &= pass;
        table.row(
            &format!("10 real camera: {}", camera.name()),
            show(&ours),
            cells(&theirs, show),
            "",
            pass,
        );
    }
    table.row(
        "10 real camera, all cells",
        show(&ours_total),
        cells(&theirs_total, show),
        "",
        every_cell && ours_total.detection_rate() >= 0.9,
    );
}
