//! Seeded series of simulated frames, as the detector bar measures them: a
//! [`Scenario`] spreads markers over a distortion-free 60° camera view,
//! then applies a row's light, background and effects; each [`Frame`]
//! comes with its true targets, and [`Scenario::run`] tallies what a
//! detector made of them ([`Counts`]).
//!
//! Every frame is seeded (`seed0 + frame`); a figure can be reproduced
//! from the scenario, the seed and the target index printed with it.

use std::collections::HashMap;
use std::f64::consts::PI;

use image::GrayImage;
use nalgebra::Vector3;
use whycode::camera::Camera;
use whycode::detect::{Detector, DetectorConfig, Target};
use whycode::family::Family;
use whycode::geometry::Marker;
use whycode::math::Pcg32;
use whycode::simulate::{
    self, LooseMarker, Placement, PrintedSquare, Scene, SceneObject, Sighting, TrueTarget,
};

use crate::tally::Counts;
use crate::{aruco4x4, tag36h11};

/// One degree in radians.
pub const DEG: f64 = PI / 180.0;

/// Printed marker diameter of every scenario's markers, metres.
pub const DIAMETER_M: f64 = 0.05;

/// Families by (bits, distance), generated once.
#[derive(Default)]
pub struct Families(HashMap<(u32, u32), Family>);

impl Families {
    /// The family of `bits`-bit codes at least `distance` apart.
    pub fn get(&mut self, bits: u32, distance: u32) -> Family {
        self.0
            .entry((bits, distance))
            .or_insert_with(|| Family::generate(bits, distance).expect("family parameters valid"))
            .clone()
    }
}

/// A distortion-free camera with a 60° horizontal field of view.
pub fn camera(width: u32, height: u32) -> Camera {
    Camera::ideal(width, height, DEFAULT_FOV_DEG)
}

/// The scenarios' horizontal field of view unless one says otherwise.
const DEFAULT_FOV_DEG: f64 = 60.0;

/// How markers are spread over a frame.
#[derive(Debug, Clone, Copy)]
pub struct Spread {
    /// Markers per frame.
    pub count: usize,
    /// Smallest and largest face-on diameter, pixels.
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
        let (marker, id) = match family {
            Some(f) => {
                let id = 1 + rng.next_u32() % f.len() as u32;
                let code = f.code(id).expect("id within the family");
                (Marker::whycode(f.bits(), code, DIAMETER_M * 1000.0), id)
            }
            None => (Marker::whycon(DIAMETER_M * 1000.0), 0),
        };
        let placement = if spread.against_view {
            // The same draws, the turn measured from the line of sight
            // instead of from the optical axis.
            let turn = tilt.hypot(pan);
            let axis = Vector3::new(tilt, -pan, 0.0) / turn.max(1e-12);
            let facing = Placement::at_pixel(camera, &marker, (u, v), d, 0.0, 0.0, roll);
            // Face-on to the line of sight has no axis to turn about.
            if turn > 0.0 {
                facing.tilted_from_sight(turn, axis)
            } else {
                facing
            }
        } else {
            Placement::at_pixel(camera, &marker, (u, v), d, tilt, pan, roll)
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

/// Cluttered 1280x720 frames without a marker (the simulator's clutter
/// at density 3, noise σ 2), seeded from 920 000: what costs time when
/// there is nothing to find. The detector bar's speed row and the
/// detection bench time the same frames.
pub fn cluttered_desk(family: &Family, frames: usize) -> Scenario<'_> {
    Scenario::new(
        Some(family),
        Spread::tilted(0, (40.0, 90.0), 0.0),
        frames,
        920_000,
    )
    .size(1280, 720)
    .look(|s, _, _| {
        s.background = simulate::Background::Clutter { density: 3.0 };
        s.noise = 2.0;
    })
}

/// A detector for `family` (legacy without) of [`DIAMETER_M`] markers,
/// with pose.
pub fn detector(family: Option<&Family>, camera: &Camera, tracking: bool) -> Detector {
    Detector::new(detector_config(family, camera, tracking))
}

/// The configuration of [`detector`], for callers that change a field of
/// it first.
pub fn detector_config(family: Option<&Family>, camera: &Camera, tracking: bool) -> DetectorConfig {
    DetectorConfig {
        target: family.map_or(Target::WhyCon, |f| Target::WhyCode(f.clone())),
        camera: Some(*camera),
        diameter_m: Some(DIAMETER_M),
        tracking,
        ..DetectorConfig::default()
    }
}

/// One frame of a scenario: its seed, the image and the true targets.
pub struct Frame {
    /// The frame's seed.
    pub seed: u64,
    /// The picture.
    pub image: GrayImage,
    /// Its markers, then its printed squares.
    pub targets: Vec<TrueTarget>,
}

/// Which targets a frame shows: our markers, or square tags of the same
/// printed footprint in their places.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Print {
    /// WhyCode (or WhyCon) markers.
    WhyCode,
    /// AprilTags (tag36h11) in the markers' places.
    AprilTag,
    /// ArUco tags (OpenCV's 4x4_50) in the markers' places.
    Aruco4x4,
}

