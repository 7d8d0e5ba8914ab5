//! Arena views: a 2 m × 1.5 m floor seen from 2.5 m above by a 1920×1080
//! camera with a strongly distorting lens (k1 = −0.26), four corner
//! markers and robots' markers scattered over it at known places and
//! headings, as the arena round trip and `examples/arena_bar` measure them.

use image::GrayImage;
use nalgebra::{Matrix3, Rotation3, Vector3};
use whycode::camera::Camera;
use whycode::family::Family;
use whycode::geometry::Marker;
use whycode::math::Pcg32;
use whycode::simulate::{self, Background, LooseMarker, Placement, Scene, SceneObject};

/// The rectangle of corner markers, metres along x and y.
pub const SIZE_M: [f64; 2] = [2.0, 1.5];
/// The corners' IDs: origin, +x corner, far corner, +y corner.
pub const CORNER_IDS: [u32; 4] = [1, 2, 3, 4];
/// Corner markers' diameter, mm.
pub const CORNER_DIAMETER_MM: f64 = 120.0;
/// Robots' markers' diameter, mm.
pub const ROBOT_DIAMETER_MM: f64 = 80.0;

/// The camera: 1920×1080, about 72° across (fx 1500 with the barrel
/// distortion), k1 = −0.26: the arena fills 1150 × 890 pixels of it.
pub fn lens() -> Camera {
    Camera {
        fx: 1500.0,
        fy: 1501.3,
        cx: 962.4,
        cy: 537.3,
        distortion: [-0.26, 0.085, 0.0007, -0.0004, -0.012],
        width: 1920,
        height: 1080,
    }
}

/// The floor's pose in the camera frame (floor → camera rotation, floor
/// origin in the camera frame): the camera 2.5 m above a point near the
/// arena's middle, looking down, tilted 8° about the arena's y and turned
/// 2° about the vertical so that nothing lines up with the image's axes.
pub fn floor_pose() -> (Matrix3<f64>, Vector3<f64>) {
    let eye = Vector3::new(1.1, 0.75, 2.5);
    // Camera axes in the floor frame looking straight down, image x along
    // the floor's +x: x = +x, y = −y, z = −z.
    let down = Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0));
    let camera_to_floor = Rotation3::from_axis_angle(&Vector3::z_axis(), 2f64.to_radians())
        * Rotation3::from_axis_angle(&Vector3::y_axis(), 8f64.to_radians());
    let camera_to_floor = camera_to_floor.matrix() * down;
    let rotation = camera_to_floor.transpose();
    (rotation, -(rotation * eye))
}

/// One marker on the arena: its ID, where it lies (metres, floor frame;
/// z its height) and its heading (its +x from the floor's +x,
/// counter-clockwise, radians).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Robot {
    /// Family ID.
    pub id: u32,
    /// Position of the marker's centre in the floor frame, metres.
    pub position: Vector3<f64>,
    /// Heading, radians.
    pub yaw: f64,
}

/// `count` robots (IDs 5, 6, ...) at seeded places inside the arena, at
/// least 0.25 m apart and from the corners, headings at random, markers
/// `height` metres above the floor.
pub fn robots(count: usize, height: f64, seed: u64) -> Vec<Robot> {
    let mut rng = Pcg32::new(seed, 44);
    let mut out: Vec<Robot> = Vec::new();
    let corners = [
        (0.0, 0.0),
        (SIZE_M[0], 0.0),
        (SIZE_M[0], SIZE_M[1]),
        (0.0, SIZE_M[1]),
    ];
    let mut attempts = 0;
    while out.len() < count && attempts < 100_000 {
        attempts += 1;
        let x = rng.range(0.1, SIZE_M[0] - 0.1);
        let y = rng.range(0.1, SIZE_M[1] - 0.1);
        let clear = out
            .iter()
            .map(|r| (r.position.x, r.position.y))
            .chain(corners)
            .all(|(px, py)| (px - x).hypot(py - y) > 0.25);
        if clear {
            out.push(Robot {
                id: 5 + out.len() as u32,
                position: Vector3::new(x, y, height),
                yaw: rng.range(-std::f64::consts::PI, std::f64::consts::PI),
            });
        }
    }
    out
}

/// The corner markers, lying on the floor at the rectangle's corners.
pub fn corners() -> Vec<Robot> {
    let [w, h] = SIZE_M;
    [(0.0, 0.0), (w, 0.0), (w, h), (0.0, h)]
        .iter()
        .zip(CORNER_IDS)
        .zip([0.3, -1.2, 2.5, 0.9])
        .map(|((&(x, y), id), yaw)| Robot {
            id,
            position: Vector3::new(x, y, 0.0),
            yaw,
        })
        .collect()
}

/// The markers' family: 8 bits, distance 2 (`whycode detect`'s default).
pub fn family() -> Family {
    Family::generate(8, 2).expect("8 bits, distance 2")
}

/// The arena seen by `camera` from [`floor_pose`]: the corner markers
/// (120 mm) and `robots` (80 mm) on a grey floor, light falling off
/// across the frame, a slightly soft lens, sensor noise.
pub fn view(camera: &Camera, robots: &[Robot], seed: u64) -> GrayImage {
    let family = family();
    let (rotation, translation) = floor_pose();
    let place = |r: &Robot, diameter_mm: f64| {
        let marker = Marker::whycode(
            family.bits(),
            family.code(r.id).expect("IDs in the family"),
            diameter_mm,
        );
        let turn = Rotation3::from_axis_angle(&Vector3::z_axis(), r.yaw);
        let placement = Placement::new(
            rotation * r.position + translation,
            rotation * turn.matrix(),
        );
        SceneObject::Marker(LooseMarker::new(marker, r.id, placement))
    };
    let mut scene = Scene::new(*camera);
    scene.objects = corners()
        .iter()
        .map(|c| place(c, CORNER_DIAMETER_MM))
        .chain(robots.iter().map(|r| place(r, ROBOT_DIAMETER_MM)))
        .collect();
    scene.background = Background::Uniform(0.35);
    scene.gradient = 1.4;
    scene.gradient_angle = 0.5;
    scene.focus_blur_px = 0.6;
    scene.noise = 1.5;
    scene.seed = seed;
    simulate::render(&scene).0
}
