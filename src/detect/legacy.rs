//! The one structure a legacy WhyCon marker has to show: a white disc of
//! 0.41 R, concentric with the black one (spec section 1). The moment tests
//! accept a disc with an off-centre hole or a washer whose hole is some
//! other size (their pixel counts fit within the tolerances blur and
//! perspective need); the inner edge, found along rays from the centre,
//! does not: it must lie at the same relative radius all round, and at
//! WhyCon's. The light inside the disc, summed (which blur moves about but
//! does not change), must then make a disc of a printed marker's area, no
//! more elongated than the outline: a bold stroke-font 'o' or '0' keeps its
//! pen's width all round, so its hole is narrower across than its outline.
//! The disc is the paper the marker is printed on, no lighter than the
//! margin round it (a hollow circle drawn on a darker ground is). Below the
//! original's own size floor no test can tell a bold 'o' of WhyCon's
//! proportions from a marker, and none is reported.

use std::ops::Deref;

use image::{ImageBuffer, Luma};

use super::ring::{self, manchester::RingEvidence};
use super::segment::Gray;
use super::{ellipse, Candidate};
use crate::geometry::{RING_INNER_RATIO, WHYCODE_WHITE_RATIO, WHYCON_WHITE_RATIO};
use crate::math::Ellipse;

/// The original WhyCon's smallest outer segment (`minSize`, pixels): it
/// never reports a marker whose black ring covers fewer pixels (its white
/// segment must exceed as many too, which puts its limit higher still,
/// about 15 px across at the ROS node's `minSize` of 30). At 100 pixels a
/// face-on marker is 12.4 px across.
pub const MIN_INK_PX: f64 = 100.0;

/// Whether candidate `c` shows a legacy marker's structure: ink enough
/// (`min_ink_px`, see [`enough_ink`]), a white margin round it, and inside
/// a white disc of WhyCon's (with the light of a printed one) or the parts
/// of a WhyCode ring that shows its Manchester structure.
pub(super) fn is_marker<C: Deref<Target = [u8]>>(
    image: &ImageBuffer<Luma<u8>, C>,
    gray: Gray<'_>,
    c: &Candidate,
    min_ink_px: f64,
) -> bool {
    if !enough_ink(&c.outer, min_ink_px) {
        return false;
    }
    let inside = concentric_white_disc(gray, &c.outer, c.black, c.white);
    let paper = inside.and_then(|_| white_margin(gray, &c.outer, c.black, c.white));
    match (inside, paper) {
        (Some(Inside::WhyConDisc), Some(paper)) => {
            white_disc_mass(gray, &c.outer, paper, &MassLimits::PRINTED)
        }
        (Some(Inside::WhyCodeRing), Some(_)) => matches!(
            ring::evidence(image, c, None, None),
            RingEvidence::Manchester(_)
        ),
        _ => false,
    }
}

/// True when the black ring inside `outer` (the black disc less WhyCon's
/// white one) covers at least `min_ink_px` pixels.
pub fn enough_ink(outer: &Ellipse, min_ink_px: f64) -> bool {
    outer.area() * (1.0 - WHYCON_WHITE_RATIO * WHYCON_WHITE_RATIO) >= min_ink_px
}

/// An inner edge found along a ray: its radius relative to the outline,
/// the outline's distance from the centre in pixels, the ray's parameter.
type Edge = (f64, f64, f64);

/// Rays cast from the centre.
const RAYS: usize = 32;

/// Largest median distance (pixels, plus a share of the radius) by which
/// the inner edge found may lie outside WhyCon's white disc.
const DISC_OFFSET_PX: f64 = 0.12;
const DISC_OFFSET_RELATIVE: f64 = 0.01;

/// Largest median distance inside it (pixels, plus a share of the
/// radius): blur shrinks a small white disc's image, and printed WhyCon
/// markers in the field come with a white disc up to 6 % of the radius
/// smaller than the spec's (the legacy markers of `many.png` all do).
const DISC_SHRINK_PX: f64 = 0.25;
const DISC_SHRINK_RELATIVE: f64 = 0.07;

