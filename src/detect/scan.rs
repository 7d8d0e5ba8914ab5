//! The scan for new markers and the tests a dark segment must pass to be
//! one (paper section 4.1, eq. 1 and 4): roundness, the white inside, the
//! area ratio, concentricity, the moment ellipse's area and a tight
//! sub-pixel outline.

use std::f64::consts::PI;

use super::segment::{
    below_levels, below_mask, below_word, spread_levels, word_thresholds, Fill, Filler, Gray,
    Labels, Stats,
};
use super::threshold::{self, ThresholdMap};
use super::timings::Stopwatch;
use super::tracking::track::Tolerances;
use super::{ellipse, Candidate, Detector, DetectorConfig, Stage, StageTimings, SCAN_CHUNK};
use crate::geometry::Design;

/// Returns None from a candidate test, recording (feature `trace`) which
/// test lost the segment of these statistics.
macro_rules! lost {
    ($walker:ident, $reached:ident, $stats:expr) => {{
        #[cfg(feature = "trace")]
        $walker.note_loss(super::trace::Reached::$reached, &$stats);
        return None;
    }};
}

/// Shares of the disc's pixels that the original WhyCon accepts as the
/// white centre's (a centre 0.34 to 0.55 of the outer diameter): blur and a
/// camera's sharpening inflate a WhyCon marker's small white centre past
/// the adaptive window around the printed 0.41, and the tests after this
/// one (the centre's light, the white margin) judge it more closely.
const ORIGINAL_WHITE_SHARE: std::ops::RangeInclusive<f64> = 0.34 * 0.34..=0.55 * 0.55;

/// Segments whose outlines a job of the pool fits (and whose candidates it
/// describes) together while the scan walks on: each takes about a tenth
/// of a millisecond.
const OUTLINE_BATCH: usize = 8;

/// Slack of the concentricity test, in outer radii: WhyCode's white region
/// has its ring sectors on one side or the other, so its centroid wanders.
fn concentricity_tolerance(design: Design) -> f64 {
    match design {
        Design::WhyCode => 0.2,
        Design::WhyCon => 0.08,
    }
}

/// The shade look's map over the rows of the scan's `map`: its tile
/// levels taken as they are (over the shaded rows only, it would read
/// every pixel of them again). Seeds are still taken in the shaded rows
/// only.
fn ratio_map(gray: Gray<'_>, map: &ThresholdMap) -> ThresholdMap {
    ThresholdMap::adaptive_ratio(gray.pixels, gray.width, gray.height, 0..gray.height, map)
}

impl Detector {
    /// Scans the whole frame with thresholds from the local map, which it
    /// returns for the looks after it, with the shade look's map when it
    /// was made beside the scan.
    pub(super) fn scan_frame(
        &mut self,
        gray: Gray<'_>,
        found: &mut Vec<Candidate>,
    ) -> (ThresholdMap, Option<ThresholdMap>) {
        let map = ThresholdMap::adaptive(gray.pixels, gray.width, gray.height);
        self.stopwatch.lap(Stage::Threshold);
        // With a family, the shade look follows wherever the map saw a
        // shadow's edge (see `look_in_shade`), whatever the scan finds. Its
        // map depends on the first map alone: on a frame the pool splits,
        // another thread makes it while this one walks, rather than both
        // waiting for it after the scan.
        let shade_ahead = self.config.target.family().is_some()
            && map.shaded_rows().is_some()
            && crate::parallel::frame_threads(gray.width * gray.height) > 1;
        if !shade_ahead {
            self.scan(Stage::Scan, gray, &map, 0..gray.height, &[], found);
            return (map, None);
        }
        let ((), ratio_map) = crate::parallel::beside(
            || self.scan(Stage::Scan, gray, &map, 0..gray.height, &[], found),
            || ratio_map(gray, &map),
        );
        // Whatever the scan waited for the shade look's map is its time.
        self.stopwatch.lap(Stage::Shade);
        (map, Some(ratio_map))
    }

    /// A second look at the rows where the scan's `map` saw a cast
    /// shadow's edge: shaded paper fell below the mid-level threshold.
    /// There thresholds that keep the paper's ratio to the ink find what
    /// the first look missed.
    /// `ratio_map` is that look's map if it was made beside the scan.
    pub(super) fn look_in_shade(
        &mut self,
        gray: Gray<'_>,
        map: &ThresholdMap,
        ratio_map: Option<ThresholdMap>,
        found: &mut Vec<Candidate>,
    ) {
        // A family's ring test stands between grey clutter (which looks
        // shaded too) and a report, and makes the look worth its time on
        // every frame; without one (legacy circles, any bit count) the
        // look is taken, as the original moves its threshold, only on a
        // frame where the first look found nothing.
        let shaded = map
            .shaded_rows()
            .filter(|_| self.config.target.family().is_some() || found.is_empty());
        let Some(rows) = shaded else {
            return;
        };
        let (width, height) = (gray.width, gray.height);
        let ratio_map = ratio_map.unwrap_or_else(|| self::ratio_map(gray, map));
        self.walker.labels.begin(width, height);
        let mut again = Vec::new();
        let near = map.near_shaded();
        self.scan_tiles(
            Stage::Shade,
            gray,
            &ratio_map,
            rows,
            near,
            found,
            &mut again,
        );
        merge_new(found, again, self.config.max_markers);
    }

