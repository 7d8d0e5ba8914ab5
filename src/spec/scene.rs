//! A simulated camera view as the front ends ask for it: `whycode
//! simulate`'s options and Python's `simulate(...)` keywords, checked once
//! and built into a [`Scene`].

use super::{limits, within, Problem, SpecError, TargetSpec};
use crate::camera::Camera;
use crate::geometry::Marker;
use crate::manifest::Manifest;
use crate::simulate::{layout, Background, MotionBlur, Scene, SceneObject, SheetPage};
use crate::units::{Angle, Length};
use std::path::PathBuf;

/// How loose markers are arranged.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Layout {
    /// A flat board of markers in rows, centred in the view.
    #[default]
    Grid,
    /// Markers scattered at random through the view, none overlapping; the
    /// spec is refused when they do not all fit.
    Scatter,
}

/// What is behind the paper.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum BackgroundKind {
    /// A uniform mid-grey surface.
    Grey,
    /// A darker table top with a faint texture.
    Table,
    /// Shapes, lines, rings and discs that are not markers.
    Clutter,
}

impl BackgroundKind {
    /// The background this names.
    pub fn background(self) -> Background {
        match self {
            BackgroundKind::Grey => Background::Uniform(0.45),
            BackgroundKind::Table => Background::Table,
            BackgroundKind::Clutter => Background::Clutter { density: 1.5 },
        }
    }
}

/// A camera view to simulate: one page of a printed sheet (`manifest`) or
/// loose markers (`ids` of `target`'s family). Every field is what the
/// option of the same name says in `whycode simulate --help`; `None` and
/// the defaults are the command line's defaults.
#[derive(Debug, Clone)]
pub struct SceneSpec {
    /// A sheet's manifest: show one of its pages.
    pub manifest: Option<PathBuf>,
    /// The page of the sheet (default 1); sheet only.
    pub page: Option<u32>,
    /// The scale the printer applied to the sheet (default 1); sheet only.
    pub print_scale: Option<f64>,
    /// The loose markers' family (a manifest names its own).
    pub target: TargetSpec,
    /// Loose markers' IDs.
    pub ids: Option<Vec<u32>>,
    /// Loose markers' diameter (default 50 mm).
    pub diameter: Option<Length>,
    /// Loose markers' arrangement (default grid).
    pub layout: Option<Layout>,
    /// A calibrated camera; without one, an ideal camera of `size` and `fov`.
    pub camera: Option<Camera>,
    /// The ideal camera's image, pixels (default 1920 x 1080).
    pub size: Option<(u32, u32)>,
    /// The ideal camera's horizontal field of view (default 60°).
    pub fov: Option<Angle>,
    /// Distance from the camera to the page centre or the marker board
    /// (default: a page fills 80 % of the frame; loose markers 1 m).
    pub camera_distance: Option<Length>,
    /// Rotation about the horizontal axis (positive: top edge towards the camera).
    pub tilt: Angle,
    /// Rotation about the vertical axis (positive: right edge towards the camera).
    pub pan: Angle,
    /// Rotation in the paper's plane, counter-clockwise as seen.
    pub roll: Angle,
    /// What is behind the paper (default: a table under a sheet, grey
    /// behind loose markers).
    pub background: Option<BackgroundKind>,
    /// Illumination ratio brightest:darkest across the frame.
    pub gradient: f64,
    /// Direction in which the light falls off (image angle, 0 = to the right).
    pub gradient_angle: Angle,
    /// Exposure (default 1, or 0.25 with `dark`).
    pub exposure: Option<f64>,
    /// A dark frame (exposure 0.25).
    pub dark: bool,
    /// Focus blur: Gaussian sigma, pixels.
    pub blur_px: f64,
    /// Motion blur: length of the smear, pixels.
    pub motion_blur_px: f64,
    /// Direction of the motion blur (image angle).
    pub motion_angle: Angle,
    /// Sensor noise: Gaussian sigma in grey levels.
    pub noise: f64,
    /// JPEG round trip at this quality (1-100).
    pub jpeg: Option<u8>,
    /// IDs of markers to put an ink blot on (over one ring sector).
    pub blot: Vec<u32>,
    /// Seed of noise, clutter and the scattered layout.
    pub seed: u64,
}

impl Default for SceneSpec {
    fn default() -> SceneSpec {
        SceneSpec {
            manifest: None,
            page: None,
            print_scale: None,
            target: TargetSpec::default(),
            ids: None,
            diameter: None,
            layout: None,
            camera: None,
            size: None,
            fov: None,
            camera_distance: None,
            tilt: Angle::from_degrees(0.0),
            pan: Angle::from_degrees(0.0),
            roll: Angle::from_degrees(0.0),
            background: None,
            gradient: 1.0,
            gradient_angle: Angle::from_degrees(0.0),
            exposure: None,
            dark: false,
            blur_px: 0.0,
            motion_blur_px: 0.0,
            motion_angle: Angle::from_degrees(0.0),
            noise: 0.0,
            jpeg: None,
            blot: Vec::new(),
            seed: 1,
        }
    }
}

