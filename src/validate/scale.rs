//! The printed scale of a page, measured against the paper itself.
//!
//! A homography fitted to the marker centres absorbs any uniform scale of
//! the print, so the markers alone cannot tell a 97 % print from a 100 %
//! one. The paper can: its size is fixed. We look for the paper's edges
//! along the normals of the page border predicted by the homography, fit a
//! line to each edge in page coordinates, and compare the paper's size in
//! manifest millimetres with the template's page size.

use crate::camera::Camera;
use crate::math::sample::{Border, Plane};
use crate::math::{Ellipse, Homography};
use image::GrayImage;
use serde::Serialize;

/// Above this deviation from 100 % the scale earns a warning.
pub const SCALE_WARNING: f64 = 0.01;
/// Above this deviation it is an error.
pub const SCALE_ERROR: f64 = 0.03;

/// Maps between image pixels and ideal (distortion-free) pixels.
#[derive(Debug, Clone, Copy)]
pub(crate) struct PixelModel {
    camera: Option<Camera>,
}

impl PixelModel {
    pub fn new(camera: Option<&Camera>) -> PixelModel {
        PixelModel {
            camera: camera.filter(|c| c.has_distortion()).copied(),
        }
    }

    pub fn to_ideal(self, u: f64, v: f64) -> (f64, f64) {
        match &self.camera {
            Some(c) => {
                let (x, y) = c.undistort(u, v);
                c.pinhole(x, y)
            }
            None => (u, v),
        }
    }