    /// When the local map found nothing (noise above the markers'
    /// contrast, say): a few levels of the reference's global threshold
    /// walk. Under a light gradient no one level suits the whole frame, so
    /// what each finds is pooled, and the level that found most is tried
    /// first next time. Only where the local map was blind (see
    /// `ThresholdMap::blind_tiles`) can a level find what it missed; a
    /// level that cuts no blind tile is not scanned.
    pub(super) fn global_fallback(
        &mut self,
        gray: Gray<'_>,
        map: &ThresholdMap,
        found: &mut Vec<Candidate>,
    ) {
        if !found.is_empty() {
            self.search.reset();
            return;
        }
        let (width, height) = (gray.width, gray.height);
        let histogram = threshold::sampled_histogram(gray.pixels, width);
        let blind = map.blind_tiles(gray.pixels, width, height);
        let mut best = 0;
        let mut seeds = Vec::new();
        for t in self.search.levels_after_miss(&histogram) {
            seeds.clear();
            seeds.extend(blind.iter().map(|&(lo, hi)| lo < t && t <= hi));
            if !seeds.contains(&true) {
                continue;
            }
            self.walker.labels.begin(width, height);
            let mut level = Vec::new();
            self.scan_tiles(
                Stage::Fallback,
                gray,
                &ThresholdMap::constant(t),
                0..height,
                &seeds,
                &[],
                &mut level,
            );
            if level.len() > best {
                best = level.len();
                self.search.hit(t);
            }
            merge_new(found, level, self.config.max_markers);
        }
    }

    /// Marks the tiles that markers followed this frame cover, so that the
    /// scan does not flood-fill them again.
    pub(super) fn mark_followed(&mut self, found: &[Candidate], width: usize, height: usize) {
        let cols = width.div_ceil(SCAN_CHUNK);
        let rows = height.div_ceil(SCAN_CHUNK);
        self.occupied.clear();
        if found.is_empty() {
            return;
        }
        self.occupied.resize(cols * rows, false);
        for c in found {
            let reach = c.reach();
            let x0 = ((c.outer.u - reach).max(0.0) as usize) / SCAN_CHUNK;
            let x1 = ((c.outer.u + reach).max(0.0) as usize / SCAN_CHUNK).min(cols - 1);
            let y0 = ((c.outer.v - reach).max(0.0) as usize) / SCAN_CHUNK;
            let y1 = ((c.outer.v + reach).max(0.0) as usize / SCAN_CHUNK).min(rows - 1);
            for ty in y0..=y1 {
                self.occupied[ty * cols + x0.min(x1)..=ty * cols + x1].fill(true);
            }
        }
    }

    /// [`Detector::scan`] with segments started only in the tiles flagged
    /// in `seed_tiles` (laid out as the scan's tiles); the segments so
    /// started are filled and tested whole, wherever they reach.
    #[allow(clippy::too_many_arguments)]
    pub(super) fn scan_tiles(
        &mut self,
        stage: Stage,
        gray: Gray<'_>,
        map: &ThresholdMap,
        rows: std::ops::Range<usize>,
        seed_tiles: &[bool],
        known: &[Candidate],
        found: &mut Vec<Candidate>,
    ) {
        if !seed_tiles.contains(&true) {
            return;
        }
        let followed = std::mem::take(&mut self.occupied);
        self.occupied.extend(
            (0..seed_tiles.len()).map(|i| !seed_tiles[i] || followed.get(i) == Some(&true)),
        );
        self.scan(stage, gray, map, rows, known, found);
        self.occupied = followed;
    }

