//! Deciding which pixels are dark.
//!
//! A single global threshold (the reference's approach) fails under a strong
//! light gradient: the white paper in the shade can be darker than the black
//! ink in the light. The map here is local instead: the image is cut into
//! square tiles, each tile's threshold is the mid-level between the darkest
//! and the brightest pixel in its neighbourhood of tiles, and tiles whose
//! neighbourhood shows no real contrast take the threshold of the nearest
//! tile that does (so the inside of a large black disc stays dark and a
//! large blank wall stays white). A constant map is the same type with one
//! tile covering everything, used when tracking already knows a marker's
//! black and white levels.

use std::sync::atomic::{AtomicU64, Ordering};

use super::segment;

#[cfg(target_arch = "x86_64")]
use std::arch::x86_64::__m128i;

/// Source of [`ThresholdMap::id`]s.
static NEXT_MAP_ID: AtomicU64 = AtomicU64::new(0);

fn next_map_id() -> u64 {
    NEXT_MAP_ID.fetch_add(1, Ordering::Relaxed)
}

/// A threshold per tile: pixel (x, y) is dark when its value is below
/// `values[(y >> shift) * cols + (x >> shift)]`.
#[derive(Debug, Clone)]
pub struct ThresholdMap {
    /// Unique per map made (clones share it): what the fill's cache of
    /// classified pixels is keyed by.
    id: u64,
    shift: u32,
    cols: usize,
    /// First tile row held, and how many: a map may cover only a band of
    /// the image; rows outside it use the nearest row held.
    row0: usize,
    rows: usize,
    values: Vec<u8>,
    /// Tiles of a large dark background (see [`ThresholdMap::floor_row`]),
    /// laid out as `values`; empty when there are none.
    floor: Vec<bool>,
    /// Least black-to-white difference that noise cannot fake.
    min_contrast: u8,
    /// Image rows holding shaded tiles (see [`ThresholdMap::shaded_rows`]).
    shaded: Option<std::ops::Range<usize>>,
    /// Tiles near a shaded tile (see [`ThresholdMap::near_shaded`]), laid
    /// out as `values`; empty when there are none.
    near_shaded: Vec<bool>,
    /// Per tile, the darkest and brightest pixel of its neighbourhood
    /// (what [`ThresholdMap::blind_tiles`] needs); empty for a constant map.
    near_lo: Vec<u8>,
    near_hi: Vec<u8>,
    /// Per tile, its own brightest pixel; empty for a constant map.
    own_hi: Vec<u8>,
    /// Per tile, its own darkest pixel (see [`ThresholdMap::darkest_row`]);
    /// empty for a constant map.
    own_lo: Vec<u8>,
}

/// Shift of the adaptive map's tiles: 16 x 16 pixels.
pub const TILE_SHIFT: u32 = 4;
/// Neighbourhood radius, in tiles, over which a tile's black and white
/// levels are taken. Two tiles reach 32-48 px, more than half the black
/// annulus of any marker up to ~250 px across; larger markers get their
/// threshold from the propagation step.
pub const NEIGHBOURHOOD_TILES: usize = 2;
/// Least difference between black and white, in grey levels, that counts as
/// contrast at all. Low enough for dark frames (white ~25).
pub const MIN_CONTRAST: u8 = 8;
/// Fewest tiles of a wholly dark, featureless region reaching the edge of
/// the map for it to count as background floor: 48 tiles are 12 000
/// pixels, the whole black annulus of a marker 150 px across. A larger
/// marker cut by the image edge is told from floor by its ink.
pub const MIN_FLOOR_TILES: usize = 48;

/// The tile shift of a map of one threshold: one tile wider than any image.
const CONSTANT_SHIFT: u32 = 31;

impl ThresholdMap {
    /// The same threshold everywhere.
    pub fn constant(threshold: u8) -> ThresholdMap {
        ThresholdMap {
            id: next_map_id(),
            shift: CONSTANT_SHIFT,
            cols: 1,
            row0: 0,
            rows: 1,
            values: vec![threshold],
            floor: Vec::new(),
            min_contrast: MIN_CONTRAST,
            shaded: None,
            near_shaded: Vec::new(),
            near_lo: Vec::new(),
            near_hi: Vec::new(),
            own_hi: Vec::new(),
            own_lo: Vec::new(),
        }
    }

    /// Image rows holding shaded tiles: flat tiles dark (but for their
    /// noise) by the mid-level threshold although their brightest pixel
    /// stands far above the darkest of the neighbourhood. That is white
    /// paper in a cast shadow next to lit paper (the mid-level of lit white
    /// and black lies above shaded white), and a marker crossed by the
    /// shadow's edge loses the shaded part of its white disc to the black.
    /// Such rows are worth a second look with
    /// [`ThresholdMap::adaptive_ratio`].
    pub fn shaded_rows(&self) -> Option<std::ops::Range<usize>> {
        self.shaded.clone()
    }

    /// The tiles within reach of a shaded tile (as far as its rows reach
    /// in [`ThresholdMap::shaded_rows`]), indexed as the scan's tiles: the
    /// only places where a marker crossed by a shadow's edge can start.
    /// Elsewhere a second look only fills the same clutter again.
    pub fn near_shaded(&self) -> &[bool] {
        &self.near_shaded
    }

    /// Where the map may be blind, for the global walk after a miss:
    /// tiles whose neighbourhood's range of grey is under twice the noise
    /// floor (so noise sets or vetoes their threshold: a marker of that
    /// contrast is cut to specks or not cut at all), yet whose tile means
    /// differ by more than noise can make them (something is there). Per
    /// tile, the levels a global threshold must take to cut it,
    /// `lo < t <= hi`; (0, 0) elsewhere. Blank walls, the flat insides of
    /// large shapes and edges of clear contrast are not blind: a global
    /// level finds nothing there that the local map missed, yet it filled
    /// them whole at every level of the walk.
    pub fn blind_tiles(&self, pixels: &[u8], width: usize, height: usize) -> Vec<(u8, u8)> {
        let n = self.near_lo.len();
        if n == 0 {
            return Vec::new();
        }
        let y_start = self.row0 << self.shift;
        let y_end = ((self.row0 + self.rows) << self.shift).min(height);
        let low_range = |i: usize| {
            u16::from(self.near_hi[i] - self.near_lo[i]) < 2 * u16::from(self.min_contrast)
        };
        // Only tiles whose neighbourhood holds a tile of low range can
        // matter below: their means alone are needed.
        let flags: Vec<u8> = (0..n).map(|i| u8::from(low_range(i))).collect();
        if !flags.contains(&1) {
            return vec![(0, 0); n];
        }
        let needed = box_filter(&flags, self.cols, self.rows, NEIGHBOURHOOD_TILES, u8::max);
        // The last column and row of tiles may be cut short by the
        // image's edges.
        let tiles = Tiles {
            pixels,
            width,
            rows: y_start..y_end,
            cols: self.cols,
        };
        let means: Vec<u8> = (0..n)
            .map(|i| {
                if needed[i] == 0 {
                    return 0;
                }
                tiles.mean(i) as u8
            })
            .collect();
        let darkest = box_filter(&means, self.cols, self.rows, NEIGHBOURHOOD_TILES, u8::min);
        let brightest = box_filter(&means, self.cols, self.rows, NEIGHBOURHOOD_TILES, u8::max);
        // A tile's mean of 256 pixels has a sixteenth of the noise's σ,
        // and the noise floor is about eight σ.
        let structure = (self.min_contrast / 8).max(2);
        (0..n)
            .map(|i| {
                if low_range(i) && brightest[i] - darkest[i] >= structure {
                    (self.near_lo[i], self.near_hi[i])
                } else {
                    (0, 0)
                }
            })
            .collect()
    }