/// Largest spread of that distance between rays (trimmed, pixels plus a
/// share of the radius).
const DISC_SPREAD_PX: f64 = 0.55;
const DISC_SPREAD_RELATIVE: f64 = 0.02;
/// Largest offset (pixels, plus a share of the radius) of the white
/// disc's centre from the outline's: perspective's on a close, steep view
/// (the scan's concentricity test allows as much), not an off-centre hole.
const MAX_DECENTRE_PX: f64 = 0.25;
const MAX_DECENTRE_RELATIVE: f64 = 0.08;
/// Further spread allowed to the edges of a WhyCode ring's parts (share of
/// the radius): rays along a sector boundary meet either edge.
const RING_PART_SPREAD: f64 = 0.05;

/// Largest excess (pixels, amplitude of the second harmonic along the
/// outline's axes) of the inner edge's distance along the major axis over
/// that along the minor one. A view of two concentric circles shows two
/// similar ellipses, and blur only rounds the smaller; a glyph drawn with a
/// pen of constant width ('o', '0') has a hole more elongated than its
/// outline.
const MAX_OVAL_PX: f64 = 0.09;
const MAX_OVAL_RELATIVE: f64 = 0.005;

/// How much darker than the white disc (share of the disc's contrast) the
/// margin around the black disc may be.
const MARGIN_SHADE: f64 = 0.25;

/// The paper's grey when the disc stands on white: WhyCon markers are
/// printed with at least 0.3 R of white margin (spec section 1), while a
/// letter 'o' or a ring drawn on a busy surface touches other ink (None).
/// Rays that leave the image say nothing (the disc's own white stands in).
pub fn white_margin(gray: Gray<'_>, outer: &Ellipse, black: f64, white: f64) -> Option<f64> {
    let mid = 0.5 * (black + white);
    // Just outside the edge's blur, and inside the 0.3 R margin.
    let rho = 1.0 + (0.15f64).max(1.5 / outer.semi_minor.max(1.0)).min(0.28);
    let mut values = Vec::with_capacity(RAYS);
    for k in 0..RAYS {
        let t = std::f64::consts::TAU * k as f64 / RAYS as f64;
        let (x, y) = outer.scaled(rho).point_at(t);
        if let Some(value) = ellipse::sample(gray, x, y) {
            values.push(value);
        }
    }
    if values.is_empty() {
        return Some(white);
    }
    let light = values.iter().filter(|&&v| v >= mid).count();
    values.sort_by(f64::total_cmp);
    // The margin is the paper the white disc is printed on: a ring whose
    // light middle is lighter than what surrounds it is a washer or a
    // drawn circle on a darker surface.
    let paper = values[values.len() / 2];
    (light * 8 >= values.len() * 7 && paper >= white - MARGIN_SHADE * (white - black))
        .then_some(paper)
}

/// What a candidate's inside was taken for by [`concentric_white_disc`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Inside {
    /// WhyCon's white disc: to be weighed with `white_disc_mass`.
    WhyConDisc,
    /// The edges of a WhyCode ring's parts: only its Manchester structure
    /// tells it from a glyph whose hole is an oval (a '0' shows edges at
    /// the two radii too, on the rays along either axis).
    WhyCodeRing,
}