    /// Scans the rows for dark pixels not yet visited and tests the
    /// segment each one starts, until `found` holds the most markers the
    /// configuration allows. Segments of the markers in `known` (found by
    /// an earlier look at the frame) are passed over, see
    /// [`Detector::evaluate`]. With the timings on, the scan's time is
    /// charged to `stage` (the look it serves), and that of describing
    /// its candidates on the way to the describe and pose stages.
    pub(super) fn scan(
        &mut self,
        stage: Stage,
        gray: Gray<'_>,
        map: &ThresholdMap,
        rows: std::ops::Range<usize>,
        known: &[Candidate],
        found: &mut Vec<Candidate>,
    ) {
        // On a large frame what reads the pixels only is done on the pool's
        // threads: the rows classified and the seed pixels found before the
        // walk, the outlines fitted while it goes on. The walk, whose fills
        // depend on the fills before them, stays on one thread, so the
        // segments and their order are the same for any number of threads.
        let parallel =
            !cfg!(feature = "trace") && crate::parallel::frame_threads(gray.width * rows.len()) > 1;
        if !parallel {
            Rules::new(&self.config, &self.tolerances, &self.occupied).walk(
                &mut self.walker,
                gray,
                map,
                rows,
                known,
                None,
                found,
                |walker, passed, found| {
                    found.extend(walker.fit_outline(gray, &passed));
                },
            );
            return;
        }
        let mut walker = std::mem::take(&mut self.walker);
        let mut seed_words = std::mem::take(&mut self.seed_words);
        let stride = seed_words_per_row(gray.width);
        // Every word is written below (`seed_row` of every row): last
        // frame's are not cleared first.
        seed_words.resize(rows.len() * stride, 0);
        // Which words may seed is the same for a tile row's sixteen pixel
        // rows: worked out once for them.
        let open = open_seed_words(gray, map, rows.clone(), &self.occupied);
        let seeds = |y: usize, words: &mut [u64]| {
            let k = y / SCAN_CHUNK - rows.start / SCAN_CHUNK;
            seed_row(gray, map, y, &open[k * stride..(k + 1) * stride], words);
        };
        if self.occupied.is_empty() {
            let extra = (seed_words.as_mut_slice(), stride);
            walker
                .filler
                .classify_rows(gray, map, rows.clone(), extra, seeds);
        } else {
            use crate::parallel::prelude::*;
            seed_words
                .par_chunks_mut(stride)
                .enumerate()
                .for_each(|(k, words)| seeds(rows.start + k, words));
        }
        self.stopwatch.lap(stage);
        let this = &*self;
        let rules = Rules::new(&this.config, &this.tolerances, &this.occupied);
        let limit = this.config.max_markers;
        let timings = this.config.timings;
        let view = image::ImageBuffer::<image::Luma<u8>, &[u8]>::from_raw(
            gray.width as u32,
            gray.height as u32,
            gray.pixels,
        )
        .expect("a frame's pixels fill it");
        // Each segment's outline, and the candidate it makes described as
        // the describe stage would (reading the detector only), while the
        // walk goes on: its pixels are in that thread's cache then.
        let fit_and_describe = |passed: &Passed| {
            let mut stopwatch = Stopwatch::default();
            stopwatch.start(timings);
            // The walk read these pixels on another core: fetched in one
            // tight loop, their misses overlap, where the outline's rays
            // (which reach past the disc into the paper) would wait on
            // them one after another.
            let e = &passed.coarse;
            super::preload_disc(gray, e.u, e.v, ellipse::edge_points_reach(e));
            let mut candidate = Detector::outline(gray, passed, &mut Vec::new());
            stopwatch.lap(stage);
            if let Some(c) = &mut candidate {
                this.describe_early(&mut stopwatch, &view, gray, c);
            }
            (candidate, stopwatch.stop())
        };
        let mut own = Stopwatch::default();
        own.start(timings);
        let spent = crate::parallel::map_alongside(OUTLINE_BATCH, &fit_and_describe, |fits| {
            let mut spent = StageTimings::default();
            let seeds = Some(seed_words.as_slice());
            rules.walk(
                &mut walker,
                gray,
                map,
                rows,
                known,
                seeds,
                found,
                |walker, passed, found| {
                    fits.push(passed);
                    // Which segments the walk tests next depends on how many
                    // made candidates.
                    if found.len() + fits.unsettled() >= limit {
                        spent += &walker.take_outlines(fits.settle(), found, limit);
                    }
                },
            );
            spent += &walker.take_outlines(fits.settle(), found, limit);
            spent
        });
        own.lap(stage);
        if let Some(mut laps) = own.stop() {
            laps += &spent;
            self.stopwatch.lap_shared(&laps);
        }
        self.walker = walker;
        self.seed_words = seed_words;
    }

