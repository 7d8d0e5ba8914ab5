//! How the marker is seen at each compared pixel: a footprint of points
//! (a pixel's area through a little blur, or smeared along a segment by
//! motion), or the pixel's area rasterised and blurred by a Gaussian as a
//! camera out of focus forms it. [`RingPixels`] holds a ring's compared
//! pixels with what every footprint samples of the marker there.

use std::f64::consts::PI;
use std::ops::Deref;

use image::{ImageBuffer, Luma};

use super::{COMPARED_RADIUS, PHASE_STEPS};
use crate::geometry::{RING_INNER_RATIO, WHYCODE_WHITE_RATIO};
use crate::math::Ellipse as ImageEllipse;

/// How one pixel's model value is formed from the marker's pattern.
pub(super) enum Footprint {
    /// Averaged over these sub-pixel offsets and weights (summing to 1).
    Points(Vec<(f64, f64, f64)>),
    /// The pixel's area (4x4 samples) seen through a Gaussian of this
    /// sigma, pixels ([`rendered_through_gaussian`]).
    Gaussian(f64),
}

/// A pixel's area seen through a Gaussian blur of `blur` pixels: a 5x5
/// grid of sub-samples, Gaussian-weighted.
pub(super) fn gaussian_footprint(blur: f64) -> Footprint {
    let sigma = (blur * blur + 1.0 / 12.0).sqrt();
    let offsets: Vec<(f64, f64, f64)> = (-2..=2)
        .flat_map(|i| (-2..=2).map(move |j| (i, j)))
        .map(|(i, j)| {
            let (dx, dy) = (f64::from(i) * 0.8 * sigma, f64::from(j) * 0.8 * sigma);
            (dx, dy, (-(dx * dx + dy * dy) / (2.0 * sigma * sigma)).exp())
        })
        .collect();
    let total: f64 = offsets.iter().map(|o| o.2).sum();
    Footprint::Points(
        offsets
            .into_iter()
            .map(|(x, y, w)| (x, y, w / total))
            .collect(),
    )
}

/// A pixel smeared along a segment of `length` pixels in direction
/// `angle`: samples a pixel apart (the pixel's own width fills between them).
pub(super) fn line_footprint(length: f64, angle: f64) -> Footprint {
    let taps = (length.ceil() as usize).max(1) + 1;
    let (s, c) = angle.sin_cos();
    Footprint::Points(
        (0..taps)
            .map(|k| {
                let t = (k as f64 / (taps - 1) as f64 - 0.5) * length;
                (t * c, t * s, 1.0 / taps as f64)
            })
            .collect(),
    )
}

/// An image point in the marker's frame: p along the outline's major axis,
/// q along the minor one turned so that the parameter runs visually
/// counter-clockwise (as in the ring reader's frame), both in radii.
#[derive(Debug, Clone, Copy)]
pub(super) struct MarkerFrame {
    u: f64,
    v: f64,
    pub(super) sin: f64,
    pub(super) cos: f64,
    pub(super) a: f64,
    pub(super) b: f64,
}

impl MarkerFrame {
    pub(super) fn of(outer: &ImageEllipse) -> MarkerFrame {
        let (sin, cos) = outer.angle.sin_cos();
        MarkerFrame {
            u: outer.u,
            v: outer.v,
            sin,
            cos,
            a: outer.semi_major,
            b: outer.semi_minor,
        }
    }

    #[inline]
    pub(super) fn marker_point(&self, x: f64, y: f64) -> (f64, f64) {
        let (dx, dy) = (x - self.u, y - self.v);
        (
            (dx * self.cos + dy * self.sin) / self.a,
            (dx * self.sin - dy * self.cos) / self.b,
        )
    }
}

