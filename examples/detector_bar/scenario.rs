//! "The bar": independent scenes from `whycode::simulate` on which the
//! detector is measured against the figures of the original WhyCode
//! detector and of AprilTag (yaw bias, wrong normals, false markers in
//! clutter, dark frames, light gradients with a shadow, motion blur, the
//! smallest readable marker, speed). Shared by `examples/detector_bar.rs`
//! (full sizes, prints a table) and `tests/bar_scenes.rs` (small, asserts).
//!
//! Every scene is seeded; a failing figure can be reproduced from the item,
//! the seed and the parameters printed with it.
#![allow(dead_code)]

use std::collections::HashMap;
use std::f64::consts::PI;

use image::GrayImage;
use nalgebra::Vector3;
use whycode::camera::Camera;
use whycode::detect::{Detection, Detector, DetectorConfig};
use whycode::family::Family;
use whycode::geometry::Marker;
use whycode::simulate::rng::Pcg32;
use whycode::simulate::{
    self, Background, GroundTruth, LooseMarker, MotionBlur, Placement, Scene, SceneObject,
};

pub const DEG: f64 = PI / 180.0;

/// Printed marker diameter used in every scene, metres.
pub const DIAMETER_M: f64 = 0.05;

/// Families by (bits, distance), generated once.
#[derive(Default)]
pub struct Families(HashMap<(u32, u32), Family>);

impl Families {
    pub fn get(&mut self, bits: u32, distance: u32) -> Family {
        self.0
            .entry((bits, distance))
            .or_insert_with(|| Family::generate(bits, distance).expect("family parameters valid"))
            .clone()
    }
}

/// A distortion-free camera with a 60° horizontal field of view.
pub fn camera(width: u32, height: u32) -> Camera {
    Camera::ideal(width, height, 60.0)
}

/// Wraps an angle difference into (-π, π].
pub fn wrap(a: f64) -> f64 {
    let w = a.rem_euclid(2.0 * PI);
    if w > PI {
        w - 2.0 * PI
    } else {
        w
    }
}

/// A marker whose centre projects to (u, v) and which would be
/// `diameter_px` across seen face-on at that depth, turned by tilt, pan and
/// roll (see [`Placement::viewed`]).
pub fn placement_at(
    camera: &Camera,
    (u, v): (f64, f64),
    diameter_px: f64,
    tilt: f64,
    pan: f64,
    roll: f64,
) -> Placement {
    let z = camera.fx * DIAMETER_M / diameter_px;
    let (x, y) = camera.undistort(u, v);
    Placement::viewed(Vector3::new(x * z, y * z, z), tilt, pan, roll)
}

/// How markers are spread over a frame.
#[derive(Debug, Clone, Copy)]
pub struct Spread {
    pub count: usize,
    pub diameter_px: (f64, f64),
    /// Largest tilt and pan, radians (each drawn uniformly in ±max).
    pub max_tilt: f64,
    /// Exact tilt of every marker about a random in-plane axis, radians;
    /// overrides `max_tilt` when set.
    pub fixed_tilt: Option<f64>,
}

