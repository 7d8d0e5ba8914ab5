//! Camera calibration from photos of a printed sheet: the intrinsics (fx,
//! fy, cx, cy) and plumb_bob distortion (k1, k2, p1, p2, k3) that
//! [`crate::camera::Camera`] holds, from markers whose places the sheet's
//! manifest records.
//!
//! Each page seen in a photo is one view of a plane. The first camera comes
//! from the views' homographies (Zhang's method, principal point at the
//! image centre), then Levenberg–Marquardt moves the intrinsics, the
//! distortion and every view's pose together (`fit`).
//!
//! A circle's image is not an ellipse centred on the image of the circle's
//! centre: perspective moves the ellipse's centre, and a distorting lens
//! bends the outline. The first round takes the ellipses' centres; every
//! later round detects the markers again with the camera just found, so the
//! detector's pose stage (which undistorts the edge points and fits the
//! circle in 3D) reports each marker's projected centre, and fits again,
//! until the camera stops moving.

mod fit;
mod photos;

use nalgebra::Vector3;

use crate::camera::Camera;
use crate::detect::{Detection, Detector, DetectorConfig, Target};
use crate::family::MatchStatus;
use crate::manifest::Manifest;
use crate::parallel::prelude::*;
use crate::pose::{self, Pose};

pub use fit::NAMES as PARAMETER_NAMES;
pub use photos::{Preview, SheetPhotos};

/// Which of the lens's parameters the fit may move.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Freedom {
    /// Hold the principal point at the image centre.
    pub fix_principal_point: bool,
    /// Square pixels: fy = fx.
    pub fix_aspect: bool,
    /// Fit the tangential terms p1, p2 (zero otherwise).
    pub tangential: bool,
    /// Fit the sixth-order radial term k3 (zero otherwise).
    pub k3: bool,
}

impl Default for Freedom {
    fn default() -> Freedom {
        Freedom {
            fix_principal_point: false,
            fix_aspect: false,
            tangential: true,
            k3: true,
        }
    }
}

/// How to calibrate: what the fit may move and how the sheet was printed.
/// Built by [`crate::spec::CalibrateSpec`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CalibrationOptions {
    /// What the fit may move.
    pub freedom: Freedom,
    /// The scale the printer applied (1 for 100 %), about the page centre;
    /// a 97 % print read as 100 % biases the focal length by 3 %.
    pub print_scale: f64,
}

impl Default for CalibrationOptions {
    fn default() -> CalibrationOptions {
        CalibrationOptions {
            freedom: Freedom::default(),
            print_scale: 1.0,
        }
    }
}

/// The markers of one page seen in one photo: where the sheet has them
/// (metres in the board frame: the page's top-left corner, x along the top
/// edge, y down the page) and where the photo shows them (pixels).
#[derive(Debug, Clone, PartialEq)]
pub struct ViewPoints {
    /// The photo and page, as reports name the view.
    pub label: String,
    /// Page number in the manifest, from 1.
    pub page: u32,
    /// Marker IDs, one per point.
    pub ids: Vec<u32>,
    /// Marker centres on the page, metres.
    pub plane: Vec<[f64; 2]>,
    /// Marker centres in the photo, pixels.
    pub pixels: Vec<[f64; 2]>,
}

/// Why no calibration was written. Each message is one line.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CalibrationError {
    /// Legacy WhyCon sheets have no IDs to tell the markers apart.
    #[error("the sheet has legacy WhyCon markers without IDs; calibration matches markers by ID")]
    Legacy,
    /// The manifest's family cannot be generated.
    #[error("the manifest's family: {0}")]
    Family(String),
    /// Not every photo has the same size.
    #[error("{name} is {}x{} but {first} is {}x{}: calibrate one camera at one resolution", size[0], size[1], first_size[0], first_size[1])]
    ImageSizes {
        /// The first photo.
        first: String,
        /// Its size.
        first_size: [u32; 2],
        /// A photo of another size.
        name: String,
        /// Its size.
        size: [u32; 2],
    },
    /// One photo given twice (or two copies of it): it would count as two
    /// views, passing the views needed and shrinking every standard
    /// deviation with nothing new measured.
    #[error("{second} is the same photo as {first}: each view counts once; give photos taken from different places")]
    SameView {
        /// The photo first given.
        first: String,
        /// The same photo again.
        second: String,
    },
    /// Fewer views than a calibration needs.
    #[error("only {usable} usable view{} ({MIN_VIEWS} needed){}", if *usable == 1 { "" } else { "s" }, skipped_text(skipped))]
    TooFewViews {
        /// Views with enough markers.
        usable: usize,
        /// The others, and why.
        skipped: Vec<String>,
    },
    /// No view is tilted enough to tell the focal length from the distance.
    #[error("all views are nearly fronto-parallel{}: the focal length cannot be told from the distance; tilt the sheet 20-45° in some photos", largest_tilt.map(|t| format!(" (largest tilt {t:.1}°)")).unwrap_or_default())]
    FrontoParallel {
        /// The largest tilt of a view, degrees, when the views gave a camera at all.
        largest_tilt: Option<f64>,
    },
    /// The points of a view fit no plane-to-image map.
    #[error("{0}: its markers fit no plane-to-image map (all in a line?)")]
    Degenerate(String),
    /// More parameters than measurements.
    #[error("{points} points cannot fix {parameters} parameters")]
    TooFewPoints {
        /// Points measured.
        points: usize,
        /// Parameters to fit.
        parameters: usize,
    },
    /// The views leave a parameter free to take almost any value.
    #[error("the views leave {parameter} undetermined (standard deviation {std_dev:.3e}); add views tilted different ways that reach the image's corners, or hold it fixed")]
    Undetermined {
        /// The parameter's name (fx, ..., k3).
        parameter: &'static str,
        /// Its standard deviation after the fit.
        std_dev: f64,
    },
    /// The fit ran away to a camera no lens gives.
    #[error("the fit did not converge to a real lens: check the manifest is the printed sheet's and the printed scale")]
    Diverged,
}