    /// The candidate a segment that passed the tests makes when its
    /// outline is an ellipse along the whole edge: squares and blobs pass
    /// the moment tests (a square's area is within 5 % of its moment
    /// ellipse's) but not this. Reads only the pixels, so a frame's
    /// segments can be fitted on several threads. `edge` is scratch.
    pub(super) fn outline(
        gray: Gray<'_>,
        passed: &Passed,
        edge: &mut Vec<(f64, f64)>,
    ) -> Option<Candidate> {
        let coarse = &passed.coarse;
        let refined = ellipse::refine(gray, coarse, edge)?;
        // A motion-blurred outline is fitted on the stretches across the
        // blur only (at least 45 % of the rays).
        let min_support = if refined.blur.is_some() { 0.45 } else { 0.75 };
        if refined.support < min_support || refined.rms > 0.35 + 0.015 * coarse.semi_major {
            return None;
        }
        Some(Candidate {
            outer: refined.ellipse,
            edge: edge.clone(),
            black: passed.black,
            white: passed.white,
            ratio: passed.ratio,
            roundness: passed.roundness,
            area_error: passed.area_error,
            tested: true,
            track: None,
            #[cfg(feature = "parallel")]
            described: None,
        })
    }
}

/// What the scan's walk reads of the detector: the configuration, the
/// tests' tolerances and the tiles followed markers cover. Borrowed beside
/// the detector's [`Walker`], which the walk writes.
pub(super) struct Rules<'a> {
    config: &'a DetectorConfig,
    tolerances: &'a Tolerances,
    occupied: &'a [bool],
}

