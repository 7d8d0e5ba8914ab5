//! Scenes of the detector bar: a [`Scenario`] is a seeded series of frames
//! from `whycode::simulate` (markers spread over a camera view, then the
//! light, background and effects of the row), and [`Counts`] / [`Errors`]
//! tally what the detector made of them against the ground truth.
//!
//! Every frame is seeded (`seed0 + frame`); a failing figure can be
//! reproduced from the row, the seed and the marker printed with it.

use std::collections::HashMap;
use std::f64::consts::PI;

use image::GrayImage;
use nalgebra::{Matrix3, Rotation3, Unit, Vector3};
use whycode::camera::Camera;
use whycode::detect::{Detection, Detector, DetectorConfig, Target};
use whycode::family::Family;
use whycode::geometry::Marker;
use whycode::math::Pcg32;
use whycode::simulate::{
    self, GroundTruth, LooseMarker, Placement, PrintedSquare, Scene, SceneObject,
};

use crate::rival::{Rival, Setup};
use crate::tag36h11;

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
    /// `fixed_tilt` is the angle between the marker's normal and its own
    /// line of sight (its view angle), not a turn about the camera's axes
    /// (which off the optical axis adds up to half the field of view).
    pub against_view: bool,
}

impl Spread {
    /// `count` markers of `diameter_px`, tilt and pan each drawn within
    /// ±`max_tilt_deg`.
    pub fn tilted(count: usize, diameter_px: (f64, f64), max_tilt_deg: f64) -> Spread {
        Spread {
            count,
            diameter_px,
            max_tilt: max_tilt_deg * DEG,
            fixed_tilt: None,
            against_view: false,
        }
    }

    /// `count` markers of `diameter_px`, each tilted by exactly `tilt_deg`
    /// about a random in-plane axis.
    pub fn fixed_tilt(count: usize, diameter_px: (f64, f64), tilt_deg: f64) -> Spread {
        Spread {
            count,
            diameter_px,
            max_tilt: 0.0,
            fixed_tilt: Some(tilt_deg * DEG),
            against_view: false,
        }
    }

    /// `count` markers of `diameter_px`, each seen at exactly `view_deg`
    /// from face-on (normal against the line of sight to its centre),
    /// tilted about a random axis.
    pub fn fixed_view(count: usize, diameter_px: (f64, f64), view_deg: f64) -> Spread {
        Spread {
            against_view: true,
            ..Spread::fixed_tilt(count, diameter_px, view_deg)
        }
    }
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
        let mut placement = placement_at(camera, (u, v), d, tilt, pan, roll);
        if spread.against_view {
            // Face-on to the line of sight, then the tilt (about an axis
            // across it): the same draws, measured from the ray instead of
            // from the optical axis.
            let face_on = placement_at(camera, (u, v), d, 0.0, 0.0, roll);
            let turn = tilt.hypot(pan);
            let axis = Vector3::new(tilt, -pan, 0.0) / turn.max(1e-12);
            let to_ray = Rotation3::rotation_between(&Vector3::z(), &face_on.position)
                .unwrap_or_else(Rotation3::identity);
            let tilted = Rotation3::from_axis_angle(&Unit::new_normalize(to_ray * axis), turn);
            placement.rotation = tilted.matrix() * to_ray.matrix() * face_on.rotation;
        }
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
        target: family.map_or(Target::WhyCon, |f| Target::WhyCode(f.clone())),
        camera: Some(*camera),
        diameter_m: Some(DIAMETER_M),
        tracking,
        ..DetectorConfig::default()
    })
}

/// One true target of a frame, whichever kind (a WhyCode marker, or the
/// AprilTag printed in its place), as the scoring sees it.
#[derive(Debug, Clone)]
pub struct Truth {
    /// Family ID of a marker, tag ID of a tag (0 for a legacy marker).
    pub id: u32,
    pub u: f64,
    pub v: f64,
    /// Longest projected size (disc diameter, or the tag's black square side), px.
    pub size_px: f64,
    pub visible: bool,
    /// Image direction of the target's +x axis, radians.
    pub yaw: f64,
    /// Rotation target → camera (columns +x, +y, normal).
    pub rotation: Matrix3<f64>,
    pub position: Vector3<f64>,
}

impl Truth {
    pub fn normal(&self) -> Vector3<f64> {
        self.rotation.column(2).into_owned()
    }

    /// The frame's targets: its markers, then its printed squares.
    pub fn of(truth: &GroundTruth) -> Vec<Truth> {
        let rotation = |r: &[[f64; 3]; 3]| Matrix3::from_fn(|i, j| r[i][j]);
        let markers = truth.markers.iter().map(|m| Truth {
            id: m.id,
            u: m.u,
            v: m.v,
            size_px: m.diameter_px,
            visible: m.visible,
            yaw: m.yaw,
            rotation: rotation(&m.rotation),
            position: Vector3::from(m.position),
        });
        let squares = truth.squares.iter().map(|q| {
            // The image of +x at the centre: from the left to the right edge's midpoint.
            let c = &q.corners;
            let du = (c[1][0] + c[2][0] - c[0][0] - c[3][0]) / 2.0;
            let dv = (c[1][1] + c[2][1] - c[0][1] - c[3][1]) / 2.0;
            Truth {
                id: q.id,
                u: q.u,
                v: q.v,
                size_px: q.side_px,
                visible: q.visible,
                yaw: dv.atan2(du),
                rotation: rotation(&q.rotation),
                position: Vector3::from(q.position),
            }
        });
        markers.chain(squares).collect()
    }
}