/// Some when the white inside the candidate is a disc of WhyCon's size
/// centred on the black one, or a WhyCode ring's parts.
///
/// Each ray's inner edge is where its profile crosses halfway between its
/// own lightest point inside the white disc and its darkest point on the
/// black annulus, so that a small disc, whose middle blur keeps from full
/// white, is not measured smaller than it is. Errors are judged in pixels
/// along the ray: a stroke-font '0' or an oval washer keeps its relative
/// hole size along the minor axis but not along the major one, which a
/// tolerance in radii would forgive on a small outline.
pub fn concentric_white_disc(
    gray: Gray<'_>,
    outer: &Ellipse,
    black: f64,
    white: f64,
) -> Option<Inside> {
    let mid = 0.5 * (black + white);
    let radius_px = outer.semi_minor.max(1.0);
    let step = (0.25 / radius_px).min(0.02);
    let mut edges = Vec::with_capacity(RAYS);
    let mut profile = Vec::new();
    for k in 0..RAYS {
        let t = std::f64::consts::TAU * k as f64 / RAYS as f64;
        let (ex, ey) = outer.point_at(t);
        let (dx, dy) = (ex - outer.u, ey - outer.v);
        let length = dx.hypot(dy);
        profile.clear();
        let mut rho: f64 = 0.0;
        while rho <= 1.0 {
            // The scaled outline's point at t, without a sine per sample.
            let k = rho.max(1e-6);
            let (x, y) = (outer.u + k * dx, outer.v + k * dy);
            let value = ellipse::sample(gray, x, y)?;
            profile.push((rho, value));
            rho += step;
        }
        let light = profile
            .iter()
            .filter(|p| p.0 <= 0.5)
            .map(|p| p.1)
            .fold(f64::MIN, f64::max);
        let dark = profile
            .iter()
            .filter(|p| p.0 >= WHYCON_WHITE_RATIO)
            .map(|p| p.1)
            .fold(f64::MAX, f64::min);
        // A ray with no light middle of its own has no inner edge.
        if light < mid || dark >= mid {
            continue;
        }
        let level = 0.5 * (light + dark);
        let start = profile
            .iter()
            .position(|p| p.0 <= 0.5 && p.1 == light)
            .unwrap_or(0);
        let crossing = profile[start..].windows(2).find_map(|w| {
            let ((r0, v0), (r1, v1)) = (w[0], w[1]);
            (v0 >= level && v1 < level).then(|| r0 + (r1 - r0) * (v0 - level) / (v0 - v1))
        });
        if let Some(r) = crossing {
            edges.push((r, length, t));
        }
    }
    if edges.len() * 8 < RAYS * 7 {
        return None;
    }
    if on_circle(&edges, WHYCON_WHITE_RATIO, outer, true) {
        return Some(Inside::WhyConDisc);
    }
    // A WhyCode marker is a WhyCon one too (paper section 5): its first
    // edge is the centre disc's (0.343 R) on rays through black sectors and
    // the ring's outside (0.6 R) on the others.
    let split = 0.5 * (RING_INNER_RATIO + WHYCODE_WHITE_RATIO);
    let (inner, outer_edges): (Vec<Edge>, Vec<Edge>) = edges.iter().partition(|e| e.0 < split);
    let whycode = inner.len() * 4 >= RAYS
        && outer_edges.len() * 4 >= RAYS
        && on_circle(&inner, RING_INNER_RATIO, outer, false)
        && on_circle(&outer_edges, WHYCODE_WHITE_RATIO, outer, false);
    whycode.then_some(Inside::WhyCodeRing)
}

/// True when the inner edges found along the rays, as (radius relative to
/// the outline, the outline's distance in pixels), lie on the circle of
/// relative radius `ratio` within a pixel tolerance that grows slowly with
/// the marker; for a whole `hole` (WhyCon's white disc, not the parts of a
/// WhyCode ring's edges, whose sectors would bias it) no more elongated
/// than the outline.
fn on_circle(edges: &[Edge], ratio: f64, outer: &Ellipse, hole: bool) -> bool {
    let size = (outer.semi_major * outer.semi_minor).sqrt();
    let mut errors: Vec<f64> = edges
        .iter()
        .map(|&(rho, length, _)| (rho - ratio) * length)
        .collect();
    // Harmonics of the error around the outline: the first is the hole's
    // offset from the outline's centre, the second its elongation.
    let harmonic = |n: f64| {
        let (mut c, mut s) = (0.0, 0.0);
        for (e, error) in edges.iter().zip(&errors) {
            c += error * (n * e.2).cos();
            s += error * (n * e.2).sin();
        }
        let scale = 2.0 / edges.len() as f64;
        (c * scale, s * scale)
    };
    let oval = harmonic(2.0).0;
    let (offset_c, offset_s) = harmonic(1.0);
    let offset = offset_c.hypot(offset_s);
    if hole {
        // Perspective moves the inner circle's image off the outer
        // ellipse's centre (the more, the closer and steeper the view):
        // the spread is judged around the fitted offset, which is bounded
        // on its own.
        for (e, error) in edges.iter().zip(errors.iter_mut()) {
            *error -= offset_c * e.2.cos() + offset_s * e.2.sin();
        }
    }
    errors.sort_by(f64::total_cmp);
    let trim = errors.len() / 10;
    let median = errors[errors.len() / 2];
    let spread = errors[errors.len() - 1 - trim] - errors[trim];
    let shrink = DISC_SHRINK_PX + DISC_SHRINK_RELATIVE * size;
    let spread_limit =
        DISC_SPREAD_PX + (DISC_SPREAD_RELATIVE + if hole { 0.0 } else { RING_PART_SPREAD }) * size;
    (-shrink..=DISC_OFFSET_PX + DISC_OFFSET_RELATIVE * size).contains(&median)
        && spread <= spread_limit
        && (!hole
            || (oval <= MAX_OVAL_PX + MAX_OVAL_RELATIVE * size
                && offset <= MAX_DECENTRE_PX + MAX_DECENTRE_RELATIVE * size))
}