impl<'a> Rules<'a> {
    pub(super) fn new(
        config: &'a DetectorConfig,
        tolerances: &'a Tolerances,
        occupied: &'a [bool],
    ) -> Rules<'a> {
        Rules {
            config,
            tolerances,
            occupied,
        }
    }

    /// The walk of [`Detector::scan`] over `rows`: each segment that passes
    /// the tests goes to `passed`, which makes it a candidate in `found`
    /// or leaves it for later. The seed pixels are `seeds` (words of
    /// [`seed_row`]) when they were found before, else found on the way.
    #[allow(clippy::too_many_arguments)]
    fn walk(
        &self,
        walker: &mut Walker,
        gray: Gray<'_>,
        map: &ThresholdMap,
        rows: std::ops::Range<usize>,
        known: &[Candidate],
        seeds: Option<&[u64]>,
        found: &mut Vec<Candidate>,
        mut passed: impl FnMut(&mut Walker, Passed, &mut Vec<Candidate>),
    ) {
        let limit = self.config.max_markers;
        const CHUNK: usize = SCAN_CHUNK;
        // Seeds are gathered a word (four chunks) at a time: the chunks'
        // seed pixels as bits, less those already in a segment.
        let shift = map.shift();
        let margin = map.seed_margin();
        let cols = gray.width.div_ceil(CHUNK);
        let stride = seed_words_per_row(gray.width);
        // Tile rows with a tile left to scan: a look at a few tiles (the
        // global walk's blind ones) passes over the others' rows at once.
        let open_rows: Vec<bool> = if self.occupied.is_empty() {
            Vec::new()
        } else {
            self.occupied
                .chunks(cols)
                .map(|tiles| tiles.contains(&false))
                .collect()
        };
        let rows_start = rows.start;
        let mut open_words: Vec<u64> = Vec::new();
        // Runs of neighbouring words with a chunk that may seed.
        let mut open_runs: Vec<std::ops::Range<usize>> = Vec::new();
        // The seed levels of the whole words' pixels (see [`seed_word`]),
        // the same for a tile row's sixteen pixel rows (when the seeds are
        // found on the way).
        let mut seed_level_bytes: Vec<u8> = Vec::new();
        let mut row_words: Vec<u64> = vec![0; stride];
        let whole_words = gray.width / WORD;
        'rows: for y in rows {
            if found.len() >= limit {
                break;
            }
            if open_rows.get(y / CHUNK) == Some(&false) {
                continue;
            }
            let row_start = y * gray.width;
            let row = &gray.pixels[row_start..row_start + gray.width];
            let thresholds = map.row(y);
            if y == rows_start || y % CHUNK == 0 {
                // The chunks that may seed: the same for the tile row's
                // sixteen pixel rows.
                let tiles = SeedTiles::new(map, self.occupied, gray.width, y);
                open_words.clear();
                open_words.extend((0..stride).map(|w| tiles.open_chunks(w)));
                open_runs.clear();
                for (w, &open) in open_words.iter().enumerate() {
                    match open_runs.last_mut() {
                        Some(run) if open != 0 && run.end == w => run.end = w + 1,
                        _ if open != 0 => open_runs.push(w..w + 1),
                        _ => {}
                    }
                }
                if seeds.is_none() {
                    seed_level_bytes.clear();
                    for w in 0..whole_words {
                        spread_levels(
                            seed_levels(thresholds, shift, margin, w),
                            &mut seed_level_bytes,
                        );
                    }
                }
            }
            // The seed bits of each run of open words first, in a loop of
            // nothing else: most words have none.
            for run in &open_runs {
                match seeds {
                    Some(words) => {
                        let start = (y - rows_start) * stride;
                        row_words[run.clone()]
                            .copy_from_slice(&words[start + run.start..start + run.end]);
                    }
                    None => {
                        let whole = run.start..run.end.min(whole_words);
                        let pixels = whole.start * WORD..whole.end * WORD;
                        for ((out, block), levels) in row_words[whole]
                            .iter_mut()
                            .zip(row[pixels.clone()].chunks_exact(WORD))
                            .zip(seed_level_bytes[pixels].chunks_exact(WORD))
                        {
                            *out = below_levels(block, levels);
                        }
                        if run.end > whole_words {
                            let tail = &row[whole_words * WORD..];
                            row_words[whole_words] =
                                seed_word(tail, thresholds, shift, margin, whole_words);
                        }
                    }
                }
            }
            for w in open_runs.iter().flat_map(|run| run.clone()) {
                let mut word = row_words[w] & open_words[w];
                if word == 0 {
                    continue;
                }
                word &= !walker.labels.dark_word(y, w);
                while word != 0 {
                    let x = w * WORD + word.trailing_zeros() as usize;
                    let seed = (x as u32, y as u32);
                    if let Some(segment) = self.evaluate(walker, gray, map, seed, known) {
                        passed(walker, segment, found);
                        if found.len() >= limit {
                            break 'rows;
                        }
                    }
                    // The fill took this seed and perhaps others of the word.
                    word &= word - 1;
                    word &= !walker.labels.dark_word(y, w);
                }
            }
        }
    }

    /// Runs the tests on the dark segment that contains `seed`. A segment
    /// centred on a marker of `known` and lying within its outline's reach
    /// is that marker seen again (under another threshold map): it is not
    /// tested a second time.
    pub(super) fn evaluate(
        &self,
        walker: &mut Walker,
        gray: Gray<'_>,
        map: &ThresholdMap,
        seed: (u32, u32),
        known: &[Candidate],
    ) -> Option<Passed> {
        let design = self.config.target.design();
        let dark = walker
            .filler
            .fill(gray, map, &mut walker.labels, seed, Fill::Dark);
        if dark.escaped {
            lost!(walker, Escaped, dark.stats);
        }
        let dark = dark.stats;
        let white_fraction = self.tolerances.ratio.expected;
        let dark_fraction = 1.0 - white_fraction;
        let min_d = self.config.min_diameter_px;
        let n = dark.count as f64;
        if n < 0.5 * dark_fraction * PI / 4.0 * min_d * min_d {
            lost!(walker, Size, dark);
        }
        let (bw, bh) = (f64::from(dark.width()), f64::from(dark.height()));
        if bw < 4.0 || bh < 4.0 {
            lost!(walker, Size, dark);
        }
        let (cu, cv) = dark.centroid();
        if !known.is_empty() {
            let seen_before = known.iter().any(|k| {
                let (e, reach) = (&k.outer, k.reach());
                (cu - e.u).hypot(cv - e.v) < 0.5 * e.semi_minor
                    && f64::from(dark.min_u) >= e.u - reach
                    && f64::from(dark.max_u) <= e.u + reach
                    && f64::from(dark.min_v) >= e.v - reach
                    && f64::from(dark.max_v) <= e.v + reach
            });
            if seen_before {
                return None;
            }
        }
        // Eq. 1: the dark pixels fill the expected share of the bounding
        // box's inscribed ellipse. An ellipse whose axes are slanted to the
        // image axes fills less of its box: by sqrt(1 - ρ²), ρ the
        // correlation of its pixels' u and v (1 for axis-parallel ones). A
        // marker seen at 70° at 45° to the rows would fail the test by
        // 40 % otherwise.
        let (cuu, cuv, cvv) = dark.covariance();
        let slant = if cuu > 0.0 && cvv > 0.0 {
            (1.0 - cuv * cuv / (cuu * cvv)).max(0.0).sqrt()
        } else {
            1.0
        };
        let roundness = n / (PI / 4.0 * bw * bh * dark_fraction * slant) - 1.0;
        if roundness.abs() >= self.tolerances.roundness.tolerance() {
            lost!(walker, Roundness, dark);
        }
        // The grey values are read only for segments that pass every test
        // up to the contrast test, which is most of all a round blob of
        // clutter with no white inside is not: the dark fill's runs are
        // kept aside for it while the white fill runs.
        walker.filler.keep_runs();
        // The white inside may come next to the segment's bounding box only
        // when the annulus is one pixel wide, on markers of a few pixels:
        // those need a family's ring model to be told from blobs.
        let inset = u32::from(self.config.target.family().is_none());
        let bounds = [
            dark.min_u + inset,
            dark.min_v + inset,
            dark.max_u.saturating_sub(inset),
            dark.max_v.saturating_sub(inset),
        ];
        let max_count = (n * white_fraction / dark_fraction * 2.5) as u64 + 16;
        let reach = concentricity_tolerance(design) * 0.25 * (bw + bh);
        let Some(white) = self.fill_inside(walker, gray, map, (cu, cv), reach, bounds, max_count)
        else {
            lost!(walker, WhiteInside, dark);
        };
        let total = dark.merged(&white);
        let ratio = white.count as f64 / total.count as f64;
        let coarse = ellipse::from_moments(&total);
        // A marker's size is its major axis, which a tilt does not shorten;
        // but only a family's ring model can tell a tilted marker of a few
        // pixels from a blob (legacy markers have no ring, and the bit
        // count of so small a ring cannot be read), so without one the
        // minor axis must reach the size too.
        let size_axis = |e: &crate::math::Ellipse| {
            if self.config.target.family().is_some() {
                e.semi_major
            } else {
                e.semi_minor
            }
        };
        let accepted = (self.tolerances.ratio.accepts(ratio)
            || ORIGINAL_WHITE_SHARE.contains(&ratio))
            && coarse.is_some_and(|e| {
                let (wu, wv) = white.centroid();
                let radius = (e.semi_major * e.semi_minor).sqrt();
                (wu - e.u).hypot(wv - e.v) < concentricity_tolerance(design) * radius + 1.0
                    && 2.0 * size_axis(&e) >= min_d
            });
        let coarse = match coarse {
            Some(e) if accepted => e,
            _ => {
                walker.filler.undo_last(&mut walker.labels);
                lost!(walker, RatioOrConcentricity, dark);
            }
        };
        // Eq. 4 on the whole disc. Pixel counts of small discs carry a
        // boundary quantisation error of about 1/(2b) of the area.
        let area_error = coarse.area() / total.count as f64 - 1.0;
        if area_error.abs() >= self.tolerances.area.tolerance() + 0.5 / coarse.semi_minor {
            lost!(walker, Area, dark);
        }
        let black = Stats {
            sum_i: walker.filler.kept_grey_sum(gray),
            ..dark
        }
        .mean_intensity();
        let white_level = Stats {
            sum_i: walker.filler.grey_sum(gray),
            ..white
        }
        .mean_intensity();
        if white_level - black < map.min_contrast() {
            lost!(walker, Contrast, dark);
        }
        Some(Passed {
            coarse,
            black,
            white: white_level,
            ratio,
            roundness,
            area_error: area_error.abs(),
            dark,
        })
    }

    /// Fills the white region around the dark segment's centroid; None when
    /// it is not enclosed by the segment. When the centroid lands on ink
    /// (the ring, or a printed centring cross, whose lines a local
    /// threshold cuts as dark inside the white disc), the fill starts at
    /// the nearest light pixel within `reach` pixels, on one of eight
    /// rays: further off, the white's centroid would fail concentricity
    /// anyway. The region's grey values are left for later (its runs are
    /// the filler's last, see `Filler::grey_sum`).
    #[allow(clippy::too_many_arguments)]
    fn fill_inside(
        &self,
        walker: &mut Walker,
        gray: Gray<'_>,
        map: &ThresholdMap,
        centre: (f64, f64),
        reach: f64,
        bounds: [u32; 4],
        max_count: u64,
    ) -> Option<Stats> {
        let (cx, cy) = (centre.0.round() as i64, centre.1.round() as i64);
        const RAYS: [(i64, i64); 8] = [
            (1, 0),
            (-1, 0),
            (0, 1),
            (0, -1),
            (1, 1),
            (-1, -1),
            (1, -1),
            (-1, 1),
        ];
        let steps = (reach.max(1.0) as i64).min(64);
        let probes = std::iter::once((0, 0))
            .chain(RAYS.iter().copied())
            .chain((2..=steps).flat_map(|k| RAYS.iter().map(move |&(dx, dy)| (k * dx, k * dy))));
        for (dx, dy) in probes {
            let (x, y) = (cx + dx, cy + dy);
            if x <= i64::from(bounds[0])
                || y <= i64::from(bounds[1])
                || x >= i64::from(bounds[2])
                || y >= i64::from(bounds[3])
            {
                continue;
            }
            // A probe on ink would fill nothing.
            if !walker
                .filler
                .takes(gray, map, &walker.labels, (x as u32, y as u32), false)
            {
                continue;
            }
            let result = walker.filler.fill(
                gray,
                map,
                &mut walker.labels,
                (x as u32, y as u32),
                Fill::White { bounds, max_count },
            );
            if result.escaped {
                walker.filler.undo_last(&mut walker.labels);
                return None;
            }
            if result.stats.count > 0 {
                return Some(result.stats);
            }
        }
        None
    }
}

