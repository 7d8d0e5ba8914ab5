//! Flood-fill segmentation with on-demand thresholding: pixels are
//! classified only when the fill reaches them, and the statistics the tests
//! need (pixel count, bounding box, first and second moments, brightness)
//! are summed while filling, in integer arithmetic.
//!
//! The fill works on horizontal runs: a run's moments have closed forms, so
//! the per-pixel work is one comparison, one label write and one addition.

use super::threshold::ThresholdMap;

/// Per-pixel visit marks, reused from frame to frame. A label is
/// `generation * 4 + kind`; bumping the generation forgets every mark of the
/// previous frame without touching the buffer, which is only cleared when
/// the generation counter wraps.
#[derive(Debug, Clone, Default)]
pub struct Labels {
    data: Vec<u8>,
    width: usize,
    height: usize,
    generation: u8,
}

const KIND_DARK: u8 = 1;
const KIND_WHITE: u8 = 2;
const MAX_GENERATION: u8 = 63;

impl Labels {
    /// Starts a fresh pass over a `width` x `height` image.
    pub fn begin(&mut self, width: usize, height: usize) {
        if self.width != width || self.height != height {
            self.data = Vec::new();
            self.data.resize(width * height, 0);
            self.width = width;
            self.height = height;
            self.generation = 0;
        }
        if self.generation >= MAX_GENERATION {
            self.data.fill(0);
            self.generation = 0;
        }
        self.generation += 1;
    }

    #[inline]
    fn dark(&self) -> u8 {
        self.generation * 4 + KIND_DARK
    }

    #[inline]
    fn white(&self) -> u8 {
        self.generation * 4 + KIND_WHITE
    }

    /// True when the pixel already belongs to a dark segment of this pass.
    #[inline]
    pub fn is_dark_visited(&self, index: usize) -> bool {
        self.data[index] == self.dark()
    }
}

/// Statistics of a segment, summed over its pixels (u = column, v = row).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stats {
    pub count: u64,
    pub min_u: u32,
    pub max_u: u32,
    pub min_v: u32,
    pub max_v: u32,
    pub sum_u: u64,
    pub sum_v: u64,
    pub sum_uu: u64,
    pub sum_uv: u64,
    pub sum_vv: u64,
    /// Sum of grey values, for the segment's mean brightness.
    pub sum_i: u64,
}

impl Default for Stats {
    fn default() -> Stats {
        Stats {
            count: 0,
            min_u: u32::MAX,
            max_u: 0,
            min_v: u32::MAX,
            max_v: 0,
            sum_u: 0,
            sum_v: 0,
            sum_uu: 0,
            sum_uv: 0,
            sum_vv: 0,
            sum_i: 0,
        }
    }
}

/// Σ k² for k in 0..=n.
#[inline]
fn sum_squares(n: u64) -> u64 {
    n * (n + 1) * (2 * n + 1) / 6
}

impl Stats {
    /// Adds the run of pixels x0..=x1 on row y.
    #[inline]
    pub fn add_run(&mut self, y: u32, x0: u32, x1: u32, sum_i: u64) {
        let n = u64::from(x1 - x0 + 1);
        let su = (u64::from(x0) + u64::from(x1)) * n / 2;
        let suu = sum_squares(u64::from(x1))
            - if x0 > 0 {
                sum_squares(u64::from(x0) - 1)
            } else {
                0
            };
        let y64 = u64::from(y);
        self.count += n;
        self.min_u = self.min_u.min(x0);
        self.max_u = self.max_u.max(x1);
        self.min_v = self.min_v.min(y);
        self.max_v = self.max_v.max(y);
        self.sum_u += su;
        self.sum_v += n * y64;
        self.sum_uu += suu;
        self.sum_uv += su * y64;
        self.sum_vv += n * y64 * y64;
        self.sum_i += sum_i;
    }

    pub fn merged(&self, other: &Stats) -> Stats {
        Stats {
            count: self.count + other.count,
            min_u: self.min_u.min(other.min_u),
            max_u: self.max_u.max(other.max_u),
            min_v: self.min_v.min(other.min_v),
            max_v: self.max_v.max(other.max_v),
            sum_u: self.sum_u + other.sum_u,
            sum_v: self.sum_v + other.sum_v,
            sum_uu: self.sum_uu + other.sum_uu,
            sum_uv: self.sum_uv + other.sum_uv,
            sum_vv: self.sum_vv + other.sum_vv,
            sum_i: self.sum_i + other.sum_i,
        }
    }

    pub fn width(&self) -> u32 {
        self.max_u - self.min_u + 1
    }

    pub fn height(&self) -> u32 {
        self.max_v - self.min_v + 1
    }

    pub fn centroid(&self) -> (f64, f64) {
        let n = self.count as f64;
        (self.sum_u as f64 / n, self.sum_v as f64 / n)
    }

