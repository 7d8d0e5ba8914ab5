//! The must-show round trips: a sheet simulated as a phone photo
//! (perspective, blur, noise, uneven light, JPEG) goes through the real
//! detector and the validation.

use crate::support::sheets::*;
use whycode::validate::scale::ScaleStatus;
use whycode::validate::{check_image, detector_for, summarise, MarkerStatus, Report};

fn validate(p: &Photo) -> Report {
    let manifest = a4_manifest();
    let (image, _) = photo(&manifest, p);
    let mut detector = detector_for(&manifest).unwrap();
    let report = check_image("photo.jpg", &manifest, &image, None, &mut detector);
    summarise(&manifest, vec![report])
}

#[test]
fn sheet_photo_with_perspective_blur_noise_and_uneven_light_validates_clean() {
    let report = validate(&Photo::default());
    assert!(report.ok, "{}", report.to_table());
    assert_eq!(report.counts.found, 12);
    let scale = report.pages[0].scale.unwrap();
    assert!((scale - 1.0).abs() < 0.005, "scale {scale}");
    assert_eq!(report.pages[0].scale_status, ScaleStatus::Ok);
}

#[test]
fn sheet_printed_at_97_percent_is_flagged_with_its_scale() {
    let report = validate(&Photo {
        print_scale: 0.97,
        ..Photo::default()
    });
    assert!(!report.ok);
    assert_eq!(report.counts.found, 12, "{}", report.to_table());
    let scale = report.pages[0].scale.unwrap();
    assert!((scale - 0.97).abs() < 0.005, "scale {scale}");
    assert_ne!(report.pages[0].scale_status, ScaleStatus::Ok);
    assert!(report.to_table().contains("printed at 97."));
}

#[test]
fn blot_over_one_ring_reports_that_marker_and_only_it() {
    let report = validate(&Photo {
        blot_ids: vec![5],
        ..Photo::default()
    });
    assert!(!report.ok);
    for m in &report.markers {
        if m.id == 5 {
            assert!(
                matches!(m.status, MarkerStatus::Misread | MarkerStatus::Unidentified),
                "{}",
                report.to_table()
            );
        } else {
            assert_eq!(m.status, MarkerStatus::Found, "{}", report.to_table());
        }
    }
}
