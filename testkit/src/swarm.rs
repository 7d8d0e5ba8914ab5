//! The scene of the sample recordings in `samples/` (written by
//! `examples/make_samples.rs`, run on by the README's recording examples):
//! five small robots, each with a WhyCode marker of the default family on
//! top, driving arcs across a grey floor, filmed by a camera 1.2 m up that
//! looks down and ahead at 30° from the vertical. The markers' IDs and
//! size, the camera and the frame rates live here, so the generator and
//! the test that runs the README on the samples agree on them.

use image::GrayImage;
use nalgebra::{Matrix3, Rotation3, Vector3};
use whycode::camera::Camera;
use whycode::family::Family;
use whycode::geometry::Marker;
use whycode::simulate::{self, Background, LooseMarker, Placement, Scene, SceneObject};

/// The robots' marker IDs (8 bits, distance 2), in the order they are drawn.
pub const IDS: [u32; 5] = [2, 5, 7, 11, 14];
/// Every marker's printed diameter, mm.
pub const DIAMETER_MM: f64 = 120.0;
/// Height of the markers above the floor (the robots' tops), metres.
pub const ROBOT_HEIGHT_M: f64 = 0.08;
/// Length of the recordings, seconds.
pub const SECONDS: f64 = 3.0;
/// The video's frame rate.
pub const VIDEO_FPS: u32 = 15;
/// The bag's frame rate: a camera driver throttled for recording, and a
/// bag of JPEG frames small enough for the repository.
pub const BAG_FPS: u32 = 5;
/// The image topic of the bag; its camera_info is on `/camera/camera_info`.
pub const BAG_TOPIC: &str = "/camera/image_raw/compressed";
/// The bag's camera frame.
pub const CAMERA_FRAME: &str = "camera_optical";
/// The bag's first stamp, nanoseconds: a robot's clock, far from zero and
/// not on a round number.
pub const FIRST_STAMP_NS: i64 = 1_717_000_000_250_000_000;
/// The camera's height above the floor, metres.
pub const CAMERA_HEIGHT_M: f64 = 1.2;
/// The camera's view from the vertical, radians (30°).
pub const CAMERA_TILT: f64 = std::f64::consts::FRAC_PI_6;

/// The camera: 640×480, about 63° across, a little barrel distortion.
pub fn camera() -> Camera {
    Camera {
        fx: 520.0,
        fy: 520.0,
        cx: 319.5,
        cy: 239.5,
        distortion: [-0.08, 0.02, 0.0, 0.0, 0.0],
        width: 640,
        height: 480,
    }
}

/// The floor's pose in the camera frame (floor → camera rotation, floor
/// origin in the camera frame). The floor frame has x to the image's
/// right, y away from the camera, z up; its origin is the point the
/// camera looks at.
pub fn floor_pose() -> (Matrix3<f64>, Vector3<f64>) {
    let eye = Vector3::new(0.0, -CAMERA_HEIGHT_M * CAMERA_TILT.tan(), CAMERA_HEIGHT_M);
    // The camera's optical axes in the floor frame: z towards the floor's
    // origin, x along the floor's x, y (image down) completing them.
    let z = (-eye).normalize();
    let x = Vector3::x();
    let y = z.cross(&x);
    let camera_to_floor = Matrix3::from_columns(&[x, y, z]);
    let rotation = camera_to_floor.transpose();
    (rotation, -(rotation * eye))
}

/// Where robot `i` is at `t` seconds: its marker's centre on the floor
/// (metres) and its heading (the marker's +x from the floor's +x,
/// counter-clockwise, radians). Each drives an arc at its own speed,
/// facing the way it goes.
pub fn robot_at(i: usize, t: f64) -> (Vector3<f64>, f64) {
    // (centre x, centre y, radius, turn rate (rad/s, + counter-clockwise), start angle)
    const ARCS: [(f64, f64, f64, f64, f64); 5] = [
        (-0.35, 0.3, 0.25, 0.7, 0.0),
        (0.3, 0.35, 0.3, -0.6, 1.0),
        (0.0, -0.05, 0.3, 0.45, 0.4),
        (-0.45, -0.3, 0.15, -1.0, 0.5),
        (0.4, -0.3, 0.2, 0.8, 3.5),
    ];
    let (cx, cy, r, rate, start) = ARCS[i];
    let angle = start + rate * t;
    let position = Vector3::new(cx + r * angle.cos(), cy + r * angle.sin(), ROBOT_HEIGHT_M);
    let heading = angle + std::f64::consts::FRAC_PI_2 * rate.signum();
    (position, heading)
}

/// The markers' family: 8 bits, distance 2 (`whycode detect`'s default).
pub fn family() -> Family {
    Family::generate(8, 2).expect("8 bits, distance 2")
}

/// The scene at `t` seconds: the robots' markers on their white cards,
/// on a grey floor lit unevenly, a slightly soft lens and sensor noise
/// (seeded by `seed`, so each frame has its own).
pub fn scene(t: f64, seed: u64) -> Scene {
    let family = family();
    let (rotation, translation) = floor_pose();
    let mut scene = Scene::new(camera());
    scene.objects = IDS
        .iter()
        .enumerate()
        .map(|(i, &id)| {
            let (position, heading) = robot_at(i, t);
            let marker = Marker::whycode(
                family.bits(),
                family.code(id).expect("IDs in the family"),
                DIAMETER_MM,
            );
            let turn = Rotation3::from_axis_angle(&Vector3::z_axis(), heading);
            let placement =
                Placement::new(rotation * position + translation, rotation * turn.matrix());
            SceneObject::Marker(LooseMarker::new(marker, id, placement))
        })
        .collect();
    scene.background = Background::Uniform(0.35);
    scene.gradient = 1.4;
    scene.gradient_angle = 0.6;
    scene.focus_blur_px = 0.6;
    scene.noise = 1.5;
    scene.seed = seed;
    scene
}

/// Frame `k` of a recording at `fps`: the picture at `k / fps` seconds.
pub fn frame(k: u32, fps: u32) -> GrayImage {
    let t = f64::from(k) / f64::from(fps);
    simulate::render(&scene(t, u64::from(k) + 1)).0
}

/// The number of frames of a recording at `fps`.
pub fn frames(fps: u32) -> u32 {
    (SECONDS * f64::from(fps)).round() as u32
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every marker stays whole in the picture, and the robots never
    /// drive into each other, over the whole recording.
    #[test]
    fn the_robots_stay_in_view_and_apart() {
        let camera = camera();
        let (rotation, translation) = floor_pose();
        for k in 0..=frames(VIDEO_FPS) {
            let t = f64::from(k) / f64::from(VIDEO_FPS);
            let places: Vec<Vector3<f64>> = (0..IDS.len()).map(|i| robot_at(i, t).0).collect();
            for (i, p) in places.iter().enumerate() {
                let (u, v) = camera
                    .project(&(rotation * p + translation))
                    .expect("in front of the camera");
                let margin = 45.0;
                assert!(
                    (margin..640.0 - margin).contains(&u) && (margin..480.0 - margin).contains(&v),
                    "robot {i} at ({u:.0}, {v:.0}) at {t} s"
                );
                for q in &places[i + 1..] {
                    assert!((p - q).norm() > 0.25, "robots within 25 cm at {t} s");
                }
            }
        }
    }
}
