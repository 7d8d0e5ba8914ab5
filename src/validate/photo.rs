//! Checking one photo: its detections ID-matched to each page of the
//! manifest, the page located by a robust homography, every printed marker
//! classified by what was detected where the homography puts it, and the
//! printed scale measured against the paper's edges.

use super::scale::{self, PixelModel, ScaleMeasurement};
use crate::camera::Camera;
use crate::manifest::{Manifest, PrintedMarker};
use crate::math::homography::{fit_robust, Correspondence, Homography};
use crate::math::Ellipse;
use image::GrayImage;
use serde::Serialize;

/// A detected marker as validation needs it (pixel coordinates of the
/// photo, origin at the top-left pixel centre).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Observation {
    /// Decoded ID, 0 when the ring did not read as a family member.
    pub id: u32,
    /// Centre column, pixels.
    pub u: f64,
    /// Centre row, pixels.
    pub v: f64,
    /// Semi-major axis of the outline, pixels.
    pub semi_major: f64,
    /// Semi-minor axis of the outline, pixels.
    pub semi_minor: f64,
    /// Direction of the major axis, atan2(dv, du).
    pub angle: f64,
    /// Image direction of the marker's +x axis, when the ring gave one.
    pub yaw: Option<f64>,
}

impl Observation {
    /// The detected outline of the black disc.
    pub fn outline(&self) -> Ellipse {
        Ellipse {
            u: self.u,
            v: self.v,
            semi_major: self.semi_major,
            semi_minor: self.semi_minor,
            angle: self.angle,
        }
    }
}

impl From<&crate::detect::Detection> for Observation {
    fn from(d: &crate::detect::Detection) -> Observation {
        Observation {
            id: d.id,
            u: d.u,
            v: d.v,
            semi_major: d.axes[0],
            semi_minor: d.axes[1],
            angle: d.angle,
            yaw: d.yaw,
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
/// What became of one printed marker in a photo.
pub enum MarkerStatus {
    /// Detected where it was printed, reading as its own ID.
    Found,
    /// Detected where it was printed, reading as another ID.
    Misread,
    /// Detected where it was printed, but the ring did not read.
    Unidentified,
    /// Its place is in the photo, but nothing was detected there.
    Missing,
    /// Its place is outside the photo (or its page was not located).
    NotInView,
}

impl MarkerStatus {
    pub(super) fn rank(self) -> u8 {
        match self {
            MarkerStatus::Found => 0,
            MarkerStatus::Misread => 1,
            MarkerStatus::Unidentified => 2,
            MarkerStatus::Missing => 3,
            MarkerStatus::NotInView => 4,
        }
    }

    /// The status in words, as reports print it.
    pub fn label(self) -> &'static str {
        match self {
            MarkerStatus::Found => "found",
            MarkerStatus::Misread => "misread",
            MarkerStatus::Unidentified => "unidentified",
            MarkerStatus::Missing => "missing",
            MarkerStatus::NotInView => "not in view",
        }
    }
}

/// One printed marker as seen in one photo.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct MarkerCheck {
    /// The printed ID.
    pub id: u32,
    /// The page it is printed on.
    pub page: u32,
    /// What became of it.
    pub status: MarkerStatus,
    /// The ID it read as, when misread.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub read_as: Option<u32>,
    /// Where it is (detected) or should be (predicted), image pixels.
    #[serde(serialize_with = "super::written::pixels")]
    pub u: f64,
    /// Row, pixels (see `u`).
    #[serde(serialize_with = "super::written::pixels")]
    pub v: f64,
    /// Distance between the detection and the predicted centre, pixels.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[serde(serialize_with = "super::written::pixels_opt")]
    pub offset_px: Option<f64>,
    /// Detected / predicted size of the disc: a marker printed at another
    /// size than its neighbours shows here.
    #[serde(skip_serializing_if = "Option::is_none")]
    #[serde(serialize_with = "super::written::ratio_opt")]
    pub size_ratio: Option<f64>,
    /// The outline to draw: the detected ellipse, or the predicted one.
    #[serde(skip)]
    pub outline: Option<Ellipse>,
}

/// A page located in a photo.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct PageCheck {
    /// Page number, from 1.
    pub page: u32,
    /// Detections whose ID is printed on this page.
    pub id_matches: usize,
    /// Of those, the ones that agree with the fitted homography.
    pub inliers: usize,
    /// Reprojection error of the inliers, pixels.
    #[serde(serialize_with = "super::written::pixels")]
    pub rms_px: f64,
    /// The scale the page was printed at, from its paper edges and markers.
    pub scale: ScaleMeasurement,
    /// Markers whose disc is a different size from their neighbours'
    /// (detected/predicted size more than 8 % off the page's median): a
    /// cross-check for markers printed at another size than the manifest
    /// says, which the scale of the page would not show.
    pub odd_sizes: Vec<OddSize>,
    #[serde(skip)]
    /// The page → image map the markers were predicted with.
    pub homography: Option<Homography>,
}