impl Print {
    /// The tag printed where `marker` was, for a print of tags: its black
    /// square as wide as the marker's disc, on a card of the same size (so
    /// the tag's white border is the card's margin); the tag's ID from the
    /// marker's.
    pub fn tag_for(self, marker: &LooseMarker) -> Option<PrintedSquare> {
        let (tags, bitmap): (u32, fn(u32) -> GrayImage) = match self {
            Print::WhyCode => return None,
            Print::AprilTag => (tag36h11::TAGS, tag36h11::bitmap),
            Print::Aruco4x4 => (aruco4x4::TAGS, aruco4x4::bitmap),
        };
        let id = marker.id % tags;
        Some(PrintedSquare {
            card_half_mm: marker.card_half_mm,
            ..PrintedSquare::new(bitmap(id), marker.marker.diameter_mm, id, marker.placement)
        })
    }

    /// Swaps the scene's markers for this print's tags (see
    /// [`Print::tag_for`]; ours stay).
    pub fn apply(self, scene: &mut Scene) {
        for object in &mut scene.objects {
            if let SceneObject::Marker(m) = object {
                if let Some(tag) = self.tag_for(m) {
                    *object = SceneObject::Square(tag);
                }
            }
        }
    }
}

type Look<'a> = dyn Fn(&mut Scene, &mut Pcg32, usize) + 'a;
type AfterRender<'a> = dyn Fn(&mut GrayImage, &mut Pcg32) + 'a;

/// A seeded series of frames: markers of `family` (legacy WhyCon without)
/// spread as `spread` over a distortion-free 60° camera, then the row's
/// look. Frame `f` draws everything from `Pcg32::new(seed0 + f, 1)`: first
/// the markers, then whatever [`Scenario::look`] and
/// [`Scenario::after_render`] draw, in that order; so the tags' frame of
/// the same `f` differs only in what is printed.
pub struct Scenario<'a> {
    /// Image size, pixels.
    pub size: (u32, u32),
    /// Horizontal field of view of the distortion-free camera, degrees.
    pub fov_deg: f64,
    /// The markers' family; `None`: legacy WhyCon.
    pub family: Option<&'a Family>,
    /// How markers are spread over each frame.
    pub spread: Spread,
    /// How many frames.
    pub frames: usize,
    /// The first frame's seed.
    pub seed0: u64,
    look: Box<Look<'a>>,
    after_render: Option<Box<AfterRender<'a>>>,
}

impl<'a> Scenario<'a> {
    /// `frames` frames of 800x600 with the simulator's default look.
    pub fn new(family: Option<&'a Family>, spread: Spread, frames: usize, seed0: u64) -> Self {
        Scenario {
            size: (800, 600),
            fov_deg: DEFAULT_FOV_DEG,
            family,
            spread,
            frames,
            seed0,
            look: Box::new(|_, _, _| {}),
            after_render: None,
        }
    }

    /// Frames of `width` x `height`.
    pub fn size(mut self, width: u32, height: u32) -> Self {
        self.size = (width, height);
        self
    }

    /// A camera of focal length `focal_px` (pixels) instead of the 60°
    /// field of view.
    pub fn focal(mut self, focal_px: f64) -> Self {
        self.fov_deg = 2.0
            * (0.5 * f64::from(self.size.0) / focal_px)
                .atan()
                .to_degrees();
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

    /// The scenario's camera.
    pub fn camera(&self) -> Camera {
        Camera::ideal(self.size.0, self.size.1, self.fov_deg)
    }

    /// Frame `f`, printed as `print`.
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
        print.apply(&mut s);
        let (mut image, truth) = simulate::render(&s);
        if let Some(change) = &self.after_render {
            change(&mut image, &mut rng);
        }
        Frame {
            seed,
            image,
            targets: truth.targets(),
        }
    }

    /// Detects every frame with `detector` (whose adaptive state carries
    /// over, as in a video), adds to `counts` and shows each frame and its
    /// reports to `visit`.
    pub fn run(
        &self,
        detector: &mut Detector,
        counts: &mut Counts,
        mut visit: impl FnMut(&Frame, &[Sighting]),
    ) {
        for f in 0..self.frames {
            let frame = self.frame(f, Print::WhyCode);
            let found: Vec<Sighting> = detector
                .detect(&frame.image)
                .iter()
                .map(Sighting::from)
                .collect();
            counts.add(frame.seed, &frame.targets, &found);
            visit(&frame, &found);
        }
    }