    /// The thresholds of one image row, indexed by `x >> shift()`.
    #[inline]
    pub fn row(&self, y: usize) -> &[u8] {
        let r = (y >> self.shift)
            .saturating_sub(self.row0)
            .min(self.rows - 1);
        &self.values[r * self.cols..(r + 1) * self.cols]
    }

    /// The pixel rows the map was computed for (a band map holds only
    /// its band and margins; the others borrow the nearest thresholds and
    /// know nothing of the floor there).
    #[inline]
    pub fn held_rows(&self) -> std::ops::Range<usize> {
        (self.row0 << self.shift)..((self.row0 + self.rows) << self.shift)
    }

    /// The darkest pixel of each tile of image row `y`'s tile row, indexed
    /// by `x >> shift()`: no pixel of a tile lies below its darkest. None
    /// for a constant map and for rows the map was not computed for.
    #[inline]
    pub fn darkest_row(&self, y: usize) -> Option<&[u8]> {
        self.held_tile_row(&self.own_lo, y)
    }

    /// Image row `y`'s tile row of `per_tile` (one of the map's per-tile
    /// vectors): None when the vector is empty or the map was not
    /// computed for that row.
    #[inline(always)]
    fn held_tile_row<'a, T>(&self, per_tile: &'a [T], y: usize) -> Option<&'a [T]> {
        if per_tile.is_empty() {
            return None;
        }
        let r = (y >> self.shift).checked_sub(self.row0)?;
        (r < self.rows).then(|| &per_tile[r * self.cols..(r + 1) * self.cols])
    }

    /// Whether the map is one threshold everywhere ([`ThresholdMap::constant`]).
    #[inline]
    pub fn is_constant(&self) -> bool {
        self.shift == CONSTANT_SHIFT
    }

    /// Whether any tile is floor.
    #[inline]
    pub fn has_floor(&self) -> bool {
        !self.floor.is_empty()
    }

    /// Least black-to-white difference that counts as a real edge here.
    pub fn min_contrast(&self) -> f64 {
        f64::from(self.min_contrast)
    }

    /// How far below its threshold a pixel must lie to start a search. A
    /// marker's black lies at least half the local contrast (itself at least
    /// the noise floor) below the threshold; a grey floor whose texture only
    /// grazes it, next to a marker, would otherwise start thousands of
    /// one-pixel searches a frame.
    pub fn seed_margin(&self) -> u8 {
        self.min_contrast / 2
    }

    /// The floor flags of one image row, indexed by `x >> shift()`; None
    /// when the map has no floor tile or was not computed for the row.
    /// Floor is a featureless region, dark in every pixel, that reaches
    /// the edge of the image and is larger than a marker's annulus. A grey
    /// floor next to white cards is such a region; flood-filling it as a
    /// candidate cost more than the rest of the frame. A marker's dark
    /// segment is ringed by white, so it never reaches the floor: a
    /// segment that does is not a marker. Rows outside the map have no
    /// floor.
    #[inline]
    pub fn floor_row(&self, y: usize) -> Option<&[bool]> {
        self.held_tile_row(&self.floor, y)
    }

    /// Whether any tile of row `y` from column `x0` to `x1` is floor.
    #[inline]
    pub fn floor_between(&self, y: usize, x0: usize, x1: usize) -> bool {
        self.floor_row(y)
            .is_some_and(|row| row[x0 >> self.shift..=x1 >> self.shift].contains(&true))
    }

    /// Whether a dark run of row `y` (one of [`ThresholdMap::held_rows`])
    /// from `x0` to `x1` touches a floor tile: beside its ends in its row,
    /// or in the rows above and below it. A dark fill takes no pixel of a
    /// floor tile (the fills classify them as not dark), so the run's own
    /// tiles are not floor, and the rows next to it need a look only where
    /// they cross into another row of tiles.
    #[inline(always)]
    pub fn run_touches_floor(
        &self,
        y: usize,
        (x0, x1): (usize, usize),
        (width, height): (usize, usize),
    ) -> bool {
        debug_assert!(self.held_rows().contains(&y));
        let Some(row) = self.floor_row(y) else {
            return false;
        };
        if row[x0.saturating_sub(1) >> self.shift] || row[(x1 + 1).min(width - 1) >> self.shift] {
            return true;
        }
        let tile_row = y >> self.shift;
        (y > 0 && (y - 1) >> self.shift != tile_row && self.floor_between(y - 1, x0, x1))
            || (y + 1 < height
                && (y + 1) >> self.shift != tile_row
                && self.floor_between(y + 1, x0, x1))
    }

    /// Tells this map from every other made in the process.
    #[inline]
    pub fn id(&self) -> u64 {
        self.id
    }

    #[inline]
    pub fn shift(&self) -> u32 {
        self.shift
    }

    /// The threshold for pixel (x, y); the detector reads whole rows, tests
    /// check single pixels.
    #[cfg(test)]
    #[inline]
    pub fn at(&self, x: usize, y: usize) -> u8 {
        self.row(y)[x >> self.shift]
    }

    /// The local map of an 8-bit image stored row-major without padding.
    pub fn adaptive(pixels: &[u8], width: usize, height: usize) -> ThresholdMap {
        ThresholdMap::adaptive_rows(pixels, width, height, 0..height)
    }

    /// The local map of the pixel rows `band` only (plus the tiles their
    /// neighbourhoods reach); other rows get the band's nearest thresholds.
    pub fn adaptive_rows(
        pixels: &[u8],
        width: usize,
        height: usize,
        band: std::ops::Range<usize>,
    ) -> ThresholdMap {
        ThresholdMap::adaptive_with(pixels, width, height, band, Level::Mid, None)
    }

    /// The local map of `band` with each tile's threshold a third of the
    /// way from its black to its white level in log light (offset by the
    /// noise floor) rather than at the mid-level: light multiplies, so paper in a shadow
    /// keeps its ratio to the ink beside it while falling below the
    /// mid-level of lit paper and ink. Lower than the mid-level everywhere,
    /// so it is kept for a second look at shaded rows. The tiles' levels
    /// are taken from `mid` (the mid-level map of the same image) where it
    /// holds the same tile rows, as it does unless the band is narrow.
    pub fn adaptive_ratio(
        pixels: &[u8],
        width: usize,
        height: usize,
        band: std::ops::Range<usize>,
        mid: &ThresholdMap,
    ) -> ThresholdMap {
        ThresholdMap::adaptive_with(pixels, width, height, band, Level::Ratio, Some(mid))
    }

    fn adaptive_with(
        pixels: &[u8],
        width: usize,
        height: usize,
        band: std::ops::Range<usize>,
        level: Level,
        base: Option<&ThresholdMap>,
    ) -> ThresholdMap {
        let tile = 1usize << TILE_SHIFT;
        let cols = width.div_ceil(tile).max(1);
        let first = (band.start >> TILE_SHIFT).saturating_sub(NEIGHBOURHOOD_TILES);
        let last = (band.end.min(height).max(1) - 1) >> TILE_SHIFT;
        let last = (last + NEIGHBOURHOOD_TILES).min(height.max(1).div_ceil(tile) - 1);
        let rows = (last + 1 - first).max(1);
        let (y_start, y_end) = (first << TILE_SHIFT, ((last + 1) << TILE_SHIFT).min(height));
        let same_tiles = base.filter(|b| {
            b.row0 == first && b.rows == rows && b.cols == cols && !b.own_hi.is_empty()
        });
        let TileLevels {
            own_hi,
            own_lo,
            near_lo: lo,
            near_hi: hi,
            noise_floor,
        } = match same_tiles {
            // The levels below depend on the tile rows' pixels only.
            Some(b) => TileLevels {
                own_hi: b.own_hi.clone(),
                own_lo: b.own_lo.clone(),
                near_lo: b.near_lo.clone(),
                near_hi: b.near_hi.clone(),
                noise_floor: b.min_contrast,
            },
            None => tile_levels(pixels, width, cols, rows, y_start..y_end),
        };
        const UNSET: u16 = u16::MAX;
        // The ratio level's powers of each grey level, once per map rather
        // than twice per tile.
        let powers: Vec<(f64, f64)> = match level {
            Level::Mid => Vec::new(),
            Level::Ratio => {
                let c = f64::from(noise_floor) / 2.0;
                (0..=255u8)
                    .map(|g| {
                        let g = f64::from(g) + c;
                        (g.powf(2.0 / 3.0), g.powf(1.0 / 3.0))
                    })
                    .collect()
            }
        };
        let mut thresholds: Vec<u16> = lo
            .iter()
            .zip(&hi)
            .map(|(&l, &h)| {
                let contrast = h - l;
                if contrast >= noise_floor && contrast >= h / 6 {
                    match level {
                        Level::Mid => (u16::from(l) + u16::from(h)).div_ceil(2),
                        Level::Ratio => {
                            let c = f64::from(noise_floor) / 2.0;
                            // A third of the way up in log light: shade
                            // to 1/5 keeps paper above it.
                            let g = powers[usize::from(l)].0 * powers[usize::from(h)].1 - c;
                            (g.round() as u16).max(u16::from(l) + u16::from(noise_floor) / 2)
                        }
                    }
                } else {
                    UNSET
                }
            })
            .collect();
        if !thresholds.iter().any(|&t| t != UNSET) {
            // No contrast anywhere: nothing is dark.
            return ThresholdMap {
                id: next_map_id(),
                shift: TILE_SHIFT,
                cols,
                row0: first,
                rows,
                values: vec![0; cols * rows],
                floor: Vec::new(),
                min_contrast: noise_floor,
                shaded: None,
                near_shaded: Vec::new(),
                near_lo: lo,
                near_hi: hi,
                own_hi,
                own_lo,
            };
        }
        spread_to_unset(&mut thresholds, cols, rows, UNSET);
        let values: Vec<u8> = thresholds.into_iter().map(|t| t.min(255) as u8).collect();
        // The darkest ink of the band: a region whose every pixel lies
        // nearer to it than to the threshold is printed black, not floor.
        let ink = lo.iter().copied().min().unwrap_or(0);
        // Featureless tiles dark in every pixel; those connected to the
        // edge of the map (the image's edges, and the rows where a band map
        // is cut) in a large enough region are floor. A band cuts the
        // floor between cards off from the image's sides; left unflagged,
        // such pockets were flood-filled as candidates every tracked frame.
        let solid: Vec<bool> = own_hi.iter().zip(&values).map(|(&h, &v)| h < v).collect();
        let tiles = Tiles {
            pixels,
            width,
            rows: y_start..y_end,
            cols,
        };
        // Shade is looked for on the mid-level map only: the ratio map is
        // the second look at what this one flags.
        let shaded_flags: Vec<u8> = if matches!(level, Level::Mid) {
            let nf = u16::from(noise_floor);
            (0..values.len())
                .map(|i| {
                    // Flat paper, dark but for the noise's brightest pixels:
                    // on shaded paper the noise alone lifts a few of a
                    // tile's 256 pixels over a threshold just above the
                    // paper's grey. A tile of a marker's ink beside its
                    // blurred edge is dark too, and stands as far above the
                    // darkest ink, but is not flat: its brightest pixel
                    // stands far above its mean (as on an edge's ramp).
                    let hi_own = u16::from(own_hi[i]);
                    let flat_paper =
                        hi_own < u16::from(values[i]) + nf && hi_own <= tiles.mean(i) + 2 * nf;
                    u8::from(flat_paper && hi_own >= 2 * u16::from(lo[i]) + 2 * nf)
                })
                .collect()
        } else {
            Vec::new()
        };
        let shaded_tiles = (0..shaded_flags.len()).filter(|&i| shaded_flags[i] != 0);
        let near_shaded = if shaded_flags.contains(&1) {
            box_filter(&shaded_flags, cols, rows, NEIGHBOURHOOD_TILES, u8::max)
                .into_iter()
                .map(|f| f != 0)
                .collect()
        } else {
            Vec::new()
        };
        let shaded = shaded_tiles
            .fold(None, |range: Option<(usize, usize)>, i| {
                let r = i / cols;
                Some(range.map_or((r, r), |(a, b)| (a.min(r), b.max(r))))
            })
            .map(|(a, b)| {
                // The marker a shaded tile belongs to reaches the
                // neighbourhood's tiles above and below.
                let top = (first + a).saturating_sub(NEIGHBOURHOOD_TILES) << TILE_SHIFT;
                let bottom = ((first + b + NEIGHBOURHOOD_TILES + 1) << TILE_SHIFT).min(height);
                top..bottom
            });
        let mut floor = vec![false; values.len()];
        let mut seen = vec![false; values.len()];
        let mut any_floor = false;
        let mut component = Vec::new();
        // The tiles along the map's edge, where floor regions start: which
        // one a region is found from changes nothing.
        let mut edge_tiles = Vec::with_capacity(2 * (rows + cols));
        for r in 0..rows {
            if r == 0 || r + 1 == rows {
                edge_tiles.extend(r * cols..(r + 1) * cols);
            } else {
                edge_tiles.extend([r * cols, (r + 1) * cols - 1]);
            }
        }
        for start in edge_tiles {
            if !solid[start] || seen[start] {
                continue;
            }
            component.clear();
            component.push(start);
            seen[start] = true;
            let mut k = 0;
            while k < component.len() {
                let i = component[k];
                k += 1;
                let (c, r) = (i % cols, i / cols);
                let neighbours = [
                    (c > 0).then(|| i - 1),
                    (c + 1 < cols).then(|| i + 1),
                    (r > 0).then(|| i - cols),
                    (r + 1 < rows).then(|| i + cols),
                ];
                for j in neighbours.into_iter().flatten() {
                    if solid[j] && !seen[j] {
                        seen[j] = true;
                        component.push(j);
                    }
                }
            }
            // A grey floor lies just under the threshold that the cards
            // on it set; the black annulus of a large marker cut by the
            // image edge is as large and as featureless, but as black as
            // ink (but for the tiles along its blurred rim): it is a
            // marker's dark segment, not floor.
            let inked = component
                .iter()
                .filter(|&&i| 2 * u16::from(own_hi[i]) <= u16::from(values[i]) + u16::from(ink))
                .count();
            if component.len() >= MIN_FLOOR_TILES && 2 * inked < component.len() {
                any_floor = true;
                for &i in &component {
                    floor[i] = true;
                }
            }
        }
        ThresholdMap {
            id: next_map_id(),
            shift: TILE_SHIFT,
            cols,
            row0: first,
            rows,
            values,
            floor: if any_floor { floor } else { Vec::new() },
            min_contrast: noise_floor,
            shaded,
            near_shaded,
            near_lo: lo,
            near_hi: hi,
            own_hi,
            own_lo,
        }
    }
}