/// One report of a detector, ours or another, as the scoring sees it.
#[derive(Debug, Clone)]
pub struct Seen {
    pub u: f64,
    pub v: f64,
    /// `None`: reported without an ID ("unknown").
    pub id: Option<u32>,
    pub yaw: Option<f64>,
    /// Unit normal of the printed face, camera frame.
    pub normal: Option<Vector3<f64>>,
    /// Full orientation: rotation target → camera (columns +x, +y, normal).
    pub rotation: Option<Matrix3<f64>>,
    /// Centre in the camera frame, metres.
    pub position: Option<Vector3<f64>>,
}

impl From<&Detection> for Seen {
    fn from(d: &Detection) -> Seen {
        Seen {
            u: d.u,
            v: d.v,
            id: (d.id != 0).then_some(d.id),
            yaw: d.yaw,
            normal: d.pose.as_ref().map(|p| p.rotation.column(2).into_owned()),
            rotation: d.pose.as_ref().map(|p| p.rotation),
            position: d.pose.as_ref().map(|p| p.position),
        }
    }
}

/// A report this close to any true target (in its sizes, plus 2 px) is
/// about that target, not a false one: the card reaches 0.75 D from the
/// centre, a blurred outline a little past D/2.
const NEAR_MARKER: f64 = 0.6;

/// Reports paired with the visible true targets: for each target the
/// nearest report within a quarter of its size (+2 px); reports near no
/// target at all (visible or not) are false.
pub struct Matched {
    pub pairs: Vec<(usize, Option<usize>)>,
    pub false_detections: Vec<usize>,
}

