use nalgebra::Vector3;
use whycode::camera::Camera;
use whycode::detect::{manchester, ring::ImageEllipse, Detector, DetectorConfig};
use whycode::family::Family;
use whycode::geometry::Marker;
use whycode::simulate::{render, LooseMarker, Placement, Scene, SceneObject};
fn main() {
    let camera = Camera::ideal(640, 480, 70.0);
    let family = Family::generate(8, 2).unwrap();
    let placement = Placement::viewed(Vector3::new(0.05, -0.02, 0.6), 0.5, 0.2, 1.0);
    let marker = Marker::whycode(8, family.code(11).unwrap(), 122.0);
    let mut scene = Scene::new(camera);
    scene
        .objects
        .push(SceneObject::Marker(LooseMarker::new(marker, 11, placement)));
    let (image, truth) = render(&scene);
    let mut det = Detector::new(DetectorConfig {
        family: Some(family.clone()),
        report_unreadable: true,
        ..Default::default()
    });
    let found = det.detect(&image);
    println!("{:?}", found);
    let e = truth.markers[0].ellipse.unwrap();
    println!("{:?}", e);
    let d = &found[0];
    let outer = ImageEllipse {
        u: d.u,
        v: d.v,
        semi_major: d.axes[0],
        semi_minor: d.axes[1],
        angle: d.angle,
    };
    println!(
        "{:?}",
        manchester::examine(&image, &outer, 20.0, 200.0, 4..=24)
    );
}