/// Gives every tile of `thresholds` (a grid of `cols` x `rows`) that is
/// `unset` the value of its nearest set tile: a breadth-first spread from
/// all set tiles at once, in index order, through the four neighbours.
/// Only set tiles beside an unset one start it, as no other spreads.
fn spread_to_unset(thresholds: &mut [u16], cols: usize, rows: usize, unset: u16) {
    if !thresholds.contains(&unset) {
        return;
    }
    // The grid framed by a border of set tiles, which are never spread
    // from: a neighbour is then one step away in every direction, with no
    // test of the grid's edges.
    let stride = cols + 2;
    let mut framed = vec![0u16; stride * (rows + 2)];
    for (row, framed_row) in thresholds
        .chunks_exact(cols)
        .zip(framed.chunks_exact_mut(stride).skip(1))
    {
        framed_row[1..=cols].copy_from_slice(row);
    }
    let steps = [1, stride];
    let beside_unset = |t: &[u16], i: usize| {
        steps
            .iter()
            .any(|&d| t[i - d] == unset || t[i + d] == unset)
    };
    let mut queue: Vec<u32> = Vec::new();
    for r in 1..=rows {
        for i in r * stride + 1..=r * stride + cols {
            if framed[i] != unset && beside_unset(&framed, i) {
                queue.push(i as u32);
            }
        }
    }
    let mut head = 0;
    while let Some(&i) = queue.get(head) {
        head += 1;
        let i = i as usize;
        let value = framed[i];
        // Left, right, up, down: the order the spread has always taken.
        for j in [i - 1, i + 1, i - stride, i + stride] {
            if framed[j] == unset {
                framed[j] = value;
                queue.push(j as u32);
            }
        }
    }
    for (row, framed_row) in thresholds
        .chunks_exact_mut(cols)
        .zip(framed.chunks_exact(stride).skip(1))
    {
        row.copy_from_slice(&framed_row[1..=cols]);
    }
}

