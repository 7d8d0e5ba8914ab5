//! Scene simulator: geometry of what it draws, ground truth, determinism.

use nalgebra::Vector3;
use whycode::camera::Camera;
use whycode::geometry::{Marker, RING_SAMPLE_RATIO};
use whycode::manifest::{FamilyRef, Manifest, PrintedMarker};
use whycode::simulate::{
    render, Background, Blot, LooseMarker, MotionBlur, Placement, Scene, SceneObject, SheetPage,
};

fn face_on_marker_scene() -> Scene {
    let camera = Camera::ideal(400, 300, 60.0);
    let mut scene = Scene::new(camera);
    // A 100 mm marker 0.5 m away: f = 346.4 px, so its disc is ~69 px across.
    let marker = Marker::whycode(8, 1, 100.0);
    scene.objects.push(SceneObject::Marker(LooseMarker::new(
        marker,
        1,
        Placement::facing(0.5),
    )));
    scene
}

fn a4_manifest() -> Manifest {
    let mut markers = Vec::new();
    let codes = [1u32, 7, 11, 13, 19, 21];
    for (k, code) in codes.iter().enumerate() {
        markers.push(PrintedMarker {
            id: k as u32 + 1,
            code: *code,
            page: 1,
            x_mm: 55.0 + 100.0 * (k % 2) as f64,
            y_mm: 60.0 + 85.0 * (k / 2) as f64,
            diameter_mm: 60.0,
        });
    }
    Manifest {
        format: "whycode-sheet".into(),
        version: 1,
        tool: "test".into(),
        family: Some(FamilyRef {
            bits: 8,
            distance: 2,
        }),
        legacy: false,
        template: "a4".into(),
        page_size_mm: [210.0, 297.0],
        pages: 1,
        files: Vec::new(),
        markers,
    }
}

#[test]
fn face_on_marker_has_the_right_size_centre_and_colours() {
    let scene = face_on_marker_scene();
    let (image, truth) = render(&scene);
    assert_eq!(image.dimensions(), (400, 300));
    let m = &truth.markers[0];
    assert!((m.u - 199.5).abs() < 1e-9 && (m.v - 149.5).abs() < 1e-9);
    let f = scene.camera.fx;
    assert!(
        (m.diameter_px - f * 0.1 / 0.5).abs() < 0.05,
        "{}",
        m.diameter_px
    );
    assert!(m.visible && !m.blotted);
    // +x of a face-on upright marker points right in the image.
    assert!(m.yaw.abs() < 1e-9);
    assert!((m.normal[2] + 1.0).abs() < 1e-12);

    let r = m.diameter_px / 2.0;
    let grey =
        |du: f64, dv: f64| image.get_pixel((m.u + du).round() as u32, (m.v + dv).round() as u32)[0];
    // Centre white, black annulus, white outside on the card, grey background.
    assert!(grey(0.0, 0.0) > 200);
    assert!(grey(0.8 * r, 0.0) < 30);
    assert!(grey(0.0, -0.8 * r) < 30);
    assert!(grey(1.2 * r, 0.0) > 200);
    assert_eq!(image.get_pixel(5, 5)[0], (0.45f64 * 255.0).round() as u8);
    // Code 1 = 00000001: sector 0 (just CCW of +x, i.e. up-right in the
    // image) is black, sector 1 white.
    let ring = RING_SAMPLE_RATIO * r;
    let at_angle = |deg: f64| {
        let a = deg.to_radians();
        grey(ring * a.cos(), -ring * a.sin())
    };
    assert!(at_angle(11.0) < 40, "sector 0 {}", at_angle(11.0));
    assert!(at_angle(34.0) > 180, "sector 1 {}", at_angle(34.0));
}

