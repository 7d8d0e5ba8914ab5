//! Pose from synthetic projections of circles with known ground truth:
//! project the marker's outer and inner circles through a camera, fit image
//! ellipses to the projected points, and check that the recovered pose
//! matches the truth.

use nalgebra::{Matrix3, Rotation3, Unit, Vector3};
use whycode::camera::Camera;
use whycode::geometry::{RING_INNER_RATIO, WHYCODE_WHITE_RATIO, WHYCON_WHITE_RATIO};
use whycode::math::Ellipse;
use whycode::pose::{
    choose_by_circle_points, choose_by_inner_circle, choose_by_radial_points, circle_poses,
    circle_poses_from_points, estimate_pose, full_pose, full_pose_from_yaw, project_circle,
    project_marker_point, projected_center, reprojection_rms, CirclePose, Pose,
};

/// Default marker of the reference ROS tools: 122 mm outer diameter.
const RADIUS: f64 = 0.061;
fn distorted_640() -> Camera {
    Camera {
        fx: 554.0,
        fy: 556.0,
        cx: 322.3,
        cy: 236.8,
        distortion: [-0.21, 0.07, 0.0009, -0.0006, -0.01],
        width: 640,
        height: 480,
    }
}

/// A marker at `distance` along the ray through normalised image point
/// (dir_x, dir_y), its normal tilted by `tilt_deg` away from facing the
/// camera about an in-image axis at `tilt_axis_deg`, and spun by `yaw_deg`
/// about its own normal.
fn marker_pose(
    distance: f64,
    (dir_x, dir_y): (f64, f64),
    tilt_deg: f64,
    tilt_axis_deg: f64,
    yaw_deg: f64,
) -> Pose {
    let position = Vector3::new(dir_x, dir_y, 1.0).normalize() * distance;
    let face_on = Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0));
    let spin = Rotation3::from_axis_angle(&Vector3::z_axis(), yaw_deg.to_radians());
    let axis = Unit::new_normalize(Vector3::new(
        tilt_axis_deg.to_radians().cos(),
        tilt_axis_deg.to_radians().sin(),
        0.0,
    ));
    let tilt = Rotation3::from_axis_angle(&axis, tilt_deg.to_radians());
    // Tilt relative to the viewing ray, not the optical axis, so `tilt_deg`
    // is the angle between the normal and the line of sight.
    let towards_ray =
        Rotation3::rotation_between(&Vector3::z(), &position).unwrap_or_else(Rotation3::identity);
    Pose::new(
        position,
        *towards_ray.matrix() * *tilt.matrix() * face_on * *spin.matrix(),
    )
}

fn circle_pixels(camera: &Camera, pose: &Pose, radius: f64, n: usize) -> Vec<(f64, f64)> {
    (0..n)
        .map(|i| {
            let t = std::f64::consts::TAU * i as f64 / n as f64;
            project_marker_point(camera, pose, radius * t.cos(), radius * t.sin())
                .expect("marker in front of camera")
        })
        .collect()
}

struct Outcome {
    normal_error_deg: f64,
    position_error_rel: f64,
    chosen_correct: bool,
    margin_px: f64,
    rotation_error_deg: f64,
}

fn recover(camera: &Camera, truth: &Pose) -> Outcome {
    let outer = Ellipse::fit(&circle_pixels(camera, truth, RADIUS, 64)).unwrap();
    let inner = Ellipse::fit(&circle_pixels(
        camera,
        truth,
        WHYCON_WHITE_RATIO * RADIUS,
        64,
    ))
    .unwrap();
    let candidates = circle_poses(camera, &outer, RADIUS);
    let errors = candidates.map(|c| {
        (
            c.normal.angle(&truth.normal()).to_degrees(),
            (c.center - truth.position).norm() / truth.position.norm(),
        )
    });
    let best = if errors[0].0 <= errors[1].0 { 0 } else { 1 };
    let (chosen, margin_px) =
        choose_by_inner_circle(camera, &candidates, &inner, WHYCON_WHITE_RATIO, RADIUS);
    // When both candidates agree to within the accuracy asked for, either
    // choice is right.
    let both_fine = errors.iter().all(|e| e.0 < 0.5);
    let x_axis_pixel =
        project_marker_point(camera, truth, WHYCODE_WHITE_RATIO * RADIUS, 0.0).unwrap();
    let pose = full_pose(camera, &candidates[best], x_axis_pixel);
    Outcome {
        normal_error_deg: errors[best].0,
        position_error_rel: errors[best].1,
        chosen_correct: chosen == best || both_fine,
        margin_px,
        rotation_error_deg: pose.rotation_angle_to(truth).to_degrees(),
    }
}