    /// [`Scenario::run`] with a fresh detector (with pose, no tracking).
    pub fn counts_with(&self, visit: impl FnMut(&Frame, &[Sighting])) -> Counts {
        let mut det = detector(self.family, &self.camera(), false);
        let mut counts = Counts::default();
        self.run(&mut det, &mut counts, visit);
        counts
    }

    /// [`Scenario::counts_with`] without looking at the frames.
    pub fn counts(&self) -> Counts {
        self.counts_with(|_, _| {})
    }
}

/// The defocus row's sizes (face-on diameter, pixels), views (degrees
/// from face-on, against each marker's line of sight) and Gaussian
/// defocus (sigma, pixels), issue 25.
pub const DEFOCUS_SIZES: [f64; 4] = [20.0, 30.0, 45.0, 60.0];
/// See [`DEFOCUS_SIZES`].
pub const DEFOCUS_VIEWS: [f64; 3] = [0.0, 45.0, 65.0];
/// See [`DEFOCUS_SIZES`].
pub const DEFOCUS_SIGMAS: [f64; 3] = [1.0, 1.5, 2.0];

/// One cell of the defocus row (issue 25): `frames` frames of 1280x720
/// (f = 1000 px), each with 8 markers of `diameter_px` seen at `view_deg`
/// from face-on, under a Gaussian defocus of `sigma_px`, sensor noise of
/// sigma 4 and light clutter.
pub fn defocused(
    family: &Family,
    diameter_px: f64,
    view_deg: f64,
    sigma_px: f64,
    frames: usize,
    seed0: u64,
) -> Scenario<'_> {
    Scenario::new(
        Some(family),
        Spread::fixed_view(8, (diameter_px, diameter_px), view_deg),
        frames,
        seed0,
    )
    .size(1280, 720)
    .focal(1000.0)
    .look(move |s, _, _| {
        s.background = simulate::Background::Clutter { density: 1.0 };
        s.noise = 4.0;
        s.focus_blur_px = sigma_px;
    })
}

/// What one realistic-camera cell does to the picture (the real-cameras
/// rows of the detector bar): each is a way photographs taken by other
/// people differ from the simulator's clean frames.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RealCamera {
    /// Each marker on a card with a third of a radius of paper round it,
    /// in a patch of shade (a fifth to a third of the light), in a bright
    /// frame (1.3 times the usual exposure).
    Shade,
    /// Grey ink on grey paper (reflectance 0.3 on 0.65), sensor noise 3.
    GreyInk,
    /// A video stream of half the resolution shown twice as large (JPEG
    /// quality 40), out of focus by 0.04-0.07 of the marker's diameter.
    Video,
    /// A phone's sharpening (unsharp mask of amount 1.5 at sigma 1.5 px)
    /// on a slightly soft picture: halos round every edge.
    Sharpened,
    /// A Bayer sensor with bilinear demosaicing, lateral chromatic
    /// aberration of 0.003 and noise 3.
    Bayer,
    /// Markers whose disc comes within 0.02 of its diameter of two of the
    /// frame's edges (a landing pad filling a drone's camera).
    Border,
    /// A Bayer sensor, sharpening, and the video stream, out of focus, at
    /// once (a webcam's stream).
    Everything,
}

impl RealCamera {
    /// Every cell, in the bar's order.
    pub const ALL: [RealCamera; 7] = [
        RealCamera::Shade,
        RealCamera::GreyInk,
        RealCamera::Video,
        RealCamera::Sharpened,
        RealCamera::Bayer,
        RealCamera::Border,
        RealCamera::Everything,
    ];

    /// The cell's name in the bar's table.
    pub fn name(self) -> &'static str {
        match self {
            RealCamera::Shade => "paper in shade, bright frame",
            RealCamera::GreyInk => "grey ink on grey paper",
            RealCamera::Video => "video upscaled x2, blur 0.04-0.07 D",
            RealCamera::Sharpened => "camera sharpening halos",
            RealCamera::Bayer => "Bayer demosaicing, chromatic offset",
            RealCamera::Border => "discs in the frame's corners",
            RealCamera::Everything => "webcam: Bayer, sharpening, video, blur",
        }
    }

    /// Face-on diameters of the cell's markers, pixels.
    fn sizes(self) -> (f64, f64) {
        match self {
            RealCamera::Shade | RealCamera::GreyInk => (30.0, 80.0),
            RealCamera::Video | RealCamera::Everything => (40.0, 60.0),
            RealCamera::Sharpened | RealCamera::Bayer => (24.0, 50.0),
            RealCamera::Border => (120.0, 300.0),
        }
    }
}