#[test]
fn anti_aliasing_gives_partial_grey_on_edges() {
    let (image, truth) = render(&face_on_marker_scene());
    let m = &truth.markers[0];
    let r = m.diameter_px / 2.0;
    // Along the row through the centre, the outer edge crosses one pixel
    // with an intermediate value.
    let row = m.v.round() as u32;
    let x_edge = (m.u + r).floor() as u32;
    let values: Vec<u8> = (x_edge - 1..=x_edge + 1)
        .map(|x| image.get_pixel(x, row)[0])
        .collect();
    assert!(values.iter().any(|&g| g > 30 && g < 190), "{values:?}");
}

#[test]
fn same_scene_and_seed_give_the_same_bytes_and_seeds_differ() {
    let mut scene = face_on_marker_scene();
    scene.background = Background::Clutter { density: 2.0 };
    scene.noise = 4.0;
    scene.focus_blur_px = 1.0;
    scene.jpeg_quality = Some(80);
    let (a, _) = render(&scene);
    let (b, _) = render(&scene);
    assert_eq!(a.as_raw(), b.as_raw());
    scene.seed = 2;
    let (c, _) = render(&scene);
    assert_ne!(a.as_raw(), c.as_raw());
}

#[test]
fn gradient_darkens_one_side_by_the_ratio() {
    let mut scene = Scene::new(Camera::ideal(300, 100, 60.0));
    scene.background = Background::Uniform(0.8);
    scene.gradient = 3.0;
    let (image, _) = render(&scene);
    let left = f64::from(image.get_pixel(0, 50)[0]);
    let right = f64::from(image.get_pixel(299, 50)[0]);
    assert!((left / right - 3.0).abs() < 0.1, "{left} / {right}");
    scene.gradient = 1.0;
    scene.exposure = 0.2;
    let (dark, _) = render(&scene);
    assert_eq!(
        dark.get_pixel(150, 50)[0],
        (0.8f64 * 0.2 * 255.0).round() as u8
    );
}

#[test]
fn tilted_page_truth_matches_its_corners_and_markers() {
    let camera = Camera::ideal(800, 600, 60.0);
    let mut scene = Scene::new(camera);
    let placement = Placement::viewed(Vector3::new(0.0, 0.0, 0.5), 30f64.to_radians(), 0.0, 0.0);
    let mut page = SheetPage::new(a4_manifest(), 1, placement);
    page.print_scale = 0.97;
    scene.objects.push(SceneObject::Page(page));
    let (image, truth) = render(&scene);
    assert_eq!(truth.markers.len(), 6);
    assert_eq!(truth.pages.len(), 1);
    let [tl, tr, br, bl] = truth.pages[0].corners;
    // Tilted top edge towards the camera: the top edge looks wider.
    assert!(tr[0] - tl[0] > br[0] - bl[0]);
    for m in &truth.markers {
        assert!(m.visible, "marker {}", m.id);
        assert!((m.diameter_mm - 60.0 * 0.97).abs() < 1e-9);
        // Every marker centre is white, a little off it inside the black disc dark.
        assert!(image.get_pixel(m.u.round() as u32, m.v.round() as u32)[0] > 180);
        let r = m.diameter_px / 2.0;
        let (dx, dy) = (m.yaw.cos(), m.yaw.sin());
        let p = image.get_pixel(
            (m.u + 0.75 * r * dx).round() as u32,
            (m.v + 0.75 * r * dy).round() as u32,
        );
        assert!(p[0] < 60, "marker {} ring {}", m.id, p[0]);
    }
    // Paper white just inside the corners, background just outside.
    let inside = image.get_pixel((tl[0] + 6.0) as u32, (tl[1] + 6.0) as u32)[0];
    let outside = image.get_pixel((tl[0] - 6.0) as u32, (tl[1] - 6.0) as u32)[0];
    assert!(inside > 200 && outside < 130, "{inside} {outside}");
}

#[test]
fn blot_marks_the_truth_and_covers_the_ring() {
    let mut scene = face_on_marker_scene();
    let SceneObject::Marker(m) = &mut scene.objects[0] else {
        unreachable!()
    };
    m.blots.push(Blot {
        x_mm: 0.0,
        y_mm: 23.0,
        radius_mm: 8.0,
        black: true,
    });
    let (image, truth) = render(&scene);
    assert!(truth.markers[0].blotted);
    let t = &truth.markers[0];
    let scale = t.diameter_px / 100.0;
    assert!(image.get_pixel(t.u.round() as u32, (t.v - 23.0 * scale).round() as u32)[0] < 30);
}