fn check_grid(camera: &Camera, distances: &[f64], label: &str) {
    let mut worst_normal: f64 = 0.0;
    let mut worst_position: f64 = 0.0;
    let mut worst_rotation: f64 = 0.0;
    let mut smallest_margin = f64::INFINITY;
    for &distance in distances {
        for tilt in [10.0, 25.0, 40.0, 55.0, 70.0] {
            for (k, direction) in [(0.0, 0.0), (0.25, -0.15), (-0.3, 0.2)]
                .into_iter()
                .enumerate()
            {
                let axis = 37.0 + 71.0 * k as f64 + tilt;
                let truth = marker_pose(distance, direction, tilt, axis, 15.0 + tilt);
                let o = recover(camera, &truth);
                let case = format!("{label}: d={distance} tilt={tilt} dir={direction:?}");
                assert!(
                    o.normal_error_deg < 0.5,
                    "{case}: normal off by {}°",
                    o.normal_error_deg
                );
                assert!(
                    o.position_error_rel < 0.005,
                    "{case}: position off by {}",
                    o.position_error_rel
                );
                assert!(
                    o.chosen_correct,
                    "{case}: wrong candidate (margin {} px)",
                    o.margin_px
                );
                assert!(
                    o.rotation_error_deg < 0.5,
                    "{case}: rotation off by {}°",
                    o.rotation_error_deg
                );
                worst_normal = worst_normal.max(o.normal_error_deg);
                worst_position = worst_position.max(o.position_error_rel);
                worst_rotation = worst_rotation.max(o.rotation_error_deg);
                smallest_margin = smallest_margin.min(o.margin_px);
            }
        }
    }
    println!(
        "{label}: worst normal {worst_normal:.2e}°, position {worst_position:.2e} rel, \
         rotation {worst_rotation:.2e}°, smallest ambiguity margin {smallest_margin:.3} px"
    );
}

#[test]
fn recovers_pose_with_ideal_cameras() {
    check_grid(
        &Camera::ideal(640, 480, 60.0),
        &[0.5, 1.0, 2.0, 3.0],
        "640x480",
    );
    check_grid(
        &Camera::ideal(1920, 1080, 60.0),
        &[0.5, 1.5, 3.0],
        "1920x1080",
    );
}

#[test]
fn recovers_pose_with_lens_distortion() {
    check_grid(&distorted_640(), &[0.5, 1.0, 2.0, 3.0], "640x480 distorted");
}

#[test]
fn exact_boundary_points_give_exact_pose_under_distortion() {
    let camera = distorted_640();
    let truth = marker_pose(0.8, (-0.45, 0.3), 50.0, 120.0, 10.0);
    let points = circle_pixels(&camera, &truth, RADIUS, 40);
    let candidates = circle_poses_from_points(&camera, &points, RADIUS).unwrap();
    let best = candidates
        .iter()
        .map(|c| c.normal.angle(&truth.normal()))
        .fold(f64::INFINITY, f64::min);
    assert!(best < 1e-7, "{best}");
    let matching = candidates
        .iter()
        .find(|c| c.normal.angle(&truth.normal()) < 1e-7)
        .unwrap();
    assert!((matching.center - truth.position).norm() < 1e-8);
}