/// The tiles of a map over an image's pixel `rows` (whole tile rows but
/// where the image ends), `cols` of them a row.
struct Tiles<'a> {
    pixels: &'a [u8],
    width: usize,
    rows: std::ops::Range<usize>,
    cols: usize,
}

impl Tiles<'_> {
    /// The mean grey of tile `i`, from the sum of its pixels: taken only
    /// for the few tiles whose mean is asked, rather than with every
    /// tile's levels. The last column's and the last row's tiles may be
    /// cut short by the image's edges.
    fn mean(&self, i: usize) -> u16 {
        let tile = 1usize << TILE_SHIFT;
        let (c, r) = (i % self.cols, i / self.cols);
        let x = c * tile..((c + 1) * tile).min(self.width);
        let y = self.rows.start + r * tile..(self.rows.start + (r + 1) * tile).min(self.rows.end);
        let area = x.len() * y.len();
        let band = &self.pixels[y.start * self.width..y.end * self.width];
        let sum = tile_sum(band, self.width, x);
        if area == tile * tile {
            // A whole tile: the division is a shift.
            return (sum >> (2 * TILE_SHIFT)) as u16;
        }
        (sum / area.max(1) as u32) as u16
    }
}

/// The sum of columns `x` of the rows of `band` (rows of `width` pixels):
/// for a whole tile's width, one vector sum of absolute differences per
/// row where the target has it.
#[inline]
fn tile_sum(band: &[u8], width: usize, x: std::ops::Range<usize>) -> u32 {
    let rows = band.chunks_exact(width).map(|row| &row[x.clone()]);
    #[cfg(target_arch = "x86_64")]
    if x.len() == 1 << TILE_SHIFT {
        // SAFETY: SSE2 is part of x86_64; each load reads one row's 16
        // pixels of the tile, a slice of exactly that length.
        unsafe {
            use std::arch::x86_64::*;
            let zero = _mm_setzero_si128();
            let sum = rows.fold(zero, |sum, row| {
                let p = _mm_loadu_si128(row.as_ptr().cast());
                _mm_add_epi64(sum, _mm_sad_epu8(p, zero))
            });
            let mut lanes = [0u64; 2];
            _mm_storeu_si128(lanes.as_mut_ptr().cast(), sum);
            return (lanes[0] + lanes[1]) as u32;
        }
    }
    rows.map(|row| segment::sum_bytes(row) as u32).sum()
}