/// One realistic-camera cell: `frames` frames of 1280x720 (f = 1000 px),
/// 8-bit markers of `family` (legacy WhyCon without) tilted up to 30°,
/// spoilt as `camera` says.
pub fn real_camera(
    family: Option<&Family>,
    camera: RealCamera,
    frames: usize,
    seed0: u64,
) -> Scenario<'_> {
    let count = if camera == RealCamera::Border { 4 } else { 8 };
    Scenario::new(
        family,
        Spread::tilted(count, camera.sizes(), 30.0),
        frames,
        seed0,
    )
    .size(1280, 720)
    .focal(1000.0)
    .look(move |s, rng, _| {
        s.background = simulate::Background::Clutter { density: 0.5 };
        s.noise = 2.0;
        match camera {
            RealCamera::Shade => {
                s.exposure = 1.3;
                shade_each_marker(s, rng);
            }
            RealCamera::GreyInk => {
                s.paper_reflectance = 0.65;
                s.ink_reflectance = 0.3;
                s.noise = 3.0;
            }
            RealCamera::Border => move_to_border(s, rng),
            _ => {}
        }
        let video = |s: &mut Scene, rng: &mut Pcg32| {
            s.focus_blur_px = rng.range(0.04, 0.07) * marker_diameter_px(s);
            s.processing.video_downscale = Some(2);
            s.processing.video_quality = 40;
        };
        match camera {
            RealCamera::Video => video(s, rng),
            RealCamera::Sharpened => {
                s.focus_blur_px = 0.8;
                s.processing.sharpen = Some((1.5, 1.5));
            }
            RealCamera::Bayer => {
                s.processing.bayer_aberration = Some(0.003);
                s.noise = 3.0;
            }
            RealCamera::Everything => {
                video(s, rng);
                s.processing.sharpen = Some((1.0, 1.5));
                s.processing.bayer_aberration = Some(0.003);
            }
            _ => {}
        }
    })
}

/// The mean face-on diameter, pixels, of the scene's markers.
fn marker_diameter_px(s: &Scene) -> f64 {
    let f = s.camera.fx;
    let sizes: Vec<f64> = s
        .objects
        .iter()
        .filter_map(|o| match o {
            SceneObject::Marker(m) => {
                Some(f * m.marker.diameter_mm / 1000.0 / m.placement.position.z)
            }
            _ => None,
        })
        .collect();
    sizes.iter().sum::<f64>() / sizes.len().max(1) as f64
}

/// Cuts each marker's card to a third of a radius of paper round the disc
/// and puts a patch of shade over it (the frame's exposure is the cell's).
fn shade_each_marker(s: &mut Scene, rng: &mut Pcg32) {
    let camera = s.camera;
    let shades: Vec<simulate::Shade> = s
        .objects
        .iter_mut()
        .filter_map(|o| match o {
            SceneObject::Marker(m) => {
                m.card_half_mm = 1.33 * m.marker.outer_radius();
                let centre = m.placement.position;
                let (u, v) = camera.project(&centre)?;
                let radius = camera.fx * m.card_half_mm / 1000.0 / centre.z;
                Some(simulate::Shade {
                    u,
                    v,
                    // The card's corners in the shade too.
                    radius_px: 1.5 * radius,
                    soft_px: 0.3 * radius,
                    factor: rng.range(0.2, 0.35),
                })
            }
            _ => None,
        })
        .collect();
    s.shades = shades;
}

/// Moves the scene's markers (as `spread_markers` placed them) so that
/// each disc comes within 0.02 of its diameter of two of the frame's
/// edges, one marker in each corner.
fn move_to_border(s: &mut Scene, rng: &mut Pcg32) {
    let camera = s.camera;
    let (w, h) = (f64::from(camera.width), f64::from(camera.height));
    for (k, object) in s.objects.iter_mut().enumerate() {
        let SceneObject::Marker(m) = object else {
            continue;
        };
        let d = camera.fx * m.marker.diameter_mm / 1000.0 / m.placement.position.z;
        // Face-on at the border: the disc's edge 0.02 D from the frame's.
        let gap = 0.02 * d + 0.5 * d;
        let (u, v) = match k % 4 {
            0 => (gap, gap),
            1 => (w - gap, gap),
            2 => (w - gap, h - gap),
            _ => (gap, h - gap),
        };
        let roll = rng.range(0.0, 2.0 * PI);
        let placement = Placement::at_pixel(&camera, &m.marker, (u, v), d, 0.0, 0.0, roll);
        *object = SceneObject::Marker(LooseMarker::new(m.marker, m.id, placement));
    }
}