#[test]
fn face_on_and_near_face_on_are_finite() {
    let camera = Camera::ideal(640, 480, 60.0);
    for tilt in [0.0, 1e-9, 1e-6, 0.01, 0.5] {
        for direction in [(0.0, 0.0), (0.3, -0.2)] {
            let truth = marker_pose(1.2, direction, tilt, 30.0, 0.0);
            let outer = Ellipse::fit(&circle_pixels(&camera, &truth, RADIUS, 64)).unwrap();
            let candidates = circle_poses(&camera, &outer, RADIUS);
            for c in &candidates {
                assert!(c
                    .center
                    .iter()
                    .chain(c.normal.iter())
                    .all(|x| x.is_finite()));
                assert!(c.normal.dot(&c.center) < 0.0 && c.center.z > 0.0);
            }
            let best = candidates
                .iter()
                .map(|c| c.normal.angle(&truth.normal()).to_degrees())
                .fold(f64::INFINITY, f64::min);
            assert!(best < 0.5, "tilt {tilt}: {best}°");
            let inner = Ellipse::fit(&circle_pixels(
                &camera,
                &truth,
                WHYCON_WHITE_RATIO * RADIUS,
                64,
            ))
            .unwrap();
            let (chosen, margin) =
                choose_by_inner_circle(&camera, &candidates, &inner, WHYCON_WHITE_RATIO, RADIUS);
            assert!(chosen < 2 && margin.is_finite());
            let x_pixel = project_marker_point(&camera, &truth, RADIUS, 0.0).unwrap();
            let pose = full_pose(&camera, &candidates[chosen], x_pixel);
            assert!(pose.quaternion.iter().all(|q| q.is_finite()));
            assert!(pose.rotation_angle_to(&truth).to_degrees() < 0.5);
        }
    }
    // An exact circle as the image ellipse, centred on the principal point.
    let circle = Ellipse {
        u: camera.cx,
        v: camera.cy,
        semi_major: 20.0,
        semi_minor: 20.0,
        angle: 0.0,
    };
    for c in circle_poses(&camera, &circle, RADIUS) {
        assert!((c.normal - Vector3::new(0.0, 0.0, -1.0)).norm() < 1e-9);
        assert!(c.center.x.abs() < 1e-9 && c.center.y.abs() < 1e-9);
        // radius / distance = 20 px / f.
        assert!((c.center.z - RADIUS * camera.fx / 20.0).abs() < 1e-9);
    }
}

#[test]
fn face_on_upright_marker_has_the_conventional_rotation() {
    let camera = Camera::ideal(1280, 720, 60.0);
    let truth = marker_pose(1.0, (0.0, 0.0), 0.0, 0.0, 0.0);
    assert!(
        (truth.rotation - Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0))).norm() < 1e-12
    );
    // Marker +x is image +u, marker +y is image -v.
    let (u0, v0) = project_marker_point(&camera, &truth, 0.0, 0.0).unwrap();
    let (ux, vx) = project_marker_point(&camera, &truth, 0.05, 0.0).unwrap();
    let (uy, vy) = project_marker_point(&camera, &truth, 0.0, 0.05).unwrap();
    assert!(ux > u0 && (vx - v0).abs() < 1e-9);
    assert!(vy < v0 && (uy - u0).abs() < 1e-9);
    assert!(truth.image_yaw(&camera).unwrap().abs() < 1e-9);
    let circle = CirclePose {
        center: truth.position,
        normal: truth.normal(),
    };
    let pose = full_pose(&camera, &circle, (ux, vx));
    assert!(pose.rotation_angle_to(&truth) < 1e-9);
    let [x, y, z, w] = pose.quaternion;
    // diag(1, -1, -1) is a half turn about x.
    assert!((x.abs() - 1.0).abs() < 1e-9 && y.abs() < 1e-9 && z.abs() < 1e-9 && w.abs() < 1e-9);
}

#[test]
fn true_centre_differs_from_ellipse_centre_under_perspective() {
    let camera = Camera::ideal(1920, 1080, 60.0);
    let truth = marker_pose(0.4, (0.35, 0.2), 60.0, 20.0, 0.0);
    let outer = Ellipse::fit(&circle_pixels(&camera, &truth, RADIUS, 64)).unwrap();
    let true_centre = camera.project(&truth.position).unwrap();
    let candidates = circle_poses(&camera, &outer, RADIUS);
    let best = candidates
        .iter()
        .min_by(|a, b| {
            a.normal
                .angle(&truth.normal())
                .total_cmp(&b.normal.angle(&truth.normal()))
        })
        .unwrap();
    let predicted = projected_center(&camera, best).unwrap();
    let offset = (outer.u - true_centre.0).hypot(outer.v - true_centre.1);
    assert!(
        offset > 1.0,
        "ellipse centre is {offset} px from the true centre"
    );
    assert!((predicted.0 - true_centre.0).hypot(predicted.1 - true_centre.1) < 1e-6);
}