/// Per tile of the pixel rows `y` (whole tile rows), its own darkest and
/// brightest pixel and its neighbourhood's; and the noise floor of those
/// rows.
fn tile_levels(
    pixels: &[u8],
    width: usize,
    cols: usize,
    rows: usize,
    y: std::ops::Range<usize>,
) -> TileLevels {
    let tile = 1usize << TILE_SHIFT;
    let band_pixels =
        &pixels[(y.start * width).min(pixels.len())..(y.end * width).min(pixels.len())];
    let mut lo = vec![255u8; cols * rows];
    let mut hi = vec![0u8; cols * rows];
    // A tile row at a time, on the pool's threads for a large frame.
    let threads = crate::parallel::frame_threads(band_pixels.len());
    let noise_floor = if threads > 1 {
        use crate::parallel::prelude::*;
        band_pixels
            .par_chunks(width.max(1) * tile)
            .zip(lo.par_chunks_mut(cols))
            .zip(hi.par_chunks_mut(cols))
            .for_each(|((band, lo), hi)| tile_row_levels(band, width, lo, hi));
        noise_contrast(band_pixels, width, y.end - y.start, true)
    } else {
        band_pixels
            .chunks(width.max(1) * tile)
            .zip(lo.chunks_mut(cols))
            .zip(hi.chunks_mut(cols))
            .for_each(|((band, lo), hi)| tile_row_levels(band, width, lo, hi));
        noise_contrast(band_pixels, width, y.end - y.start, false)
    };
    let noise_floor = MIN_CONTRAST.max(noise_floor);
    let near_lo = box_filter(&lo, cols, rows, NEIGHBOURHOOD_TILES, u8::min);
    let near_hi = box_filter(&hi, cols, rows, NEIGHBOURHOOD_TILES, u8::max);
    TileLevels {
        own_hi: hi,
        own_lo: lo,
        near_lo,
        near_hi,
        noise_floor,
    }
}

/// The darkest and brightest pixel of each tile of one row of tiles
/// (`band`, rows of `width` pixels), a tile's column of chunks folded row
/// by row and reduced once: the reduction across a chunk's bytes costs
/// more than the folds, and was paid per row. Where the target has
/// vectors, four neighbouring whole tiles are folded side by side and
/// reduced together (one reduction then narrows eight vectors, where each
/// tile's own would narrow two), the whole tiles left over one at a time;
/// a tile cut by the band's right end is folded pixel by pixel.
fn tile_row_levels(band: &[u8], width: usize, lo: &mut [u8], hi: &mut [u8]) {
    let tile = 1usize << TILE_SHIFT;
    let rows = band.len() / width.max(1);
    let mut x0 = 0;
    #[cfg(target_arch = "x86_64")]
    if rows > 0 {
        while x0 + 4 * tile <= width {
            let (l, h) = whole_tiles_min_max::<4>(band, width, rows, x0);
            lo[x0 / tile..][..4].copy_from_slice(&l);
            hi[x0 / tile..][..4].copy_from_slice(&h);
            x0 += 4 * tile;
        }
        while x0 + tile <= width {
            let ([l], [h]) = whole_tiles_min_max::<1>(band, width, rows, x0);
            (lo[x0 / tile], hi[x0 / tile]) = (l, h);
            x0 += tile;
        }
    }
    while x0 < width {
        let x1 = (x0 + tile).min(width);
        (lo[x0 / tile], hi[x0 / tile]) = tile_min_max(band, width, rows, x0..x1);
        x0 = x1;
    }
}

/// The darkest and brightest pixel of each of the `N` (1 to 4) whole tiles
/// from column `x0` of the `rows` rows of `band` (rows of `width` pixels,
/// with `x0 + 16 N <= width` and `rows > 0`).
#[cfg(target_arch = "x86_64")]
#[inline]
fn whole_tiles_min_max<const N: usize>(
    band: &[u8],
    width: usize,
    rows: usize,
    x0: usize,
) -> ([u8; N], [u8; N]) {
    const { assert!(N >= 1 && N <= 4) };
    let tile = 1usize << TILE_SHIFT;
    assert!(rows > 0 && x0 + N * tile <= width && rows * width <= band.len());
    // SAFETY: SSE2 is part of x86_64; each load reads 16 bytes of row k
    // from column x0 + 16 q (q < N), which the assertion keeps in the row
    // and the row in the band.
    unsafe {
        use std::arch::x86_64::*;
        let base = band.as_ptr().add(x0);
        let load = |k: usize, q: usize| _mm_loadu_si128(base.add(k * width + q * tile).cast());
        let mut lo: [__m128i; N] = std::array::from_fn(|q| load(0, q));
        let mut hi = lo;
        let mut fold = |k: usize| {
            for q in 0..N {
                let p = load(k, q);
                lo[q] = _mm_min_epu8(lo[q], p);
                hi[q] = _mm_max_epu8(hi[q], p);
            }
        };
        // A whole tile's rows in a loop of known length, which the
        // compiler unrolls.
        if rows == tile {
            (1..1 << TILE_SHIFT).for_each(&mut fold);
        } else {
            (1..rows).for_each(fold);
        }
        // Fewer than four tiles repeat their last: the reduction's extra
        // lanes then hold a copy of its result.
        let four = |v: [__m128i; N]| std::array::from_fn(|q| v[q.min(N - 1)]);
        let l = narrow_four(four(lo), |a, b| _mm_min_epu8(a, b));
        let h = narrow_four(four(hi), |a, b| _mm_max_epu8(a, b));
        let both = _mm_cvtsi128_si64(_mm_unpacklo_epi32(l, h)).to_le_bytes();
        (
            std::array::from_fn(|q| both[q]),
            std::array::from_fn(|q| both[4 + q]),
        )
    }
}