/// The pixels of one ring that the model is compared with, and what each
/// footprint samples of the marker at them: read once, then compared with
/// the family and with rings of the neighbouring bit counts
/// ([`RingPixels::neighbour_count_fits_better`]), whose sectors differ but whose
/// samples do not.
pub(super) struct RingPixels {
    pub(super) frame: MarkerFrame,
    /// (x, y, grey) of each pixel compared.
    pub(super) pixels: Vec<(f64, f64, f64)>,
    pub(super) sum_y: f64,
    /// Σ (y − ȳ)².
    pub(super) syy: f64,
    pub(super) footprints: Vec<Sampled>,
    /// What every pixel's area covers of the marker, for the Gaussians.
    pub(super) subsamples: Option<SubSamples>,
}

/// A footprint's samples of the marker at the compared pixels.
pub(super) enum Sampled {
    /// Per pixel: the weight on white outside the code ring, and the
    /// (angle, weight) of each sample inside the ring.
    Points(Vec<f64>, PerPixel<(f64, f64)>),
    /// The pixel's area seen through a Gaussian of this sigma, pixels.
    Gaussian(f64),
}

impl RingPixels {
    /// `None` when the ring leaves the image or shows too few pixels (or
    /// none but one grey) to compare.
    pub(super) fn read<C: Deref<Target = [u8]>>(
        image: &ImageBuffer<Luma<u8>, C>,
        outer: &ImageEllipse,
        footprints: &[Footprint],
        stride: u32,
    ) -> Option<RingPixels> {
        let (a, b) = (outer.semi_major, outer.semi_minor);
        if !(a.is_finite() && b > 1.0 && outer.u.is_finite() && outer.v.is_finite()) {
            return None;
        }
        let frame = MarkerFrame::of(outer);
        let (width, height) = image.dimensions();
        let reach = a * COMPARED_RADIUS + 1.0;
        let (x0, x1) = ((outer.u - reach).floor(), (outer.u + reach).ceil());
        let (y0, y1) = ((outer.v - reach).floor(), (outer.v + reach).ceil());
        if x0 < 0.0 || y0 < 0.0 || x1 >= f64::from(width) || y1 >= f64::from(height) {
            return None;
        }
        let mut pixels: Vec<(f64, f64, f64)> = Vec::new();
        for y in (y0 as u32..=y1 as u32).step_by(stride as usize) {
            for x in (x0 as u32..=x1 as u32).step_by(stride as usize) {
                let (p, q) = frame.marker_point(f64::from(x), f64::from(y));
                if radius(p, q) <= COMPARED_RADIUS {
                    pixels.push((
                        f64::from(x),
                        f64::from(y),
                        f64::from(image.get_pixel(x, y).0[0]),
                    ));
                }
            }
        }
        let count = pixels.len() as f64;
        if count < 12.0 {
            return None;
        }
        let sum_y: f64 = pixels.iter().map(|p| p.2).sum();
        let syy = pixels.iter().map(|p| p.2 * p.2).sum::<f64>() - sum_y * sum_y / count;
        if syy <= 0.0 {
            return None;
        }
        // The pixels' coverage of the marker is formed once for every
        // Gaussian tried, out to the widest one's reach.
        let widest = footprints
            .iter()
            .filter_map(|f| match f {
                Footprint::Gaussian(sigma) => Some(gaussian_kernel(*sigma).1),
                Footprint::Points(_) => None,
            })
            .max();
        let subsamples = widest.map(|reach| SubSamples::of(&pixels, reach, &frame));
        let footprints = footprints
            .iter()
            .map(|f| match f {
                Footprint::Gaussian(sigma) => Sampled::Gaussian(*sigma),
                Footprint::Points(offsets) => {
                    let (fixed, ring) = sampled_through(&pixels, offsets, &frame);
                    Sampled::Points(fixed, ring)
                }
            })
            .collect();
        Some(RingPixels {
            frame,
            pixels,
            sum_y,
            syy,
            footprints,
            subsamples,
        })
    }
}

