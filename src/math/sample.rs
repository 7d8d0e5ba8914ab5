//! The one bilinear sampler, with pixel centres at integer coordinates and an
//! explicit policy for what happens near the image border.
//!
//! The policies differ on purpose: the detector must not invent grey levels
//! beyond the last pixel (a ray leaving the image ends there), the paper-edge
//! search of `validate` may land exactly on the last row or column, and the
//! simulator's blur smears the border outwards like a real lens does.

/// A row-major grey plane borrowed from an image buffer.
#[derive(Debug, Clone, Copy)]
pub struct Plane<'a, T> {
    /// The samples, row after row, without padding.
    pub pixels: &'a [T],
    /// Samples per row.
    pub width: usize,
    /// Number of rows.
    pub height: usize,
}

/// What [`Plane::at`] does near the border.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Border {
    /// `None` unless the whole 2×2 neighbourhood lies in the image (the
    /// last row and column are only reached from inside).
    Interior,
    /// `None` outside the rectangle of pixel centres [0, w-1] × [0, h-1];
    /// on the last row or column the missing neighbour has weight zero.
    Closed,
    /// Coordinates clamped to the rectangle of pixel centres: the border
    /// extends outwards. `None` only for an empty plane.
    Clamp,
}

/// `(floor(x), floor(y))` where the pixel after each is still inside a
/// plane of `width` × `height` (0 ≤ x < width - 1, 0 ≤ y < height - 1),
/// else `None`. Signed, and the floor a bare truncation: an unsigned
/// conversion either way, or a saturating one, is a dozen instructions,
/// and the ring and pose stages sample a thousand times per marker.
#[inline(always)]
pub(crate) fn floor_inside(x: f64, y: f64, width: usize, height: usize) -> Option<(i64, i64)> {
    let (x_end, y_end) = ((width as i64 - 1) as f64, (height as i64 - 1) as f64);
    if !(x >= 0.0 && y >= 0.0 && x < x_end && y < y_end) {
        return None;
    }
    // SAFETY: x and y are finite, non-negative and below a usize, so they
    // fit an i64; truncation is floor for non-negative values.
    Some(unsafe { (x.to_int_unchecked::<i64>(), y.to_int_unchecked::<i64>()) })
}

/// The bilinear blend of the 2×2 neighbourhood whose top-left pixel is
/// `q[0]` (rows `width` apart; `q` holds `width + 2` pixels), at the
/// offsets (`fx`, `fy`) from that pixel.
#[inline(always)]
fn blend_2x2<T: Texel>(q: &[T], width: usize, fx: f64, fy: f64) -> T::Value {
    let top = T::blend(q[0], q[1], fx);
    let bottom = T::blend(q[width], q[width + 1], fx);
    T::blend_values(top, bottom, fy)
}

/// A pixel type the sampler can blend, and the precision it blends in.
pub trait Texel: Copy {
    /// What a blend computes in: f64 for bytes, so blends never round in
    /// between; f32 stays f32, as the simulator's image bytes depend on it.
    type Value: Copy;
    /// Interpolates between `a` (t = 0) and `b` (t = 1).
    fn blend(a: Self, b: Self, t: f64) -> Self::Value;
    /// Interpolates between two already blended values.
    fn blend_values(a: Self::Value, b: Self::Value, t: f64) -> Self::Value;
}

/// 8-bit photos blend in f64 as a + t (b - a).
impl Texel for u8 {
    type Value = f64;
    #[inline]
    fn blend(a: u8, b: u8, t: f64) -> f64 {
        Self::blend_values(f64::from(a), f64::from(b), t)
    }
    #[inline]
    fn blend_values(a: f64, b: f64, t: f64) -> f64 {
        a + t * (b - a)
    }
}

/// The simulator's linear-light planes blend in f32 as a (1 - t) + b t:
/// its rendered image bytes depend on this exact arithmetic.
impl Texel for f32 {
    type Value = f32;
    #[inline]
    fn blend(a: f32, b: f32, t: f64) -> f32 {
        Self::blend_values(a, b, t)
    }
    #[inline]
    fn blend_values(a: f32, b: f32, t: f64) -> f32 {
        let t = t as f32;
        a * (1.0 - t) + b * t
    }
}