#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
/// A marker whose printed size differs from its neighbours'.
pub struct OddSize {
    /// The marker's ID.
    pub id: u32,
    /// Its size relative to the page's median marker, 1 = as expected.
    #[serde(serialize_with = "super::written::ratio")]
    pub relative_size: f64,
}

/// Relative size deviation that makes a marker's size odd.
const ODD_SIZE: f64 = 0.08;

fn odd_sizes(checks: &[MarkerCheck]) -> Vec<OddSize> {
    let mut ratios: Vec<f64> = checks.iter().filter_map(|c| c.size_ratio).collect();
    if ratios.len() < 3 {
        return Vec::new();
    }
    ratios.sort_by(f64::total_cmp);
    let median = ratios[ratios.len() / 2];
    checks
        .iter()
        .filter_map(|c| {
            let relative_size = c.size_ratio? / median;
            ((relative_size - 1.0).abs() > ODD_SIZE).then_some(OddSize {
                id: c.id,
                relative_size,
            })
        })
        .collect()
}

/// A detection on a located page where no marker was printed.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct StrayDetection {
    /// The ID it read as.
    pub id: u32,
    /// The page it lies on.
    pub page: u32,
    /// Centre column, pixels.
    #[serde(serialize_with = "super::written::pixels")]
    pub u: f64,
    /// Centre row, pixels.
    #[serde(serialize_with = "super::written::pixels")]
    pub v: f64,
}

#[derive(Debug, Clone, PartialEq, Serialize)]
/// The check of one photo against the manifest.
pub struct PhotoReport {
    /// The photo's name (usually its path).
    pub photo: String,
    /// Image width, pixels.
    pub width: u32,
    /// Image height, pixels.
    pub height: u32,
    /// Number of markers the detector found.
    pub detections: usize,
    /// The pages located in the photo.
    pub pages: Vec<PageCheck>,
    /// Every printed marker of the located pages.
    pub markers: Vec<MarkerCheck>,
    /// Detections on located pages where nothing was printed.
    pub stray: Vec<StrayDetection>,
    /// Signs that the photo shows another sheet than the manifest's (rings
    /// of another family, IDs the manifest does not list).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
}

/// Least point pairs that locate a page (a homography needs four); below
/// this many ID matches, markers' rim points are added to the centres.
const MIN_PAGE_MATCHES: usize = 4;

fn page_markers(manifest: &Manifest, page: u32) -> Vec<&PrintedMarker> {
    manifest.markers.iter().filter(|m| m.page == page).collect()
}