/// Radii of a marker's white centre, relative to the outline, that the
/// original accepts (its pixel-count window), for discs out of focus: the
/// spec's 0.41 R, the 0.354 R of the original's own prints, the larger
/// centres of other printers' (0.43-0.46 R on robots' blurred markers in
/// the field), and a WhyCode ring smeared into its centre (0.49 R). In
/// focus the window is the printed one ([`MassLimits::PRINTED`]): bold
/// letters and washers with holes of 0.45-0.5 R are as sharp as a marker.
const WHITE_CENTRE: std::ops::RangeInclusive<f64> = 0.34..=0.55;

/// Whether candidate `c`, out of focus, still shows a marker's disc: a
/// WhyCon circle, or a WhyCode marker whose ring the blur has smeared into
/// its centre's light. The edges inside such a disc no longer lie where
/// they were printed (blur and a camera's sharpening move them by a share
/// of the blur), but the light inside still adds up to a centre of a
/// marker's size, about the outline's centre, under a white margin; only
/// the shape of that light is judged more loosely. No letter of printed
/// text is as large, so this is asked of discs of
/// [`super::identity::MIN_NO_RING_DIAMETER_PX`] and more.
pub(super) fn is_blurred_marker(gray: Gray<'_>, c: &Candidate) -> bool {
    let outer = &c.outer;
    if 2.0 * outer.semi_minor < super::identity::MIN_NO_RING_DIAMETER_PX {
        return false;
    }
    let Some(sigma) = ellipse::defocus(gray, outer).filter(|&s| s >= MIN_BLUR_PX) else {
        return false;
    };
    let Some(paper) = white_margin(gray, outer, c.black, c.white) else {
        return false;
    };
    white_disc_mass(gray, outer, paper, &MassLimits::blurred(sigma))
}

/// Focus blur (Gaussian sigma, pixels) the outline must show for
/// [`is_blurred_marker`]'s looser judgement: a sharp disc is judged by its
/// edges.
const MIN_BLUR_PX: f64 = 1.0;

/// Bounds on the light inside a disc ([`white_disc_mass`]).
struct MassLimits {
    /// Least and greatest radius, relative to the outline, that the light
    /// adds up to.
    ratio: std::ops::RangeInclusive<f64>,
    /// Largest excess elongation, relative to the light's spread.
    elongation: f64,
    /// Further offset (pixels) of the light's centroid allowed.
    decentre_px: f64,
}

impl MassLimits {
    /// A printed WhyCon marker's white disc seen in focus: the spec's
    /// 0.41 R, and the 0.354 R of the original's printed markers
    /// (`many.png`, where every one of 48 weighs 0.354-0.356 R but the
    /// held-up print, 0.38 R).
    const PRINTED: MassLimits = MassLimits {
        ratio: 0.34..=0.43,
        elongation: MAX_MASS_ELONGATION,
        decentre_px: 0.0,
    };

    /// A marker's light under a focus blur of `sigma` pixels: the
    /// original's window of white centres ([`WHITE_CENTRE`]), which holds a
    /// WhyCode marker's smeared ring too (its centre and the white
    /// half of its ring weigh 0.49 R); an elongation up to what blocky
    /// video compression gives a blurred centre; an offset up to the blur.
    fn blurred(sigma: f64) -> MassLimits {
        MassLimits {
            ratio: WHITE_CENTRE,
            elongation: MAX_BLURRED_MASS_ELONGATION,
            decentre_px: sigma,
        }
    }
}