/// A passed segment's candidate, if its outline makes one, with the time
/// fitting and describing it took (with the timings on).
type Fitted = (Option<Candidate>, Option<StageTimings>);

/// What the scan's walk writes as it goes: the labels of the frame's
/// segments, the flood fill's buffers, the outline's edge points and
/// (feature `trace`) where each segment was lost. The walk only reads the
/// detector, so that the pool's other threads can read it meanwhile.
#[derive(Debug, Clone, Default)]
pub(super) struct Walker {
    pub(super) labels: Labels,
    filler: Filler,
    pub(super) edge: Vec<(f64, f64)>,
    #[cfg(feature = "trace")]
    pub(super) trace: Vec<super::trace::Loss>,
}

impl Walker {
    /// The box of every pixel this walker's fills labelled (and perhaps
    /// unlabelled again) since the last call.
    #[cfg(feature = "parallel")]
    pub(super) fn take_reach(&mut self) -> Option<[u32; 4]> {
        self.filler.take_reach()
    }

    /// [`Detector::outline`] of `passed`, noting (feature `trace`) whether
    /// it made a candidate.
    pub(super) fn fit_outline(&mut self, gray: Gray<'_>, passed: &Passed) -> Option<Candidate> {
        let candidate = Detector::outline(gray, passed, &mut self.edge);
        self.note_outline(passed, candidate.is_some());
        candidate
    }