/// Per pixel of `pixels`: the weight of its footprint `offsets` on white
/// outside the code ring, and the (angle, weight) of the footprint's
/// samples inside the ring.
fn sampled_through(
    pixels: &[(f64, f64, f64)],
    offsets: &[(f64, f64, f64)],
    frame: &MarkerFrame,
) -> (Vec<f64>, PerPixel<(f64, f64)>) {
    let mut fixed = Vec::with_capacity(pixels.len());
    let mut ring_samples = PerPixel::with_capacity(pixels.len(), pixels.len() * offsets.len());
    for &(x, y, _) in pixels {
        let mut white = 0.0;
        for &(dx, dy, w) in offsets {
            let (p, q) = frame.marker_point(x + dx, y + dy);
            let rho = radius(p, q);
            if !(RING_INNER_RATIO..1.0).contains(&rho) {
                white += w;
            } else if rho < WHYCODE_WHITE_RATIO {
                ring_samples.push((q.atan2(p).rem_euclid(2.0 * PI), w));
            }
        }
        fixed.push(white);
        ring_samples.end_pixel();
    }
    (fixed, ring_samples)
}

/// Entries per compared pixel, every pixel's run in one buffer: a ring's
/// pixels are sampled for every blur and bit count compared, and one
/// allocation a pixel cost more than the sampling.
pub(super) struct PerPixel<T> {
    /// Where each pixel's run ends in `entries`.
    ends: Vec<usize>,
    entries: Vec<T>,
}

impl<T> PerPixel<T> {
    fn with_capacity(pixels: usize, entries: usize) -> PerPixel<T> {
        PerPixel {
            ends: Vec::with_capacity(pixels),
            entries: Vec::with_capacity(entries),
        }
    }

    /// Adds an entry to the current pixel's run.
    fn push(&mut self, entry: T) {
        self.entries.push(entry);
    }

    /// Closes the current pixel's run; the next entry is the next pixel's.
    fn end_pixel(&mut self) {
        self.ends.push(self.entries.len());
    }

    /// The entries of the current pixel's run so far.
    fn current_mut(&mut self) -> &mut [T] {
        let start = self.ends.last().copied().unwrap_or(0);
        &mut self.entries[start..]
    }

    /// Every pixel's run, in the pixels' order.
    pub(super) fn runs(&self) -> impl Iterator<Item = &[T]> {
        self.ends.iter().scan(0, |start, &end| {
            let run = &self.entries[*start..end];
            *start = end;
            Some(run)
        })
    }
}

/// The wedge of `wedges` (equal, the first from angle 0) holding the
/// angle `t` in [0, 2π).
fn wedge_of(t: f64, wedges: usize) -> usize {
    let wedge_angle = 2.0 * PI / wedges as f64;
    ((t / wedge_angle) as usize).min(wedges - 1)
}

/// Samples at angles binned into the wedges of a ring of `sectors`
/// ([`WEDGES_PER_SECTOR`] a sector), one entry a wedge.
pub(super) fn in_wedges(samples: &PerPixel<(f64, f64)>, sectors: usize) -> PerPixel<(usize, f64)> {
    let wedges = sectors * WEDGES_PER_SECTOR;
    let mut binned = PerPixel::with_capacity(samples.ends.len(), samples.entries.len());
    for inside in samples.runs() {
        for &(t, w) in inside {
            let wedge = wedge_of(t, wedges);
            // Neighbouring samples mostly share a wedge.
            match binned.current_mut().iter_mut().find(|(j, _)| *j == wedge) {
                Some((_, sum)) => *sum += w,
                None => binned.push((wedge, w)),
            }
        }
        binned.end_pixel();
    }
    binned
}

/// Wedges a half-sector is cut into: the phase steps within it, so every
/// phase the comparison tries is a whole number of wedges.
pub(super) const WEDGES_PER_SECTOR: usize = PHASE_STEPS / 2;

/// Weights under the blur below this are left out.
const NEGLIGIBLE_WEIGHT: f64 = 1e-5;