fn skipped_text(skipped: &[String]) -> String {
    if skipped.is_empty() {
        String::new()
    } else {
        format!(": {}", skipped.join("; "))
    }
}

/// Views a calibration needs at least.
pub const MIN_VIEWS: usize = 3;
/// Markers a view needs at least (a homography takes 4; a few more make
/// one wrong centre stand out).
pub const MIN_MARKERS_PER_VIEW: usize = 6;
/// A view tilted less than this (degrees) is fronto-parallel.
const FRONTO_PARALLEL_DEG: f64 = 8.0;
/// Tilts about an axis below this (degrees) leave that direction unmeasured.
const USEFUL_TILT_DEG: f64 = 15.0;
/// Rounds of detection with the camera found so far.
const MAX_ROUNDS: usize = 5;
/// The camera moved less than this (pixels, mean over the image) in a round.
const SETTLED_PX: f64 = 0.001;

/// One view in the report.
#[derive(Debug, Clone, PartialEq)]
pub struct ViewReport {
    /// The photo and page.
    pub label: String,
    /// Markers used.
    pub markers: usize,
    /// Markers whose centre disagreed with the rest, by ID.
    pub rejected: Vec<u32>,
    /// Reprojection RMS, pixels.
    pub rms: f64,
    /// Angle between the sheet's normal and the optical axis, degrees.
    pub tilt_deg: f64,
    /// Board → camera rotation.
    pub rotation: nalgebra::Matrix3<f64>,
    /// Board origin in the camera frame, metres.
    pub position: Vector3<f64>,
}

/// Where in the image the markers were: counts per cell of a 3×3 grid.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Coverage {
    /// Points per cell, row by row from the top-left.
    pub counts: [[usize; 3]; 3],
}

impl Coverage {
    /// The markers of `views` per ninth of a `width` x `height` image.
    pub fn of(views: &[ViewPoints], width: u32, height: u32) -> Coverage {
        let (w, h) = (f64::from(width), f64::from(height));
        let mut counts = [[0usize; 3]; 3];
        for view in views {
            for p in &view.pixels {
                let col = ((3.0 * (p[0] + 0.5) / w).floor().max(0.0) as usize).min(2);
                let row = ((3.0 * (p[1] + 0.5) / h).floor().max(0.0) as usize).min(2);
                counts[row][col] += 1;
            }
        }
        Coverage { counts }
    }
}

/// A calibration and how far to trust it.
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// The camera found.
    pub camera: Camera,
    /// Reprojection RMS over every point, pixels.
    pub rms: f64,
    /// Each view used.
    pub views: Vec<ViewReport>,
    /// Photos and pages left out, and why.
    pub skipped: Vec<String>,
    /// Standard deviation of fx, fy, cx, cy, k1, k2, p1, p2, k3 (0 when held).
    pub std_devs: [f64; 9],
    /// Which parameters were fitted.
    pub fitted: [bool; 9],
    /// Where the points were.
    pub coverage: Coverage,
    /// What the photos lack, in words.
    pub advice: Vec<String>,
    /// Rounds of detection (the first with ellipse centres).
    pub rounds: usize,
}

/// Every marker of page `page` in the board frame (metres: the page's
/// top-left corner, x along the top edge, y down the page), printed at
/// `print_scale` about the page centre.
pub fn board_points(manifest: &Manifest, page: u32, print_scale: f64) -> Vec<(u32, [f64; 2])> {
    let [w, h] = manifest.page_size_mm;
    manifest
        .markers
        .iter()
        .filter(|m| m.page == page)
        .map(|m| {
            let x = w / 2.0 + print_scale * (m.x_mm - w / 2.0);
            let y = h / 2.0 + print_scale * (m.y_mm - h / 2.0);
            (m.id, [x / 1000.0, y / 1000.0])
        })
        .collect()
}