/// Markers on a jittered grid over the frame, none overlapping, each with
/// a random in-plane rotation and a random member of `family` (legacy
/// WhyCon markers without a family).
pub fn spread_markers(
    camera: &Camera,
    family: Option<&Family>,
    spread: Spread,
    rng: &mut Pcg32,
) -> Vec<SceneObject> {
    let (w, h) = (f64::from(camera.width), f64::from(camera.height));
    let cols = ((spread.count as f64 * w / h).sqrt().ceil() as usize).max(1);
    let rows = spread.count.div_ceil(cols);
    let (cell_w, cell_h) = (w / cols as f64, h / rows as f64);
    // The card is 1.5 R around the centre: keep 0.8 D (plus a pixel) free.
    let reach = 0.8 * spread.diameter_px.1 + 2.0;
    let mut out = Vec::with_capacity(spread.count);
    for k in 0..spread.count {
        let (col, row) = ((k % cols) as f64, (k / cols) as f64);
        let jitter_u = (cell_w / 2.0 - reach).max(0.0);
        let jitter_v = (cell_h / 2.0 - reach).max(0.0);
        let u = (col + 0.5) * cell_w + rng.range(-jitter_u, jitter_u.max(1e-9));
        let v = (row + 0.5) * cell_h + rng.range(-jitter_v, jitter_v.max(1e-9));
        let d = rng.range(
            spread.diameter_px.0,
            spread.diameter_px.1.max(spread.diameter_px.0 + 1e-9),
        );
        let roll = rng.range(0.0, 2.0 * PI);
        let (tilt, pan) = match spread.fixed_tilt {
            Some(t) => {
                let axis = rng.range(0.0, 2.0 * PI);
                (t * axis.cos(), t * axis.sin())
            }
            None => (
                rng.range(-spread.max_tilt, spread.max_tilt.max(1e-12)),
                rng.range(-spread.max_tilt, spread.max_tilt.max(1e-12)),
            ),
        };
        let placement = placement_at(camera, (u, v), d, tilt, pan, roll);
        let (marker, id) = match family {
            Some(f) => {
                let id = 1 + rng.next_u32() % f.len() as u32;
                let code = f.code(id).expect("id within the family");
                (Marker::whycode(f.bits(), code, DIAMETER_M * 1000.0), id)
            }
            None => (Marker::whycon(DIAMETER_M * 1000.0), 0),
        };
        out.push(SceneObject::Marker(LooseMarker::new(marker, id, placement)));
    }
    out
}

/// A scene with the simulator's defaults and these objects.
pub fn scene(camera: &Camera, objects: Vec<SceneObject>, seed: u64) -> Scene {
    let mut s = Scene::new(*camera);
    s.objects = objects;
    s.seed = seed;
    s
}

/// A detector for `family` (legacy without), with pose.
pub fn detector(family: Option<&Family>, camera: &Camera, tracking: bool) -> Detector {
    Detector::new(DetectorConfig {
        family: family.cloned(),
        camera: Some(*camera),
        diameter_m: Some(DIAMETER_M),
        tracking,
        ..DetectorConfig::default()
    })
}

/// Detections paired with the visible true markers: for each true marker
/// the nearest detection within a quarter diameter (+2 px); detections near
/// no marker at all (visible or not) are false.
pub struct Matched {
    pub pairs: Vec<(usize, Option<usize>)>,
    pub false_detections: Vec<usize>,
}

pub fn match_truth(truth: &GroundTruth, found: &[Detection]) -> Matched {
    let mut used = vec![false; found.len()];
    let mut pairs = Vec::new();
    for (t, m) in truth.markers.iter().enumerate() {
        let radius = 0.25 * m.diameter_px + 2.0;
        let best = found
            .iter()
            .enumerate()
            .filter(|(k, d)| !used[*k] && (d.u - m.u).hypot(d.v - m.v) < radius)
            .min_by(|a, b| {
                let da = (a.1.u - m.u).hypot(a.1.v - m.v);
                let db = (b.1.u - m.u).hypot(b.1.v - m.v);
                da.total_cmp(&db)
            })
            .map(|(k, _)| k);
        if let Some(k) = best {
            used[k] = true;
        }
        if m.visible {
            pairs.push((t, best));
        }
    }
    let false_detections = (0..found.len())
        .filter(|&k| {
            !used[k]
                && !truth
                    .markers
                    .iter()
                    .any(|m| (found[k].u - m.u).hypot(found[k].v - m.v) < 0.6 * m.diameter_px + 2.0)
        })
        .collect();
    Matched {
        pairs,
        false_detections,
    }
}

/// Darkens the image beyond a straight soft-edged line (a cast shadow):
/// pixels on the far side of the line through (u0, v0) with direction
/// `angle` get `factor` of their light, over a `soft` px transition.
pub fn cast_shadow(
    image: &mut GrayImage,
    (u0, v0): (f64, f64),
    angle: f64,
    factor: f64,
    soft: f64,
) {
    let (s, c) = angle.sin_cos();
    for (x, y, p) in image.enumerate_pixels_mut() {
        // Signed distance from the line, positive on the shadow side.
        let d = -(f64::from(x) - u0) * s + (f64::from(y) - v0) * c;
        let t = (d / soft + 0.5).clamp(0.0, 1.0);
        let light = 1.0 - (1.0 - factor) * t;
        p.0[0] = (f64::from(p.0[0]) * light).round().clamp(0.0, 255.0) as u8;
    }
}