/// What each pixel's area covers of the marker, for [`rendered_through_gaussian`]:
/// white (the centre disc and the paper), and each of the ring's thin
/// wedges (4x4 samples a pixel, as a camera's pixel integrates).
pub(super) struct Coverage<'a> {
    white: &'a Patch,
    /// Per wedge: the pixels it covers and by how much.
    wedges: Vec<Vec<(i64, i64, f64)>>,
}

/// The 4x4 samples of every pixel's area around a ring, for [`Coverage`]:
/// which fall on white, and the angle of each that falls in the code ring
/// (binned into wedges once per bit count).
pub(super) struct SubSamples {
    white: Patch,
    /// (x, y, angle) of each sample in the ring, a pixel's together.
    ring: Vec<(i64, i64, f64)>,
}

/// The smallest box (x0, y0, x1, y1, inclusive) holding the pixels.
fn pixel_box(pixels: &[(f64, f64, f64)]) -> (i64, i64, i64, i64) {
    pixels.iter().fold(
        (i64::MAX, i64::MAX, i64::MIN, i64::MIN),
        |(x0, y0, x1, y1), &(x, y, _)| {
            let (x, y) = (x as i64, y as i64);
            (x0.min(x), y0.min(y), x1.max(x), y1.max(y))
        },
    )
}

/// Samples a side of a pixel's area in [`SubSamples`].
const SUBSAMPLES_SIDE: usize = 4;

impl SubSamples {
    /// Over the box of `pixels` grown by `reach`.
    fn of(pixels: &[(f64, f64, f64)], reach: i64, frame: &MarkerFrame) -> SubSamples {
        let (x0, y0, x1, y1) = pixel_box(pixels);
        let (gx, gy) = (x0 - reach, y0 - reach);
        let (gw, gh) = (x1 - x0 + 1 + 2 * reach, y1 - y0 + 1 + 2 * reach);
        let mut white = Patch::zeros(gx, gy, gw, gh);
        let mut ring = Vec::new();
        let share = 1.0 / (SUBSAMPLES_SIDE * SUBSAMPLES_SIDE) as f64;
        for py in gy..gy + gh {
            for px in gx..gx + gw {
                let mut light = 0u32;
                for k in 0..SUBSAMPLES_SIDE * SUBSAMPLES_SIDE {
                    let du = ((k % SUBSAMPLES_SIDE) as f64 + 0.5) / SUBSAMPLES_SIDE as f64 - 0.5;
                    let dv = ((k / SUBSAMPLES_SIDE) as f64 + 0.5) / SUBSAMPLES_SIDE as f64 - 0.5;
                    let (p, q) = frame.marker_point(px as f64 + du, py as f64 + dv);
                    let rho = radius(p, q);
                    if !(RING_INNER_RATIO..1.0).contains(&rho) {
                        light += 1;
                    } else if rho < WHYCODE_WHITE_RATIO {
                        ring.push((px, py, q.atan2(p).rem_euclid(2.0 * PI)));
                    }
                }
                if light > 0 {
                    white.set(px, py, f64::from(light) * share);
                }
            }
        }
        SubSamples { white, ring }
    }

    /// The coverage of the wedges of a ring of `sectors`.
    pub(super) fn binned(&self, sectors: usize) -> Coverage<'_> {
        let count = sectors * WEDGES_PER_SECTOR;
        let share = 1.0 / (SUBSAMPLES_SIDE * SUBSAMPLES_SIDE) as f64;
        let mut wedges: Vec<Vec<(i64, i64, f64)>> = vec![Vec::new(); count];
        for &(px, py, t) in &self.ring {
            let cells = &mut wedges[wedge_of(t, count)];
            // A pixel's samples come together: its cell is the last one.
            match cells.last_mut() {
                Some((x, y, w)) if (*x, *y) == (px, py) => *w += share,
                _ => cells.push((px, py, share)),
            }
        }
        Coverage {
            white: &self.white,
            wedges,
        }
    }
}