/// The four vectors' bytes each brought down to one by `keep` (the lesser
/// or the greater of two), in bytes 0-3 of the result, vector `q`'s in
/// byte `q`. Interleaving two vectors and keeping one of each pair of
/// halves narrows both at once: after bytes, then pairs of bytes, every
/// 4-byte group holds the four side by side, each over a quarter of its
/// bytes; two shifts fold the groups.
#[cfg(target_arch = "x86_64")]
#[inline(always)]
fn narrow_four(v: [__m128i; 4], keep: impl Fn(__m128i, __m128i) -> __m128i) -> __m128i {
    use std::arch::x86_64::*;
    // SAFETY: SSE2 is part of x86_64; the operations touch registers only.
    unsafe {
        let pair = |a, b| keep(_mm_unpacklo_epi8(a, b), _mm_unpackhi_epi8(a, b));
        let (v01, v23) = (pair(v[0], v[1]), pair(v[2], v[3]));
        let n = keep(_mm_unpacklo_epi16(v01, v23), _mm_unpackhi_epi16(v01, v23));
        let n = keep(n, _mm_srli_si128::<8>(n));
        keep(n, _mm_srli_si128::<4>(n))
    }
}

/// What [`tile_levels`] gives.
struct TileLevels {
    own_hi: Vec<u8>,
    own_lo: Vec<u8>,
    near_lo: Vec<u8>,
    near_hi: Vec<u8>,
    noise_floor: u8,
}

/// The darkest and brightest pixel of columns `x` of the first `n_rows`
/// rows of `band` (rows of `width` pixels), pixel by pixel: a tile cut by
/// the band's end, and every tile where the target has no vectors.
#[inline]
fn tile_min_max(band: &[u8], width: usize, n_rows: usize, x: std::ops::Range<usize>) -> (u8, u8) {
    assert!(n_rows * width <= band.len() && x.end <= width);
    band.chunks_exact(width.max(1))
        .take(n_rows)
        .flat_map(|row| &row[x.clone()])
        .fold((255u8, 0u8), |(l, h), &p| (l.min(p), h.max(p)))
}

/// Where between a tile's black and white levels its threshold lies.
#[derive(Debug, Clone, Copy)]
enum Level {
    Mid,
    Ratio,
}

/// The least contrast that sensor noise cannot fake: a flat, noisy area
/// spans about ±4 σ over a neighbourhood of thousands of pixels, or it
/// would be cut in half and flood-filled as countless specks. σ comes from
/// the median difference between horizontal neighbours (≈ 0.95 σ), which
/// edges, being few pixels, do not move. Every eighth row is read, on the
/// pool's threads with `parallel`.
fn noise_contrast(pixels: &[u8], width: usize, height: usize, parallel: bool) -> u8 {
    let rows: Vec<&[u8]> = pixels
        .chunks_exact(width.max(1))
        .take(height)
        .step_by(8)
        .collect();
    // The median of a noisy frame's differences is a few grey levels:
    // where the target has vectors, counting those at most 0..=3, then
    // 4..=7, ... (a pass each, sixteen at a time) gets there before a
    // histogram of every difference would be filled.
    #[cfg(target_arch = "x86_64")]
    {
        let total: u64 = rows.iter().map(|r| r.len().saturating_sub(1) as u64).sum();
        let add = |a: [u64; 4], b: [u64; 4]| std::array::from_fn(|k| a[k] + b[k]);
        for first in (0..16u8).step_by(4) {
            let levels = [first, first + 1, first + 2, first + 3];
            let rows_at_most = |rows: &[&[u8]]| {
                rows.iter()
                    .fold([0; 4], |sum, row| add(sum, diffs_at_most(row, levels)))
            };
            let seen = over_bands(&rows, parallel, rows_at_most)
                .into_iter()
                .fold([0; 4], add);
            for (level, seen) in levels.into_iter().zip(seen) {
                if 2 * seen >= total {
                    return level * 8;
                }
            }
        }
    }
    let histogram_of = |rows: &[&[u8]]| {
        let mut histogram = [0u64; 256];
        for row in rows {
            for (&a, &b) in row.iter().zip(&row[1..]) {
                histogram[usize::from(a.abs_diff(b))] += 1;
            }
        }
        histogram
    };
    let mut histogram = [0u64; 256];
    for part in over_bands(&rows, parallel, histogram_of) {
        for (sum, count) in histogram.iter_mut().zip(part) {
            *sum += count;
        }
    }
    contrast_at_median(&histogram)
}

/// `f` of bands of 64 of `rows` on the pool's threads with `parallel`,
/// else of all of them at once.
fn over_bands<T: Send>(
    rows: &[&[u8]],
    parallel: bool,
    f: impl Fn(&[&[u8]]) -> T + Sync + Send,
) -> Vec<T> {
    use crate::parallel::prelude::*;
    if parallel {
        rows.par_chunks(64).map(f).collect()
    } else {
        vec![f(rows)]
    }
}

/// How many of the differences between neighbouring pixels of `row` are
/// at most each of `levels`: sixteen pixels at a time, counted in bytes
/// and summed before they could overflow.
#[cfg(target_arch = "x86_64")]
fn diffs_at_most(row: &[u8], levels: [u8; 4]) -> [u64; 4] {
    let diffs = row.len().saturating_sub(1);
    let mut seen = [0u64; 4];
    // SAFETY: SSE2 is part of x86_64; each load reads 16 bytes of `row`
    // from x or x + 1, and x + 17 <= row.len() for every x read.
    let done = unsafe {
        use std::arch::x86_64::*;
        let zero = _mm_setzero_si128();
        let limits = levels.map(|l| _mm_set1_epi8(l as i8));
        let vectors = diffs / 16;
        let p = row.as_ptr();
        for block in (0..vectors).step_by(255) {
            let mut counts = [zero; 4];
            for v in block..(block + 255).min(vectors) {
                let a = _mm_loadu_si128(p.add(16 * v).cast());
                let b = _mm_loadu_si128(p.add(16 * v + 1).cast());
                let d = _mm_or_si128(_mm_subs_epu8(a, b), _mm_subs_epu8(b, a));
                for (count, &limit) in counts.iter_mut().zip(&limits) {
                    // All ones (-1) where d <= limit.
                    let within = _mm_cmpeq_epi8(_mm_min_epu8(d, limit), d);
                    *count = _mm_sub_epi8(*count, within);
                }
            }
            for (total, count) in seen.iter_mut().zip(counts) {
                let mut lanes = [0u64; 2];
                _mm_storeu_si128(lanes.as_mut_ptr().cast(), _mm_sad_epu8(count, zero));
                *total += lanes[0] + lanes[1];
            }
        }
        16 * vectors
    };
    for pair in row[done..].windows(2) {
        let d = pair[0].abs_diff(pair[1]);
        for (total, &level) in seen.iter_mut().zip(&levels) {
            *total += u64::from(d <= level);
        }
    }
    seen
}

/// Eight times the median difference a histogram of differences counts:
/// the contrast below which the frame's noise alone reaches.
fn contrast_at_median(histogram: &[u64; 256]) -> u8 {
    let total: u64 = histogram.iter().sum();
    let mut seen = 0;
    for (diff, &count) in histogram.iter().enumerate() {
        seen += count;
        if 2 * seen >= total {
            return (diff * 8).min(255) as u8;
        }
    }
    0
}