/// Largest excess elongation of a blurred disc's light (see
/// [`MassLimits::blurred`]): bold letters reach 0.1-0.3 but are never as
/// large as the discs this is asked of.
const MAX_BLURRED_MASS_ELONGATION: f64 = 0.25;

/// Largest excess elongation of the white disc's light over the outline's:
/// anisotropy of the second moments (px²), beyond the outline's own scaled
/// by the area ratio, relative to their mean, plus a floor for the noise on
/// a disc of a few pixels (8 px markers at noise 2 reach 0.08 px² of 0.75).
/// The sharpened photo of the held-up print in `many.png` makes 0.076 of
/// its mean; a stroke-font 'o' of WhyCon's proportions 0.1-0.2, a '0' 0.3.
const MAX_MASS_ELONGATION: f64 = 0.08;
const MASS_ELONGATION_PX2: f64 = 0.03;

/// Largest offset (pixels) of the light's centroid from the outline's
/// centre: noise on small discs, plus perspective, which moves the inner
/// circle's image by a share of the squared size (px²; 0.0006 at 30° in a
/// 60° view, four times as much allowed for wider lenses).
const MASS_DECENTRE_PX: f64 = 0.08;
const MASS_DECENTRE_PERSPECTIVE: f64 = 0.0025;

/// Part of the outline's radii that holds the white disc and its blur,
/// and stays clear of the outer edge's.
const MASS_REACH: f64 = 0.72;

/// Part of the outline's radii that is the white disc's middle, clear of
/// its edge's blur on discs of some pixels.
const MIDDLE: f64 = 0.25;

/// Largest excess of the disc's middle over the margin's paper (share of
/// the paper's contrast to the ink): a margin sampled inside the outer
/// edge's blur is darker than the paper (blur 2 px, noise 5: up to 0.085);
/// hollow circles drawn on a darker ground reach 0.28-0.34 on desk frames.
const MAX_GLOW: f64 = 0.15;

/// Three standard deviations of the median of n samples (1.25 σ / √n).
const MEDIAN_SIGMAS: f64 = 3.75;

/// Samples across the region weighed (sparser on large discs).
const MASS_SAMPLES: f64 = 28.0;