    /// Adds the candidates of segments whose outlines were fitted
    /// (`fitted`, in the walk's order) to `found`, up to `limit`.
    /// Gives the time the outlines and descriptions took.
    fn take_outlines(
        &mut self,
        fitted: Vec<(Passed, Fitted)>,
        found: &mut Vec<Candidate>,
        limit: usize,
    ) -> StageTimings {
        let mut spent = StageTimings::default();
        for (passed, (candidate, laps)) in fitted {
            if let Some(laps) = laps {
                spent += &laps;
            }
            if found.len() >= limit {
                continue;
            }
            self.note_outline(&passed, candidate.is_some());
            found.extend(candidate);
        }
        spent
    }

    /// Notes (feature `trace`) whether a segment's outline made it a
    /// candidate.
    #[allow(unused_variables)]
    pub(super) fn note_outline(&mut self, passed: &Passed, fitted: bool) {
        #[cfg(feature = "trace")]
        self.note_loss(
            if fitted {
                super::trace::Reached::Candidate
            } else {
                super::trace::Reached::EllipseFit
            },
            &passed.dark,
        );
    }
}

/// Seed pixels go one bit each into 64-bit words, each row padded to whole
/// words.
const WORD: usize = 64;

fn seed_words_per_row(width: usize) -> usize {
    width.div_ceil(WORD)
}

/// The seed pixels of word `w` of a row (`block` its pixels, `thresholds`
/// the row's): those darker than their tile's threshold by the map's seed
/// margin.
#[inline(always)]
fn seed_word(block: &[u8], thresholds: &[u8], shift: u32, margin: u8, w: usize) -> u64 {
    if block.len() == WORD {
        below_word(block, seed_levels(thresholds, shift, margin, w))
    } else {
        block
            .chunks(SCAN_CHUNK)
            .enumerate()
            .fold(0u64, |m, (q, chunk)| {
                let t = thresholds[(w * WORD + q * SCAN_CHUNK) >> shift].saturating_sub(margin);
                m | u64::from(below_mask(chunk, t)) << (q * SCAN_CHUNK)
            })
    }
}

/// The seed levels of whole word `w`'s four chunks (`thresholds` the
/// row's): each tile's threshold less the map's seed margin.
#[inline(always)]
fn seed_levels(thresholds: &[u8], shift: u32, margin: u8, w: usize) -> [u8; 4] {
    word_thresholds(thresholds, shift, w).map(|t| t.saturating_sub(margin))
}

/// Whether tile `tile` of a row may hold a seed: its darkest pixel
/// (`darkest`, [`ThresholdMap::darkest_row`]) lies below its seed level
/// (its threshold in `thresholds` less the map's seed `margin`).
#[inline(always)]
fn may_seed(darkest: &[u8], thresholds: &[u8], margin: u8, tile: usize) -> bool {
    darkest[tile] < thresholds[tile].saturating_sub(margin)
}

/// What decides where the walk may seed in a row of tiles: the followed
/// markers' chunks (`occupied`, laid out as the scan's chunks; none when
/// empty), the map's floor, and each tile's darkest pixel against its seed
/// level.
struct SeedTiles<'a> {
    closed: Option<&'a [bool]>,
    floor: Option<&'a [bool]>,
    darkest: Option<&'a [u8]>,
    thresholds: &'a [u8],
    shift: u32,
    margin: u8,
    width: usize,
}