/// Running statistics of signed errors.
#[derive(Debug, Clone, Copy, Default)]
pub struct Errors {
    pub n: usize,
    pub sum: f64,
    pub sum_abs: f64,
    pub max_abs: f64,
    /// Where the largest error was: (seed, marker index in the truth).
    pub worst: Option<(u64, usize)>,
}

impl Errors {
    pub fn add(&mut self, e: f64, at: (u64, usize)) {
        self.n += 1;
        self.sum += e;
        self.sum_abs += e.abs();
        if e.abs() >= self.max_abs {
            self.max_abs = e.abs();
            self.worst = Some(at);
        }
    }
    pub fn mean(&self) -> f64 {
        if self.n == 0 {
            f64::NAN
        } else {
            self.sum / self.n as f64
        }
    }
    pub fn mean_abs(&self) -> f64 {
        if self.n == 0 {
            f64::NAN
        } else {
            self.sum_abs / self.n as f64
        }
    }
}

/// What happened to the true markers of a set of scenes.
#[derive(Debug, Clone, Copy, Default)]
pub struct Counts {
    pub markers: usize,
    pub detected: usize,
    pub correct_id: usize,
    /// Detected but ID 0.
    pub unknown_id: usize,
    /// Detected with another member's ID: a guess that went wrong.
    pub wrong_id: usize,
    pub false_detections: usize,
    /// False detections that even carry a member ID.
    pub false_with_id: usize,
    pub frames: usize,
    /// First seed with a missed marker, a wrong ID and a false detection.
    pub first_miss: Option<(u64, usize)>,
    pub first_wrong: Option<(u64, usize)>,
    pub first_false: Option<(u64, (f64, f64))>,
}

impl Counts {
    pub fn add(&mut self, seed: u64, truth: &GroundTruth, found: &[Detection]) {
        let matched = match_truth(truth, found);
        self.frames += 1;
        for &(t, d) in &matched.pairs {
            self.markers += 1;
            let Some(d) = d else {
                self.first_miss.get_or_insert((seed, t));
                continue;
            };
            self.detected += 1;
            let want = truth.markers[t].id;
            let got = found[d].id;
            if got == 0 {
                self.unknown_id += 1;
            } else if got == want {
                self.correct_id += 1;
            } else {
                self.wrong_id += 1;
                self.first_wrong.get_or_insert((seed, t));
            }
        }
        for &k in &matched.false_detections {
            self.false_detections += 1;
            if found[k].id != 0 {
                self.false_with_id += 1;
            }
            self.first_false
                .get_or_insert((seed, (found[k].u, found[k].v)));
        }
    }
    pub fn detection_rate(&self) -> f64 {
        self.detected as f64 / self.markers.max(1) as f64
    }
    pub fn id_rate(&self) -> f64 {
        self.correct_id as f64 / self.markers.max(1) as f64
    }
    pub fn false_per_frame(&self) -> f64 {
        self.false_detections as f64 / self.frames.max(1) as f64
    }
}

/// Renders `scene`, detects with `detector` and adds to `counts`.
pub fn run(
    scene: &Scene,
    detector: &mut Detector,
    counts: &mut Counts,
) -> (GrayImage, GroundTruth, Vec<Detection>) {
    let (image, truth) = simulate::render(scene);
    let found = detector.detect(&image);
    counts.add(scene.seed, &truth, &found);
    (image, truth, found)
}

// ---------------------------------------------------------------- items

/// The scene of item 1 (and 2): 800x600, markers of `family` spread on a
/// mid-grey background.
pub fn yaw_scene(family: &Family, spread: Spread, seed: u64) -> Scene {
    let cam = camera(800, 600);
    let mut rng = Pcg32::new(seed, 1);
    scene(
        &cam,
        spread_markers(&cam, Some(family), spread, &mut rng),
        seed,
    )
}