/// The sampled Gaussian of `sigma` pixels out to three sigma, normalised,
/// and its reach.
fn gaussian_kernel(sigma: f64) -> (Vec<f64>, i64) {
    let reach = (3.0 * sigma).ceil().max(1.0) as i64;
    let kernel: Vec<f64> = (-reach..=reach)
        .map(|i| (-((i * i) as f64) / (2.0 * sigma * sigma)).exp())
        .collect();
    let total: f64 = kernel.iter().sum();
    (kernel.into_iter().map(|w| w / total).collect(), reach)
}

/// [`sampled_through`] for a Gaussian focus blur of `sigma` pixels,
/// formed as a camera forms it: the `coverage` of each pixel's area (by
/// white, black and each of the ring's thin wedges) blurred by the sampled
/// Gaussian. A footprint of a few points samples sharp sector edges too
/// coarsely under a blur of a pixel or two (a step of a fifth of the
/// contrast as an edge crosses a point: residuals several times the
/// noise's on a ring out of focus); this does not. Each wedge's weight
/// carries the wedge's middle angle, so the phases the comparison tries
/// (whole wedges) split the wedges exactly at the sector edges.
pub(super) fn rendered_through_gaussian(
    pixels: &[(f64, f64, f64)],
    sigma: f64,
    coverage: &Coverage,
) -> (Vec<f64>, PerPixel<(usize, f64)>) {
    let (kernel, reach) = gaussian_kernel(sigma);
    let white = coverage.white.blurred(&kernel, reach);
    let fixed: Vec<f64> = pixels
        .iter()
        .map(|&(x, y, _)| white.get(x as i64, y as i64))
        .collect();
    // Each wedge's blurred coverage is handed to the compared pixels it
    // reaches (a pixel's wedges in order), through the pixels' index on
    // the grid of their box.
    let index = PixelIndex::of(pixels);
    let blurred: Vec<(usize, Patch)> = coverage
        .wedges
        .iter()
        .enumerate()
        .filter_map(|(j, cells)| {
            let (a, b, c, d) = cells.iter().fold(None, |span, &(x, y, _)| {
                let (a, b, c, d) = span.unwrap_or((x, y, x, y));
                Some((a.min(x), b.min(y), c.max(x), d.max(y)))
            })?;
            let mut patch = Patch::zeros(a, b, c - a + 1, d - b + 1);
            for &(x, y, w) in cells {
                patch.set(x, y, w);
            }
            Some((j, patch.blurred(&kernel, reach)))
        })
        .collect();
    // Two passes: how many wedges reach each pixel, then the wedges in
    // order into each pixel's run.
    let mut ends = vec![0usize; pixels.len()];
    for (_, patch) in &blurred {
        index.for_each_within(patch, |k, w| {
            if w > NEGLIGIBLE_WEIGHT {
                ends[k] += 1;
            }
        });
    }
    let mut total = 0;
    for end in &mut ends {
        total += *end;
        *end = total;
    }
    let mut next: Vec<usize> = std::iter::once(0)
        .chain(ends.iter().copied())
        .take(pixels.len())
        .collect();
    let mut entries = vec![(0usize, 0.0f64); total];
    for (j, patch) in &blurred {
        index.for_each_within(patch, |k, w| {
            if w > NEGLIGIBLE_WEIGHT {
                entries[next[k]] = (*j, w);
                next[k] += 1;
            }
        });
    }
    (fixed, PerPixel { ends, entries })
}

/// Where each compared pixel lies on the grid of the pixels' box.
struct PixelIndex {
    x0: i64,
    y0: i64,
    width: i64,
    height: i64,
    /// Per grid cell, the pixel there ([`usize::MAX`] for none).
    cells: Vec<usize>,
}

impl PixelIndex {
    fn of(pixels: &[(f64, f64, f64)]) -> PixelIndex {
        let (x0, y0, x1, y1) = pixel_box(pixels);
        let (width, height) = ((x1 - x0 + 1).max(0), (y1 - y0 + 1).max(0));
        let mut cells = vec![usize::MAX; (width * height) as usize];
        for (k, &(x, y, _)) in pixels.iter().enumerate() {
            cells[((y as i64 - y0) * width + (x as i64 - x0)) as usize] = k;
        }
        PixelIndex {
            x0,
            y0,
            width,
            height,
            cells,
        }
    }

