//! Scene simulator: renders what a camera would see of markers and printed
//! sheets posed in 3D, with the ground truth of every marker.
//!
//! Geometry comes from [`crate::geometry::Marker`] (the one marker shape) and
//! the camera model from [`crate::camera::Camera`] (with lens distortion);
//! each pixel's viewing ray is intersected with the paper planes, so
//! perspective and distortion are exact, and edge pixels are supersampled.
//! Then come the imaging effects in the order a camera applies them: uneven
//! illumination, motion blur, focus blur, sensor noise, 8-bit quantisation
//! and JPEG compression. Same scene and seed give the same bytes.
//!
//! Object frames: a loose marker's frame is the marker frame (origin at the
//! centre, +x along sector angle 0, +y along sector angle 90°, +z out of the
//! printed face). A page's frame has its origin at the page centre, +x to the
//! right, +y towards the top edge, +z out of the printed face, so a marker
//! printed unrotated on the page shares the page's orientation.
//! [`Placement`] maps an object frame (metres) into the camera frame
//! (OpenCV optical: x right, y down, z forward).

mod background;
pub(crate) mod effects;
pub mod layout;
mod matching;
mod raster;
mod square;
mod truth;

pub use matching::{
    match_reports, nearest, IdRead, Located, Matching, Reach, Sighting, TrueTarget,
};
pub use square::{PrintedSquare, TrueSquare};
pub use truth::{GroundTruth, TrueMarker, TruePage};

use crate::camera::Camera;
use crate::geometry::Marker;
use crate::manifest::Manifest;
use nalgebra::{Matrix3, Rotation3, Vector3};

/// Where an object sits: object frame (metres) → camera frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Placement {
    /// Position of the object's origin in the camera frame, metres.
    pub position: Vector3<f64>,
    /// Rotation object → camera.
    pub rotation: Matrix3<f64>,
}

impl Placement {
    /// A placement at `position` (metres, camera frame) with `rotation` from the object's frame to the camera's.
    pub fn new(position: Vector3<f64>, rotation: Matrix3<f64>) -> Placement {
        Placement { position, rotation }
    }

    /// Face-on and upright at `distance` metres straight ahead.
    pub fn facing(distance: f64) -> Placement {
        Placement::viewed(Vector3::new(0.0, 0.0, distance), 0.0, 0.0, 0.0)
    }

    /// An object at `position` (metres, camera frame), turned from face-on
    /// and upright by `roll` (in its own plane, counter-clockwise as seen),
    /// then `tilt` (about the camera's horizontal axis; positive brings the
    /// top edge towards the camera), then `pan` (about the camera's vertical
    /// axis; positive brings the right edge towards the camera). Radians.
    pub fn viewed(position: Vector3<f64>, tilt: f64, pan: f64, roll: f64) -> Placement {
        let face_on = Matrix3::from_diagonal(&Vector3::new(1.0, -1.0, -1.0));
        let roll_m = *Rotation3::from_axis_angle(&Vector3::z_axis(), roll).matrix();
        let tilt_m = *Rotation3::from_axis_angle(&Vector3::x_axis(), tilt).matrix();
        let pan_m = *Rotation3::from_axis_angle(&Vector3::y_axis(), -pan).matrix();
        Placement {
            position,
            rotation: pan_m * tilt_m * face_on * roll_m,
        }
    }

    /// A point of the object frame given in millimetres, in the camera frame
    /// in metres.
    pub fn to_camera_mm(&self, x_mm: f64, y_mm: f64) -> Vector3<f64> {
        self.position + self.rotation * Vector3::new(x_mm / 1000.0, y_mm / 1000.0, 0.0)
    }

    /// Unit normal of the printed face, camera frame.
    pub fn normal(&self) -> Vector3<f64> {
        self.rotation.column(2).into_owned()
    }
}

/// A disc of ink (or of white correction paint) over the print, e.g. to
/// damage a marker's ring.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Blot {
    /// Centre in the object's print coordinates: for a loose marker the
    /// marker frame (mm); for a page the manifest's page coordinates (mm
    /// from the top-left corner, y down, before any print scaling).
    pub x_mm: f64,
    /// Centre y, mm (see `x_mm`).
    pub y_mm: f64,
    /// Radius, mm.
    pub radius_mm: f64,
    /// Ink-black when true, paper-white otherwise.
    pub black: bool,
}