#[test]
fn distorted_camera_moves_off_axis_markers_as_the_lens_model_says() {
    let mut camera = Camera::ideal(640, 480, 70.0);
    camera.distortion = [-0.3, 0.1, 0.0, 0.0, 0.0];
    let mut scene = Scene::new(camera);
    scene.motion_blur = Some(MotionBlur {
        length_px: 3.0,
        angle: 0.3,
    });
    let placement = Placement::new(
        Vector3::new(0.25, 0.15, 0.8),
        Placement::facing(0.8).rotation,
    );
    scene.objects.push(SceneObject::Marker(LooseMarker::new(
        Marker::whycode(8, 7, 80.0),
        2,
        placement,
    )));
    let (image, truth) = render(&scene);
    let m = &truth.markers[0];
    let (u, v) = camera.project(&Vector3::new(0.25, 0.15, 0.8)).unwrap();
    assert!((m.u - u).abs() < 1e-9 && (m.v - v).abs() < 1e-9);
    // Barrel distortion pulls the point towards the centre.
    let pinhole = camera.pinhole(0.25 / 0.8, 0.15 / 0.8);
    assert!(m.u < pinhole.0 && m.v < pinhole.1);
    assert!(image.get_pixel(m.u.round() as u32, m.v.round() as u32)[0] > 180);
}

/// A bitmap printed as a square: rendered tilted, then every cell read back
/// at its centre through the homography of the true corners must show the
/// bitmap's ink (a 10x10 checkerboard with a random-looking pattern, so a
/// flipped or rotated square would fail).
#[test]
fn printed_square_round_trips_through_its_true_corners() {
    use whycode::math::Homography;
    use whycode::simulate::PrintedSquare;
    let cells = 10u32;
    let ink = |col: u32, row: u32| (col * 7 + row * 3 + col * row) % 5 < 2;
    let bitmap = image::GrayImage::from_fn(cells, cells, |c, r| {
        image::Luma([if ink(c, r) { 0 } else { 255 }])
    });
    let camera = Camera::ideal(640, 480, 60.0);
    let mut scene = Scene::new(camera);
    let placement = Placement::viewed(Vector3::new(0.02, -0.01, 0.4), 0.5, -0.3, 0.7);
    let mut square = PrintedSquare::new(bitmap, 80.0, 42, placement);
    square.card_half_mm = 50.0;
    scene.objects.push(SceneObject::Square(square));
    let (image, truth) = render(&scene);
    assert_eq!(truth.squares.len(), 1);
    let t = &truth.squares[0];
    assert!(t.visible && t.id == 42);
    // Corner order: top-left, top-right, bottom-right, bottom-left of the bitmap.
    let unit = [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)];
    let pairs: Vec<_> = unit
        .iter()
        .zip(&t.corners)
        .map(|(&p, c)| (p, (c[0], c[1])))
        .collect();
    let h = Homography::fit(&pairs).expect("four corners");
    let mut wrong = Vec::new();
    for row in 0..cells {
        for col in 0..cells {
            let x = (f64::from(col) + 0.5) / f64::from(cells);
            let y = (f64::from(row) + 0.5) / f64::from(cells);
            let (u, v) = h.apply(x, y).expect("in front");
            let grey = image.get_pixel(u.round() as u32, v.round() as u32).0[0];
            if (grey < 128) != ink(col, row) {
                wrong.push((col, row, grey));
            }
        }
    }
    assert!(wrong.is_empty(), "cells read back wrong: {wrong:?}");
    // The projected centre is the centre of the corners' homography.
    let (cu, cv) = h.apply(0.5, 0.5).unwrap();
    assert!((cu - t.u).abs() < 1e-6 && (cv - t.v).abs() < 1e-6);
}