    /// Calls `visit` with (pixel, value) of every compared pixel inside
    /// `patch`.
    fn for_each_within(&self, patch: &Patch, mut visit: impl FnMut(usize, f64)) {
        let (xa, xb) = (
            patch.x0.max(self.x0),
            (patch.x0 + patch.width).min(self.x0 + self.width),
        );
        let (ya, yb) = (
            patch.y0.max(self.y0),
            (patch.y0 + patch.height).min(self.y0 + self.height),
        );
        if xa >= xb {
            return;
        }
        for y in ya..yb {
            let cells = &self.cells[((y - self.y0) * self.width + (xa - self.x0)) as usize..]
                [..(xb - xa) as usize];
            let values = &patch.values[((y - patch.y0) * patch.width + (xa - patch.x0)) as usize..]
                [..(xb - xa) as usize];
            for (&k, &value) in cells.iter().zip(values) {
                if k != usize::MAX {
                    visit(k, value);
                }
            }
        }
    }
}

/// A dense box of values on the pixel grid, zero outside.
#[derive(Clone)]
struct Patch {
    x0: i64,
    y0: i64,
    width: i64,
    height: i64,
    values: Vec<f64>,
}

impl Patch {
    fn zeros(x0: i64, y0: i64, width: i64, height: i64) -> Patch {
        Patch {
            x0,
            y0,
            width,
            height,
            values: vec![0.0; (width.max(0) * height.max(0)) as usize],
        }
    }

    fn index(&self, x: i64, y: i64) -> Option<usize> {
        let (i, j) = (x - self.x0, y - self.y0);
        ((0..self.width).contains(&i) && (0..self.height).contains(&j))
            .then(|| (j * self.width + i) as usize)
    }

    fn get(&self, x: i64, y: i64) -> f64 {
        self.index(x, y).map_or(0.0, |k| self.values[k])
    }

    fn set(&mut self, x: i64, y: i64, value: f64) {
        if let Some(k) = self.index(x, y) {
            self.values[k] = value;
        }
    }

    /// Blurred by the separable `kernel` (2 `reach` + 1 taps), grown by
    /// `reach` on every side so nothing is cut.
    fn blurred(&self, kernel: &[f64], reach: i64) -> Patch {
        let mut rows = Patch::zeros(
            self.x0 - reach,
            self.y0,
            self.width + 2 * reach,
            self.height,
        );
        for y in 0..self.height {
            for x in 0..self.width {
                let v = self.values[(y * self.width + x) as usize];
                if v == 0.0 {
                    continue;
                }
                let base = (y * rows.width + x) as usize;
                for (k, w) in kernel.iter().enumerate() {
                    rows.values[base + k] += w * v;
                }
            }
        }
        let mut out = Patch::zeros(
            rows.x0,
            self.y0 - reach,
            rows.width,
            self.height + 2 * reach,
        );
        for y in 0..rows.height {
            for x in 0..rows.width {
                let v = rows.values[(y * rows.width + x) as usize];
                if v == 0.0 {
                    continue;
                }
                for (k, w) in kernel.iter().enumerate() {
                    out.values[((y + k as i64) * out.width + x) as usize] += w * v;
                }
            }
        }
        out
    }
}

/// The radii the model's pixels are sorted by.
const RADIUS_BOUNDS: [f64; 4] = [RING_INNER_RATIO, WHYCODE_WHITE_RATIO, COMPARED_RADIUS, 1.0];