    pub fn to_image(self, x: f64, y: f64) -> (f64, f64) {
        match &self.camera {
            Some(c) => c.distort_normalized((x - c.cx) / c.fx, (y - c.cy) / c.fy),
            None => (x, y),
        }
    }
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
/// How far a measured print scale is from 1.
pub enum ScaleStatus {
    /// Within [`SCALE_WARNING`] of 1.
    Ok,
    /// Off by more than [`SCALE_WARNING`]: worth a look.
    Warning,
    /// Off by more than [`SCALE_ERROR`]: the page was printed at the wrong size.
    Error,
    /// Could not be measured.
    Unknown,
}

impl ScaleStatus {
    /// The status of a measured scale.
    pub fn of(scale: f64) -> ScaleStatus {
        let deviation = (scale - 1.0).abs();
        if deviation > SCALE_ERROR {
            ScaleStatus::Error
        } else if deviation > SCALE_WARNING {
            ScaleStatus::Warning
        } else {
            ScaleStatus::Ok
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize)]
/// One page's print scale as measured in a photo.
pub struct ScaleMeasurement {
    /// Printed size / intended size (0.97 = "printed at 97 %").
    #[serde(serialize_with = "super::written::ratio_opt")]
    pub scale: Option<f64>,
    /// The same across the page (from its left and right edges) ...
    #[serde(serialize_with = "super::written::ratio_opt")]
    pub scale_x: Option<f64>,
    /// ... and down the page (from its top and bottom edges).
    #[serde(serialize_with = "super::written::ratio_opt")]
    pub scale_y: Option<f64>,
    /// Whether the scale is within tolerance.
    pub status: ScaleStatus,
    /// Paper edges found: "top", "right", "bottom", "left".
    pub edges: Vec<&'static str>,
    /// Why the scale is unknown, or a remark on it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// Each paper corner whose two edges were found: its index (0
    /// top-left, 1 top-right, 2 bottom-right, 3 bottom-left) and place in
    /// the image. Two of them can pin a page that has too few markers.
    #[serde(skip)]
    pub found_corners: Vec<(usize, (f64, f64))>,
}

impl ScaleMeasurement {
    /// A measurement that found no scale, saying why.
    pub fn unknown(note: impl Into<String>) -> ScaleMeasurement {
        ScaleMeasurement {
            scale: None,
            scale_x: None,
            scale_y: None,
            status: ScaleStatus::Unknown,
            edges: Vec::new(),
            note: Some(note.into()),
            found_corners: Vec::new(),
        }
    }
}

const SIDE_NAMES: [&str; 4] = ["top", "right", "bottom", "left"];
/// Sample lines per side.
const LINES_PER_SIDE: usize = 32;

/// A fitted paper edge: its outward offset from the nominal border,
/// `offset(s) = a + b·s`, s the coordinate along the side (mm).
#[derive(Debug, Clone, Copy)]
struct EdgeLine {
    a: f64,
    b: f64,
}

impl EdgeLine {
    fn offset(&self, s: f64) -> f64 {
        self.a + self.b * s
    }
}

/// Measures the printed scale of one page. `markers` are the page's
/// markers as (x, y, radius) in manifest millimetres; the search keeps
/// clear of them so that a disc's edge is not taken for the paper's.
pub(crate) fn measure(
    image: &GrayImage,
    model: &PixelModel,
    homography: &Homography,
    page_size_mm: [f64; 2],
    markers: &[(f64, f64, f64)],
) -> ScaleMeasurement {
    let [w, h] = page_size_mm;
    let mut lines: [Option<EdgeLine>; 4] = [None; 4];
    let mut failures = Vec::new();
    for (side, line) in lines.iter_mut().enumerate() {
        match find_edge(image, model, homography, [w, h], markers, side) {
            Ok(l) => *line = Some(l),
            Err(why) => failures.push((SIDE_NAMES[side], why)),
        }
    }
    let found_corners: Vec<(usize, (f64, f64))> = paper_corners([w, h], lines)
        .into_iter()
        .enumerate()
        .filter_map(|(k, corner)| {
            let (x, y) = corner?;
            let (iu, iv) = homography.apply(x, y)?;
            Some((k, model.to_image(iu, iv)))
        })
        .collect();
    let [top, right, bottom, left] = lines;
    // Paper width in manifest units at mid-height, height at mid-width.
    let scale_x = match (left, right) {
        (Some(l), Some(r)) => Some(w / (w + l.offset(h / 2.0) + r.offset(h / 2.0))),
        _ => None,
    };
    let scale_y = match (top, bottom) {
        (Some(t), Some(b)) => Some(h / (h + t.offset(w / 2.0) + b.offset(w / 2.0))),
        _ => None,
    };
    let edges: Vec<&'static str> = lines
        .iter()
        .zip(SIDE_NAMES)
        .filter(|(l, _)| l.is_some())
        .map(|(_, n)| n)
        .collect();
    let scale = match (scale_x, scale_y) {
        (Some(x), Some(y)) => Some((x + y) / 2.0),
        (x, y) => x.or(y),
    };
    let elsewhere = failures
        .iter()
        .any(|(_, why)| *why == EdgeMiss::NotWhereExpected);
    let failures = grouped_failures(&failures);
    let Some(s) = scale else {
        let hint = if elsewhere {
            "; if the paper's edges are plainly in view, the photo is of another sheet than \
             this manifest's"
        } else {
            ""
        };
        return ScaleMeasurement {
            edges,
            found_corners,
            ..ScaleMeasurement::unknown(format!("needs two opposite paper edges: {failures}{hint}"))
        };
    };
    let mut notes = Vec::new();
    if let (Some(x), Some(y)) = (scale_x, scale_y) {
        if (x - y).abs() > SCALE_WARNING {
            notes.push(format!(
                "uneven scale: {:.1} % across, {:.1} % down",
                x * 100.0,
                y * 100.0
            ));
        }
    } else {
        notes.push(format!(
            "measured {} only ({failures})",
            if scale_x.is_some() { "across" } else { "down" },
        ));
    }
    // The worse of the two axes decides the status.
    let worst = [scale_x, scale_y]
        .iter()
        .flatten()
        .copied()
        .max_by(|a, b| (a - 1.0).abs().total_cmp(&(b - 1.0).abs()))
        .unwrap_or(s);
    ScaleMeasurement {
        scale: Some(s),
        scale_x,
        scale_y,
        status: ScaleStatus::of(worst),
        edges,
        note: (!notes.is_empty()).then(|| notes.join("; ")),
        found_corners,
    }
}

impl ScaleMeasurement {
    /// The paper's corners in the image (top-left, top-right, bottom-right,
    /// bottom-left) when all four edges were found.
    pub fn corners(&self) -> Option<[(f64, f64); 4]> {
        if self.found_corners.len() < 4 {
            return None;
        }
        let mut out = [(0.0, 0.0); 4];
        for &(k, p) in &self.found_corners {
            out[k] = p;
        }
        Some(out)
    }
}

/// A printed disc as the photo shows it, for [`measure_discs`].
#[derive(Debug, Clone, Copy)]
pub(crate) struct DiscView {
    /// The disc's outline in the photo (image pixels).
    pub outline: Ellipse,
    /// The radius it was meant to have, mm.
    pub radius_mm: f64,
}

/// The printed scale from the discs' own size, for a page with too few
/// markers to pin the layout: the paper's four corners, found by
/// [`measure`], map the photo onto the paper exactly (it is the paper's own
/// outline), and each disc's outline mapped there is a circle whose radius
/// is the printed one.
pub(crate) fn measure_discs(
    paper: &ScaleMeasurement,
    model: &PixelModel,
    page_size_mm: [f64; 2],
    discs: &[DiscView],
) -> ScaleMeasurement {
    let Some(corners) = paper.corners() else {
        let why = paper
            .note
            .as_deref()
            .map_or(String::new(), |n| format!(" ({n})"));
        return ScaleMeasurement {
            edges: paper.edges.clone(),
            ..ScaleMeasurement::unknown(format!(
                "a page with so few markers is measured by their size against the whole paper, and not all four paper edges were found{why}"
            ))
        };
    };
    let [w, h] = page_size_mm;
    let pairs: Vec<_> = [(0.0, 0.0), (w, 0.0), (w, h), (0.0, h)]
        .into_iter()
        .zip(corners)
        .map(|(page, (u, v))| (page, model.to_ideal(u, v)))
        .collect();
    let Some(to_paper) = Homography::fit(&pairs).and_then(|p| p.inverse()) else {
        return ScaleMeasurement::unknown("the paper's corners are degenerate");
    };
    let ratios: Vec<f64> = discs
        .iter()
        .filter_map(|disc| {
            let points: Option<Vec<(f64, f64)>> = disc
                .outline
                .boundary_points(24)
                .into_iter()
                .map(|(u, v)| {
                    let (x, y) = model.to_ideal(u, v);
                    to_paper.apply(x, y)
                })
                .collect();
            let radius = fit_circle_radius(&points?)?;
            Some(radius / disc.radius_mm)
        })
        .collect();
    if ratios.is_empty() {
        return ScaleMeasurement::unknown("no disc outline could be mapped onto the paper");
    }
    let scale = ratios.iter().sum::<f64>() / ratios.len() as f64;
    ScaleMeasurement {
        scale: Some(scale),
        scale_x: None,
        scale_y: None,
        status: ScaleStatus::of(scale),
        edges: paper.edges.clone(),
        note: Some(format!(
            "measured from the size of {} disc{} against the paper (too few markers to measure the layout)",
            ratios.len(),
            if ratios.len() == 1 { "" } else { "s" }
        )),
        found_corners: paper.found_corners.clone(),
    }
}

/// Radius of the least-squares circle through the points (Kåsa's fit:
/// linear in the centre and x²+y² offset, exact for points on a circle).
fn fit_circle_radius(points: &[(f64, f64)]) -> Option<f64> {
    let mut normal = nalgebra::Matrix3::<f64>::zeros();
    let mut rhs = nalgebra::Vector3::<f64>::zeros();
    for &(x, y) in points {
        let row = nalgebra::Vector3::new(x, y, 1.0);
        normal += row * row.transpose();
        rhs += row * (x * x + y * y);
    }
    let solution = normal.lu().solve(&rhs)?;
    let (cx, cy) = (solution[0] / 2.0, solution[1] / 2.0);
    let r2 = solution[2] + cx * cx + cy * cy;
    (r2 > 0.0).then(|| r2.sqrt())
}

/// Corners of the paper in manifest coordinates (top-left, top-right,
/// bottom-right, bottom-left), each where both of its edges were found.
fn paper_corners([w, h]: [f64; 2], lines: [Option<EdgeLine>; 4]) -> [Option<(f64, f64)>; 4] {
    // top: y = -(a + b x); bottom: y = h + a + b x;
    // left: x = -(a + b y); right: x = w + a + b y.
    let solve = |hy: (f64, f64, f64), vx: (f64, f64, f64)| -> Option<(f64, f64)> {
        // y = hy.0 + hy.1 * x ; x = vx.0 + vx.1 * y
        let det = 1.0 - hy.1 * vx.1;
        if det.abs() < 1e-9 {
            return None;
        }
        let x = (vx.0 + vx.1 * hy.0) / det;
        Some((x, hy.0 + hy.1 * x))
    };
    let [top, right, bottom, left] = lines;
    let t = top.map(|e| (-e.a, -e.b, 0.0));
    let b = bottom.map(|e| (h + e.a, e.b, 0.0));
    let l = left.map(|e| (-e.a, -e.b, 0.0));
    let r = right.map(|e| (w + e.a, e.b, 0.0));
    let corner = |hy: Option<(f64, f64, f64)>, vx: Option<(f64, f64, f64)>| solve(hy?, vx?);
    [corner(t, l), corner(t, r), corner(b, r), corner(b, l)]
}

/// Bilinear grey value, `None` outside the rectangle of pixel centres.
fn sample(image: &GrayImage, u: f64, v: f64) -> Option<f64> {
    let (w, h) = (image.width() as usize, image.height() as usize);
    Plane::new(image.as_raw(), w, h).at(u, v, Border::Closed)
}

/// Finds one paper edge. Side 0..4 = top, right, bottom, left.
fn find_edge(
    image: &GrayImage,
    model: &PixelModel,
    homography: &Homography,
    [w, h]: [f64; 2],
    markers: &[(f64, f64, f64)],
    side: usize,
) -> Result<EdgeLine, EdgeMiss> {
    // Base point on the nominal border at along-side coordinate s, and the
    // outward normal.
    let (length, across) = if side.is_multiple_of(2) {
        (w, h)
    } else {
        (h, w)
    };
    let base = |s: f64| -> (f64, f64) {
        match side {
            0 => (s, 0.0),
            1 => (w, s),
            2 => (s, h),
            _ => (0.0, s),
        }
    };
    let normal = match side {
        0 => (0.0, -1.0),
        1 => (1.0, 0.0),
        2 => (0.0, 1.0),
        _ => (-1.0, 0.0),
    };
    // Prints from about 85 % to 115 % keep their paper edge in this range.
    let half = across / 2.0;
    let (t_lo, t_hi) = (-0.12 * half, 0.2 * half);

    let mut points: Vec<(f64, f64)> = Vec::new();
    let mut out_of_view = 0;
    let mut low_contrast = 0;
    for k in 0..LINES_PER_SIDE {
        let s = length * (0.1 + 0.8 * (k as f64 + 0.5) / LINES_PER_SIDE as f64);
        let b = base(s);
        let mut t_start = t_lo;
        for &(mx, my, r) in markers {
            let (dx, dy) = (mx - b.0, my - b.1);
            let along = dx * normal.0 + dy * normal.1;
            let perpendicular = (dx * normal.1 - dy * normal.0).abs();
            let clearance = 1.15 * r;
            if perpendicular < clearance {
                t_start = t_start.max(along + clearance);
            }
        }
        if t_start >= t_hi - 0.02 * half {
            continue;
        }
        let to_image = |t: f64| -> Option<(f64, f64)> {
            let (x, y) = (b.0 + t * normal.0, b.1 + t * normal.1);
            let (iu, iv) = homography.apply(x, y)?;
            Some(model.to_image(iu, iv))
        };
        // Step of about half a pixel in the image.
        let j = homography.jacobian(b.0, b.1);
        let px_per_mm = (j * nalgebra::Vector2::new(normal.0, normal.1)).norm();
        if px_per_mm.is_nan() || px_per_mm <= 1e-6 {
            continue;
        }
        let step = 0.5 / px_per_mm;
        let count = (((t_hi - t_start) / step).ceil() as usize).min(4000);
        let mut profile = Vec::with_capacity(count);
        for i in 0..count {
            let t = t_start + i as f64 * step;
            match to_image(t).and_then(|(u, v)| sample(image, u, v)) {
                Some(g) => profile.push(g),
                None => break,
            }
        }
        // Windows of ~2.5 mm (at least 3 px) see bright-to-dark steps on
        // the scale of a paper edge; thin printed strokes score less.
        let window = ((2.5 / step).round() as usize).clamp(6, 40);
        if profile.len() < 2 * window + 3 {
            out_of_view += 1;
            continue;
        }
        let mut prefix = vec![0.0; profile.len() + 1];
        for (i, g) in profile.iter().enumerate() {
            prefix[i + 1] = prefix[i] + g;
        }
        let mean = |a: usize, b: usize| (prefix[b] - prefix[a]) / (b - a) as f64;
        let steps: Vec<(f64, f64)> = (window..profile.len() - window)
            .map(|i| {
                let inside = mean(i - window, i);
                (inside - mean(i, i + window), inside)
            })
            .collect();
        let strongest = steps.iter().map(|s| s.0).fold(f64::MIN, f64::max);
        // The paper ends at the first strong step outward, not the
        // strongest: a darker object lying beside the paper makes a bigger
        // step further out than the paper's own edge against it.
        let strong =
            |(stepv, inside): (f64, f64)| stepv >= 12.0f64.max(0.25 * inside).max(0.5 * strongest);
        // Printed ink near the border (the scale bar, the caption) makes a
        // step too, but the paper is bright again a few millimetres on;
        // beyond the paper's own edge it is not.
        let stays_dark = |k: usize| {
            let i = window + k;
            let (from, to) = (i + window, (i + 3 * window).min(profile.len()));
            let (stepv, inside) = steps[k];
            to <= from || mean(from, to) <= inside - 0.5 * stepv
        };
        let Some(first) = (0..steps.len()).find(|&k| strong(steps[k]) && stays_dark(k)) else {
            low_contrast += 1;
            continue;
        };
        // The peak of that step, not where it first clears the bar.
        let best_i = window
            + (first..steps.len())
                .take_while(|&k| strong(steps[k]))
                .max_by(|&a, &b| steps[a].0.total_cmp(&steps[b].0))
                .unwrap_or(first);
        // Sub-sample location: the steepest descent near the step, refined
        // by a parabola through the gradient.
        let lo = best_i.saturating_sub(window / 2).max(1);
        let hi = (best_i + window / 2).min(profile.len() - 2);
        let grad = |i: usize| profile[i - 1] - profile[i + 1];
        let peak = (lo..=hi)
            .max_by(|&a, &b| grad(a).total_cmp(&grad(b)))
            .unwrap_or(best_i);
        let mut pos = peak as f64;
        if peak > lo && peak < hi {
            let (gm, g0, gp) = (grad(peak - 1), grad(peak), grad(peak + 1));
            let denom = gm - 2.0 * g0 + gp;
            if denom.abs() > 1e-9 {
                pos += (0.5 * (gm - gp) / denom).clamp(-0.5, 0.5);
            }
        }
        points.push((s, t_start + pos * step));
    }
    if points.len() < 6 {
        return Err(if out_of_view >= low_contrast && out_of_view > 0 {
            EdgeMiss::NotInPhoto
        } else if low_contrast > 0 {
            EdgeMiss::NotWhereExpected
        } else {
            EdgeMiss::HiddenBehindMarkers
        });
    }
    fit_edge_line(&points).ok_or(EdgeMiss::NotStraight)
}

/// Why one paper edge was not found.
#[derive(Debug, Clone, Copy, PartialEq, Eq, thiserror::Error)]
enum EdgeMiss {
    /// The sample lines left the photo before reaching it.
    #[error("not in the photo")]
    NotInPhoto,
    /// No step from paper to background where the page should end. Said
    /// with where it was looked for: a paper edge plainly visible elsewhere
    /// means the manifest's page is not the one in the photo.
    #[error(
        "no paper edge where the manifest's page puts it (searched from 12 % of the page inside \
         to 20 % outside)"
    )]
    NotWhereExpected,
    /// Markers near the border left too few places to look.
    #[error("hidden behind markers")]
    HiddenBehindMarkers,
    /// The edge points found lie on no straight line.
    #[error("not straight (folded or occluded?)")]
    NotStraight,
}