/// Item 1: yaw of markers with a correct ID against the true image
/// direction of +x. Returns errors in degrees and the ID counts.
pub fn yaw_errors(
    families: &mut Families,
    bits: &[u32],
    frames_per_bits: usize,
    spread: Spread,
    seed0: u64,
) -> (Errors, Counts) {
    let cam = camera(800, 600);
    let mut errors = Errors::default();
    let mut counts = Counts::default();
    for (b, &n) in bits.iter().enumerate() {
        let family = families.get(n, 2);
        let mut det = detector(Some(&family), &cam, false);
        for f in 0..frames_per_bits {
            let seed = seed0 + 1000 * b as u64 + f as u64;
            let mut rng = Pcg32::new(seed, 1);
            let s = scene(
                &cam,
                spread_markers(&cam, Some(&family), spread, &mut rng),
                seed,
            );
            let (_, truth, found) = run(&s, &mut det, &mut counts);
            for (t, d) in match_truth(&truth, &found).pairs {
                let Some(d) = d else { continue };
                let (m, d) = (&truth.markers[t], &found[d]);
                if let (true, Some(yaw)) = (d.id == m.id, d.yaw) {
                    errors.add(wrap(yaw - m.yaw) / DEG, (seed, t));
                }
            }
        }
    }
    (errors, counts)
}

/// Item 2: angle between the estimated and the true marker normal, in
/// degrees, per 10° band of the true viewing angle (between the normal and
/// the line of sight); and how many exceed `wrong_deg` (the wrong one of
/// the two candidate normals picked). Also the in-plane rotation error of
/// the full pose (its +x axis against the true one, degrees) and the centre
/// errors (px) of `Detection::u, v` and of the pose's projected position.
pub struct NormalResult {
    pub per_view: Vec<(f64, Errors)>,
    pub all: Errors,
    pub wrong_picks: usize,
    pub first_wrong: Option<(u64, usize, f64)>,
    pub pose_roll: Errors,
    pub centre: Errors,
    pub pose_centre: Errors,
    pub counts: Counts,
}

/// View angle of a true marker: between its normal and the direction to
/// the camera, degrees.
pub fn view_angle(m: &simulate::TrueMarker) -> f64 {
    let n = Vector3::from(m.normal);
    let to_camera = -Vector3::from(m.position).normalize();
    n.dot(&to_camera).clamp(-1.0, 1.0).acos() / DEG
}

pub fn normal_errors(
    families: &mut Families,
    tilts_deg: &[f64],
    frames_per_tilt: usize,
    markers_per_frame: usize,
    diameter_px: (f64, f64),
    wrong_deg: f64,
    seed0: u64,
) -> NormalResult {
    let cam = camera(800, 600);
    let family = families.get(8, 2);
    let mut det = detector(Some(&family), &cam, false);
    let mut bands = vec![Errors::default(); 9];
    let mut result = NormalResult {
        per_view: Vec::new(),
        all: Errors::default(),
        wrong_picks: 0,
        first_wrong: None,
        pose_roll: Errors::default(),
        centre: Errors::default(),
        pose_centre: Errors::default(),
        counts: Counts::default(),
    };
    for (k, &tilt) in tilts_deg.iter().enumerate() {
        for f in 0..frames_per_tilt {
            let seed = seed0 + 1000 * k as u64 + f as u64;
            let spread = Spread {
                count: markers_per_frame,
                diameter_px,
                max_tilt: 0.0,
                fixed_tilt: Some(tilt * DEG),
            };
            let s = yaw_scene(&family, spread, seed);
            let (_, truth, found) = run(&s, &mut det, &mut result.counts);
            for (t, d) in match_truth(&truth, &found).pairs {
                let Some(d) = d.map(|d| &found[d]) else {
                    continue;
                };
                let m = &truth.markers[t];
                result.centre.add((d.u - m.u).hypot(d.v - m.v), (seed, t));
                let Some(pose) = d.pose.as_ref() else {
                    continue;
                };
                if let Some((pu, pv)) = cam.project(&pose.position) {
                    result
                        .pose_centre
                        .add((pu - m.u).hypot(pv - m.v), (seed, t));
                }
                let n = pose.rotation.column(2).into_owned();
                let want = Vector3::from(m.normal);
                let angle = n.normalize().dot(&want).clamp(-1.0, 1.0).acos() / DEG;
                let band = ((view_angle(m) / 10.0) as usize).min(bands.len() - 1);
                bands[band].add(angle, (seed, t));
                result.all.add(angle, (seed, t));
                if angle > wrong_deg {
                    result.wrong_picks += 1;
                    result.first_wrong.get_or_insert((seed, t, angle));
                }
                if d.id == m.id {
                    // Rotation about the normal: the estimated +x axis
                    // against the true one, both projected onto the true
                    // marker plane.
                    let rot = nalgebra::Matrix3::from_fn(|i, j| m.rotation[i][j]);
                    let x_est = rot.transpose() * pose.rotation.column(0).into_owned();
                    result
                        .pose_roll
                        .add(x_est.y.atan2(x_est.x) / DEG, (seed, t));
                }
            }
        }
    }
    result.per_view = bands
        .into_iter()
        .enumerate()
        .filter(|(_, e)| e.n > 0)
        .map(|(k, e)| (10.0 * k as f64, e))
        .collect();
    result
}

