//! Validation logic on simulated photos with ideal detections (the true
//! ellipses and IDs): page location, marker verdicts, and the printed scale
//! measured against the paper's edges in the real simulated image.

use crate::support::sheets::*;
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

#[test]
fn lens_distortion_is_removed_with_the_camera_calibration() {
    use whycode::simulate::{layout, render, Background, Scene, SceneObject, SheetPage};
    let manifest = a4_manifest();
    let mut camera = whycode::camera::Camera::ideal(2000, 1500, 62.0);
    camera.distortion = [-0.15, 0.06, 0.0004, -0.0002, 0.0];
    let mut page = SheetPage::new(
        manifest.clone(),
        1,
        layout::centred(
            layout::distance_to_fill(&camera, 210.0, 297.0, 0.85),
            0.35,
            0.15,
            0.1,
        ),
    );
    page.print_scale = 0.98;
    let mut scene = Scene::new(camera);
    scene.objects.push(SceneObject::Page(page));
    scene.background = Background::Table;
    scene.noise = 2.0;
    scene.focus_blur_px = 0.8;
    let (image, truth) = render(&scene);
    let obs = ideal_observations(&truth);
    let report = check_photo("p.png", &manifest, &obs, &image, Some(&camera));
    let scale = report.pages[0].scale.scale.unwrap();
    assert!((scale - 0.98).abs() < 0.003, "scale {scale}");
    assert!(
        report.pages[0].rms_px < 0.5,
        "rms {}",
        report.pages[0].rms_px
    );
    assert!(report
        .markers
        .iter()
        .all(|m| m.status == MarkerStatus::Found));
}

#[test]
fn two_pages_in_two_photos_combine_into_one_verdict() {
    let family = whycode::family::Family::generate(BITS, DISTANCE).unwrap();
    let mut manifest = a4_manifest();
    manifest.pages = 2;
    for (k, id) in (13..=16u32).enumerate() {
        manifest.markers.push(whycode::manifest::PrintedMarker {
            id,
            code: family.code(id).unwrap(),
            page: 2,
            x_mm: 60.0 + 90.0 * (k % 2) as f64,
            y_mm: 70.0 + 150.0 * (k / 2) as f64,
            diameter_mm: 60.0,
        });
    }
    let mut reports = Vec::new();
    for page in [1, 2] {
        use whycode::simulate::{layout, render, Scene, SceneObject, SheetPage};
        let camera = camera();
        let mut scene = Scene::new(camera);
        scene.objects.push(SceneObject::Page(SheetPage::new(
            manifest.clone(),
            page,
            layout::centred(
                layout::distance_to_fill(&camera, 210.0, 297.0, 0.8),
                0.2,
                0.0,
                0.0,
            ),
        )));
        let (image, truth) = render(&scene);
        reports.push(check_photo(
            &format!("page{page}.png"),
            &manifest,
            &ideal_observations(&truth),
            &image,
            None,
        ));
    }
    assert_eq!(reports[1].pages.len(), 1);
    assert_eq!(reports[1].pages[0].page, 2);
    let one_photo = summarise(&manifest, vec![reports[0].clone()]);
    assert!(!one_photo.ok);
    assert_eq!(one_photo.counts.missing, 4);
    let both = summarise(&manifest, reports);
    assert!(both.ok, "{}", both.to_table());
    assert_eq!(both.counts.found, 16);
    assert!(both.pages.iter().all(|p| p.scale_status == ScaleStatus::Ok));
}

#[test]
fn a_marker_printed_at_another_size_is_noted() {
    let manifest = a4_manifest();
    let mut printed = manifest.clone();
    printed.markers[5].diameter_mm = 38.0; // ID 6, 45 mm in the manifest
    let (image, truth) = photo(&printed, &Photo::default());
    let report = check_photo(
        "p.jpg",
        &manifest,
        &ideal_observations(&truth),
        &image,
        None,
    );
    let odd = &report.pages[0].odd_sizes;
    assert_eq!(odd.len(), 1, "{odd:?}");
    assert_eq!(odd[0].id, 6);
    assert!((odd[0].relative_size - 38.0 / 45.0).abs() < 0.02, "{odd:?}");
    let table = summarise(&manifest, vec![report]).to_table();
    assert!(table.contains("marker 6 on page 1 is -16 %"), "{table}");
}