/// How a round of [`calibrate`] read the markers' centres: through a
/// camera, with the markers posed at one diameter.
#[derive(Debug, Clone, Copy)]
pub struct Posed<'a> {
    /// The camera the detector posed the markers with.
    pub camera: &'a Camera,
    /// The diameter it posed them at, metres.
    pub diameter_m: f64,
}

/// The views in one photo's detections: its markers matched to the
/// manifest by ID, page by page. An ID read twice in one photo is left out.
///
/// With `posed`, detections without a pose (whose centre is the ellipse's)
/// are left out, and each marker's centre is that of whichever of its two
/// pose solutions faces the page: every marker of a page lies in its
/// plane, and the page's normal is the one most of its markers agree on.
/// On a small marker seen nearly face-on the detector's own pick is close
/// to a coin toss, and the wrong one's centre is off by a few tenths of a
/// pixel, enough to bend the lens found.
pub fn observe(
    manifest: &Manifest,
    photo: &str,
    detections: &[Detection],
    print_scale: f64,
    posed: Option<Posed<'_>>,
) -> Vec<ViewPoints> {
    let read = |d: &&Detection| {
        matches!(d.status, Some(MatchStatus::Exact | MatchStatus::Corrected))
            && (posed.is_none() || d.pose.is_some())
    };
    let mut views = Vec::new();
    for page in 1..=manifest.pages {
        let mut found: Vec<(u32, [f64; 2], &Detection)> = Vec::new();
        for (id, plane) in board_points(manifest, page, print_scale) {
            let mut seen = detections.iter().filter(read).filter(|d| d.id == id);
            if let (Some(d), None) = (seen.next(), seen.next()) {
                found.push((id, plane, d));
            }
        }
        if found.is_empty() {
            continue;
        }
        let mut view = ViewPoints {
            label: if manifest.pages > 1 {
                format!("{photo} page {page}")
            } else {
                photo.to_string()
            },
            page,
            ids: Vec::new(),
            plane: Vec::new(),
            pixels: Vec::new(),
        };
        let centres: Vec<Option<(f64, f64)>> = match posed {
            Some(posed) => {
                let poses: Vec<&Pose> = found
                    .iter()
                    .filter_map(|(_, _, d)| d.pose.as_ref())
                    .collect();
                centres_on_one_plane(posed, &poses)
            }
            None => found.iter().map(|(_, _, d)| Some((d.u, d.v))).collect(),
        };
        for ((id, plane, _), centre) in found.into_iter().zip(centres) {
            if let Some((u, v)) = centre {
                view.ids.push(id);
                view.plane.push(plane);
                view.pixels.push([u, v]);
            }
        }
        views.push(view);
    }
    views
}

/// The projected centres of markers printed on one plane, from their
/// poses: each takes whichever of its two pose solutions faces the plane,
/// whose normal is the one most of the markers agree on.
fn centres_on_one_plane(posed: Posed<'_>, poses: &[&Pose]) -> Vec<Option<(f64, f64)>> {
    const AGREE_RAD: f64 = 0.05;
    let normals: Vec<Vector3<f64>> = poses
        .iter()
        .map(|p| p.rotation.column(2).into_owned())
        .collect();
    let score = |n: &Vector3<f64>| {
        let angles = normals.iter().map(|m| m.angle(n));
        let agreeing = angles.clone().filter(|&a| a < AGREE_RAD).count();
        (agreeing, -angles.sum::<f64>())
    };
    let Some(plane_normal) = normals
        .iter()
        .map(|n| (score(n), n))
        .max_by(|(a, _), (b, _)| a.0.cmp(&b.0).then(a.1.total_cmp(&b.1)))
        .map(|(_, n)| *n)
    else {
        return Vec::new();
    };
    poses
        .iter()
        .map(|p| {
            let (circle, _) = pose::facing_plane(p, posed.diameter_m / 2.0, &plane_normal)?;
            posed.camera.project(&circle.center)
        })
        .collect()
}

/// Mean and worst distance, pixels, between where two cameras put the
/// same viewing ray, over every pixel of a grid across the whole image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Disagreement {
    /// Mean over the grid, pixels.
    pub mean: f64,
    /// Largest, pixels.
    pub worst: f64,
}