/// Min or max over a (2r+1)² window of a grid, clipped at the borders.
/// Generic over `op` so that it is inlined into the loops.
fn box_filter(
    grid: &[u8],
    cols: usize,
    rows: usize,
    r: usize,
    op: impl Fn(u8, u8) -> u8 + Copy,
) -> Vec<u8> {
    // `op` is a min or a max: the window is folded in one shifted row
    // at a time, whole rows at once.
    let mut horizontal = grid.to_vec();
    for (row, out) in grid
        .chunks_exact(cols)
        .zip(horizontal.chunks_exact_mut(cols))
    {
        for d in 1..=r.min(cols - 1) {
            for (o, &v) in out[..cols - d].iter_mut().zip(&row[d..]) {
                *o = op(*o, v);
            }
            for (o, &v) in out[d..].iter_mut().zip(&row[..cols - d]) {
                *o = op(*o, v);
            }
        }
    }
    let mut out = vec![0u8; grid.len()];
    for y in 0..rows {
        let (a, b) = (y.saturating_sub(r), (y + r).min(rows - 1));
        let out_row = &mut out[y * cols..(y + 1) * cols];
        out_row.copy_from_slice(&horizontal[a * cols..(a + 1) * cols]);
        for yy in a + 1..=b {
            let src = &horizontal[yy * cols..(yy + 1) * cols];
            for (o, &v) in out_row.iter_mut().zip(src) {
                *o = op(*o, v);
            }
        }
    }
    out
}

/// Global thresholds to try one after another after a miss: the binary
/// subdivision of the grey range, 128, 64, 192, 32, 96, 160, 224, 16, ...
/// so that every level is eventually tried and coarse steps come first.
#[derive(Debug, Clone, Default)]
pub struct ThresholdSearch {
    step: u32,
    /// The level that last found markers, tried first after a miss.
    last_hit: Option<u8>,
}

/// Most global levels scanned in one frame after the local map found
/// nothing. One level per frame left a single still image with the first
/// level only (128, hopeless in a dark frame), and a sequence blind for
/// several frames; a handful keeps a frame without markers affordable.
pub const LEVELS_PER_MISS: usize = 6;

impl ThresholdSearch {
    /// The k-th threshold of the sequence (k = 0 gives 128).
    pub fn nth(k: u32) -> u8 {
        let k = k % 255;
        let level = 31 - (k + 1).leading_zeros();
        let j = k + 1 - (1 << level);
        ((256 * (2 * j + 1)) >> (level + 1)) as u8
    }

    /// The next threshold to try after a miss.
    pub fn next_after_miss(&mut self) -> u8 {
        let t = Self::nth(self.step);
        self.step = (self.step + 1) % 255;
        t
    }

    /// Up to [`LEVELS_PER_MISS`] levels to scan in this frame: the last
    /// level that found markers, then the walk's next levels that split the
    /// image. A level with (almost) every pixel on one side of it cannot
    /// outline a black disc on white, so it is passed over without a scan;
    /// `histogram` counts the grey values of (a sample of) the image.
    pub fn levels_after_miss(&mut self, histogram: &[u64; 256]) -> Vec<u8> {
        let total: u64 = histogram.iter().sum();
        let mut below = [0u64; 257];
        for (i, &n) in histogram.iter().enumerate() {
            below[i + 1] = below[i] + n;
        }
        // Some dark pixels (a small marker is a few dozen), and enough
        // light ones to surround a disc.
        let splits = |t: u8| {
            let dark = below[usize::from(t)];
            dark >= 4 && (total - dark) * 200 >= total
        };
        let mut levels: Vec<u8> = self.last_hit.filter(|&t| splits(t)).into_iter().collect();
        for _ in 0..255 {
            if levels.len() >= LEVELS_PER_MISS {
                break;
            }
            let t = self.next_after_miss();
            if splits(t) && !levels.contains(&t) {
                levels.push(t);
            }
        }
        levels
    }

    /// A global level found markers: the walk restarts from the top, and
    /// this level is tried first after the next miss.
    pub fn hit(&mut self, level: u8) {
        self.step = 0;
        self.last_hit = Some(level);
    }

    /// After a hit the walk restarts from the top.
    pub fn reset(&mut self) {
        self.step = 0;
    }
}