/// Item 3: cluttered frames (circles, rings of wrong proportions, bars,
/// lines) with a few real markers.
pub fn clutter(
    family: Option<&Family>,
    frames: usize,
    density: f64,
    real_markers: usize,
    seed0: u64,
) -> Counts {
    let cam = camera(800, 600);
    let mut det = detector(family, &cam, false);
    let mut counts = Counts::default();
    for f in 0..frames {
        let seed = seed0 + f as u64;
        let mut rng = Pcg32::new(seed, 1);
        let spread = Spread {
            count: real_markers,
            diameter_px: (40.0, 90.0),
            max_tilt: 30.0 * DEG,
            fixed_tilt: None,
        };
        let mut s = scene(&cam, spread_markers(&cam, family, spread, &mut rng), seed);
        s.background = Background::Clutter { density };
        s.noise = 2.0;
        run(&s, &mut det, &mut counts);
    }
    counts
}

/// One frame of item 4.
pub fn dark_scene(
    family: Option<&Family>,
    markers_per_frame: usize,
    exposure: (f64, f64),
    worn_ink: bool,
    seed: u64,
) -> Scene {
    let cam = camera(800, 600);
    let mut rng = Pcg32::new(seed, 1);
    let spread = Spread {
        count: markers_per_frame,
        diameter_px: (40.0, 90.0),
        max_tilt: 30.0 * DEG,
        fixed_tilt: None,
    };
    let mut s = scene(&cam, spread_markers(&cam, family, spread, &mut rng), seed);
    s.background = Background::Table;
    s.exposure = rng.range(exposure.0, exposure.1);
    s.noise = rng.range(1.0, 2.5);
    if worn_ink {
        s.ink_reflectance = 0.15;
    }
    s
}

/// Item 4: dark frames on a dark table top with sensor noise; every other
/// frame a worn, greyer ink. `exposure` 0.15-0.35 gives frames with a mean
/// grey of 10-25 (white paper at 33-77); 0.065-0.13 gives means of 5-9
/// (paper at 14-28). Returns the counts and the range of the frames' means.
pub fn dark(
    family: Option<&Family>,
    frames: usize,
    markers_per_frame: usize,
    exposure: (f64, f64),
    seed0: u64,
) -> (Counts, (f64, f64)) {
    let cam = camera(800, 600);
    let mut det = detector(family, &cam, false);
    let mut counts = Counts::default();
    let mut means = (f64::MAX, f64::MIN);
    for f in 0..frames {
        let seed = seed0 + f as u64;
        let s = dark_scene(family, markers_per_frame, exposure, f % 2 == 1, seed);
        let (image, ..) = run(&s, &mut det, &mut counts);
        let mean = image.as_raw().iter().map(|&p| f64::from(p)).sum::<f64>() / image.len() as f64;
        means = (means.0.min(mean), means.1.max(mean));
    }
    (counts, means)
}