/// Checks one photo's detections against the manifest. The image is
/// needed for the paper-edge scale measurement; `camera` (with lens
/// distortion) makes the homography exact for wide-angle lenses.
pub fn check_photo(
    photo: &str,
    manifest: &Manifest,
    observations: &[Observation],
    image: &GrayImage,
    camera: Option<&Camera>,
) -> PhotoReport {
    let model = PixelModel::new(camera);
    let ideal: Vec<(f64, f64)> = observations
        .iter()
        .map(|o| model.to_ideal(o.u, o.v))
        .collect();
    let mut report = PhotoReport {
        photo: photo.to_string(),
        width: image.width(),
        height: image.height(),
        detections: observations.len(),
        pages: Vec::new(),
        markers: Vec::new(),
        stray: Vec::new(),
        notes: Vec::new(),
    };
    let page_count = manifest
        .pages
        .max(manifest.markers.iter().map(|m| m.page).max().unwrap_or(0));
    let mut claimed = vec![false; observations.len()];
    for page in 1..=page_count {
        let printed = page_markers(manifest, page);
        // ID-matched pairs: manifest position ↔ detected centre.
        let matches: Vec<(usize, &PrintedMarker)> = observations
            .iter()
            .enumerate()
            .filter(|(_, o)| o.id != 0)
            .filter_map(|(k, o)| printed.iter().find(|m| m.id == o.id).map(|m| (k, *m)))
            .collect();
        let Some((h, fit_inliers, rms)) = locate_page(&matches, observations, &ideal) else {
            continue;
        };
        let (checks, strays) = classify(
            manifest,
            page,
            &printed,
            &h,
            observations,
            &ideal,
            &model,
            image,
            &mut claimed,
        );
        let odd = odd_sizes(&checks);
        report.markers.extend(checks);
        report.stray.extend(strays);
        let discs: Vec<(f64, f64, f64)> = printed
            .iter()
            .map(|m| (m.x_mm, m.y_mm, m.diameter_mm / 2.0))
            .collect();
        let mut scale = scale::measure(image, &model, &h, manifest.page_size_mm, &discs);
        if matches.len() <= MIN_PAGE_MATCHES && scale.corners().is_none() {
            // One marker's rim pins the page well near the marker and loosely
            // far from it, so the far edges can fall outside their search.
            // The corners that were found are exact: with them the page is
            // pinned across its whole extent, and the search runs again.
            if let Some(pinned) = pin_with_corners(
                &matches,
                observations,
                &ideal,
                &scale,
                &model,
                manifest.page_size_mm,
            ) {
                scale = scale::measure(image, &model, &pinned, manifest.page_size_mm, &discs);
            }
        }
        if matches.len() <= MIN_PAGE_MATCHES {
            // A homography pinned by a few markers' rims is too loose to carry
            // millimetres out to the paper's edges; the discs' size is not.
            let views: Vec<scale::DiscView> = matches
                .iter()
                .map(|&(k, m)| scale::DiscView {
                    outline: observations[k].outline(),
                    radius_mm: m.diameter_mm / 2.0,
                })
                .collect();
            scale = scale::measure_discs(&scale, &model, manifest.page_size_mm, &views);
        }
        report.pages.push(PageCheck {
            page,
            id_matches: matches.len(),
            inliers: fit_inliers,
            rms_px: rms,
            scale,
            odd_sizes: odd,
            homography: Some(h),
        });
    }
    report
}

/// Fits the page's homography to its ID matches, refining it so that the
/// projected circles' ellipse centres (what a detector measures) match.
fn locate_page(
    matches: &[(usize, &PrintedMarker)],
    observations: &[Observation],
    ideal: &[(f64, f64)],
) -> Option<(Homography, usize, f64)> {
    if matches.is_empty() {
        return None;
    }
    let mut pairs = marker_correspondences(matches, observations, ideal);
    let observed: Vec<(f64, f64)> = pairs[..matches.len()].iter().map(|p| p.image).collect();
    let mut fit = fit_robust(&pairs)?;
    for _ in 0..3 {
        // Under perspective a circle's image centre is not the image of its
        // centre: move each observation by the predicted shift and refit.
        for (pair, (&(_, m), obs)) in pairs.iter_mut().zip(matches.iter().zip(&observed)) {
            let centre = fit.homography.apply(m.x_mm, m.y_mm);
            let ellipse = fit
                .homography
                .circle_image(m.x_mm, m.y_mm, m.diameter_mm / 2.0);
            if let (Some(c), Some(e)) = (centre, ellipse) {
                pair.image = (obs.0 - (e.u - c.0), obs.1 - (e.v - c.1));
            }
        }
        fit = fit_robust(&pairs)?;
    }
    let inliers = fit.inliers.iter().filter(|&&i| i).count();
    (inliers >= MIN_PAGE_MATCHES).then_some((fit.homography, inliers, fit.rms_px))
}

/// Page ↔ photo pairs of a page's ID-matched markers: their centres, in
/// `matches` order, then, for a page with too few centres to fit a
/// homography with anything to spare (four fit exactly, whatever they are),
/// each marker's own rim, placed by its ellipse and yaw.
fn marker_correspondences(
    matches: &[(usize, &PrintedMarker)],
    observations: &[Observation],
    ideal: &[(f64, f64)],
) -> Vec<Correspondence> {
    let mut pairs: Vec<Correspondence> = matches
        .iter()
        .map(|&(k, m)| Correspondence {
            plane: (m.x_mm, m.y_mm),
            image: ideal[k],
            // A detection more than a third of a radius off is not this marker.
            tolerance: (observations[k].semi_major / 3.0).max(2.0),
        })
        .collect();
    if matches.len() <= MIN_PAGE_MATCHES {
        pairs.extend(
            matches
                .iter()
                .flat_map(|&(k, m)| rim_correspondences(m, &observations[k], ideal[k])),
        );
    }
    pairs
}