/// The ideal camera's image size without `size`.
pub const DEFAULT_SIZE: (u32, u32) = (1920, 1080);
/// The ideal camera's field of view without `fov`, degrees.
pub const DEFAULT_FOV_DEG: f64 = 60.0;
/// Loose markers' diameter without `diameter`, mm.
pub const DEFAULT_DIAMETER_MM: f64 = 50.0;

impl SceneSpec {
    /// Checks every option and builds the scene.
    pub fn build(&self) -> Result<Scene, SpecError> {
        let camera = self.camera()?;
        let mut scene = Scene::new(camera);
        let (tilt, pan, roll) = (
            finite_angle("tilt", self.tilt)?,
            finite_angle("pan", self.pan)?,
            finite_angle("roll", self.roll)?,
        );
        let distance = self
            .camera_distance
            .map(|d| within("camera_distance", d.m(), limits::CAMERA_DISTANCE_M))
            .transpose()?;
        match &self.manifest {
            Some(path) => {
                self.refuse_loose_options()?;
                let manifest = Manifest::load(path).map_err(SpecError::general)?;
                let page_number = self.page.unwrap_or(1);
                if page_number == 0 || page_number > manifest.pages.max(1) {
                    return Err(SpecError::invalid(
                        "page",
                        format!("{} has no page {page_number}", path.display()),
                    ));
                }
                let [w, h] = manifest.page_size_mm;
                let distance =
                    distance.unwrap_or_else(|| layout::distance_to_fill(&camera, w, h, 0.8));
                let sheet_name = path
                    .file_stem()
                    .map(|s| s.to_string_lossy().into_owned())
                    .unwrap_or_default();
                let mut page = SheetPage::new(
                    manifest.clone(),
                    page_number,
                    layout::centred(distance, tilt, pan, roll),
                )
                .with_printed_text(&sheet_name);
                page.print_scale = within(
                    "print_scale",
                    self.print_scale.unwrap_or(1.0),
                    limits::PRINT_SCALE,
                )?;
                for &id in &self.blot {
                    let entry = manifest
                        .markers
                        .iter()
                        .find(|m| m.id == id && m.page == page_number)
                        .ok_or_else(|| {
                            SpecError::invalid(
                                "blot",
                                format!("no marker {id} on page {page_number}"),
                            )
                        })?;
                    let marker = SheetPage::marker_of(&manifest, entry);
                    page.blots
                        .extend(layout::ring_blots(&marker, entry.x_mm, entry.y_mm, false));
                }
                scene.objects.push(SceneObject::Page(page));
                scene.background = Background::Table;
            }
            None => {
                for (given, option) in [
                    (self.page.is_some(), "page"),
                    (self.print_scale.is_some(), "print_scale"),
                ] {
                    if given {
                        return Err(SpecError::of(
                            option,
                            Problem::Conflict(
                                "applies to a sheet's page: give the manifest".into(),
                            ),
                        ));
                    }
                }
                let Some(ids) = &self.ids else {
                    return Err(SpecError::general(Problem::Invalid(
                        "say what to show: a sheet's manifest, or the IDs of loose markers (and their family)".into(),
                    )));
                };
                within("ids", ids.len() as f64, limits::SCENE_MARKERS).map_err(|_| {
                    SpecError::invalid(
                        "ids",
                        format!("give between 1 and {} IDs", limits::SCENE_MARKERS.max),
                    )
                })?;
                let family = self.target.family()?;
                let diameter_mm = within(
                    "diameter",
                    self.diameter.map_or(DEFAULT_DIAMETER_MM, Length::mm),
                    limits::MARKER_DIAMETER_MM,
                )?;
                let markers = ids
                    .iter()
                    .map(|&id| {
                        let code = family.code(id).ok_or_else(|| {
                            SpecError::invalid(
                                "ids",
                                crate::render::sheet::id_range_error(&family, id).to_string(),
                            )
                        })?;
                        Ok((Marker::whycode(family.bits(), code, diameter_mm), id))
                    })
                    .collect::<Result<Vec<_>, SpecError>>()?;
                let distance = distance.unwrap_or(1.0);
                let mut loose = match self.layout.unwrap_or_default() {
                    Layout::Grid => {
                        layout::marker_grid(&markers, &layout::centred(distance, tilt, pan, roll))
                    }
                    Layout::Scatter => {
                        let max_tilt = if tilt != 0.0 {
                            tilt.abs()
                        } else {
                            40f64.to_radians()
                        };
                        let placed = layout::marker_scatter(
                            &camera, &markers, distance, max_tilt, self.seed,
                        );
                        // A scene missing markers asked for would pass for a
                        // detector that lost them.
                        if placed.len() < markers.len() {
                            return Err(SpecError::invalid(
                                "layout",
                                format!(
                                    "only {} of {} markers fit into the {}x{} view without overlapping ({} did not); \
                                     scatter fewer, make them smaller, move them further away or lay them out in a grid",
                                    placed.len(),
                                    markers.len(),
                                    camera.width,
                                    camera.height,
                                    markers.len() - placed.len()
                                ),
                            ));
                        }
                        placed
                    }
                };
                for &id in &self.blot {
                    let m = loose.iter_mut().find(|m| m.id == id).ok_or_else(|| {
                        SpecError::invalid("blot", format!("no marker {id} in the scene"))
                    })?;
                    let blots = layout::ring_blots(&m.marker, 0.0, 0.0, true);
                    m.blots.extend(blots);
                }
                scene
                    .objects
                    .extend(loose.into_iter().map(SceneObject::Marker));
                scene.background = Background::Uniform(0.45);
            }
        }
        if let Some(kind) = self.background {
            scene.background = kind.background();
        }
        scene.gradient = within("gradient", self.gradient, limits::LIGHT_GRADIENT)?;
        scene.gradient_angle = finite_angle("gradient_angle", self.gradient_angle)?;
        scene.exposure = match (self.exposure, self.dark) {
            (Some(_), true) => {
                return Err(SpecError::of(
                    "exposure",
                    Problem::Conflict("give an exposure or a dark frame, not both".into()),
                ))
            }
            (Some(e), false) => within("exposure", e, limits::EXPOSURE)?,
            (None, true) => 0.25,
            (None, false) => 1.0,
        };
        scene.focus_blur_px = within("blur", self.blur_px, limits::BLUR_PX)?;
        let motion = within("motion_blur", self.motion_blur_px, limits::BLUR_PX)?;
        if motion > 0.0 {
            scene.motion_blur = Some(MotionBlur {
                length_px: motion,
                angle: finite_angle("motion_angle", self.motion_angle)?,
            });
        }
        scene.noise = within("noise", self.noise, limits::NOISE_GREY_LEVELS)?;
        if let Some(q) = self.jpeg {
            within("jpeg", f64::from(q), limits::JPEG_QUALITY)?;
        }
        scene.jpeg_quality = self.jpeg;
        scene.seed = self.seed;
        Ok(scene)
    }