/// True when the light inside the black disc adds up to a white disc of a
/// printed WhyCon marker: of its area, and shaped as the outline.
///
/// Each pixel within `MASS_REACH` of the outline counts for its share of
/// the way from the annulus's ink to the margin's `paper`. Blur spreads the
/// white disc's light but keeps its sum, so the area is a printed ratio at
/// every size (the radius where an edge crosses halfway shrinks on a small,
/// blurred disc); and it adds the same spread in every direction, so the
/// anisotropy of the light's second moments is the disc's own: for a view
/// of concentric circles, the outline's scaled by the area ratio.
fn white_disc_mass(gray: Gray<'_>, outer: &Ellipse, paper: f64, limits: &MassLimits) -> bool {
    let reach = MASS_REACH * outer.semi_major;
    let (x0, x1) = ((outer.u - reach).floor(), (outer.u + reach).ceil());
    let (y0, y1) = ((outer.v - reach).floor(), (outer.v + reach).ceil());
    if x0 < 0.0 || y0 < 0.0 || x1 >= gray.width as f64 || y1 >= gray.height as f64 {
        // Cut by the border: the edge tests alone decide.
        return true;
    }
    let stride = ((x1 - x0) / MASS_SAMPLES).ceil().max(1.0) as usize;
    let (s, c) = outer.angle.sin_cos();
    // Squared radius relative to the outline, and the grey, of each sample.
    let samples = (y0 as usize..=y1 as usize)
        .step_by(stride)
        .flat_map(|y| {
            (x0 as usize..=x1 as usize)
                .step_by(stride)
                .map(move |x| (x, y))
        })
        .map(|(x, y)| {
            let (dx, dy) = (x as f64 - outer.u, y as f64 - outer.v);
            let (p, q) = (dx * c + dy * s, -dx * s + dy * c);
            let rho2 = (p / outer.semi_major).powi(2) + (q / outer.semi_minor).powi(2);
            (dx, dy, rho2, f64::from(gray.pixels[y * gray.width + x]))
        });
    // The ink: the annulus between the white disc's blur and the edge's.
    let mut ink: Vec<f64> = samples
        .clone()
        .filter(|t| (0.62 * 0.62..=0.85 * 0.85).contains(&t.2))
        .map(|t| t.3)
        .collect();
    if ink.is_empty() {
        return true;
    }
    let middle = ink.len() / 2;
    let black = *ink.select_nth_unstable_by(middle, f64::total_cmp).1;
    // The ink's noise (median absolute deviation), which every pixel
    // weighed carries too.
    let mut deviations: Vec<f64> = ink.iter().map(|g| (g - black).abs()).collect();
    let noise_grey = 1.4826 * *deviations.select_nth_unstable_by(middle, f64::total_cmp).1;
    // The white disc is the paper the marker is printed on, so its middle
    // is no lighter than the margin beyond what the margin's blur and the
    // noise explain: a light middle that outshines its surroundings is a
    // hole onto something lighter (a washer, a ring drawn on a darker
    // ground). Its light is then weighed against its own white, not the
    // margin's, or a darker margin would make the disc look larger.
    let mut middle: Vec<f64> = samples
        .clone()
        .filter(|t| t.2 <= MIDDLE * MIDDLE)
        .map(|t| t.3)
        .collect();
    let mut white = paper;
    if !middle.is_empty() {
        let half = middle.len() / 2;
        let light = *middle.select_nth_unstable_by(half, f64::total_cmp).1;
        let slack = MEDIAN_SIGMAS * noise_grey / (middle.len() as f64).sqrt();
        if light - paper > MAX_GLOW * (paper - black) + slack {
            return false;
        }
        white = white.max(light);
    }
    let contrast = white - black;
    if contrast <= 0.0 {
        return false;
    }
    let (mut m0, mut mx, mut my, mut mxx, mut mxy, mut myy) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    // Sums of the squared lever arms of the first and second moments, for
    // their noise.
    let (mut n, mut r2_sum, mut r4_sum) = (0.0f64, 0.0, 0.0);
    for (dx, dy, rho2, grey) in samples {
        if rho2 <= MASS_REACH * MASS_REACH {
            let w = (grey - black) / contrast;
            m0 += w;
            mx += w * dx;
            my += w * dy;
            mxx += w * dx * dx;
            mxy += w * dx * dy;
            myy += w * dy * dy;
            let r2 = dx * dx + dy * dy;
            n += 1.0;
            r2_sum += r2;
            r4_sum += r2 * r2;
        }
    }
    if m0 <= 0.0 {
        return false;
    }
    let cell = (stride * stride) as f64;
    let area = m0 * cell;
    let ratio = (area / outer.area()).sqrt();
    let (cx, cy) = (mx / m0, my / m0);
    let (cxx, cxy, cyy) = (mxx / m0 - cx * cx, mxy / m0 - cx * cy, myy / m0 - cy * cy);
    // Anisotropy as (cos 2θ, sin 2θ) parts; a uniform ellipse of semi-axes
    // a, b has (a² - b²) / 8 along its major axis.
    let expected = ratio * ratio * (outer.semi_major.powi(2) - outer.semi_minor.powi(2)) / 8.0;
    let (s2, c2) = (2.0 * outer.angle).sin_cos();
    let excess = (0.5 * (cxx - cyy) - expected * c2).hypot(cxy - expected * s2);
    let spread = 0.5 * (cxx + cyy);
    let size2 = outer.semi_major * outer.semi_minor;
    // Three standard deviations of what the noise alone moves each measure.
    let noise = 3.0 * noise_grey / contrast;
    let ratio_slack = noise * n.sqrt() * cell / outer.area() / (2.0 * ratio);
    let excess_slack = noise * (r4_sum / 4.0).sqrt() / m0;
    let offset_slack = noise * (r2_sum / 2.0).sqrt() / m0;
    (limits.ratio.start() - ratio_slack..=limits.ratio.end() + ratio_slack).contains(&ratio)
        && excess <= MASS_ELONGATION_PX2 + limits.elongation * spread + excess_slack
        && cx.hypot(cy)
            <= MASS_DECENTRE_PX
                + MASS_DECENTRE_PERSPECTIVE * size2
                + limits.decentre_px
                + offset_slack
}