/// How far apart `a` and `b` map the rays through `a`'s pixels: each
/// pixel of a 4-pixel grid over the image is taken back to its ray through
/// `a` and projected again through `b`.
pub fn disagreement(a: &Camera, b: &Camera) -> Disagreement {
    let (w, h) = (f64::from(a.width), f64::from(a.height));
    let step = 4.0;
    let (mut sum, mut worst, mut n) = (0.0, 0.0f64, 0usize);
    let mut v = -0.5;
    while v <= h - 0.5 {
        let mut u = -0.5;
        while u <= w - 0.5 {
            let (x, y) = a.undistort(u, v);
            let (pu, pv) = b.distort_normalized(x, y);
            let d = (pu - u).hypot(pv - v);
            sum += d;
            worst = worst.max(d);
            n += 1;
            u += step;
        }
        v += step;
    }
    Disagreement {
        mean: sum / n as f64,
        worst,
    }
}

/// Calibrates from views already measured (no centre correction; see
/// [`calibrate`] for photos), `width` x `height` pixels.
pub fn calibrate_views(
    views: Vec<ViewPoints>,
    width: u32,
    height: u32,
    options: &CalibrationOptions,
) -> Result<Calibration, CalibrationError> {
    let mut skipped = Vec::new();
    let mut usable = Vec::new();
    for view in views {
        if view.ids.len() < MIN_MARKERS_PER_VIEW {
            skipped.push(format!(
                "{}: {} marker{} read ({MIN_MARKERS_PER_VIEW} needed)",
                view.label,
                view.ids.len(),
                if view.ids.len() == 1 { "" } else { "s" }
            ));
        } else {
            usable.push(view);
        }
    }
    if usable.len() < MIN_VIEWS {
        return Err(CalibrationError::TooFewViews {
            usable: usable.len(),
            skipped,
        });
    }
    let freedom = options.freedom;
    let (initial, poses) = fit::initial_guess(&usable, &freedom, width, height)?;
    let largest_tilt = poses
        .iter()
        .map(|p| p.tilt().to_degrees())
        .fold(0.0, f64::max);
    if largest_tilt < FRONTO_PARALLEL_DEG {
        return Err(CalibrationError::FrontoParallel {
            largest_tilt: Some(largest_tilt),
        });
    }
    let mut result = fit::refine(&usable, &initial, &poses, &freedom)?;
    // Centres that disagree with the rest (a misread ID, a smudge) are
    // dropped and the fit run again, until none stands out.
    let mut rejected: Vec<Vec<u32>> = vec![Vec::new(); usable.len()];
    for _ in 0..3 {
        let mut norms: Vec<f64> = result
            .residuals
            .iter()
            .flatten()
            .map(|r| r[0].hypot(r[1]))
            .collect();
        norms.sort_by(f64::total_cmp);
        let median = norms[norms.len() / 2];
        let limit = (6.0 * median).max(0.2);
        let mut any = false;
        for (k, view) in usable.iter_mut().enumerate() {
            let keep: Vec<bool> = result.residuals[k]
                .iter()
                .map(|r| r[0].hypot(r[1]) <= limit)
                .collect();
            if keep.iter().all(|&k| k) {
                continue;
            }
            any = true;
            let mut at = 0;
            let (ids, plane, pixels) = (&mut view.ids, &mut view.plane, &mut view.pixels);
            ids.retain(|id| {
                let k2 = keep[at];
                at += 1;
                if !k2 {
                    rejected[k].push(*id);
                }
                k2
            });
            let mut at = 0;
            plane.retain(|_| {
                at += 1;
                keep[at - 1]
            });
            let mut at = 0;
            pixels.retain(|_| {
                at += 1;
                keep[at - 1]
            });
        }
        if !any {
            break;
        }
        if usable.iter().any(|v| v.ids.len() < 4) {
            break;
        }
        result = fit::refine(&usable, &result.camera, &result.poses, &freedom)?;
    }
    check_determined(&result, &freedom, width, height)?;
    // A loose parameter is named above; a fit that ran off to a camera
    // no lens gives although every parameter is pinned down is refused here.
    if result.camera.check_plausible().is_err() {
        return Err(CalibrationError::Diverged);
    }
    Ok(report(usable, result, rejected, skipped, &freedom))
}

/// Refuses a fit whose parameters the views leave loose: a focal length
/// known to worse than 2 %, a principal point to worse than 5 % of the
/// image, distortion terms whose spread is as large as any lens's value.
fn check_determined(
    fit: &fit::Fit,
    freedom: &Freedom,
    width: u32,
    height: u32,
) -> Result<(), CalibrationError> {
    let camera = &fit.camera;
    let limits = [
        0.02 * camera.fx,
        0.02 * camera.fy,
        0.05 * f64::from(width),
        0.05 * f64::from(height),
        0.5,
        2.0,
        0.02,
        0.02,
        10.0,
    ];
    let held = |k: usize| {
        (k == 1 && freedom.fix_aspect)
            || ((k == 2 || k == 3) && freedom.fix_principal_point)
            || ((k == 6 || k == 7) && !freedom.tangential)
            || (k == 8 && !freedom.k3)
    };
    for (k, (&sd, &limit)) in fit.std_devs.iter().zip(&limits).enumerate() {
        // NaN counts as undetermined.
        if !held(k) && (sd.is_nan() || sd > limit) {
            return Err(CalibrationError::Undetermined {
                parameter: fit::NAMES[k],
                std_dev: sd,
            });
        }
    }
    Ok(())
}