/// "top and right edges: not in the photo; bottom edge: ...": the sides
/// that failed for one reason named together, so that a reason is said once.
fn grouped_failures(failures: &[(&str, EdgeMiss)]) -> String {
    let mut reasons: Vec<EdgeMiss> = Vec::new();
    for &(_, why) in failures {
        if !reasons.contains(&why) {
            reasons.push(why);
        }
    }
    reasons
        .iter()
        .map(|why| {
            let sides: Vec<&str> = failures
                .iter()
                .filter(|(_, w)| w == why)
                .map(|(side, _)| *side)
                .collect();
            let named = match sides.as_slice() {
                [one] => format!("{one} edge"),
                [init @ .., last] => format!("{} and {last} edges", init.join(", ")),
                [] => String::new(),
            };
            format!("{named}: {why}")
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// Robust straight-line fit offset = a + b·s: least squares, then again
/// without the points far from the first fit.
fn fit_edge_line(points: &[(f64, f64)]) -> Option<EdgeLine> {
    let fit = |pts: &[(f64, f64)]| -> Option<EdgeLine> {
        let n = pts.len() as f64;
        let (ms, mt) = pts
            .iter()
            .fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
        let sxx: f64 = pts.iter().map(|p| (p.0 - ms).powi(2)).sum();
        let sxy: f64 = pts.iter().map(|p| (p.0 - ms) * (p.1 - mt)).sum();
        if sxx <= 0.0 {
            return None;
        }
        let b = sxy / sxx;
        Some(EdgeLine { a: mt - b * ms, b })
    };
    // Start from the line most points agree with, not the least-squares
    // line of all: an object touching a stretch of the edge moves a third
    // of the points together, which drags a plain fit and fools the
    // median-based trimming that follows.
    const AGREE_MM: f64 = 0.3;
    let mut consensus: Option<(usize, Vec<(f64, f64)>)> = None;
    for (i, p) in points.iter().enumerate() {
        for q in &points[i + 1..] {
            if (q.0 - p.0).abs() < 1e-9 {
                continue;
            }
            let b = (q.1 - p.1) / (q.0 - p.0);
            let through = EdgeLine {
                a: p.1 - b * p.0,
                b,
            };
            let agreeing: Vec<(f64, f64)> = points
                .iter()
                .filter(|r| (r.1 - through.offset(r.0)).abs() <= AGREE_MM)
                .copied()
                .collect();
            if consensus.as_ref().is_none_or(|(n, _)| agreeing.len() > *n) {
                consensus = Some((agreeing.len(), agreeing));
            }
        }
    }
    let start = match &consensus {
        Some((n, agreeing)) if *n >= 6 => agreeing.as_slice(),
        _ => points,
    };
    let mut line = fit(start)?;
    for _ in 0..3 {
        let mut residuals: Vec<f64> = points
            .iter()
            .map(|p| (p.1 - line.offset(p.0)).abs())
            .collect();
        let mut sorted = residuals.clone();
        sorted.sort_by(f64::total_cmp);
        let mad = sorted[sorted.len() / 2];
        let limit = (3.0 * 1.4826 * mad).max(0.15);
        let kept: Vec<(f64, f64)> = points
            .iter()
            .zip(residuals.iter_mut())
            .filter(|(_, r)| **r <= limit)
            .map(|(p, _)| *p)
            .collect();
        if kept.len() < 6 || kept.len() * 5 < points.len() * 2 {
            return None;
        }
        line = fit(&kept)?;
    }
    Some(line)
}