/// A marker on its own small card of paper.
#[derive(Debug, Clone, PartialEq)]
pub struct LooseMarker {
    /// The marker's shape and size.
    pub marker: Marker,
    /// Family ID reported in the ground truth (0 if none).
    pub id: u32,
    /// Pose of the marker centre.
    pub placement: Placement,
    /// Half the side of the square white card around the marker, mm. The
    /// default leaves half a radius of white, more than the 0.3 R minimum.
    pub card_half_mm: f64,
    /// Damage drawn over the card.
    pub blots: Vec<Blot>,
}

impl LooseMarker {
    /// A marker on a card of the default size, undamaged.
    pub fn new(marker: Marker, id: u32, placement: Placement) -> LooseMarker {
        LooseMarker {
            card_half_mm: marker.outer_radius() * 1.5,
            marker,
            id,
            placement,
            blots: Vec::new(),
        }
    }
}

/// One page of a printed sheet: a white sheet of paper of the manifest's
/// page size with its markers.
#[derive(Debug, Clone, PartialEq)]
pub struct SheetPage {
    /// The sheet's record of its markers and page size.
    pub manifest: Manifest,
    /// Page number, from 1.
    pub page: u32,
    /// Scale the printer applied to the content about the page centre
    /// (e.g. 0.97 for "fit to page"); the paper keeps its size.
    pub print_scale: f64,
    /// Pose of the page centre.
    pub placement: Placement,
    /// Damage drawn over the page.
    pub blots: Vec<Blot>,
    /// What else is printed on the page (labels, scale bar, caption), in
    /// page millimetres; see [`SheetPage::with_printed_text`].
    pub decor: Option<crate::render::page::Page>,
}

impl SheetPage {
    /// Page `page` of the sheet, printed at scale 1, markers only.
    pub fn new(manifest: Manifest, page: u32, placement: Placement) -> SheetPage {
        SheetPage {
            manifest,
            page,
            print_scale: 1.0,
            placement,
            blots: Vec::new(),
            decor: None,
        }
    }

    /// Prints the page's labels, scale bar and caption too, as the sheet
    /// named `sheet_name` had them, when the manifest can be laid out again
    /// exactly (a built-in template); otherwise the page shows its markers
    /// only. A validation photo should carry the same ink near the paper's
    /// edges as the real print.
    pub fn with_printed_text(mut self, sheet_name: &str) -> SheetPage {
        self.decor = crate::render::sheet::relayout(&self.manifest, sheet_name)
            .and_then(|sheet| sheet.pages.into_iter().nth(self.page as usize - 1))
            .map(|mut page| {
                page.items
                    .retain(|item| !matches!(item, crate::render::page::Item::Marker { .. }));
                page
            });
        self
    }

    /// The marker shape of one manifest entry (WhyCode when the manifest
    /// names a family, WhyCon otherwise), at the intended size.
    pub fn marker_of(manifest: &Manifest, entry: &crate::manifest::PrintedMarker) -> Marker {
        match manifest.family {
            Some(f) if !manifest.legacy => Marker::whycode(f.bits, entry.code, entry.diameter_mm),
            _ => Marker::whycon(entry.diameter_mm),
        }
    }
}

#[derive(Debug, Clone, PartialEq)]
/// One object in front of the camera.
pub enum SceneObject {
    /// A single marker on its own card.
    Marker(LooseMarker),
    /// A page of a printed sheet.
    Page(SheetPage),
    /// A square bitmap on its own card (another kind of fiducial).
    Square(PrintedSquare),
}

/// What is behind the objects.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Background {
    /// A uniform surface of this reflectance (0 black .. 1 white).
    Uniform(f64),
    /// A darker table top with a faint low-frequency texture.
    Table,
    /// Random shapes, lines, rings and discs that are not markers, to test
    /// for false detections.
    Clutter {
        /// Shapes per 100×100 pixels.
        density: f64,
    },
}

/// Motion blur along a straight line.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MotionBlur {
    /// Length of the smear, pixels.
    pub length_px: f64,
    /// Direction, radians, atan2(dv, du).
    pub angle: f64,
}