#[test]
fn ambiguity_resolved_from_points_on_the_inner_circle() {
    let camera = Camera::ideal(1280, 720, 60.0);
    for tilt in [20.0, 45.0, 70.0] {
        let truth = marker_pose(0.7, (0.2, 0.1), tilt, 100.0, 0.0);
        let outer = Ellipse::fit(&circle_pixels(&camera, &truth, RADIUS, 64)).unwrap();
        let candidates = circle_poses(&camera, &outer, RADIUS);
        let right = if candidates[0].normal.angle(&truth.normal())
            < candidates[1].normal.angle(&truth.normal())
        {
            0
        } else {
            1
        };
        // Edge points of the code ring's inner border, 24 of them.
        let ring_edge = circle_pixels(&camera, &truth, RING_INNER_RATIO * RADIUS, 24);
        let (chosen, margin) =
            choose_by_circle_points(&camera, &candidates, &ring_edge, RING_INNER_RATIO * RADIUS);
        assert_eq!(chosen, right, "tilt {tilt}");
        assert!(margin > 0.0);
    }
}

#[test]
fn yaw_round_trip_and_spin() {
    for camera in [Camera::ideal(1280, 720, 60.0), distorted_640()] {
        for (tilt, yaw) in [(0.0, 0.0), (30.0, 100.0), (65.0, -140.0)] {
            let truth = marker_pose(0.9, (0.15, -0.1), tilt, 200.0, yaw);
            let image_yaw = truth.image_yaw(&camera).unwrap();
            let pose = full_pose_from_yaw(&camera, &truth.circle(), image_yaw);
            let error = pose.rotation_angle_to(&truth).to_degrees();
            assert!(error < 1e-3, "tilt {tilt} yaw {yaw}: {error}°");

            // Spinning a provisional pose by the marker angle of the true +x
            // axis recovers the truth.
            let provisional = full_pose_from_yaw(&camera, &truth.circle(), 0.3);
            let x_true = provisional.rotation.transpose() * truth.rotation.column(0);
            let spun = provisional.spun(x_true.y.atan2(x_true.x));
            assert!(spun.rotation_angle_to(&truth) < 1e-9);
        }
    }
}

#[test]
fn pose_helpers_are_consistent() {
    let camera = distorted_640();
    let truth = marker_pose(1.3, (-0.2, 0.25), 35.0, 10.0, 77.0);
    let q = truth.quaternion;
    assert!(q[3] >= 0.0 && (q.iter().map(|x| x * x).sum::<f64>() - 1.0).abs() < 1e-12);
    let from_quaternion = nalgebra::UnitQuaternion::from_quaternion(nalgebra::Quaternion::new(
        q[3], q[0], q[1], q[2],
    ));
    assert!((from_quaternion.to_rotation_matrix().matrix() - truth.rotation).norm() < 1e-12);
    let (roll, pitch, yaw) = truth.roll_pitch_yaw();
    let rebuilt = Rotation3::from_euler_angles(roll, pitch, yaw);
    assert!((rebuilt.matrix() - truth.rotation).norm() < 1e-12);

    let marker_points = [(0.0, 0.0), (0.03, 0.01), (-0.05, 0.02), (0.01, -0.06)];
    let matches: Vec<_> = marker_points
        .iter()
        .map(|&(x, y)| ((x, y), project_marker_point(&camera, &truth, x, y).unwrap()))
        .collect();
    assert!(reprojection_rms(&camera, &truth, &matches).unwrap() < 1e-9);
    let off = truth.spun(0.05);
    assert!(reprojection_rms(&camera, &off, &matches).unwrap() > 0.5);
    assert!(reprojection_rms(&camera, &truth, &[]).is_none());
}

/// Deterministic normal noise (Box-Muller over a 64-bit LCG).
struct Noise(u64);