pub fn match_truth(truth: &[Truth], found: &[Seen]) -> Matched {
    let mut used = vec![false; found.len()];
    let mut pairs = Vec::new();
    let distance = |d: &Seen, m: &Truth| (d.u - m.u).hypot(d.v - m.v);
    for (t, m) in truth.iter().enumerate() {
        let radius = 0.25 * m.size_px + 2.0;
        let best = found
            .iter()
            .enumerate()
            .filter(|(k, d)| !used[*k] && distance(d, m) < radius)
            .min_by(|a, b| distance(a.1, m).total_cmp(&distance(b.1, m)))
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
                    .iter()
                    .any(|m| distance(&found[k], m) < NEAR_MARKER * m.size_px + 2.0)
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
    pub fn add(&mut self, seed: u64, truth: &[Truth], found: &[Seen]) {
        let matched = match_truth(truth, found);
        self.frames += 1;
        for &(t, d) in &matched.pairs {
            self.markers += 1;
            let Some(d) = d else {
                self.first_miss.get_or_insert((seed, t));
                continue;
            };
            self.detected += 1;
            match found[d].id {
                None => self.unknown_id += 1,
                Some(id) if id == truth[t].id => self.correct_id += 1,
                Some(_) => {
                    self.wrong_id += 1;
                    self.first_wrong.get_or_insert((seed, t));
                }
            }
        }
        for &k in &matched.false_detections {
            self.false_detections += 1;
            if found[k].id.is_some() {
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

/// One frame of a scenario: its seed, the image and the true targets.
pub struct Frame {
    pub seed: u64,
    pub image: GrayImage,
    pub targets: Vec<Truth>,
}

/// Which targets a frame shows: our markers, or tag36h11 AprilTags of the
/// same printed footprint in their places.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Print {
    WhyCode,
    AprilTag,
}

/// The tag printed where `marker` was: its black square as wide as the
/// marker's disc, on a card of the same size, so the tag's white border
/// (two cells) is the card's margin; tag ID from the marker's ID.
pub fn tag_for(marker: &LooseMarker) -> PrintedSquare {
    let id = marker.id % tag36h11::TAGS;
    PrintedSquare {
        card_half_mm: marker.card_half_mm,
        ..PrintedSquare::new(
            tag36h11::bitmap(id),
            marker.marker.diameter_mm,
            id,
            marker.placement,
        )
    }
}

/// A scene's markers swapped for AprilTags (see [`tag_for`]).
pub fn with_tags(scene: &mut Scene) {
    for object in &mut scene.objects {
        if let SceneObject::Marker(m) = object {
            *object = SceneObject::Square(tag_for(m));
        }
    }
}

type Look<'a> = dyn Fn(&mut Scene, &mut Pcg32, usize) + 'a;
type AfterRender<'a> = dyn Fn(&mut GrayImage, &mut Pcg32) + 'a;

/// A seeded series of frames: markers of `family` (legacy WhyCon without)
/// spread as `spread` over a distortion-free 60° camera, then the row's
/// look. Frame `f` draws everything from `Pcg32::new(seed0 + f, 1)`: first
/// the markers, then whatever [`Scenario::look`] and
/// [`Scenario::after_render`] draw, in that order; so the AprilTag frame
/// of the same `f` differs only in what is printed.
pub struct Scenario<'a> {
    pub size: (u32, u32),
    pub family: Option<&'a Family>,
    pub spread: Spread,
    pub frames: usize,
    pub seed0: u64,
    look: Box<Look<'a>>,
    after_render: Option<Box<AfterRender<'a>>>,
}

impl<'a> Scenario<'a> {
    /// `frames` frames of 800x600 with the simulator's default look.
    pub fn new(family: Option<&'a Family>, spread: Spread, frames: usize, seed0: u64) -> Self {
        Scenario {
            size: (800, 600),
            family,
            spread,
            frames,
            seed0,
            look: Box::new(|_, _, _| {}),
            after_render: None,
        }
    }

    pub fn size(mut self, width: u32, height: u32) -> Self {
        self.size = (width, height);
        self
    }

    /// Sets the scene's background, light and effects; gets the frame's
    /// generator and the frame number.
    pub fn look(mut self, look: impl Fn(&mut Scene, &mut Pcg32, usize) + 'a) -> Self {
        self.look = Box::new(look);
        self
    }

    /// Changes the rendered image (what the simulator cannot draw itself).
    pub fn after_render(mut self, change: impl Fn(&mut GrayImage, &mut Pcg32) + 'a) -> Self {
        self.after_render = Some(Box::new(change));
        self
    }

    pub fn camera(&self) -> Camera {
        camera(self.size.0, self.size.1)
    }

    pub fn frame(&self, f: usize, print: Print) -> Frame {
        let seed = self.seed0 + f as u64;
        let cam = self.camera();
        let mut rng = Pcg32::new(seed, 1);
        let mut s = scene(
            &cam,
            spread_markers(&cam, self.family, self.spread, &mut rng),
            seed,
        );
        (self.look)(&mut s, &mut rng, f);
        if print == Print::AprilTag {
            with_tags(&mut s);
        }
        let (mut image, truth) = simulate::render(&s);
        if let Some(change) = &self.after_render {
            change(&mut image, &mut rng);
        }
        Frame {
            seed,
            image,
            targets: Truth::of(&truth),
        }
    }

    /// Detects every frame with `detector` (whose adaptive state carries
    /// over, as in a video), adds to `counts` and shows each frame and its
    /// reports to `visit`.
    pub fn run(
        &self,
        detector: &mut Detector,
        counts: &mut Counts,
        mut visit: impl FnMut(&Frame, &[Seen]),
    ) {
        for f in 0..self.frames {
            let frame = self.frame(f, Print::WhyCode);
            let found: Vec<Seen> = detector
                .detect(&frame.image)
                .iter()
                .map(Seen::from)
                .collect();
            counts.add(frame.seed, &frame.targets, &found);
            visit(&frame, &found);
        }
    }

    /// The same frames read by `rival` (all at once: one process per
    /// scenario), with its own markers printed in ours' places if it has
    /// any; like [`Scenario::run`], and gives its time per frame, ms.
    pub fn run_rival(
        &self,
        rival: &dyn Rival,
        counts: &mut Counts,
        mut visit: impl FnMut(&Frame, &[Seen]),
    ) -> Result<Vec<f64>, String> {
        let frames: Vec<Frame> = (0..self.frames)
            .map(|f| self.frame(f, rival.print()))
            .collect();
        let images: Vec<&GrayImage> = frames.iter().map(|f| &f.image).collect();
        let setup = Setup {
            camera: &self.camera(),
            size_m: DIAMETER_M,
            family: self.family.map(|f| (f.bits(), f.distance())),
            targets: self.spread.count,
        };
        let results = rival.detect(&setup, &images)?;
        let mut times = Vec::with_capacity(frames.len());
        for (frame, (found, ms)) in frames.iter().zip(results) {
            counts.add(frame.seed, &frame.targets, &found);
            visit(frame, &found);
            times.push(ms);
        }
        Ok(times)
    }

    /// [`Scenario::run`] with a fresh detector (with pose, no tracking).
    pub fn counts_with(&self, visit: impl FnMut(&Frame, &[Seen])) -> Counts {
        let mut det = detector(self.family, &self.camera(), false);
        let mut counts = Counts::default();
        self.run(&mut det, &mut counts, visit);
        counts
    }

    pub fn counts(&self) -> Counts {
        self.counts_with(|_, _| {})
    }

    /// A rival's counts on the same frames; `None` when it cannot be run
    /// (the reason was said once, at the start).
    pub fn rival_counts(&self, rival: Option<&dyn Rival>) -> Option<Counts> {
        let rival = rival?;
        let mut counts = Counts::default();
        match self.run_rival(rival, &mut counts, |_, _| {}) {
            Ok(_) => Some(counts),
            Err(e) => {
                eprintln!("{} failed: {e}", rival.name());
                None
            }
        }
    }
}