/// A patch of shade: light falls to `factor` inside a circle of
/// `radius_px` around (`u`, `v`), over a soft edge of `soft_px` (paper in
/// the shadow of a person or a shelf, in a frame lit by lamps and windows).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shade {
    /// Centre column, pixels.
    pub u: f64,
    /// Centre row, pixels.
    pub v: f64,
    /// Radius of the fully shaded part, pixels.
    pub radius_px: f64,
    /// Width of the edge over which the light returns, pixels.
    pub soft_px: f64,
    /// Share of the light left in the shade (0..1).
    pub factor: f64,
}

/// What a real camera's own processing does after the lens, in the order
/// it does it: a colour sensor's mosaic, its noise, demosaicing,
/// sharpening, then a video encoder's resizing and compression.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Processing {
    /// A Bayer (RGGB) sensor read by bilinear demosaicing, with the lens's
    /// lateral chromatic aberration: the red image magnified about the
    /// centre by 1 + this, the blue by 1 - this (0.002 shifts red and blue
    /// a pixel apart at 500 px from the centre). None: a grey sensor.
    pub bayer_aberration: Option<f64>,
    /// An unsharp mask of (amount, Gaussian sigma in pixels), as phones and
    /// webcams apply: edges gain a light and a dark halo.
    pub sharpen: Option<(f64, f64)>,
    /// A video stream of lower resolution shown larger: the frame shrunk
    /// by this whole factor, encoded as JPEG at `video_quality`, decoded
    /// and scaled back up bilinearly.
    pub video_downscale: Option<u32>,
    /// JPEG quality of that stream (1-100).
    pub video_quality: u8,
}

#[derive(Debug, Clone, PartialEq)]
/// A camera view to synthesise: what is in front of the camera, the light, and the ways a real camera spoils the picture; [`render`] turns it into an image with exact ground truth.
pub struct Scene {
    /// The camera: intrinsics, distortion and image size.
    pub camera: Camera,
    /// The objects, drawn in order (later ones in front).
    pub objects: Vec<SceneObject>,
    /// What shows where no object is.
    pub background: Background,
    /// Ratio of the brightest to the darkest illumination across the frame
    /// (1 = even light, 3 = "3:1").
    pub gradient: f64,
    /// Direction in which the light falls off, radians, atan2(dv, du).
    pub gradient_angle: f64,
    /// Overall exposure: 1 puts white paper near grey 220; 0.2 is a dark frame.
    pub exposure: f64,
    /// Reflectance of the paper, 0 black .. 1 white.
    pub paper_reflectance: f64,
    /// Reflectance of the ink, 0 black .. 1 white.
    pub ink_reflectance: f64,
    /// Focus blur: Gaussian sigma, pixels.
    pub focus_blur_px: f64,
    /// Motion blur, if the camera or the objects moved during exposure.
    pub motion_blur: Option<MotionBlur>,
    /// Patches of shade over the frame's light.
    pub shades: Vec<Shade>,
    /// Sensor noise: Gaussian sigma in grey levels.
    pub noise: f64,
    /// The camera's processing after the sensor.
    pub processing: Processing,
    /// JPEG round trip at this quality (1-100).
    pub jpeg_quality: Option<u8>,
    /// Seed of the noise, texture and clutter: the same scene gives the same
    /// bytes.
    pub seed: u64,
    /// Samples per pixel side on edges (n×n).
    pub supersampling: u32,
}

impl Scene {
    /// An empty scene with a mid-grey background, even light and no effects.
    pub fn new(camera: Camera) -> Scene {
        Scene {
            camera,
            objects: Vec::new(),
            background: Background::Uniform(0.45),
            gradient: 1.0,
            gradient_angle: 0.0,
            exposure: 1.0,
            paper_reflectance: 0.86,
            ink_reflectance: 0.05,
            focus_blur_px: 0.0,
            motion_blur: None,
            shades: Vec::new(),
            noise: 0.0,
            processing: Processing::default(),
            jpeg_quality: None,
            seed: 1,
            supersampling: 4,
        }
    }
}

/// Renders the scene: the camera image and the ground truth of every marker.
pub fn render(scene: &Scene) -> (image::GrayImage, GroundTruth) {
    let reflectance = raster::render_reflectance(scene);
    let image = effects::develop(scene, reflectance);
    (image, truth::ground_truth(scene))
}