impl Noise {
    fn uniform(&mut self) -> f64 {
        self.0 = self
            .0
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 + 0.5) / (1u64 << 53) as f64
    }

    fn gauss(&mut self) -> f64 {
        let (a, b) = (self.uniform(), self.uniform());
        (-2.0 * a.ln()).sqrt() * (std::f64::consts::TAU * b).cos()
    }
}

#[test]
fn noisy_ellipses_still_give_accurate_pose_and_the_right_candidate() {
    // 0.1 px boundary noise on 64 points per ellipse, 640x480 at 60° fov,
    // 122 mm marker at 1 m (outer semi-major ~35 px).
    let camera = Camera::ideal(640, 480, 60.0);
    let mut noise = Noise(42);
    for tilt in [25.0, 45.0, 65.0] {
        let truth = marker_pose(1.0, (0.2, 0.1), tilt, 60.0, 0.0);
        let trials = 40;
        let (mut wrong, mut error_sum) = (0, 0.0);
        for _ in 0..trials {
            let mut jitter = |points: Vec<(f64, f64)>| -> Vec<(f64, f64)> {
                points
                    .into_iter()
                    .map(|(u, v)| (u + 0.1 * noise.gauss(), v + 0.1 * noise.gauss()))
                    .collect()
            };
            let outer = Ellipse::fit(&jitter(circle_pixels(&camera, &truth, RADIUS, 64)));
            let inner = Ellipse::fit(&jitter(circle_pixels(
                &camera,
                &truth,
                WHYCON_WHITE_RATIO * RADIUS,
                64,
            )));
            let candidates = circle_poses(&camera, &outer.unwrap(), RADIUS);
            let (chosen, _) = choose_by_inner_circle(
                &camera,
                &candidates,
                &inner.unwrap(),
                WHYCON_WHITE_RATIO,
                RADIUS,
            );
            let errors = candidates.map(|c| c.normal.angle(&truth.normal()));
            if errors[chosen] > errors[1 - chosen] {
                wrong += 1;
            }
            error_sum += errors[chosen].to_degrees();
        }
        let mean = error_sum / trials as f64;
        assert_eq!(wrong, 0, "tilt {tilt}");
        assert!(mean < 0.5, "tilt {tilt}: mean normal error {mean}°");
    }
}

#[test]
fn projected_circle_matches_projected_points() {
    for camera in [Camera::ideal(1280, 720, 60.0), distorted_640()] {
        let truth = marker_pose(0.6, (0.3, -0.2), 55.0, 80.0, 0.0);
        let direct = project_circle(&camera, &truth.circle(), RADIUS).unwrap();
        let fitted = Ellipse::fit(&circle_pixels(&camera, &truth, RADIUS, 64)).unwrap();
        assert!((direct.u - fitted.u).hypot(direct.v - fitted.v) < 1e-3);
        assert!((direct.semi_major - fitted.semi_major).abs() < 1e-3);
        assert!((direct.semi_minor - fitted.semi_minor).abs() < 1e-3);
        assert!((direct.angle - fitted.angle).abs() < 1e-4);
    }
    // A circle reaching behind the camera has no image ellipse.
    let camera = Camera::ideal(640, 480, 60.0);
    let grazing = CirclePose {
        center: Vector3::new(0.0, 0.0, 0.05),
        normal: Vector3::new(0.0, -1.0, 0.0),
    };
    assert!(project_circle(&camera, &grazing, 0.1).is_none());
}