fn rms(residuals: &[[f64; 2]]) -> f64 {
    if residuals.is_empty() {
        return 0.0;
    }
    (residuals
        .iter()
        .map(|r| r[0] * r[0] + r[1] * r[1])
        .sum::<f64>()
        / residuals.len() as f64)
        .sqrt()
}

fn report(
    views: Vec<ViewPoints>,
    fit: fit::Fit,
    rejected: Vec<Vec<u32>>,
    skipped: Vec<String>,
    freedom: &Freedom,
) -> Calibration {
    let camera = fit.camera;
    let coverage = Coverage::of(&views, camera.width, camera.height);
    let counts = coverage.counts;
    let all: Vec<[f64; 2]> = fit.residuals.iter().flatten().copied().collect();
    let reports: Vec<ViewReport> = views
        .iter()
        .zip(&fit.poses)
        .zip(&fit.residuals)
        .zip(rejected)
        .map(|(((view, pose), residuals), rejected)| ViewReport {
            label: view.label.clone(),
            markers: view.ids.len(),
            rejected,
            rms: rms(residuals),
            tilt_deg: pose.tilt().to_degrees(),
            rotation: pose.matrix(),
            position: pose.translation,
        })
        .collect();
    let mut advice = Vec::new();
    // How far each view turns the sheet about the camera's vertical (y)
    // and horizontal (x) axes: its normal's lean in x and in y.
    let lean = |axis: usize| {
        fit.poses
            .iter()
            .map(|p| {
                let n = p.matrix().column(2).into_owned();
                n[axis].abs().atan2(n.z.abs()).to_degrees()
            })
            .fold(0.0, f64::max)
    };
    if lean(0) < USEFUL_TILT_DEG {
        advice.push(
            "no view tilted about the vertical axis: turn the sheet's left or right edge towards the camera"
                .to_string(),
        );
    }
    if lean(1) < USEFUL_TILT_DEG {
        advice.push(
            "no view tilted about the horizontal axis: turn the sheet's top or bottom edge towards the camera"
                .to_string(),
        );
    }
    let corners: Vec<&str> = [
        (0, 0, "top-left"),
        (0, 2, "top-right"),
        (2, 0, "bottom-left"),
        (2, 2, "bottom-right"),
    ]
    .iter()
    .filter(|(r, c, _)| counts[*r][*c] == 0)
    .map(|(_, _, name)| *name)
    .collect();
    if !corners.is_empty() {
        advice.push(format!(
            "corners of the image not covered ({}): the distortion there is extrapolated",
            corners.join(", ")
        ));
    }
    if views.len() < 8 {
        advice.push(format!(
            "only {} views: 10-20 views give a steadier fit",
            views.len()
        ));
    }
    let overall = rms(&all);
    if overall > 0.5 {
        advice.push(format!(
            "reprojection RMS {overall:.2} px is high: blurred photos, a sheet not lying flat, or a wrong printed scale"
        ));
    }
    let fitted = [
        true,
        !freedom.fix_aspect,
        !freedom.fix_principal_point,
        !freedom.fix_principal_point,
        true,
        true,
        freedom.tangential,
        freedom.tangential,
        freedom.k3,
    ];
    Calibration {
        camera,
        rms: overall,
        views: reports,
        skipped,
        std_devs: fit.std_devs,
        fitted,
        coverage,
        advice,
        rounds: 1,
    }
}

/// The detector every round of [`calibrate`] reads the photos with: the
/// manifest's family, reporting the markers' centres through `camera` when
/// one is given (the ellipses' centres without). A front end that takes
/// photos one at a time detects each with it (no camera) and shows, as it
/// goes, the views [`observe`] finds, their [`Coverage`] and a first fit
/// by [`calibrate_views`], before it calibrates them all.
pub fn sheet_detector(
    manifest: &Manifest,
    camera: Option<Camera>,
) -> Result<DetectorConfig, CalibrationError> {
    let family_ref = match manifest.family {
        Some(f) if !manifest.legacy => f,
        _ => return Err(CalibrationError::Legacy),
    };
    let family = crate::family::Family::generate(family_ref.bits, family_ref.distance)
        .map_err(|e| CalibrationError::Family(e.to_string()))?;
    // Any diameter gives the same projected centre (a circle's cone fixes
    // the direction to its centre whatever its size); the manifest's first
    // keeps the pose in plausible units.
    let diameter = manifest.markers.first().map(|m| m.diameter_mm / 1000.0);
    Ok(DetectorConfig {
        target: Target::WhyCode(family),
        max_markers: manifest.markers.len() * 2 + 64,
        tracking: false,
        camera,
        diameter_m: camera.and(diameter),
        // A calibration is only as good as the centres it is fitted to.
        fine_edges: true,
        ..Default::default()
    })
}