/// hypot(p, q) as far as the comparisons with [`RADIUS_BOUNDS`] can tell:
/// the plain square root is a few times cheaper than `hypot` (a library
/// call), and differs from it by an ulp or so, which matters only within
/// a hair of a bound, where `hypot` decides as before. The model is
/// compared at 75 sub-samples per pixel, on every small round candidate
/// of a cluttered frame.
#[inline]
fn radius(p: f64, q: f64) -> f64 {
    let r = (p * p + q * q).sqrt();
    if RADIUS_BOUNDS.iter().any(|&b| (r - b).abs() <= 1e-9) {
        p.hypot(q)
    } else {
        r
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::detect::ring::test_images::draw;
    use crate::family::Family;
    use crate::geometry::Marker;

    #[test]
    fn a_footprint_of_points_weighs_one_pixel() {
        for blur in [0.35, 0.7, 1.05] {
            let Footprint::Points(offsets) = gaussian_footprint(blur) else {
                panic!("points");
            };
            let total: f64 = offsets.iter().map(|o| o.2).sum();
            assert!((total - 1.0).abs() < 1e-12, "{blur}: {total}");
        }
        // A smear 5 px long at 30°: its ends 5 px apart in that direction.
        let Footprint::Points(taps) = line_footprint(5.0, 30f64.to_radians()) else {
            panic!("points");
        };
        let total: f64 = taps.iter().map(|t| t.2).sum();
        assert!((total - 1.0).abs() < 1e-12, "{total}");
        let (first, last) = (taps[0], taps[taps.len() - 1]);
        let (dx, dy) = (last.0 - first.0, last.1 - first.1);
        assert!((dx.hypot(dy) - 5.0).abs() < 1e-12);
        assert!((dy.atan2(dx) - 30f64.to_radians()).abs() < 1e-12);
    }

    #[test]
    fn a_blurred_patch_keeps_its_weight_and_spreads_it_evenly() {
        let mut patch = Patch::zeros(10, 20, 1, 1);
        patch.set(10, 20, 1.0);
        let (kernel, reach) = gaussian_kernel(1.0);
        let blurred = patch.blurred(&kernel, reach);
        let total: f64 = blurred.values.iter().sum();
        assert!((total - 1.0).abs() < 1e-12, "{total}");
        let centre = blurred.get(10, 20);
        for (x, y) in [(9, 20), (11, 20), (10, 19), (10, 21)] {
            assert!((blurred.get(x, y) - blurred.get(10, 21)).abs() < 1e-15);
            assert!(blurred.get(x, y) < centre);
        }
        // Nothing beyond the kernel's reach.
        assert_eq!(blurred.get(10 + reach + 1, 20), 0.0);
    }

    /// Through a Gaussian, each pixel's area is shared between the white
    /// (the centre disc and the paper), the ring's wedges and the black:
    /// white and wedges together never weigh more than the pixel.
    #[test]
    fn a_pixel_through_a_gaussian_is_white_ring_and_black() {
        let family = Family::generate(8, 2).unwrap();
        let marker = Marker::whycode(8, family.code(3).unwrap(), 50.0);
        let (image, outline) = draw(&marker, 20.0, 32, (16.0, 16.0), 0.0);
        let sigma = 0.5;
        let ring = RingPixels::read(&image, &outline, &[Footprint::Gaussian(sigma)], 1).unwrap();
        let coverage = ring.subsamples.as_ref().unwrap().binned(16);
        let (fixed, wedges) = rendered_through_gaussian(&ring.pixels, sigma, &coverage);
        let mut in_ring = 0;
        for ((&(x, y, _), &white), run) in ring.pixels.iter().zip(&fixed).zip(wedges.runs()) {
            let inside: f64 = run.iter().map(|s| s.1).sum();
            assert!(white >= 0.0 && white + inside <= 1.0 + 1e-9, "{x} {y}");
            if (x, y) == (16.0, 16.0) {
                // The centre disc alone.
                assert!(
                    (white - 1.0).abs() < 1e-9 && run.is_empty(),
                    "{white} {run:?}"
                );
            }
            if inside > 0.9 {
                in_ring += 1;
            }
        }
        // The ring is 2.6 px wide here: a pixel in its middle sees it almost
        // alone.
        assert!(in_ring > 0);
    }
}