#[test]
fn ambiguity_resolved_from_partial_ring_borders() {
    // A WhyCode ring shows its outer border (the white disc's edge) only beside white
    // sectors and its inner border only beside black ones.
    let camera = distorted_640();
    let truth = marker_pose(0.9, (-0.1, 0.15), 40.0, 300.0, 0.0);
    let outer = Ellipse::fit(&circle_pixels(&camera, &truth, RADIUS, 64)).unwrap();
    let candidates = circle_poses(&camera, &outer, RADIUS);
    let right = if candidates[0].normal.angle(&truth.normal())
        < candidates[1].normal.angle(&truth.normal())
    {
        0
    } else {
        1
    };
    let sectors = 16;
    let points: Vec<_> = (0..sectors * 4)
        .map(|i| {
            let theta = std::f64::consts::TAU * i as f64 / (sectors * 4) as f64;
            let white = (i / 4) % 2 == 0;
            let radius = if white {
                WHYCODE_WHITE_RATIO
            } else {
                RING_INNER_RATIO
            } * RADIUS;
            let pixel =
                project_marker_point(&camera, &truth, radius * theta.cos(), radius * theta.sin())
                    .unwrap();
            (pixel, radius)
        })
        .collect();
    let (chosen, margin) = choose_by_radial_points(&camera, &candidates, &points);
    assert_eq!(chosen, right);
    assert!(margin > 1e-4, "margin {margin} m");
}

#[test]
fn estimate_pose_in_one_call() {
    let camera = distorted_640();
    let truth = marker_pose(0.8, (0.1, -0.2), 45.0, 30.0, 120.0);
    let outer = Ellipse::fit(&circle_pixels(&camera, &truth, RADIUS, 64)).unwrap();
    let inner = Ellipse::fit(&circle_pixels(
        &camera,
        &truth,
        WHYCON_WHITE_RATIO * RADIUS,
        64,
    ))
    .unwrap();
    let yaw = truth.image_yaw(&camera).unwrap();
    let estimate = estimate_pose(
        &camera,
        &outer,
        RADIUS,
        Some((&inner, WHYCON_WHITE_RATIO)),
        Some(yaw),
    )
    .unwrap();
    assert!(estimate.pose.rotation_angle_to(&truth).to_degrees() < 0.2);
    assert!((estimate.pose.position - truth.position).norm() < 0.002 * truth.position.norm());
    assert!(estimate.ambiguity_margin_px > 0.5);
    // The alternative is the mirror solution: the normal is off by about
    // twice the view angle.
    let alternative_error = estimate
        .alternative
        .normal()
        .angle(&truth.normal())
        .to_degrees();
    assert!(
        (alternative_error - 90.0).abs() < 5.0,
        "{alternative_error}"
    );
    let (u, v) = camera.project(&truth.position).unwrap();
    assert!((estimate.center_px.0 - u).hypot(estimate.center_px.1 - v) < 0.05);

    // Legacy marker without yaw: normal right, +x towards image +u.
    let legacy = estimate_pose(
        &camera,
        &outer,
        RADIUS,
        Some((&inner, WHYCON_WHITE_RATIO)),
        None,
    )
    .unwrap();
    assert!(legacy.pose.normal().angle(&truth.normal()).to_degrees() < 0.2);
    assert!(legacy.pose.image_yaw(&camera).unwrap().abs() < 1e-5);

    let broken = Ellipse {
        semi_minor: 0.0,
        ..outer
    };
    assert!(estimate_pose(&camera, &broken, RADIUS, None, None).is_none());
}

#[test]
fn ambiguity_margin_follows_the_documented_rule_of_thumb() {
    let camera = Camera::ideal(640, 480, 60.0);
    for distance in [1.0, 2.0, 3.0] {
        for tilt in [10.0f64, 25.0, 40.0, 55.0, 70.0] {
            let truth = marker_pose(distance, (0.2, 0.1), tilt, 60.0, 0.0);
            let outer = Ellipse::fit(&circle_pixels(&camera, &truth, RADIUS, 64)).unwrap();
            let inner = Ellipse::fit(&circle_pixels(
                &camera,
                &truth,
                WHYCON_WHITE_RATIO * RADIUS,
                64,
            ))
            .unwrap();
            let candidates = circle_poses(&camera, &outer, RADIUS);
            let (_, margin) =
                choose_by_inner_circle(&camera, &candidates, &inner, WHYCON_WHITE_RATIO, RADIUS);
            let rule = (1.0 - WHYCON_WHITE_RATIO * WHYCON_WHITE_RATIO) * outer.semi_major.powi(2)
                / camera.fx
                * (2.0 * tilt.to_radians()).sin();
            let ratio = margin / rule;
            assert!(
                (0.75..1.33).contains(&ratio),
                "d={distance} tilt={tilt}: {margin} vs {rule}"
            );
        }
    }
}