/// The page's homography from its markers and the paper corners the scale
/// measurement found (at least two), or None with fewer corners.
fn pin_with_corners(
    matches: &[(usize, &PrintedMarker)],
    observations: &[Observation],
    ideal: &[(f64, f64)],
    paper: &ScaleMeasurement,
    model: &PixelModel,
    [w, h]: [f64; 2],
) -> Option<Homography> {
    if paper.found_corners.len() < 2 {
        return None;
    }
    let page_corners = [(0.0, 0.0), (w, 0.0), (w, h), (0.0, h)];
    let mut pairs: Vec<((f64, f64), (f64, f64))> =
        marker_correspondences(matches, observations, ideal)
            .into_iter()
            .map(|c| (c.plane, c.image))
            .collect();
    pairs.extend(
        paper
            .found_corners
            .iter()
            .map(|&(k, (u, v))| (page_corners[k], model.to_ideal(u, v))),
    );
    Homography::fit(&pairs)
}

/// The four points where a marker's axes meet its rim, page ↔ photo.
/// In the photo they lie on the outer ellipse: +x along the read yaw, +y on
/// the conjugate diameter (where a circle's perpendicular diameter goes
/// under an affine view), on the side that keeps the page's handedness
/// (+y of the marker is up the page, -y in page coordinates).
fn rim_correspondences(
    m: &PrintedMarker,
    o: &Observation,
    centre: (f64, f64),
) -> Vec<Correspondence> {
    let Some(yaw) = o.yaw else {
        return Vec::new();
    };
    let (a, b) = (o.semi_major, o.semi_minor);
    if !(a > 0.0 && b > 0.0) {
        return Vec::new();
    }
    // Ellipse parameter of the point in direction `yaw` from the centre.
    let (s, c) = (yaw - o.angle).sin_cos();
    let phi = (s / b).atan2(c / a);
    let (sa, ca) = o.angle.sin_cos();
    let to_image = |x: f64, y: f64| (x * ca - y * sa, x * sa + y * ca);
    let x_axis = to_image(a * phi.cos(), b * phi.sin());
    let mut y_axis = to_image(-a * phi.sin(), b * phi.cos());
    if x_axis.0 * y_axis.1 - x_axis.1 * y_axis.0 > 0.0 {
        y_axis = (-y_axis.0, -y_axis.1);
    }
    let r = m.diameter_mm / 2.0;
    let tolerance = (a / 4.0).max(2.0);
    [
        ((r, 0.0), x_axis, 1.0),
        ((r, 0.0), x_axis, -1.0),
        ((0.0, -r), y_axis, 1.0),
        ((0.0, -r), y_axis, -1.0),
    ]
    .into_iter()
    .map(|((dx, dy), (du, dv), sign)| Correspondence {
        plane: (m.x_mm + sign * dx, m.y_mm + sign * dy),
        image: (centre.0 + sign * du, centre.1 + sign * dv),
        tolerance,
    })
    .collect()
}

#[allow(clippy::too_many_arguments)]
fn classify(
    manifest: &Manifest,
    page: u32,
    printed: &[&PrintedMarker],
    h: &Homography,
    observations: &[Observation],
    ideal: &[(f64, f64)],
    model: &PixelModel,
    image: &GrayImage,
    claimed: &mut [bool],
) -> (Vec<MarkerCheck>, Vec<StrayDetection>) {
    let (w, hgt) = (f64::from(image.width()), f64::from(image.height()));
    let mut checks = Vec::new();
    for m in printed {
        let predicted = h.circle_image(m.x_mm, m.y_mm, m.diameter_mm / 2.0);
        let Some(e) = predicted else {
            checks.push(not_in_view(m, (f64::NAN, f64::NAN)));
            continue;
        };
        let centre = model.to_image(e.u, e.v);
        // The nearest unclaimed detection within half the predicted radius.
        let near = ideal
            .iter()
            .enumerate()
            .filter(|(k, _)| !claimed[*k])
            .map(|(k, p)| (k, (p.0 - e.u).hypot(p.1 - e.v)))
            .filter(|&(_, d)| d < 0.5 * e.semi_minor.max(1.0))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((k, d)) = near {
            claimed[k] = true;
            let o = &observations[k];
            let (status, read_as) = match o.id {
                id if id == m.id => (MarkerStatus::Found, None),
                0 => (MarkerStatus::Unidentified, None),
                other => (MarkerStatus::Misread, Some(other)),
            };
            checks.push(MarkerCheck {
                id: m.id,
                page,
                status,
                read_as,
                u: o.u,
                v: o.v,
                offset_px: Some(d),
                size_ratio: Some(
                    (o.semi_major * o.semi_minor).sqrt() / (e.semi_major * e.semi_minor).sqrt(),
                ),
                outline: Some(Ellipse {
                    u: o.u,
                    v: o.v,
                    semi_major: o.semi_major,
                    semi_minor: o.semi_minor,
                    angle: o.angle,
                }),
            });
            continue;
        }
        // Wholly inside the photo (with a little margin for the detector)?
        let inside = (0..16).all(|k| {
            let (x, y) = e.point_at(k as f64 / 16.0 * std::f64::consts::TAU);
            let (u, v) = model.to_image(x, y);
            u >= 1.0 && v >= 1.0 && u <= w - 2.0 && v <= hgt - 2.0
        });
        let outline = Some(Ellipse {
            u: centre.0,
            v: centre.1,
            ..e
        });
        checks.push(MarkerCheck {
            status: if inside {
                MarkerStatus::Missing
            } else {
                MarkerStatus::NotInView
            },
            outline,
            ..not_in_view(m, centre)
        });
    }
    // Detections inside this page's paper that belong to no printed marker.
    let mut strays = Vec::new();
    if let Some(inv) = h.inverse() {
        let [pw, ph] = manifest.page_size_mm;
        for (k, p) in ideal.iter().enumerate() {
            if claimed[k] {
                continue;
            }
            if let Some((x, y)) = inv.apply(p.0, p.1) {
                if (0.0..=pw).contains(&x) && (0.0..=ph).contains(&y) {
                    claimed[k] = true;
                    strays.push(StrayDetection {
                        id: observations[k].id,
                        page,
                        u: observations[k].u,
                        v: observations[k].v,
                    });
                }
            }
        }
    }
    (checks, strays)
}