fn views_in(
    config: &DetectorConfig,
    manifest: &Manifest,
    name: &str,
    image: &image::GrayImage,
    print_scale: f64,
) -> Vec<ViewPoints> {
    let detections = Detector::new(config.clone()).detect(image);
    let posed = config
        .camera
        .as_ref()
        .zip(config.diameter_m)
        .map(|(camera, diameter_m)| Posed { camera, diameter_m });
    let views = observe(manifest, name, &detections, print_scale, posed);
    if !views.is_empty() {
        return views;
    }
    // A photo that gives no view at all is still named among those left
    // out, with what it does show: a sheet of another family or other IDs
    // reads as rings the manifest does not list.
    let others = detections.iter().filter(|d| d.id != 0).count();
    let unknown = detections.len() - others;
    let label = if detections.is_empty() {
        format!("{name} (no marker found)")
    } else {
        format!(
            "{name} (none of this sheet's markers: {others} of other IDs, {unknown} without an ID; \
             a photo of another sheet, or printed in another family?)"
        )
    };
    vec![ViewPoints {
        label,
        page: 0,
        ids: Vec::new(),
        plane: Vec::new(),
        pixels: Vec::new(),
    }]
}

/// Calibrates a camera from photos (name, grey image) of the sheet
/// `manifest` describes, all of one size: detect, fit, then detect again
/// with the camera found until it settles (see the module's notes).
pub fn calibrate(
    manifest: &Manifest,
    photos: &[(String, image::GrayImage)],
    options: &CalibrationOptions,
) -> Result<Calibration, CalibrationError> {
    let Some((first, first_image)) = photos.first() else {
        return Err(CalibrationError::TooFewViews {
            usable: 0,
            skipped: Vec::new(),
        });
    };
    let (width, height) = first_image.dimensions();
    if let Some((name, image)) = photos
        .iter()
        .find(|(_, i)| i.dimensions() != (width, height))
    {
        return Err(CalibrationError::ImageSizes {
            first: first.clone(),
            first_size: [width, height],
            name: name.clone(),
            size: [image.width(), image.height()],
        });
    }
    let mut pixels_seen: std::collections::HashMap<&[u8], &String> =
        std::collections::HashMap::new();
    for (name, image) in photos {
        if let Some(first) = pixels_seen.insert(image.as_raw(), name) {
            return Err(CalibrationError::SameView {
                first: first.clone(),
                second: name.clone(),
            });
        }
    }
    let views_through = |camera: Option<Camera>| -> Result<Vec<ViewPoints>, CalibrationError> {
        let config = sheet_detector(manifest, camera)?;
        let per_photo: Vec<Vec<ViewPoints>> = photos
            .par_iter()
            .map(|(name, image)| views_in(&config, manifest, name, image, options.print_scale))
            .collect();
        Ok(per_photo.into_iter().flatten().collect())
    };
    let mut result = calibrate_views(views_through(None)?, width, height, options)?;
    let mut rounds = 1;
    while rounds < MAX_ROUNDS {
        let next = calibrate_views(views_through(Some(result.camera))?, width, height, options)?;
        rounds += 1;
        let moved = disagreement(&result.camera, &next.camera).mean;
        result = next;
        if moved < SETTLED_PX {
            break;
        }
    }
    result.rounds = rounds;
    result.camera = to_written_precision(result.camera);
    Ok(result)
}

/// The camera at the precision calibration files carry: 1e-4 px for the
/// focal lengths and principal point, 1e-6 for the distortion terms. That
/// is a hundred times finer than the fit's spread, and coarse enough
/// that the command line, Python and the browser page write the same
/// bytes for the same photos (WebAssembly rounds the last bits of sin, cos
/// and atan2 its own way, and those bits reach the fit's last digits; what
/// finer rounding gave: docs/calibration.md, "Written precision").
fn to_written_precision(camera: Camera) -> Camera {
    Camera {
        fx: rounded(camera.fx, 4),
        fy: rounded(camera.fy, 4),
        cx: rounded(camera.cx, 4),
        cy: rounded(camera.cy, 4),
        distortion: camera.distortion.map(|d| rounded(d, 6)),
        ..camera
    }
}