/// Grey-level histogram of every fourth row: enough to tell which global
/// levels split the image.
pub fn sampled_histogram(pixels: &[u8], width: usize) -> [u64; 256] {
    // Four counts per level, for consecutive pixels: runs of one grey
    // value then increment different counters instead of waiting on one.
    let mut counts = [[0u32; 256]; 4];
    for row in pixels.chunks_exact(width.max(1)).step_by(4) {
        let mut quads = row.chunks_exact(4);
        for q in &mut quads {
            for (lane, &p) in q.iter().enumerate() {
                counts[lane][usize::from(p)] += 1;
            }
        }
        for &p in quads.remainder() {
            counts[0][usize::from(p)] += 1;
        }
    }
    std::array::from_fn(|g| counts.iter().map(|c| u64::from(c[g])).sum())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::Pcg32;

    #[test]
    fn subdivision_sequence_starts_like_the_reference() {
        let seq: Vec<u8> = (0..8).map(ThresholdSearch::nth).collect();
        assert_eq!(seq, [128, 64, 192, 32, 96, 160, 224, 16]);
        let mut all: Vec<u8> = (0..255).map(ThresholdSearch::nth).collect();
        all.sort_unstable();
        all.dedup();
        assert_eq!(all.len(), 255, "every level 1..=255 is visited once");
    }

    #[test]
    fn a_miss_walks_only_levels_that_split_the_image() {
        // A dark frame: every pixel below 60.
        let mut histogram = [0u64; 256];
        histogram[3] = 1_000;
        histogram[20] = 5_000;
        histogram[55] = 4_000;
        let mut search = ThresholdSearch::default();
        let levels = search.levels_after_miss(&histogram);
        assert_eq!(levels, [32, 16, 48, 8, 24, 40]);
        search.hit(16);
        assert_eq!(search.levels_after_miss(&histogram)[0], 16);
    }

    #[test]
    fn gradient_keeps_black_below_and_white_above_threshold() {
        // Black squares (ink reflects 10 %) and white paper (90 %) under
        // illumination falling 3:1 from left to right.
        let (w, h) = (320usize, 64usize);
        let mut px = vec![0u8; w * h];
        for y in 0..h {
            for x in 0..w {
                let light = 255.0 * (1.0 - 2.0 / 3.0 * x as f64 / w as f64);
                let ink = (x / 20 + y / 20) % 2 == 0;
                px[y * w + x] = (light * if ink { 0.1 } else { 0.9 }) as u8;
            }
        }
        let map = ThresholdMap::adaptive(&px, w, h);
        for y in 0..h {
            for x in 0..w {
                let ink = (x / 20 + y / 20) % 2 == 0;
                assert_eq!(px[y * w + x] < map.at(x, y), ink, "pixel {x},{y}");
            }
        }
    }

    #[test]
    fn a_band_map_equals_the_full_map_inside_the_band() {
        let (w, h) = (200usize, 300usize);
        let px: Vec<u8> = (0..w * h)
            .map(|i| ((i % w) * 7 + (i / w) * 13 % 97) as u8)
            .collect();
        let full = ThresholdMap::adaptive(&px, w, h);
        let band = ThresholdMap::adaptive_rows(&px, w, h, 100..180);
        for y in 100..180 {
            assert_eq!(full.row(y), band.row(y), "row {y}");
        }
        let _ = band.row(0);
        let _ = band.row(h - 1);
    }

    /// A dim disc of a contrast near the noise floor on a noisy dark
    /// background is where the global walk must look (its tiles are
    /// blind, at levels between the disc and the background); the flat
    /// noise around it and an inked disc on white paper are not.
    #[test]
    fn blind_tiles_cover_a_dim_disc_and_nothing_clear_or_flat() {
        let (w, h) = (480usize, 160usize);
        let mut state = 12345u32;
        let px: Vec<u8> = (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as i32, (i / w) as i32);
                state = state.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
                let noise = (state >> 29) as i32 - 3;
                let d2 = |cx: i32, cy: i32| (x - cx).pow(2) + (y - cy).pow(2);
                let level = if x >= 320 {
                    // Paper with an inked disc.
                    if d2(400, 80) < 900 {
                        15
                    } else {
                        200
                    }
                } else if d2(80, 80) < 900 {
                    8
                } else {
                    20
                };
                (level + noise).clamp(0, 255) as u8
            })
            .collect();
        let map = ThresholdMap::adaptive(&px, w, h);
        let blind = map.blind_tiles(&px, w, h);
        let cols = w.div_ceil(16);
        let at = |x: usize, y: usize| blind[(y / 16) * cols + x / 16];
        let (lo, hi) = at(80, 80);
        assert!(lo < 14 && 14 <= hi, "dim disc: {:?}", (lo, hi));
        assert_eq!(at(250, 80), (0, 0), "flat noise");
        assert_eq!(at(400, 80), (0, 0), "inked disc on paper");
        assert_eq!(at(400, 40), (0, 0), "inked disc's edge");
    }

    #[cfg(target_arch = "x86_64")]
    proptest::proptest! {
        /// The vector count of small differences agrees with one taken
        /// pixel by pixel, across the blocks where the byte counts are
        /// summed (rows past 255 vectors).
        #[test]
        fn small_differences_are_counted_as_one_by_one(
            seed in proptest::prelude::any::<u64>(),
            len in 0usize..5000,
            spread in 1u8..40,
            first in 0u8..16,
        ) {
            let mut rng = Pcg32::new(seed, 0);
            let row: Vec<u8> = (0..len)
                .map(|_| 128u8.wrapping_add((rng.next_u32() % u32::from(spread)) as u8))
                .collect();
            let levels = [first, first + 1, first + 2, first + 3];
            let expected: [u64; 4] = std::array::from_fn(|k| {
                row.windows(2).filter(|w| w[0].abs_diff(w[1]) <= levels[k]).count() as u64
            });
            proptest::prop_assert_eq!(diffs_at_most(&row, levels), expected);
        }
    }

    proptest::proptest! {
        /// Every tile's darkest and brightest pixel, four tiles at a time
        /// or one, as a pixel-by-pixel fold finds them.
        #[test]
        fn tile_levels_are_the_tiles_extremes(
            seed in proptest::prelude::any::<u64>(),
            width in 1usize..300,
            rows in 1usize..=16,
        ) {
            let mut rng = Pcg32::new(seed, 0);
            let band: Vec<u8> = (0..width * rows).map(|_| rng.next_u32() as u8).collect();
            let tile = 1usize << TILE_SHIFT;
            let cols = width.div_ceil(tile);
            let (mut lo, mut hi) = (vec![0u8; cols], vec![0u8; cols]);
            tile_row_levels(&band, width, &mut lo, &mut hi);
            for c in 0..cols {
                let x = c * tile..((c + 1) * tile).min(width);
                let pixels = band.chunks_exact(width).flat_map(|row| &row[x.clone()]);
                proptest::prop_assert_eq!(lo[c], *pixels.clone().min().unwrap());
                proptest::prop_assert_eq!(hi[c], *pixels.max().unwrap());
            }
        }
    }

    proptest::proptest! {
        /// The framed spread gives every unset tile the value a plain
        /// breadth-first spread from every set tile, in index order, gives.
        #[test]
        fn unset_tiles_take_the_value_the_plain_spread_gives(
            cols in 1usize..12,
            rows in 1usize..12,
            seed in proptest::prelude::any::<u64>(),
            share in 1u64..8,
        ) {
            const UNSET: u16 = u16::MAX;
            let mut rng = Pcg32::new(seed, 0);
            let grid: Vec<u16> = (0..cols * rows)
                .map(|_| {
                    let r = rng.next_u32();
                    if u64::from(r % 8) < share { (r >> 8) as u16 % 200 } else { UNSET }
                })
                .collect();
            let mut plain = grid.clone();
            let mut queue: std::collections::VecDeque<usize> =
                (0..plain.len()).filter(|&i| plain[i] != UNSET).collect();
            while let Some(i) = queue.pop_front() {
                let (c, r) = (i % cols, i / cols);
                let near = [
                    (c > 0).then(|| i - 1),
                    (c + 1 < cols).then(|| i + 1),
                    (r > 0).then(|| i - cols),
                    (r + 1 < rows).then(|| i + cols),
                ];
                for j in near.into_iter().flatten() {
                    if plain[j] == UNSET {
                        plain[j] = plain[i];
                        queue.push_back(j);
                    }
                }
            }
            let mut framed = grid;
            spread_to_unset(&mut framed, cols, rows, UNSET);
            proptest::prop_assert_eq!(framed, plain);
        }
    }

    #[test]
    fn flat_image_has_no_dark_pixels() {
        let px = vec![90u8; 100 * 50];
        let map = ThresholdMap::adaptive(&px, 100, 50);
        assert!(px
            .iter()
            .enumerate()
            .all(|(i, &p)| p >= map.at(i % 100, i / 100)));
    }
}