impl<'a, T: Texel> Plane<'a, T> {
    /// A view of `pixels` as `height` rows of `width`; the buffer must hold
    /// that many samples (checked in debug builds).
    pub fn new(pixels: &'a [T], width: usize, height: usize) -> Plane<'a, T> {
        debug_assert!(pixels.len() >= width * height);
        Plane {
            pixels,
            width,
            height,
        }
    }

    /// Bilinear value at (x, y) under the `border` policy.
    // Always inlined: the policy is a constant at every call site, and the
    // ring and pose stages call this a thousand times per marker.
    #[inline(always)]
    pub fn at(&self, x: f64, y: f64, border: Border) -> Option<T::Value> {
        let (w, h) = (self.width, self.height);
        let (x0, y0, x1, y1, fx, fy) = match border {
            Border::Interior => {
                // The whole 2×2 neighbourhood inside.
                let (x0, y0) = floor_inside(x, y, w, h)?;
                let (fx, fy) = (x - x0 as f64, y - y0 as f64);
                // The four pixels as one slice: one bounds check, not four.
                let start = y0 as usize * w + x0 as usize;
                return Some(blend_2x2(&self.pixels[start..start + w + 2], w, fx, fy));
            }
            Border::Closed | Border::Clamp => {
                if w == 0 || h == 0 {
                    return None;
                }
                let (max_x, max_y) = ((w - 1) as f64, (h - 1) as f64);
                let (x, y) = if border == Border::Clamp {
                    (x.clamp(0.0, max_x), y.clamp(0.0, max_y))
                } else if x >= 0.0 && y >= 0.0 && x <= max_x && y <= max_y {
                    (x, y)
                } else {
                    return None;
                };
                let (x0, y0) = (x.floor() as usize, y.floor() as usize);
                let (x1, y1) = ((x0 + 1).min(w - 1), (y0 + 1).min(h - 1));
                (x0, y0, x1, y1, x - x0 as f64, y - y0 as f64)
            }
        };
        let p = self.pixels;
        let top = T::blend(p[y0 * w + x0], p[y0 * w + x1], fx);
        let bottom = T::blend(p[y1 * w + x0], p[y1 * w + x1], fx);
        Some(T::blend_values(top, bottom, fy))
    }
}

impl Plane<'_, u8> {
    /// The values [`Plane::at`] gives with [`Border::Interior`] at the
    /// points `origin + dir·(start + step·j)`, one for each slot `j` of
    /// `out`; false (`out` then partly written) when any point has none.
    ///
    /// Each coordinate of those points, computed as written, moves one way
    /// along the line: every operation rounds monotonically. So the points
    /// lie within the box of the first and the last, and when those two
    /// have their neighbourhoods inside, every point has: the rays that
    /// measure an outline check two points, not each of their samples.
    pub fn line(
        &self,
        origin: (f64, f64),
        dir: (f64, f64),
        (start, step): (f64, f64),
        out: &mut [f64],
    ) -> bool {
        let point = |j: usize| {
            let d = start + step * j as f64;
            (origin.0 + dir.0 * d, origin.1 + dir.1 * d)
        };
        let Some(last) = out.len().checked_sub(1) else {
            return true;
        };
        let (first_point, last_point) = (point(0), point(last));
        let (w, h) = (self.width, self.height);
        let (Some(a), Some(b)) = (
            floor_inside(first_point.0, first_point.1, w, h),
            floor_inside(last_point.0, last_point.1, w, h),
        ) else {
            return false;
        };
        // The furthest neighbourhood any point can reach, checked against
        // the buffer once (a plane's buffer may be longer than its rows).
        let furthest = a.1.max(b.1) as usize * w + a.0.max(b.0) as usize + w + 2;
        if furthest > self.pixels.len() {
            for (j, slot) in out.iter_mut().enumerate() {
                let (x, y) = point(j);
                match self.at(x, y, Border::Interior) {
                    Some(value) => *slot = value,
                    None => return false,
                }
            }
            return true;
        }
        for (j, slot) in out.iter_mut().enumerate() {
            let (x, y) = point(j);
            debug_assert!(floor_inside(x, y, w, h).is_some());
            // SAFETY: (x, y) lies in the box of the two end points, whose
            // coordinates are finite and non-negative (see above), so the
            // truncations are floors within them, and the neighbourhood's
            // last pixel is at most `furthest - 1`, inside the buffer.
            let (q, fx, fy) = unsafe {
                let (x0, y0) = (x.to_int_unchecked::<i64>(), y.to_int_unchecked::<i64>());
                let start = y0 as usize * w + x0 as usize;
                let q = self.pixels.get_unchecked(start..start + w + 2);
                (q, x - x0 as f64, y - y0 as f64)
            };
            *slot = blend_2x2(q, w, fx, fy);
        }
        true
    }

