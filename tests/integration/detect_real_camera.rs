//! What photographs taken by other people do to markers, rendered by the
//! simulator and read back: paper in the shade of a bright room, a blurred
//! marker from a compressed video whose ring cannot be read, a legacy
//! circle whose white centre the blur has grown, a disc at the frame's
//! border. Each marker a person sees in these pictures must be found, and
//! named where its ring can be read; never with a wrong ID.

use whycode::camera::Camera;
use whycode::detect::{Detection, Detector, DetectorConfig, Target, Unnamed};
use whycode::family::Family;
use whycode::geometry::Marker;
use whycode::simulate::{self, Background, LooseMarker, Placement, Scene, SceneObject, Shade};
use whycode_testkit::scenario::{detector, real_camera, RealCamera};
use whycode_testkit::tally::Counts;

const DIAMETER_MM: f64 = 50.0;

fn camera() -> Camera {
    whycode_testkit::scenes::camera(1280, 720, 1000.0)
}

fn family() -> Family {
    Family::generate(8, 2).unwrap()
}

/// A marker of `diameter_px` at the pixel (u, v), face-on, with ID `id`
/// of the 8-bit family (legacy WhyCon for ID 0).
fn marker_at(camera: &Camera, id: u32, (u, v): (f64, f64), diameter_px: f64) -> LooseMarker {
    let marker = if id == 0 {
        Marker::whycon(DIAMETER_MM)
    } else {
        Marker::whycode(8, family().code(id).unwrap(), DIAMETER_MM)
    };
    let placement = Placement::at_pixel(camera, &marker, (u, v), diameter_px, 0.0, 0.0, 0.7);
    LooseMarker::new(marker, id, placement)
}

fn detect(image: &image::GrayImage, target: Target) -> Vec<Detection> {
    Detector::new(DetectorConfig {
        target,
        ..DetectorConfig::default()
    })
    .detect(image)
}

fn near(found: &[Detection], (u, v): (f64, f64), reach: f64) -> Vec<&Detection> {
    found
        .iter()
        .filter(|d| (d.u - u).hypot(d.v - v) < reach)
        .collect()
}

/// A sharp 150 px marker on a card in the shade (a third of the light:
/// paper grey ~65, ink ~20) with a quarter radius of paper round it, in a
/// frame of lit walls (grey ~200): the mid-level between ink and wall lies
/// above the shaded paper.
fn shaded_scene(id: u32) -> (image::GrayImage, (f64, f64)) {
    let camera = camera();
    let centre = (640.0, 360.0);
    let mut m = marker_at(&camera, id, centre, 150.0);
    m.card_half_mm = 1.25 * m.marker.outer_radius();
    let mut scene = Scene::new(camera);
    scene.background = Background::Uniform(0.9);
    scene.ink_reflectance = 0.25;
    scene.objects = vec![SceneObject::Marker(m)];
    scene.shades = vec![Shade {
        u: centre.0,
        v: centre.1,
        radius_px: 0.5 * 150.0 * 1.25 * std::f64::consts::SQRT_2 + 4.0,
        soft_px: 6.0,
        factor: 0.3,
    }];
    scene.noise = 2.0;
    (simulate::render(&scene).0, centre)
}

#[test]
fn a_marker_in_the_shade_of_a_bright_frame_is_found_in_the_first_frame() {
    let (legacy, centre) = shaded_scene(0);
    let found = detect(&legacy, Target::WhyCon);
    assert_eq!(near(&found, centre, 5.0).len(), 1, "{found:?}");
    assert_eq!(found.len(), 1, "{found:?}");
    let (coded, centre) = shaded_scene(7);
    let found = detect(&coded, Target::WhyCode(family()));
    let at = near(&found, centre, 5.0);
    assert_eq!(at.len(), 1, "{found:?}");
    assert_eq!(at[0].id, 7, "{found:?}");
}

/// Three markers of 40-57 px on a floor, out of focus by 0.055 of their
/// diameter, from a video of half the resolution shown twice as large.
fn video_scene(ids: [u32; 3]) -> (image::GrayImage, [(f64, f64); 3]) {
    let camera = camera();
    let places = [(300.0, 200.0), (700.0, 420.0), (1000.0, 250.0)];
    let sizes = [40.0, 48.0, 57.0];
    let mut scene = Scene::new(camera);
    scene.background = Background::Table;
    scene.objects = (0..3)
        .map(|k| SceneObject::Marker(marker_at(&camera, ids[k], places[k], sizes[k])))
        .collect();
    scene.focus_blur_px = 0.055 * 48.0;
    scene.processing.video_downscale = Some(2);
    scene.processing.video_quality = 40;
    scene.noise = 2.0;
    (simulate::render(&scene).0, places)
}