/// A calibration's report as JSON writes it (see [`Calibration::to_json`]).
#[derive(serde::Serialize)]
struct Written<'a> {
    rms_px: f64,
    rounds: usize,
    views: Vec<WrittenView<'a>>,
    skipped: &'a [String],
    parameters: Vec<WrittenParameter>,
    coverage: [[usize; 3]; 3],
    advice: &'a [String],
}

#[derive(serde::Serialize)]
struct WrittenView<'a> {
    label: &'a str,
    markers: usize,
    rejected: &'a [u32],
    rms_px: f64,
    tilt_deg: f64,
    position: [f64; 3],
    rotation: [[f64; 3]; 3],
}

#[derive(serde::Serialize)]
struct WrittenParameter {
    name: &'static str,
    value: f64,
    /// None when the parameter was held.
    std_dev: Option<f64>,
}

/// Rounded for the report: far finer than the fit's spread, and coarse
/// enough that the command line and the browser page (whose WebAssembly
/// rounds the last bits of sin and cos its own way) write the same text.
fn rounded(value: f64, decimals: i32) -> f64 {
    let scale = 10f64.powi(decimals);
    (value * scale).round() / scale
}

impl Calibration {
    /// The report as JSON, for programs (Python's `calibrate`, the browser
    /// page): overall and per-view RMS (pixels), each view's tilt (degrees)
    /// and pose (board → camera, metres), the photos skipped, every
    /// parameter with its standard deviation (`null` when held), markers
    /// per ninth of the image (rows from the top) and the advice. The camera
    /// itself is the calibration file's.
    pub fn to_json(&self) -> String {
        let values = fit::values(&self.camera);
        let written = Written {
            rms_px: rounded(self.rms, 4),
            rounds: self.rounds,
            views: self
                .views
                .iter()
                .map(|v| WrittenView {
                    label: &v.label,
                    markers: v.markers,
                    rejected: &v.rejected,
                    rms_px: rounded(v.rms, 4),
                    tilt_deg: rounded(v.tilt_deg, 3),
                    position: std::array::from_fn(|k| rounded(v.position[k], 6)),
                    rotation: std::array::from_fn(|r| {
                        std::array::from_fn(|col| rounded(v.rotation[(r, col)], 6))
                    }),
                })
                .collect(),
            skipped: &self.skipped,
            parameters: PARAMETER_NAMES
                .iter()
                .enumerate()
                .map(|(k, &name)| {
                    let decimals = if k < 4 { 6 } else { 9 };
                    WrittenParameter {
                        name,
                        value: rounded(values[k], decimals),
                        std_dev: self.fitted[k].then(|| rounded(self.std_devs[k], decimals)),
                    }
                })
                .collect(),
            coverage: self.coverage.counts,
            advice: &self.advice,
        };
        serde_json::to_string_pretty(&written).expect("a calibration report serialises")
    }