pub(super) fn not_in_view(m: &PrintedMarker, (u, v): (f64, f64)) -> MarkerCheck {
    MarkerCheck {
        id: m.id,
        page: m.page,
        status: MarkerStatus::NotInView,
        read_as: None,
        u,
        v,
        offset_px: None,
        size_ratio: None,
        outline: None,
    }
}

/// Detects the markers in one photo and checks them against the manifest.
pub fn check_image(
    photo: &str,
    manifest: &Manifest,
    image: &GrayImage,
    camera: Option<&Camera>,
    detector: &mut crate::detect::Detector,
) -> PhotoReport {
    detector.reset();
    let detections = detector.detect(image);
    let observations: Vec<Observation> = detections.iter().map(Observation::from).collect();
    let mut report = check_photo(photo, manifest, &observations, image, camera);
    report.notes = other_sheet_signs(manifest, &detections, &report);
    report
}

/// What says the photo is of another sheet than `manifest` describes:
/// without it, a wrong manifest reads as a sheet whose every marker is
/// missing.
fn other_sheet_signs(
    manifest: &Manifest,
    detections: &[crate::detect::Detection],
    report: &PhotoReport,
) -> Vec<String> {
    let Some(family) = manifest.family.filter(|_| !manifest.legacy) else {
        return Vec::new();
    };
    let name = format!("{}-bit d{}", family.bits, family.distance);
    let mut check = crate::detect::family_check::FamilyCheck::new(Some(family.bits));
    check.observe(detections);
    let mut notes = Vec::new();
    if let Some(bits) = check.dominant_other_bits() {
        let n = check.other_bits.values().sum::<usize>();
        notes.push(format!(
            "{n} marker{} here carr{} {bits}-bit codes, but the manifest's family is {name}: \
             it is not the manifest of the sheet photographed",
            if n == 1 { "" } else { "s" },
            if n == 1 { "ies" } else { "y" },
        ));
    } else if check.mostly_corrected() {
        notes.push(format!(
            "{} of {} IDs read only through error correction: the sheet was probably printed \
             with another family than the manifest's {name}",
            check.corrected,
            check.exact + check.corrected
        ));
    }
    let listed: std::collections::BTreeSet<u32> = manifest.markers.iter().map(|m| m.id).collect();
    let unlisted: std::collections::BTreeSet<u32> = detections
        .iter()
        .map(|d| d.id)
        .filter(|id| *id != 0 && !listed.contains(id))
        .collect();
    if report.pages.is_empty() && !unlisted.is_empty() {
        let shown: Vec<String> = unlisted.iter().take(8).map(u32::to_string).collect();
        notes.push(format!(
            "{} ID{} read here {} not on the manifest ({}{}): is it the manifest of the sheet \
             photographed?",
            unlisted.len(),
            if unlisted.len() == 1 { "" } else { "s" },
            if unlisted.len() == 1 { "is" } else { "are" },
            shown.join(", "),
            if unlisted.len() > 8 { ", ..." } else { "" }
        ));
    }
    notes
}