impl<'a> SeedTiles<'a> {
    /// The tiles of image row `y`'s tile row: the same for its sixteen
    /// pixel rows.
    fn new(map: &'a ThresholdMap, occupied: &'a [bool], width: usize, y: usize) -> Self {
        debug_assert!(map.is_constant() || 1 << map.shift() == SCAN_CHUNK);
        let cols = width.div_ceil(SCAN_CHUNK);
        let t = y / SCAN_CHUNK;
        SeedTiles {
            closed: (!occupied.is_empty()).then(|| &occupied[t * cols..(t + 1) * cols]),
            floor: map.floor_row(y),
            darkest: map.darkest_row(y),
            thresholds: map.row(y),
            shift: map.shift(),
            margin: map.seed_margin(),
            width,
        }
    }

    /// The bits of word `w` in the chunks that may seed: in the row, not
    /// followed, not floor, and with a pixel darker than the seed level
    /// (the pixels of most tiles are not).
    #[inline(always)]
    fn open_chunks(&self, w: usize) -> u64 {
        let chunks = (self.width - w * WORD)
            .div_ceil(SCAN_CHUNK)
            .min(WORD / SCAN_CHUNK);
        let mut open = u64::MAX >> (WORD - chunks * SCAN_CHUNK);
        if self.closed.is_none() && self.floor.is_none() && self.darkest.is_none() {
            return open;
        }
        for q in 0..chunks {
            let x0 = w * WORD + q * SCAN_CHUNK;
            let tile = x0 >> self.shift;
            if self.closed.is_some_and(|c| c[x0 / SCAN_CHUNK])
                || self.floor.is_some_and(|f| f[tile])
                || self
                    .darkest
                    .is_some_and(|d| !may_seed(d, self.thresholds, self.margin, tile))
            {
                open &= !(0xffff << (q * SCAN_CHUNK));
            }
        }
        open
    }
}

/// For each tile row of `rows`, whether each word of its pixel rows has a
/// chunk the walk may seed in ([`SeedTiles::open_chunks`]). Most words of
/// a frame have none, and their pixels are not read.
fn open_seed_words(
    gray: Gray<'_>,
    map: &ThresholdMap,
    rows: std::ops::Range<usize>,
    occupied: &[bool],
) -> Vec<bool> {
    use crate::parallel::prelude::*;
    let stride = seed_words_per_row(gray.width);
    let tile_rows = (rows.start / SCAN_CHUNK)..rows.end.div_ceil(SCAN_CHUNK);
    let mut open = vec![false; tile_rows.len() * stride];
    open.par_chunks_mut(stride)
        .enumerate()
        .for_each(|(k, open)| {
            let y = ((tile_rows.start + k) * SCAN_CHUNK).max(rows.start);
            let tiles = SeedTiles::new(map, occupied, gray.width, y);
            for (w, open) in open.iter_mut().enumerate() {
                *open = tiles.open_chunks(w) != 0;
            }
        });
    open
}

/// [`seed_word`] of every word of row `y` that is `open`
/// ([`open_seed_words`] of its tile row), into `words`; zero for the others.
fn seed_row(gray: Gray<'_>, map: &ThresholdMap, y: usize, open: &[bool], words: &mut [u64]) {
    let (shift, margin) = (map.shift(), map.seed_margin());
    let row = &gray.pixels[y * gray.width..(y + 1) * gray.width];
    let thresholds = map.row(y);
    for (w, ((block, out), &open)) in row.chunks(WORD).zip(words).zip(open).enumerate() {
        *out = if open {
            seed_word(block, thresholds, shift, margin, w)
        } else {
            0
        };
    }
}

/// A segment that passed every test that reads the labels, with what its
/// candidate keeps: its outline's fit is left (see [`Detector::outline`]).
#[derive(Debug, Clone)]
pub(super) struct Passed {
    coarse: crate::math::Ellipse,
    black: f64,
    white: f64,
    ratio: f64,
    roundness: f64,
    area_error: f64,
    /// The dark segment, for the trace of losses.
    #[cfg_attr(not(feature = "trace"), allow(dead_code))]
    dark: Stats,
}

/// Adds the candidates of another look that are not already found (no
/// found centre within their semi-minor axis), up to `limit`.
fn merge_new(found: &mut Vec<Candidate>, more: Vec<Candidate>, limit: usize) {
    for c in more {
        if found.len() < limit
            && !found
                .iter()
                .any(|o| (o.outer.u - c.outer.u).hypot(o.outer.v - c.outer.v) < o.outer.semi_minor)
        {
            found.push(c);
        }
    }
}