    /// Reads one byte of every cache line the rows `y` span across the
    /// columns `x` (clipped to the plane). A marker's pixels lie on a
    /// hundred rows, each a separate line far from the last; loads in a
    /// tight loop overlap in flight, while the stages that need them fetch
    /// them one after another between their arithmetic. Called just before a
    /// marker's stages, it cuts the time those spend waiting on memory.
    pub fn preload(&self, x: std::ops::Range<f64>, y: std::ops::Range<f64>) {
        const LINE: usize = 64;
        let clip = |r: std::ops::Range<f64>, n: usize| {
            (r.start.max(0.0) as usize).min(n)..(r.end.max(0.0) as usize).min(n)
        };
        let (x, y) = (clip(x, self.width), clip(y, self.height));
        if x.is_empty() {
            return;
        }
        let mut sum = 0u8;
        for row in y {
            let line = &self.pixels[row * self.width..][x.clone()];
            for k in (0..line.len()).step_by(LINE) {
                sum ^= line[k];
            }
            sum ^= line[line.len() - 1];
        }
        std::hint::black_box(sum);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    // 3×2 image:  0  10  20
    //            30  40  50
    const PIXELS: [u8; 6] = [0, 10, 20, 30, 40, 50];

    #[test]
    fn interior_needs_the_whole_neighbourhood() {
        let plane = Plane::new(&PIXELS, 3, 2);
        assert_eq!(plane.at(0.5, 0.5, Border::Interior), Some(20.0));
        assert_eq!(plane.at(1.25, 0.0, Border::Interior), Some(12.5));
        assert_eq!(plane.at(2.0, 0.0, Border::Interior), None);
        assert_eq!(plane.at(0.0, 1.0, Border::Interior), None);
        assert_eq!(plane.at(-0.1, 0.0, Border::Interior), None);
        assert_eq!(plane.at(f64::NAN, 0.0, Border::Interior), None);
    }

    #[test]
    fn a_line_reads_what_each_of_its_points_reads() {
        // A 40×30 gradient with texture; rays from inside, through the
        // border, from outside in, along an edge, and of one sample.
        let (w, h) = (40, 30);
        let pixels: Vec<u8> = (0..w * h)
            .map(|i| ((i % w) * 5 + (i / w) * 3 + (i * 7919) % 13) as u8)
            .collect();
        let plane = Plane::new(&pixels, w, h);
        let mut angle = 0.1f64;
        for (origin, start, step, n) in [
            ((20.3, 15.7), 0.0, 0.7, 20),
            ((20.3, 15.7), -3.0, 1.1, 30),
            ((1.2, 28.6), 0.0, 0.5, 9),
            ((-2.0, 10.0), 0.0, 0.9, 12),
            ((38.9, 28.9), 0.0, 0.01, 5),
            ((5.5, 5.5), 2.0, 0.0, 1),
        ] {
            for _ in 0..24 {
                angle += 0.27;
                let dir = (angle.cos(), angle.sin());
                let mut got = vec![f64::NAN; n];
                let inside = plane.line(origin, dir, (start, step), &mut got);
                let each: Option<Vec<f64>> = (0..n)
                    .map(|j| {
                        let d = start + step * j as f64;
                        let (x, y) = (origin.0 + dir.0 * d, origin.1 + dir.1 * d);
                        plane.at(x, y, Border::Interior)
                    })
                    .collect();
                match each {
                    Some(expected) => {
                        assert!(inside, "{origin:?} {dir:?}");
                        assert_eq!(
                            got.iter().map(|v| v.to_bits()).collect::<Vec<_>>(),
                            expected.iter().map(|v| v.to_bits()).collect::<Vec<_>>()
                        );
                    }
                    None => assert!(!inside, "{origin:?} {dir:?}"),
                }
            }
        }
        assert!(plane.line((1.0, 1.0), (1.0, 0.0), (0.0, 1.0), &mut []));
        assert!(!plane.line((f64::NAN, 1.0), (1.0, 0.0), (0.0, 1.0), &mut [0.0; 3]));
    }

    #[test]
    fn closed_reaches_the_last_pixel_centres() {
        let plane = Plane::new(&PIXELS, 3, 2);
        assert_eq!(plane.at(2.0, 1.0, Border::Closed), Some(50.0));
        assert_eq!(plane.at(1.5, 1.0, Border::Closed), Some(45.0));
        assert_eq!(plane.at(2.01, 0.0, Border::Closed), None);
        assert_eq!(plane.at(0.0, -0.01, Border::Closed), None);
    }

    #[test]
    fn clamp_extends_the_border() {
        let plane = Plane::new(&PIXELS, 3, 2);
        assert_eq!(plane.at(-5.0, -5.0, Border::Clamp), Some(0.0));
        assert_eq!(plane.at(9.0, 0.5, Border::Clamp), Some(35.0));
        let light = [0.0f32, 1.0, 0.5, 0.25];
        let plane = Plane::new(&light, 2, 2);
        assert_eq!(plane.at(0.5, 0.5, Border::Clamp), Some(0.4375));
        assert_eq!(
            Plane::<u8>::new(&[], 0, 0).at(0.0, 0.0, Border::Clamp),
            None
        );
    }
}