    /// The report as text for people: each view, the fit, its spread,
    /// where the points were and what the photos lack.
    pub fn to_table(&self) -> String {
        use std::fmt::Write;
        let mut out = String::new();
        let width = self
            .views
            .iter()
            .map(|v| v.label.chars().count())
            .max()
            .unwrap_or(4)
            .max(4);
        let _ = writeln!(out, "{:<width$}  markers  rms px   tilt", "view");
        for v in &self.views {
            let _ = write!(
                out,
                "{:<width$}  {:>7}  {:>6.3}  {:>5.1}°",
                v.label, v.markers, v.rms, v.tilt_deg
            );
            if !v.rejected.is_empty() {
                let ids: Vec<String> = v.rejected.iter().map(u32::to_string).collect();
                let _ = write!(out, "  rejected ID {}", ids.join(", "));
            }
            out.push('\n');
        }
        for s in &self.skipped {
            let _ = writeln!(out, "skipped {s}");
        }
        let points: usize = self.views.iter().map(|v| v.markers).sum();
        let _ = writeln!(
            out,
            "overall RMS {:.3} px over {points} markers in {} views ({} rounds of detection)",
            self.rms,
            self.views.len(),
            self.rounds
        );
        let values = fit::values(&self.camera);
        for (k, name) in PARAMETER_NAMES.iter().enumerate() {
            let precision = if k < 4 { 3 } else { 6 };
            if self.fitted[k] {
                let _ = writeln!(
                    out,
                    "{name:>2} = {:>12.precision$} ± {:.precision$}",
                    values[k], self.std_devs[k]
                );
            } else {
                let _ = writeln!(out, "{name:>2} = {:>12.precision$} (held)", values[k]);
            }
        }
        let _ = writeln!(out, "markers per ninth of the image:");
        for row in &self.coverage.counts {
            let _ = writeln!(out, "  {:>5} {:>5} {:>5}", row[0], row[1], row[2]);
        }
        for a in &self.advice {
            let _ = writeln!(out, "advice: {a}");
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn true_camera() -> Camera {
        Camera {
            fx: 1010.0,
            fy: 1008.0,
            cx: 645.0,
            cy: 478.0,
            distortion: [-0.26, 0.09, 0.0008, -0.0005, -0.015],
            width: 1280,
            height: 960,
        }
    }

    /// A 5×7 grid of points on an A4 page seen from `n` poses.
    fn synthetic(camera: &Camera, poses: &[(f64, f64, f64, [f64; 3])]) -> Vec<ViewPoints> {
        poses
            .iter()
            .enumerate()
            .map(|(k, &(tilt, pan, roll, at))| {
                let placement = crate::simulate::Placement::viewed(
                    Vector3::from(at),
                    tilt.to_radians(),
                    pan.to_radians(),
                    roll.to_radians(),
                );
                let mut view = ViewPoints {
                    label: format!("view {k}"),
                    page: 1,
                    ids: Vec::new(),
                    plane: Vec::new(),
                    pixels: Vec::new(),
                };
                for i in 0..5 {
                    for j in 0..7 {
                        let (x, y) = (0.025 + 0.04 * f64::from(i), 0.03 + 0.04 * f64::from(j));
                        // Page frame (y down, z into the page) to the
                        // simulator's (centre, y up, z out).
                        let p =
                            placement.to_camera_mm(1000.0 * (x - 0.105), -1000.0 * (y - 0.1485));
                        let (u, v) = camera.project(&p).unwrap();
                        view.ids.push(view.ids.len() as u32);
                        view.plane.push([x, y]);
                        view.pixels.push([u, v]);
                    }
                }
                view
            })
            .collect()
    }

    fn spread_poses() -> Vec<(f64, f64, f64, [f64; 3])> {
        vec![
            (25.0, 0.0, 5.0, [0.0, 0.0, 0.45]),
            (-20.0, 15.0, -10.0, [-0.08, -0.06, 0.4]),
            (10.0, -30.0, 20.0, [0.08, 0.06, 0.42]),
            (30.0, 25.0, 0.0, [0.09, -0.07, 0.5]),
            (-25.0, -20.0, 40.0, [-0.09, 0.07, 0.5]),
            (5.0, 35.0, -30.0, [0.0, 0.08, 0.45]),
        ]
    }

    #[test]
    fn exact_points_give_the_camera_back() {
        let camera = true_camera();
        let views = synthetic(&camera, &spread_poses());
        let result = calibrate_views(views, 1280, 960, &CalibrationOptions::default()).unwrap();
        let d = disagreement(&camera, &result.camera);
        assert!(d.worst < 1e-4, "{d:?} {:?}", result.camera);
        assert!(result.rms < 1e-6, "{}", result.rms);
    }

    #[test]
    fn fronto_parallel_views_are_refused() {
        let camera = true_camera();
        let poses: Vec<_> = spread_poses()
            .into_iter()
            .map(|(_, _, roll, at)| (0.0, 0.0, roll, at))
            .collect();
        let err = calibrate_views(
            synthetic(&camera, &poses),
            1280,
            960,
            &CalibrationOptions::default(),
        )
        .unwrap_err();
        assert!(
            matches!(err, CalibrationError::FrontoParallel { .. }),
            "{err}"
        );
    }

    #[test]
    fn a_sheet_small_in_the_middle_leaves_the_lens_undetermined() {
        let camera = true_camera();
        // Far away and small: the points span a tenth of the image, where
        // the higher radial terms change nothing measurable.
        let poses: Vec<_> = spread_poses()
            .into_iter()
            .map(|(tilt, pan, roll, at)| (tilt, pan, roll, [at[0] * 0.1, at[1] * 0.1, 4.0]))
            .collect();
        let mut views = synthetic(&camera, &poses);
        let mut rng = crate::math::Pcg32::new(1, 2);
        for view in &mut views {
            for p in &mut view.pixels {
                p[0] += 0.05 * rng.gaussian();
                p[1] += 0.05 * rng.gaussian();
            }
        }
        let err = calibrate_views(views, 1280, 960, &CalibrationOptions::default()).unwrap_err();
        assert!(
            matches!(err, CalibrationError::Undetermined { .. }),
            "{err}"
        );
        // Far and small, the focal length is as loose as the distortion:
        // the first loose parameter is named.
        let text = err.to_string();
        assert!(
            text.starts_with("the views leave ") && !text.contains('\n'),
            "{text}"
        );
    }

    #[test]
    fn two_views_are_refused() {
        let camera = true_camera();
        let err = calibrate_views(
            synthetic(&camera, &spread_poses()[..2]),
            1280,
            960,
            &CalibrationOptions::default(),
        )
        .unwrap_err();
        assert!(
            err.to_string()
                .starts_with("only 2 usable views (3 needed)"),
            "{err}"
        );
    }
}