    pub fn mean_intensity(&self) -> f64 {
        self.sum_i as f64 / self.count as f64
    }

    /// The covariance (uu, uv, vv), computed exactly in integers before the
    /// one division, so large coordinates lose no precision.
    pub fn covariance(&self) -> (f64, f64, f64) {
        let n = u128::from(self.count);
        let n2 = (n * n) as f64;
        let c = |sab: u64, sa: u64, sb: u64| -> f64 {
            let v = n as i128 * i128::from(sab) - i128::from(sa) * i128::from(sb);
            v as f64 / n2
        };
        (
            c(self.sum_uu, self.sum_u, self.sum_u),
            c(self.sum_uv, self.sum_u, self.sum_v),
            c(self.sum_vv, self.sum_v, self.sum_v),
        )
    }
}

/// What a fill should collect.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fill {
    /// Dark pixels not yet in a dark segment of this pass.
    Dark,
    /// Pixels at or above the threshold, inside `bounds` (min u, min v,
    /// max u, max v of the enclosing segment): a white region that reaches
    /// the bounds, or grows past `max_count`, is not enclosed by its dark
    /// segment and the fill gives up.
    White { bounds: [u32; 4], max_count: u64 },
}

/// The outcome of a fill.
#[derive(Debug, Clone, Copy)]
pub struct FillResult {
    pub stats: Stats,
    /// The white fill gave up (not enclosed or too large), or the dark fill
    /// reached the map's floor.
    pub escaped: bool,
}

/// A grey image borrowed as rows of bytes.
pub type Gray<'a> = crate::math::sample::Plane<'a, u8>;

/// The reusable work space of the flood fill.
#[derive(Debug, Clone, Default)]
pub struct Filler {
    stack: Vec<(u32, u32)>,
    /// Runs (y, x0, x1) of the last fill, to undo a failed white fill.
    runs: Vec<(u32, u32, u32)>,
}

impl Filler {
    /// Fills from (x, y) and returns the segment's statistics; the segment's
    /// pixels are labelled so that no later fill of the pass visits them.
    pub fn fill(
        &mut self,
        image: Gray<'_>,
        map: &ThresholdMap,
        labels: &mut Labels,
        seed: (u32, u32),
        mode: Fill,
    ) -> FillResult {
        let width = image.width;
        let mut stats = Stats::default();
        self.stack.clear();
        self.runs.clear();
        let (dark_label, white_label) = (labels.dark(), labels.white());
        let shift = map.shift();
        let (mark, bounds, max_count) = match mode {
            Fill::Dark => (dark_label, [0, 0, u32::MAX, u32::MAX], u64::MAX),
            Fill::White { bounds, max_count } => (white_label, bounds, max_count),
        };
        let dark = mode == Fill::Dark;
        // Fill range in x and y. A white region that reaches the segment's
        // bounding box is not enclosed by it (the box's outermost row and
        // column hold the segment's own extreme pixels, with nothing of it
        // beyond); one that only comes next to them may be: on a marker a
        // few pixels across, the black annulus is one pixel wide.
        let (x_lo, x_hi) = if dark {
            (0usize, width - 1)
        } else {
            (bounds[0] as usize, (bounds[2] as usize).min(width - 1))
        };
        let (y_lo, y_hi) = if dark {
            (0usize, image.height - 1)
        } else {
            (
                bounds[1] as usize,
                (bounds[3] as usize).min(image.height - 1),
            )
        };
        // The floor test only where there is floor: it sits in the inner loop.
        let floor_row = |y: usize| if dark { map.floor_row(y) } else { None };
        let fillable = |labels: &Labels,
                        thresholds: &[u8],
                        floor: Option<&[bool]>,
                        x: usize,
                        y: usize|
         -> bool {
            let i = y * width + x;
            let p = image.pixels[i];
            let l = labels.data[i];
            let t = thresholds[x >> shift];
            if dark {
                p < t && l != dark_label && !floor.is_some_and(|f| f[x >> shift])
            } else {
                p >= t && l != dark_label && l != white_label
            }
        };
        let (sx, sy) = (seed.0 as usize, seed.1 as usize);
        if sx < x_lo || sx > x_hi || sy < y_lo || sy > y_hi {
            return FillResult {
                stats,
                escaped: !dark,
            };
        }
        self.stack.push(seed);
        let mut escaped = false;
        while let Some((x, y)) = self.stack.pop() {
            let (x, y) = (x as usize, y as usize);
            // Past the rows of a band map the floor is unknown: a dark
            // segment that gets there is larger than any marker the band
            // was sized for, and following it would flood the floor
            // outside the band (most of a tracked frame's time on cards
            // lying on a grey floor).
            if dark && !map.holds_row(y) {
                escaped = true;
                break;
            }
            let thresholds = map.row(y);
            let floor = floor_row(y);
            if !fillable(labels, thresholds, floor, x, y) {
                continue;
            }
            let mut left = x;
            while left > x_lo && fillable(labels, thresholds, floor, left - 1, y) {
                left -= 1;
            }
            let mut right = x;
            while right < x_hi && fillable(labels, thresholds, floor, right + 1, y) {
                right += 1;
            }
            let row = y * width;
            labels.data[row + left..=row + right].fill(mark);
            let sum_i: u64 = image.pixels[row + left..=row + right]
                .iter()
                .map(|&p| u64::from(p))
                .sum();
            stats.add_run(y as u32, left as u32, right as u32, sum_i);
            self.runs.push((y as u32, left as u32, right as u32));
            // Every pixel of a floor tile is dark, so a run touching one
            // belongs to the background floor, not to a marker. Filling the
            // rest of the segment first (to label it once) cost tracked
            // frames, whose band scan reached the whole floor's fringe.
            if dark
                && (map.is_floor(left.saturating_sub(1), y)
                    || map.is_floor((right + 1).min(width - 1), y)
                    || (y > 0 && map.floor_between(y - 1, left, right))
                    || (y + 1 < image.height && map.floor_between(y + 1, left, right)))
            {
                escaped = true;
                break;
            }
            if !dark
                && (left == x_lo
                    || right == x_hi
                    || y == y_lo
                    || y == y_hi
                    || stats.count > max_count)
            {
                escaped = true;
                break;
            }
            for ny in [y.wrapping_sub(1), y + 1] {
                if ny < y_lo || ny > y_hi {
                    continue;
                }
                let thresholds = map.row(ny);
                let floor = floor_row(ny);
                let mut in_run = false;
                for nx in left..=right {
                    let f = fillable(labels, thresholds, floor, nx, ny);
                    if f && !in_run {
                        self.stack.push((nx as u32, ny as u32));
                    }
                    in_run = f;
                }
            }
        }
        FillResult { stats, escaped }
    }

