//! Cost of the pose stage per marker: `cargo bench --bench pose`.

use divan::black_box;
use nalgebra::{Matrix3, Vector3};
use whycode::camera::Camera;
use whycode::geometry::WHYCON_WHITE_RATIO;
use whycode::math::Ellipse;
use whycode::pose::{choose_by_inner_circle, circle_poses, full_pose, project_marker_point, Pose};

fn main() {
    divan::main();
}

const RADIUS: f64 = 0.061;
const INNER_RATIO: f64 = WHYCON_WHITE_RATIO;

fn distorted() -> Camera {
    Camera {
        distortion: [-0.21, 0.07, 0.0009, -0.0006, -0.01],
        ..Camera::ideal(640, 480, 60.0)
    }
}

fn tilted_marker() -> Pose {
    let (s, c) = 40f64.to_radians().sin_cos();
    // Face-on diag(1, -1, -1), then tilted 40° about the camera x axis.
    let rotation = Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -s, 0.0, s, c)
        * Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0));
    Pose::new(Vector3::new(0.2, -0.1, 1.2), rotation)
}

fn ellipse(camera: &Camera, pose: &Pose, radius: f64) -> Ellipse {
    let points: Vec<_> = (0..64)
        .map(|i| {
            let t = std::f64::consts::TAU * i as f64 / 64.0;
            project_marker_point(camera, pose, radius * t.cos(), radius * t.sin()).unwrap()
        })
        .collect();
    Ellipse::fit(&points).unwrap()
}

#[divan::bench(args = [false, true])]
fn circle_poses_from_ellipse(bencher: divan::Bencher, with_distortion: bool) {
    let camera = if with_distortion {
        distorted()
    } else {
        Camera::ideal(640, 480, 60.0)
    };
    let outer = ellipse(&camera, &tilted_marker(), RADIUS);
    bencher.bench(|| circle_poses(black_box(&camera), black_box(&outer), RADIUS));
}

#[divan::bench(args = [false, true])]
fn full_pipeline_with_ambiguity_and_yaw(bencher: divan::Bencher, with_distortion: bool) {
    let camera = if with_distortion {
        distorted()
    } else {
        Camera::ideal(640, 480, 60.0)
    };
    let truth = tilted_marker();
    let outer = ellipse(&camera, &truth, RADIUS);
    let inner = ellipse(&camera, &truth, INNER_RATIO * RADIUS);
    let x_pixel = project_marker_point(&camera, &truth, 0.03, 0.0).unwrap();
    bencher.bench(|| {
        let candidates = circle_poses(&camera, black_box(&outer), RADIUS);
        let (chosen, _) =
            choose_by_inner_circle(&camera, &candidates, black_box(&inner), INNER_RATIO, RADIUS);
        full_pose(&camera, &candidates[chosen], x_pixel)
    });
}

#[divan::bench]
fn ellipse_fit_64_points(bencher: divan::Bencher) {
    let camera = Camera::ideal(640, 480, 60.0);
    let truth = tilted_marker();
    let points: Vec<_> = (0..64)
        .map(|i| {
            let t = std::f64::consts::TAU * i as f64 / 64.0;
            project_marker_point(&camera, &truth, RADIUS * t.cos(), RADIUS * t.sin()).unwrap()
        })
        .collect();
    bencher.bench(|| Ellipse::fit(black_box(&points)));
}

#[divan::bench]
fn undistort_corner_pixel(bencher: divan::Bencher) {
    let camera = distorted();
    bencher.bench(|| camera.undistort(black_box(3.0), black_box(470.0)));
}