/// One frame of item 5, rendered (the shadow is applied to the image).
pub fn gradient_frame(
    family: Option<&Family>,
    markers_per_frame: usize,
    ratio: f64,
    shadow: Option<f64>,
    seed: u64,
) -> (GrayImage, GroundTruth) {
    let cam = camera(800, 600);
    let mut rng = Pcg32::new(seed, 1);
    let spread = Spread {
        count: markers_per_frame,
        diameter_px: (40.0, 90.0),
        max_tilt: 30.0 * DEG,
        fixed_tilt: None,
    };
    let mut s = scene(&cam, spread_markers(&cam, family, spread, &mut rng), seed);
    s.background = Background::Table;
    s.gradient = ratio;
    s.gradient_angle = rng.range(0.0, 2.0 * PI);
    s.exposure = 1.1;
    s.noise = 1.5;
    let (mut image, truth) = simulate::render(&s);
    if let Some(factor) = shadow {
        let through = (rng.range(200.0, 600.0), rng.range(150.0, 450.0));
        cast_shadow(&mut image, through, rng.range(0.0, 2.0 * PI), factor, 12.0);
    }
    (image, truth)
}

/// Item 5: a light gradient of `ratio`:1 across the frame in a random
/// direction, plus (when `shadow` is set) a soft cast shadow at that
/// fraction of the light over part of the frame.
pub fn gradient(
    family: Option<&Family>,
    frames: usize,
    markers_per_frame: usize,
    ratio: f64,
    shadow: Option<f64>,
    seed0: u64,
) -> Counts {
    let cam = camera(800, 600);
    let mut det = detector(family, &cam, false);
    let mut counts = Counts::default();
    for f in 0..frames {
        let seed = seed0 + f as u64;
        let (image, truth) = gradient_frame(family, markers_per_frame, ratio, shadow, seed);
        let found = det.detect(&image);
        counts.add(seed, &truth, &found);
    }
    counts
}

/// Item 6: motion blur of `length_px` in a random direction.
pub fn motion_blur(
    family: &Family,
    frames: usize,
    markers_per_frame: usize,
    length_px: f64,
    seed0: u64,
) -> Counts {
    let cam = camera(800, 600);
    let mut det = detector(Some(family), &cam, false);
    let mut counts = Counts::default();
    for f in 0..frames {
        let seed = seed0 + f as u64;
        let mut rng = Pcg32::new(seed, 1);
        let spread = Spread {
            count: markers_per_frame,
            diameter_px: (50.0, 100.0),
            max_tilt: 30.0 * DEG,
            fixed_tilt: None,
        };
        let mut s = scene(
            &cam,
            spread_markers(&cam, Some(family), spread, &mut rng),
            seed,
        );
        s.motion_blur = Some(MotionBlur {
            length_px,
            angle: rng.range(0.0, PI),
        });
        s.noise = 2.0;
        run(&s, &mut det, &mut counts);
    }
    counts
}

/// Item 7: markers of one diameter (px), slight tilts, a little focus blur
/// and noise.
pub fn small(
    family: Option<&Family>,
    diameter_px: f64,
    frames: usize,
    markers_per_frame: usize,
    seed0: u64,
) -> Counts {
    let cam = camera(640, 480);
    let mut det = detector(family, &cam, false);
    let mut counts = Counts::default();
    for f in 0..frames {
        let seed = seed0 + f as u64;
        let mut rng = Pcg32::new(seed, 1);
        let spread = Spread {
            count: markers_per_frame,
            diameter_px: (diameter_px, diameter_px),
            max_tilt: 15.0 * DEG,
            fixed_tilt: None,
        };
        let mut s = scene(&cam, spread_markers(&cam, family, spread, &mut rng), seed);
        s.focus_blur_px = 0.5;
        s.noise = 2.0;
        run(&s, &mut det, &mut counts);
    }
    counts
}