    /// The camera: the calibrated one, or the ideal one of `size` and `fov`.
    fn camera(&self) -> Result<Camera, SpecError> {
        if let Some(camera) = self.camera {
            for (given, option) in [(self.size.is_some(), "size"), (self.fov.is_some(), "fov")] {
                if given {
                    return Err(SpecError::of(
                        option,
                        Problem::Conflict(
                            "describes the ideal camera: leave it out with a calibrated one".into(),
                        ),
                    ));
                }
            }
            return Ok(camera);
        }
        let (w, h) = self.size.unwrap_or(DEFAULT_SIZE);
        for side in [w, h] {
            within("size", f64::from(side), limits::IMAGE_SIDE_PX)?;
        }
        let fov = within(
            "fov",
            self.fov.map_or(DEFAULT_FOV_DEG, Angle::degrees),
            limits::FIELD_OF_VIEW_DEG,
        )?;
        Ok(Camera::ideal(w, h, fov))
    }

    /// Loose markers' options make no sense with a sheet's page: refused
    /// rather than ignored.
    fn refuse_loose_options(&self) -> Result<(), SpecError> {
        let t = &self.target;
        let named = [
            (t.family.is_some() || t.family_file.is_some(), "family"),
            (t.bits.is_some(), "bits"),
            (t.distance.is_some(), "distance"),
            (t.legacy, "legacy"),
            (self.ids.is_some(), "ids"),
            (self.diameter.is_some(), "diameter"),
            (self.layout.is_some(), "layout"),
        ];
        for (given, option) in named {
            if given {
                return Err(SpecError::of(
                    option,
                    Problem::Conflict(
                        "describes loose markers: a sheet's manifest names its own".into(),
                    ),
                ));
            }
        }
        Ok(())
    }
}

fn finite_angle(option: &'static str, angle: Angle) -> Result<f64, SpecError> {
    let radians = angle.radians();
    if radians.is_finite() {
        Ok(radians)
    } else {
        Err(SpecError::invalid(option, "not a finite angle"))
    }
}
