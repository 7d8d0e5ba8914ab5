//! Validation logic on simulated photos with ideal detections (the true
//! ellipses and IDs): page location, marker verdicts, and the printed scale
//! measured against the paper's edges in the real simulated image.

mod validate_common;

use validate_common::*;
use whycode::validate::scale::ScaleStatus;
use whycode::validate::{check_photo, summarise, MarkerStatus};

#[test]
fn correct_sheet_validates_clean_with_scale_near_100_percent() {
    let manifest = a4_manifest();
    let (image, truth) = photo(&manifest, &Photo::default());
    let obs = ideal_observations(&truth);
    assert_eq!(obs.len(), 12);
    let report = check_photo("p.jpg", &manifest, &obs, &image, None);
    assert_eq!(report.pages.len(), 1);
    let page = &report.pages[0];
    assert_eq!(page.inliers, 12);
    assert!(page.rms_px < 0.05, "rms {}", page.rms_px);
    let scale = page.scale.scale.expect("paper edges found");
    assert!((scale - 1.0).abs() < 0.003, "scale {scale}");
    assert_eq!(page.scale.edges.len(), 4);
    let summary = summarise(&manifest, vec![report]);
    assert!(summary.ok, "{}", summary.to_table());
    assert_eq!(summary.counts.found, 12);
}

#[test]
fn print_at_97_percent_is_measured_from_the_paper() {
    let manifest = a4_manifest();
    let (image, truth) = photo(
        &manifest,
        &Photo {
            print_scale: 0.97,
            ..Photo::default()
        },
    );
    let report = check_photo(
        "p.jpg",
        &manifest,
        &ideal_observations(&truth),
        &image,
        None,
    );
    let s = &report.pages[0].scale;
    let scale = s.scale.expect("paper edges found");
    assert!((scale - 0.97).abs() < 0.005, "scale {scale}");
    assert!(matches!(
        s.status,
        ScaleStatus::Warning | ScaleStatus::Error
    ));
    let summary = summarise(&manifest, vec![report]);
    assert!(!summary.ok);
    assert_eq!(summary.counts.found, 12);
    assert!(
        summary.to_table().contains("printed at 97."),
        "{}",
        summary.to_table()
    );
}

#[test]
fn misread_unidentified_and_missing_markers_are_told_apart() {
    let manifest = a4_manifest();
    let (image, truth) = photo(&manifest, &Photo::default());
    let mut obs = ideal_observations(&truth);
    obs.iter_mut().find(|o| o.id == 4).unwrap().id = 9; // now two detections say 9
    obs.iter_mut().find(|o| o.id == 7).unwrap().id = 0;
    obs.retain(|o| o.id != 11);
    let report = check_photo("p.jpg", &manifest, &obs, &image, None);
    let status = |id: u32| report.markers.iter().find(|m| m.id == id).unwrap().status;
    assert_eq!(status(4), MarkerStatus::Misread);
    assert_eq!(
        report.markers.iter().find(|m| m.id == 4).unwrap().read_as,
        Some(9)
    );
    assert_eq!(status(7), MarkerStatus::Unidentified);
    assert_eq!(status(11), MarkerStatus::Missing);
    assert_eq!(status(9), MarkerStatus::Found);
    let others = report
        .markers
        .iter()
        .filter(|m| ![4, 7, 11].contains(&m.id))
        .all(|m| m.status == MarkerStatus::Found);
    assert!(others);
    let summary = summarise(&manifest, vec![report]);
    assert!(!summary.ok);
    assert_eq!(
        (
            summary.counts.misread,
            summary.counts.unidentified,
            summary.counts.missing
        ),
        (1, 1, 1)
    );
}

#[test]
fn close_up_with_paper_edges_out_of_frame_reports_scale_unknown_and_why() {
    let manifest = a4_manifest();
    let (image, truth) = photo(
        &manifest,
        &Photo {
            fill: 2.2,
            tilt_deg: 0.0,
            pan_deg: 0.0,
            roll_deg: 0.0,
            ..Photo::default()
        },
    );
    let obs = ideal_observations(&truth);
    let report = check_photo("p.jpg", &manifest, &obs, &image, None);
    let page = &report.pages[0];
    assert_eq!(page.scale.status, ScaleStatus::Unknown);
    let note = page.scale.note.clone().unwrap();
    assert!(note.contains("not in the photo"), "{note}");
    // Markers cut off by the frame are not in view rather than missing.
    for m in &report.markers {
        let t = truth.marker(m.id).unwrap();
        if t.visible {
            assert_eq!(m.status, MarkerStatus::Found, "id {}", m.id);
        } else {
            assert_eq!(m.status, MarkerStatus::NotInView, "id {}", m.id);
        }
    }
}