#[test]
fn a_blurred_marker_whose_ring_cannot_be_read_is_reported_as_unknown() {
    let (image, places) = video_scene([0, 0, 0]);
    let found = detect(&image, Target::WhyCode(family()));
    assert_eq!(found.len(), 3, "{found:?}");
    for place in places {
        let at = near(&found, place, 4.0);
        assert_eq!(at.len(), 1, "{place:?}: {found:?}");
        assert_eq!(at[0].id, 0);
        assert_eq!(at[0].unnamed, Some(Unnamed::NoCodeRing), "{:?}", at[0]);
    }
    // WhyCode markers under the same blur: found, and never misnamed.
    let ids = [3, 9, 14];
    let (image, places) = video_scene(ids);
    let found = detect(&image, Target::WhyCode(family()));
    assert_eq!(found.len(), 3, "{found:?}");
    for (place, id) in places.into_iter().zip(ids) {
        let at = near(&found, place, 4.0);
        assert_eq!(at.len(), 1, "{place:?}: {found:?}");
        assert!(at[0].id == id || at[0].id == 0, "{:?}", at[0]);
        assert_eq!(at[0].unnamed.is_some(), at[0].id == 0, "{:?}", at[0]);
    }
}

#[test]
fn a_blurred_legacy_circle_whose_white_centre_has_grown_is_found() {
    // WhyCon circles printed with a white centre of 0.46 of the diameter
    // (as robots' markers in the field measure), seen through the video's
    // blur, by a legacy and by a WhyCode detector.
    let camera = camera();
    let places = [(300.0, 200.0), (700.0, 420.0), (1000.0, 250.0)];
    for blur in [0.055, 0.07] {
        let mut scene = Scene::new(camera);
        scene.background = Background::Table;
        scene.objects = [40.0, 48.0, 57.0]
            .into_iter()
            .zip(places)
            .map(|(size, place)| {
                let mut m = marker_at(&camera, 0, place, size);
                m.blots.push(simulate::Blot {
                    x_mm: 0.0,
                    y_mm: 0.0,
                    radius_mm: 0.46 * m.marker.outer_radius(),
                    black: false,
                });
                SceneObject::Marker(m)
            })
            .collect();
        scene.focus_blur_px = blur * 48.0;
        scene.processing.video_downscale = Some(2);
        scene.processing.video_quality = 40;
        scene.noise = 2.0;
        let image = simulate::render(&scene).0;
        for target in [Target::WhyCon, Target::WhyCode(family())] {
            let found = detect(&image, target);
            assert_eq!(found.len(), 3, "blur {blur}: {found:?}");
            for place in places {
                let at = near(&found, place, 4.0);
                assert_eq!(at.len(), 1, "blur {blur}, {place:?}: {found:?}");
                assert_eq!(at[0].id, 0);
            }
        }
    }
}

#[test]
fn a_disc_a_fiftieth_of_its_diameter_from_the_border_is_found_and_named() {
    // A landing pad filling a drone's camera: 344 px across in a frame 360
    // px high, 0.02 of its diameter from three of its edges.
    let camera = whycode_testkit::scenes::camera(640, 360, 500.0);
    let d = 344.0;
    let gap = 0.5 * (360.0 - d);
    for (id, target) in [(5, Target::WhyCode(family())), (0, Target::WhyCon)] {
        for place in [(gap + d / 2.0, 180.0), (640.0 - gap - d / 2.0, 180.0)] {
            let mut scene = Scene::new(camera);
            scene.background = Background::Uniform(0.7);
            scene.objects = vec![SceneObject::Marker(marker_at(&camera, id, place, d))];
            scene.noise = 2.0;
            let image = simulate::render(&scene).0;
            let found = detect(&image, target.clone());
            let at = near(&found, place, 3.0);
            assert_eq!(at.len(), 1, "{place:?}: {found:?}");
            assert_eq!(at[0].id, id, "{:?}", at[0]);
        }
    }
}

/// The realistic-camera cells of the detector bar, a frame each: most
/// markers found, none misnamed, no false report.
#[test]
fn realistic_camera_cells_find_their_markers_and_name_none_wrongly() {
    let family = family();
    let mut total = Counts::default();
    for (k, cell) in RealCamera::ALL.into_iter().enumerate() {
        let scenario = real_camera(Some(&family), cell, 1, 7_000 + 10 * k as u64);
        let mut counts = Counts::default();
        scenario.run(
            &mut detector(Some(&family), &scenario.camera(), false),
            &mut counts,
            |_, _| {},
        );
        assert_eq!(counts.wrong_id, 0, "{cell:?}: {counts:?}");
        assert_eq!(counts.false_detections, 0, "{cell:?}: {counts:?}");
        total.merge(&counts);
    }
    assert!(total.detection_rate() >= 0.9, "{total:?}");
}