    /// Forgets the labels of the last fill (a white region that turned out
    /// not to be a marker's inside may be another candidate's).
    pub fn undo_last(&self, labels: &mut Labels, width: usize) {
        for &(y, x0, x1) in &self.runs {
            let row = y as usize * width;
            labels.data[row + x0 as usize..=row + x1 as usize].fill(0);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn brute_stats(pixels: &[(u32, u32)]) -> Stats {
        let mut s = Stats::default();
        for &(x, y) in pixels {
            s.add_run(y, x, x, 0);
        }
        s
    }

    #[test]
    fn run_moments_equal_pixel_moments() {
        let mut runs = Stats::default();
        runs.add_run(7, 3, 9, 0);
        runs.add_run(8, 0, 4, 0);
        let pixels: Vec<(u32, u32)> = (3..=9)
            .map(|x| (x, 7))
            .chain((0..=4).map(|x| (x, 8)))
            .collect();
        assert_eq!(runs, brute_stats(&pixels));
    }

    /// A white card with a marker-like ring on a grey floor: the floor is
    /// dark under the card's threshold, and a fill that starts in it must
    /// give up at once instead of labelling the whole floor (which cost a
    /// 5000x5000 frame most of its time), while the ring fills as before.
    #[test]
    fn a_fill_into_the_floor_gives_up_and_a_ring_does_not() {
        let (w, h) = (480usize, 320usize);
        let mut px = vec![112u8; w * h];
        let (cx, cy) = (240i32, 160i32);
        for y in 0..h {
            for x in 0..w {
                let (dx, dy) = (x as i32 - cx, y as i32 - cy);
                if dx.abs() <= 50 && dy.abs() <= 50 {
                    let d2 = dx * dx + dy * dy;
                    px[y * w + x] = if (100..=900).contains(&d2) { 12 } else { 220 };
                }
            }
        }
        let image = Gray {
            pixels: &px,
            width: w,
            height: h,
        };
        let map = ThresholdMap::adaptive(&px, w, h);
        assert!(map.is_floor(5, 5) && map.is_floor(w - 1, h - 1));
        assert!(!map.is_floor(cx as usize - 20, cy as usize));
        let mut labels = Labels::default();
        labels.begin(w, h);
        let mut filler = Filler::default();
        let floor = filler.fill(
            image,
            &map,
            &mut labels,
            (cx as u32 - 60, cy as u32),
            Fill::Dark,
        );
        assert!(floor.escaped);
        let floor_pixels = px.iter().filter(|&&p| p == 112).count() as u64;
        assert!(
            floor.stats.count * 10 < floor_pixels,
            "{} of {floor_pixels} floor pixels filled",
            floor.stats.count
        );
        let ring = filler.fill(
            image,
            &map,
            &mut labels,
            (cx as u32 - 20, cy as u32),
            Fill::Dark,
        );
        assert!(!ring.escaped);
        assert_eq!(
            ring.stats.count,
            px.iter().filter(|&&p| p == 12).count() as u64
        );
    }

    /// Floor between white cards that reaches the image's sides only
    /// outside a tracked frame's band: within the band map it must still be
    /// floor, and no dark fill may run on past the rows the map holds.
    #[test]
    fn a_band_map_stops_fills_in_floor_the_band_cuts_off() {
        let (w, h) = (480usize, 480usize);
        let mut px = vec![112u8; w * h];
        // A white U open at the top: the floor inside it meets the rest of
        // the floor above row 60 only.
        for y in 60..420 {
            for x in 100..380 {
                let bar = !(140..340).contains(&x) || y >= 380;
                if bar {
                    px[y * w + x] = 220;
                }
            }
        }
        // Ink on the cards (a marker's black), darker than the floor.
        for y in 290..310 {
            px[y * w + 110..y * w + 130].fill(15);
        }
        let image = Gray {
            pixels: &px,
            width: w,
            height: h,
        };
        let band = ThresholdMap::adaptive_rows(&px, w, h, 250..330);
        assert!(band.is_floor(240, 300), "the pocket inside the U is floor");
        let mut labels = Labels::default();
        labels.begin(w, h);
        let mut filler = Filler::default();
        // Seeded next to a bar, in a tile the floor test does not cover.
        let pocket = filler.fill(image, &band, &mut labels, (141, 300), Fill::Dark);
        assert!(pocket.escaped);
        assert!(pocket.stats.count < 2_000, "{}", pocket.stats.count);
    }

    /// A dark bar too narrow to be floor running the height of the frame:
    /// a band map's fill gives up where the map's rows end.
    #[test]
    fn a_band_fill_stops_where_the_map_ends() {
        let (w, h) = (240usize, 480usize);
        let mut px = vec![220u8; w * h];
        for y in 0..h {
            px[y * w + 104..y * w + 128].fill(20);
        }
        let image = Gray {
            pixels: &px,
            width: w,
            height: h,
        };
        let band = ThresholdMap::adaptive_rows(&px, w, h, 250..330);
        assert!(!band.is_floor(120, 300));
        let mut labels = Labels::default();
        labels.begin(w, h);
        let mut filler = Filler::default();
        let bar = filler.fill(image, &band, &mut labels, (110, 300), Fill::Dark);
        assert!(bar.escaped);
        assert!(bar.stats.count < 24 * 200, "{}", bar.stats.count);
        // The whole-frame map holds every row: the bar fills whole.
        let full = ThresholdMap::adaptive(&px, w, h);
        labels.begin(w, h);
        let bar = filler.fill(image, &full, &mut labels, (110, 300), Fill::Dark);
        assert!(!bar.escaped);
        assert_eq!(bar.stats.count, (24 * h) as u64);
    }

    #[test]
    fn fills_a_ring_and_its_hole_separately() {
        let (w, h) = (40usize, 30usize);
        let mut px = vec![255u8; w * h];
        for y in 0..h {
            for x in 0..w {
                let d2 = (x as i32 - 20).pow(2) + (y as i32 - 15).pow(2);
                if (25..=100).contains(&d2) {
                    px[y * w + x] = 0;
                }
            }
        }
        let image = Gray {
            pixels: &px,
            width: w,
            height: h,
        };
        let map = ThresholdMap::constant(128);
        let mut labels = Labels::default();
        labels.begin(w, h);
        let mut filler = Filler::default();
        let ring = filler.fill(image, &map, &mut labels, (10, 15), Fill::Dark);
        let expected = px.iter().filter(|&&p| p == 0).count() as u64;
        assert_eq!(ring.stats.count, expected);
        assert_eq!(ring.stats.centroid(), (20.0, 15.0));
        let s = ring.stats;
        let hole = filler.fill(
            image,
            &map,
            &mut labels,
            (20, 15),
            Fill::White {
                bounds: [s.min_u, s.min_v, s.max_u, s.max_v],
                max_count: 1000,
            },
        );
        assert!(!hole.escaped);
        let inside = (0..w * h)
            .filter(|&i| ((i % w) as i32 - 20).pow(2) + ((i / w) as i32 - 15).pow(2) < 25)
            .count() as u64;
        assert_eq!(hole.stats.count, inside);
        // Outside the ring the white region reaches the bounds.
        let outside = filler.fill(
            image,
            &map,
            &mut labels,
            (11, 6),
            Fill::White {
                bounds: [s.min_u, s.min_v, s.max_u, s.max_v],
                max_count: 1000,
            },
        );
        assert!(outside.escaped);
    }
}
