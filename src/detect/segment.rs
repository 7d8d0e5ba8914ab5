//! Flood-fill segmentation with on-demand thresholding: pixels are
//! classified only when the fill reaches them, and the statistics the tests
//! need (pixel count, bounding box, first and second moments, brightness)
//! are summed while filling, in integer arithmetic.
//!
//! The fill works on horizontal runs held as bit masks: a row's pixels are
//! classified dark or light 16 at a time (one threshold tile) into 64-bit
//! words, once per threshold map, and visit marks are bits too. Finding a
//! run's ends, the runs of the rows above and below that it touches, and
//! marking it visited are then a few word operations per 64 pixels; a
//! run's moments have closed forms, so what is left per pixel is adding its
//! grey value. Large clutter shapes, which every frame is full of and no
//! test can refuse before they are whole, cost by their runs, not pixels.

use super::threshold::ThresholdMap;

/// Bits per mask word.
const WORD: usize = 64;
/// Pixels classified at once: one threshold tile's width.
const CHUNK: usize = 16;

/// One bit per pixel, row after row, each row padded to whole words (the
/// padding bits stay clear, so runs never reach past the row's end).
fn words_per_row(width: usize) -> usize {
    width.div_ceil(WORD)
}

/// Bit `i` set when `chunk[i] < t`: one vector compare and a byte mask
/// per full chunk where the target has them.
#[inline]
pub fn below_mask(chunk: &[u8], t: u8) -> u16 {
    #[cfg(target_arch = "x86_64")]
    if chunk.len() == CHUNK {
        // SAFETY: SSE2 is part of x86_64; the load reads the chunk's 16
        // bytes, unaligned. p < t exactly when min(p, t - 1) == p (t > 0).
        unsafe {
            use std::arch::x86_64::*;
            if t == 0 {
                return 0;
            }
            let p = _mm_loadu_si128(chunk.as_ptr().cast());
            let below = _mm_cmpeq_epi8(_mm_min_epu8(p, _mm_set1_epi8((t - 1) as i8)), p);
            return _mm_movemask_epi8(below) as u16;
        }
    }
    chunk
        .iter()
        .enumerate()
        .fold(0u16, |m, (i, &p)| m | u16::from(p < t) << i)
}

/// Bit `i` set when `block[i]` (64 pixels) lies below its chunk's
/// threshold, `t[q]` for pixels 16 q to 16 q + 15.
#[inline(always)]
pub fn below_word(block: &[u8], t: [u8; 4]) -> u64 {
    let block: &[u8; WORD] = block.try_into().expect("a whole word of pixels");
    #[cfg(target_arch = "x86_64")]
    // SAFETY: SSE2 is part of x86_64; each load reads 16 of the block's
    // 64 bytes, unaligned. Bytes are compared as signed after flipping
    // their top bit, which orders them as unsigned; nothing is below 0.
    unsafe {
        use std::arch::x86_64::*;
        let flip = _mm_set1_epi8(i8::MIN);
        // The four thresholds spread to four bytes each, then each to a
        // whole vector: fewer shuffles than four broadcasts.
        let t = _mm_xor_si128(_mm_cvtsi32_si128(i32::from_le_bytes(t)), flip);
        let t = _mm_unpacklo_epi8(t, t);
        let t = _mm_unpacklo_epi16(t, t);
        let ts = [
            _mm_shuffle_epi32::<0x00>(t),
            _mm_shuffle_epi32::<0x55>(t),
            _mm_shuffle_epi32::<0xaa>(t),
            _mm_shuffle_epi32::<0xff>(t),
        ];
        let mut bits = 0u64;
        for (q, &tq) in ts.iter().enumerate() {
            let p = _mm_loadu_si128(block.as_ptr().add(q * CHUNK).cast());
            let below = _mm_cmplt_epi8(_mm_xor_si128(p, flip), tq);
            bits |= u64::from(_mm_movemask_epi8(below) as u16) << (q * CHUNK);
        }
        bits
    }
    #[cfg(not(target_arch = "x86_64"))]
    (0..WORD / CHUNK).fold(0u64, |bits, q| {
        bits | u64::from(below_mask(&block[q * CHUNK..(q + 1) * CHUNK], t[q])) << (q * CHUNK)
    })
}

/// The levels `t` of a word's four chunks spread to a byte per pixel,
/// appended to `out`: what [`below_levels`] compares a word with.
#[inline]
pub fn spread_levels(t: [u8; 4], out: &mut Vec<u8>) {
    for level in t {
        out.extend_from_slice(&[level; CHUNK]);
    }
}

/// [`below_word`] against levels already spread to a byte per pixel
/// ([`spread_levels`]). A word with no pixel below its level, most words
/// of a frame, costs one test for its 64 pixels rather than a mask per
/// chunk.
#[inline(always)]
pub fn below_levels(block: &[u8], levels: &[u8]) -> u64 {
    let block: &[u8; WORD] = block.try_into().expect("a whole word of pixels");
    let levels: &[u8; WORD] = levels.try_into().expect("a whole word of levels");
    #[cfg(target_arch = "x86_64")]
    // SAFETY: SSE2 is part of x86_64; each load reads 16 of the 64 bytes
    // of `block` or `levels`, unaligned. The saturating difference
    // level - pixel is non-zero exactly where the pixel lies below.
    unsafe {
        use std::arch::x86_64::*;
        let zero = _mm_setzero_si128();
        let (b, t) = (block.as_ptr(), levels.as_ptr());
        let below = |q: usize| {
            let p = _mm_loadu_si128(b.add(q * CHUNK).cast());
            _mm_subs_epu8(_mm_loadu_si128(t.add(q * CHUNK).cast()), p)
        };
        let (d0, d1, d2, d3) = (below(0), below(1), below(2), below(3));
        let any = _mm_or_si128(_mm_or_si128(d0, d1), _mm_or_si128(d2, d3));
        if _mm_movemask_epi8(_mm_cmpeq_epi8(any, zero)) == 0xffff {
            return 0;
        }
        let mask = |d: __m128i| u64::from(!(_mm_movemask_epi8(_mm_cmpeq_epi8(d, zero)) as u16));
        mask(d0) | mask(d1) << CHUNK | mask(d2) << (2 * CHUNK) | mask(d3) << (3 * CHUNK)
    }
    // Each chunk's pixels share one level.
    #[cfg(not(target_arch = "x86_64"))]
    below_word(block, std::array::from_fn(|q| levels[q * CHUNK]))
}

/// The floor flags of the four chunks of word `w` of a row (see
/// [`ThresholdMap::floor_row`]).
#[inline(always)]
fn word_floor(floor: &[bool], shift: u32, w: usize) -> [bool; 4] {
    if shift == CHUNK.trailing_zeros() {
        floor[w * 4..w * 4 + 4].try_into().expect("four tiles")
    } else {
        std::array::from_fn(|q| floor[(w * WORD + q * CHUNK) >> shift])
    }
}

/// The thresholds of the four chunks of word `w` of a row (see
/// [`ThresholdMap::row`]).
#[inline(always)]
pub fn word_thresholds(thresholds: &[u8], shift: u32, w: usize) -> [u8; 4] {
    if shift == CHUNK.trailing_zeros() {
        thresholds[w * 4..w * 4 + 4].try_into().expect("four tiles")
    } else {
        std::array::from_fn(|q| thresholds[(w * WORD + q * CHUNK) >> shift])
    }
}

/// The sum of a run's grey values: sixteen at a time where the target
/// has a sum-of-absolute-differences instruction (to zero).
#[inline]
pub(super) fn sum_bytes(run: &[u8]) -> u64 {
    #[cfg(target_arch = "x86_64")]
    {
        let mut blocks = run.chunks_exact(CHUNK);
        let mut total = 0u64;
        // SAFETY: SSE2 is part of x86_64; each load reads one block's 16
        // bytes, unaligned.
        unsafe {
            use std::arch::x86_64::*;
            let mut acc = _mm_setzero_si128();
            for block in &mut blocks {
                let p = _mm_loadu_si128(block.as_ptr().cast());
                acc = _mm_add_epi64(acc, _mm_sad_epu8(p, _mm_setzero_si128()));
            }
            let mut lanes = [0u64; 2];
            _mm_storeu_si128(lanes.as_mut_ptr().cast(), acc);
            total += lanes[0] + lanes[1];
        }
        total
            + blocks
                .remainder()
                .iter()
                .map(|&p| u64::from(p))
                .sum::<u64>()
    }
    #[cfg(not(target_arch = "x86_64"))]
    run.iter().map(|&p| u64::from(p)).sum()
}

/// Per-pixel visit marks, reused from frame to frame: dark segments and
/// white insides each have a bit per pixel. A row's bits are valid only
/// when its stamp equals the pass's generation, so starting a pass
/// forgets every mark without touching the buffers; a row is cleared when
/// first written in a pass.
#[derive(Debug, Clone, Default)]
pub struct Labels {
    dark: Vec<u64>,
    white: Vec<u64>,
    /// A row of clear marks, for rows not yet written in this pass.
    zeros: Vec<u64>,
    stamps: Vec<u32>,
    stride: usize,
    width: usize,
    height: usize,
    generation: u32,
}

impl Labels {
    /// Starts a fresh pass over a `width` x `height` image.
    pub fn begin(&mut self, width: usize, height: usize) {
        if self.width != width || self.height != height {
            self.stride = words_per_row(width);
            self.dark = vec![0; self.stride * height];
            self.white = vec![0; self.stride * height];
            self.zeros = vec![0; self.stride];
            self.stamps = vec![0; height];
            self.width = width;
            self.height = height;
            self.generation = 0;
        }
        if self.generation == u32::MAX {
            self.stamps.fill(0);
            self.generation = 0;
        }
        self.generation += 1;
    }

    /// The dark-segment marks of word `w` (pixels 64 w to 64 w + 63) of
    /// row `y`.
    #[inline(always)]
    pub fn dark_word(&self, y: usize, w: usize) -> u64 {
        if self.stamps[y] == self.generation {
            self.dark[y * self.stride + w]
        } else {
            0
        }
    }

    /// Row `y`'s marks, cleared first if they are a previous pass's.
    #[inline]
    fn row_mut(&mut self, y: usize, dark: bool) -> &mut [u64] {
        let range = y * self.stride..(y + 1) * self.stride;
        if self.stamps[y] != self.generation {
            self.dark[range.clone()].fill(0);
            self.white[range.clone()].fill(0);
            self.stamps[y] = self.generation;
        }
        if dark {
            &mut self.dark[range]
        } else {
            &mut self.white[range]
        }
    }

    /// True when the pixel already belongs to a dark segment of this pass.
    #[inline]
    pub fn is_dark_visited(&self, index: usize) -> bool {
        let (y, x) = (index / self.width, index % self.width);
        self.dark_word(y, x / WORD) >> (x % WORD) & 1 == 1
    }

    /// Appends the marks of `area` (min u, min v, max u, max v; whole
    /// words) that are set to `out`, and clears them when `take`.
    #[cfg(feature = "parallel")]
    pub fn marks_in(&mut self, area: [u32; 4], take: bool, out: &mut Vec<Marks>) {
        let (w0, w1) = (area[0] as usize / WORD, area[2] as usize / WORD);
        for y in area[1] as usize..=(area[3] as usize).min(self.height - 1) {
            if self.stamps[y] != self.generation {
                continue;
            }
            let row = y * self.stride;
            for w in w0..=w1.min(self.stride - 1) {
                let (dark, white) = (self.dark[row + w], self.white[row + w]);
                if dark | white != 0 {
                    out.push(Marks {
                        row: y as u32,
                        word: w as u32,
                        dark,
                        white,
                    });
                    if take {
                        self.dark[row + w] = 0;
                        self.white[row + w] = 0;
                    }
                }
            }
        }
    }

    /// Sets `marks` (from [`Labels::marks_in`] of this image's pass).
    #[cfg(feature = "parallel")]
    pub fn put_marks(&mut self, marks: &[Marks]) {
        for m in marks {
            let (y, w) = (m.row as usize, m.word as usize);
            self.row_mut(y, true)[w] |= m.dark;
            self.row_mut(y, false)[w] |= m.white;
        }
    }
}

/// One word of a row's labels: the dark and the white marks of its 64
/// pixels.
#[cfg(feature = "parallel")]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Marks {
    pub row: u32,
    pub word: u32,
    pub dark: u64,
    pub white: u64,
}

/// Sets (or clears) bits x0..=x1 of a row of words.
#[inline]
fn set_bits(row: &mut [u64], x0: usize, x1: usize, on: bool) {
    let (w0, w1) = (x0 / WORD, x1 / WORD);
    if w0 == w1 {
        let mask = (!0u64 << (x0 % WORD)) & (!0u64 >> (WORD - 1 - x1 % WORD));
        if on {
            row[w0] |= mask;
        } else {
            row[w0] &= !mask;
        }
        return;
    }
    // The end words, then the whole words between them: indexed, as an
    // iterator skipping to the first word compiles to a call per run.
    let ends = [
        (w0, !0u64 << (x0 % WORD)),
        (w1, !0u64 >> (WORD - 1 - x1 % WORD)),
    ];
    for (w, mask) in ends {
        if on {
            row[w] |= mask;
        } else {
            row[w] &= !mask;
        }
    }
    row[w0 + 1..w1].fill(if on { !0 } else { 0 });
}

/// The pixels of an image classified under one threshold map as fills
/// first reach them: `dark` below the threshold and outside floor tiles
/// (what a dark fill may take), `light` at or above it (what a white fill
/// may take). Under a frame's adaptive map a row is classified whole, as
/// its fills reach most rows; under one threshold (a tracked marker's, a
/// level of the global walk) on a wide frame a few words at a time, since
/// a fill of one marker there needs a few hundred pixels of each row it
/// crosses, not the row.
#[derive(Debug, Clone, Default)]
struct Classes {
    /// The map and image the rows were classified for.
    key: Option<(u64, usize, usize)>,
    dark: Vec<u64>,
    light: Vec<u64>,
    /// Rows classified whole.
    stamps: Vec<u32>,
    /// Runs of [`CLASS_RUN`] words classified, `runs_per_row` a row.
    run_stamps: Vec<u32>,
    runs_per_row: usize,
    /// Whether rows are classified a run of words at a time.
    by_runs: bool,
    generation: u32,
    stride: usize,
}

/// Words of a row classified together when a fill reaches one of them.
const CLASS_RUN: usize = 4;

/// Rows of more words than this are classified a run of words at a time
/// under one threshold; narrower ones whole, which costs a fill less than
/// keeping track of the runs.
const BY_RUNS_FROM_WORDS: usize = 32;

/// Whether rows may be classified in runs at all. Not in the browser: its
/// frames are a camera's, narrower than [`BY_RUNS_FROM_WORDS`] words, and
/// the page's first load has a size budget that the run-by-run copy of the
/// fill would spend for nothing. The fills' results are the same either way.
/// Tested again where the fill picks its copy and in [`Classes::ensure`],
/// beside `by_runs`, so that the compiler leaves the copy's code out.
const BY_RUNS_BUILT: bool = !cfg!(target_arch = "wasm32");

impl Classes {
    /// Forgets the rows unless they were classified for this map and image.
    fn select(&mut self, image: Gray<'_>, map: &ThresholdMap) {
        let key = (map.id(), image.pixels.as_ptr() as usize, image.width);
        let stride = words_per_row(image.width);
        if self.stride != stride || self.stamps.len() != image.height {
            self.stride = stride;
            self.runs_per_row = stride.div_ceil(CLASS_RUN);
            self.dark = vec![0; stride * image.height];
            self.light = vec![0; stride * image.height];
            self.stamps = vec![0; image.height];
            self.run_stamps = vec![0; self.runs_per_row * image.height];
            self.generation = 0;
            self.key = None;
        }
        if self.key != Some(key) {
            self.key = Some(key);
            self.by_runs = BY_RUNS_BUILT && map.is_constant() && stride > BY_RUNS_FROM_WORDS;
            if self.generation == u32::MAX {
                self.stamps.fill(0);
                self.run_stamps.fill(0);
                self.generation = 0;
            }
            self.generation += 1;
        }
    }

    /// Whether row `y` is classified whole.
    #[inline(always)]
    fn row_ready(&self, y: usize) -> bool {
        self.stamps[y] == self.generation
    }

    /// Classifies row `y` whole unless it already is.
    #[inline(always)]
    fn ensure_row(&mut self, image: Gray<'_>, map: &ThresholdMap, y: usize) {
        if !self.row_ready(y) {
            self.classify_row(image, map, y);
        }
    }

    /// Classifies words `w0..=w1` of row `y` unless they already are (or
    /// the row is, when rows are classified whole).
    #[inline(always)]
    fn ensure(&mut self, image: Gray<'_>, map: &ThresholdMap, y: usize, w0: usize, w1: usize) {
        if self.row_ready(y) {
            return;
        }
        if !(BY_RUNS_BUILT && self.by_runs) {
            self.classify_row(image, map, y);
            return;
        }
        let stamps = y * self.runs_per_row;
        for run in w0 / CLASS_RUN..=w1 / CLASS_RUN {
            if self.run_stamps[stamps + run] != self.generation {
                self.classify_run(image, map, y, run);
            }
        }
    }

    /// Classifies row `y` whole.
    #[inline(never)]
    fn classify_row(&mut self, image: Gray<'_>, map: &ThresholdMap, y: usize) {
        self.stamps[y] = self.generation;
        let row = y * self.stride..(y + 1) * self.stride;
        classify_words(
            image,
            map,
            y,
            0..self.stride,
            &mut self.dark[row.clone()],
            &mut self.light[row],
        );
    }

    /// Classifies the words of run `run` of row `y`.
    #[inline(never)]
    fn classify_run(&mut self, image: Gray<'_>, map: &ThresholdMap, y: usize, run: usize) {
        self.run_stamps[y * self.runs_per_row + run] = self.generation;
        let words = run * CLASS_RUN..((run + 1) * CLASS_RUN).min(self.stride);
        let row = y * self.stride..(y + 1) * self.stride;
        classify_words(
            image,
            map,
            y,
            words,
            &mut self.dark[row.clone()],
            &mut self.light[row],
        );
    }

    /// Classifies `rows` on the pool's threads, for a scan of a large
    /// frame whose fills will reach most of them, and runs `also` on each
    /// row (its number and its `per_row` items of `extra`) while its
    /// pixels are in the cache.
    fn classify_rows<T: Send>(
        &mut self,
        image: Gray<'_>,
        map: &ThresholdMap,
        rows: std::ops::Range<usize>,
        (extra, per_row): (&mut [T], usize),
        also: impl Fn(usize, &mut [T]) + Sync,
    ) {
        use crate::parallel::prelude::*;
        // A row without items would end the zip below at once, leaving
        // every row unclassified.
        assert!(
            per_row > 0 && extra.len() == rows.len() * per_row,
            "a row of `extra` per row"
        );
        let range = rows.start * self.stride..rows.end * self.stride;
        let generation = self.generation;
        self.dark[range.clone()]
            .par_chunks_mut(self.stride)
            .zip(self.light[range].par_chunks_mut(self.stride))
            .zip(self.stamps[rows.clone()].par_iter_mut())
            .zip(extra.par_chunks_mut(per_row))
            .enumerate()
            .for_each(|(k, (((dark, light), stamp), extra))| {
                let y = rows.start + k;
                if *stamp != generation {
                    classify_words(image, map, y, 0..dark.len(), dark, light);
                    *stamp = generation;
                }
                also(y, extra);
            });
    }
}

/// Words `words` of row `y` of `image` classified under `map` into `dark`
/// and `light` (the row's words), a bit per pixel (see [`Classes`]).
fn classify_words(
    image: Gray<'_>,
    map: &ThresholdMap,
    y: usize,
    words: std::ops::Range<usize>,
    dark: &mut [u64],
    light: &mut [u64],
) {
    let thresholds = map.row(y);
    let floor = map.floor_row(y);
    let shift = map.shift();
    let pixels = &image.pixels[y * image.width..(y + 1) * image.width];
    // Whole words first: four chunks, no partial chunk to mask.
    let full = pixels.len() / WORD;
    let whole = words.start.min(full)..words.end.min(full);
    let (dark_whole, light_whole) = (&mut dark[whole.clone()], &mut light[whole.clone()]);
    let blocks = pixels[whole.start * WORD..whole.end * WORD].chunks_exact(WORD);
    let targets = dark_whole.iter_mut().zip(light_whole.iter_mut());
    // One threshold for every chunk of a constant map: not looked up per
    // chunk from the row's tiles.
    let constant = map.is_constant().then(|| [thresholds[0]; 4]);
    for (((dark, light), block), w) in targets.zip(blocks).zip(whole.clone()) {
        let t = constant.unwrap_or_else(|| word_thresholds(thresholds, shift, w));
        let below = below_word(block, t);
        (*dark, *light) = (below, !below);
    }
    if let Some(f) = floor {
        for (d, w) in dark_whole.iter_mut().zip(whole) {
            let tiles = word_floor(f, shift, w);
            if tiles != [false; 4] {
                for (q, _) in tiles.iter().enumerate().filter(|(_, &t)| t) {
                    *d &= !(0xffff << (q * CHUNK));
                }
            }
        }
    }
    let tail = &pixels[full * WORD..];
    if !tail.is_empty() && words.contains(&full) {
        let w = full;
        let (mut dw, mut lw) = (0u64, 0u64);
        for (q, chunk) in tail.chunks(CHUNK).enumerate() {
            let x0 = w * WORD + q * CHUNK;
            let below = below_mask(chunk, thresholds[x0 >> shift]);
            let valid = (1u32 << chunk.len()) - 1;
            let on_floor = floor.is_some_and(|f| f[x0 >> shift]);
            if !on_floor {
                dw |= u64::from(below) << (q * CHUNK);
            }
            lw |= u64::from(!below & valid as u16) << (q * CHUNK);
        }
        dark[w] = dw;
        light[w] = lw;
    }
}

/// The pixels of one row a fill may take: dark fills dark pixels of no
/// dark segment yet, white fills light pixels of no segment of either
/// kind. The row's words are borrowed once rather than looked up per word;
/// the kind is a constant so that the fill's inner loops do not test it.
struct Fillable<'a, const DARK: bool> {
    class: &'a [u64],
    dark_marks: &'a [u64],
    white_marks: &'a [u64],
}

impl<'a, const DARK: bool> Fillable<'a, DARK> {
    /// Row `y` of the image `classes` was last selected for.
    #[inline(always)]
    fn new(classes: &'a Classes, labels: &'a Labels, y: usize) -> Fillable<'a, DARK> {
        assert!(
            y < labels.height
                && labels.stride == classes.stride
                && classes.dark.len() == labels.height * labels.stride,
            "row {y} of labels and classes of another size"
        );
        // SAFETY: what `in_frame` needs, just checked.
        unsafe { Fillable::in_frame(classes, labels, y) }
    }

    /// Row `y` without bounds checks on the rows' slices, for the fill's
    /// loop, which builds three of these per run: there the checks were a
    /// large share of the fill's work (docs/benchmarks.md, the fill's work
    /// per run).
    ///
    /// # Safety
    ///
    /// `y` is below the height of the image `classes` was last selected
    /// for, and `labels` were begun for an image of that image's size
    /// (which [`Filler::fill`] asserts).
    #[inline(always)]
    unsafe fn in_frame(classes: &'a Classes, labels: &'a Labels, y: usize) -> Fillable<'a, DARK> {
        let stride = classes.stride;
        debug_assert!(y < labels.height && labels.stride == stride);
        debug_assert!(classes.dark.len() == stride * labels.height);
        let range = y * stride..(y + 1) * stride;
        // SAFETY: the classes and the labels hold `stride` words for each
        // of the image's rows, and `y` is one of them (the caller's word).
        let (class, marks) = unsafe {
            let class = if DARK {
                classes.dark.get_unchecked(range.clone())
            } else {
                classes.light.get_unchecked(range.clone())
            };
            let marks = if *labels.stamps.get_unchecked(y) == labels.generation {
                (
                    labels.dark.get_unchecked(range.clone()),
                    labels.white.get_unchecked(range),
                )
            } else {
                (&labels.zeros[..], &labels.zeros[..])
            };
            (class, marks)
        };
        // One length for the rows read, so that indexing one of them
        // checks the index for all; a dark fill reads no white marks.
        let n = class.len();
        Fillable {
            class,
            dark_marks: &marks.0[..n],
            white_marks: if DARK { &[] } else { &marks.1[..n] },
        }
    }
}

impl<const DARK: bool> Row for Fillable<'_, DARK> {
    #[inline(always)]
    fn word(&self, w: usize) -> u64 {
        if DARK {
            self.class[w] & !self.dark_marks[w]
        } else {
            self.class[w] & !(self.dark_marks[w] | self.white_marks[w])
        }
    }
}

/// A source of a row's fillable bits, word by word.
trait Row {
    fn word(&self, w: usize) -> u64;
}

impl<F: Fn(usize) -> u64> Row for F {
    #[inline(always)]
    fn word(&self, w: usize) -> u64 {
        self(w)
    }
}

/// The ends of the run of set bits through bit `x` (which must be set) of
/// a row of `stride` words.
#[inline]
fn run_through(row: &impl Row, stride: usize, x: usize) -> (usize, usize) {
    run_within(row, 0, stride, x)
}

/// [`run_through`] within words `first..end` of the row.
#[inline(always)]
fn run_within(row: &impl Row, first: usize, end: usize, x: usize) -> (usize, usize) {
    let (w, b) = (x / WORD, x % WORD);
    let word = row.word(w);
    // Right: the set bits from x up.
    let ones = (!(word >> b)).trailing_zeros() as usize;
    let mut right = x + ones - 1;
    if ones == WORD - b {
        for next in w + 1..end {
            let t = row.word(next).trailing_ones() as usize;
            right += t;
            if t < WORD {
                break;
            }
        }
    }
    // Left: the set bits from x down.
    let ones = (!(word << (WORD - 1 - b))).leading_zeros() as usize;
    let mut left = x + 1 - ones;
    if ones == b + 1 {
        for prev in (first..w).rev() {
            let t = row.word(prev).leading_ones() as usize;
            left -= t;
            if t < WORD {
                break;
            }
        }
    }
    (left, right)
}

/// [`run_through`] the fillable pixel (`x`, `y`) of a row classified a
/// run of words at a time: read within the words classified round `x`,
/// widened while the run reaches their ends. None when the pixel is not
/// fillable.
#[inline(never)]
fn run_in_runs<const DARK: bool>(
    classes: &mut Classes,
    image: Gray<'_>,
    map: &ThresholdMap,
    labels: &Labels,
    y: usize,
    x: usize,
) -> Option<(usize, usize)> {
    let (stride, run) = (classes.stride, x / WORD / CLASS_RUN);
    let mut reach = 0;
    loop {
        let (w0, w1) = (
            run.saturating_sub(reach) * CLASS_RUN,
            ((run + reach + 1) * CLASS_RUN).min(stride) - 1,
        );
        classes.ensure(image, map, y, w0, w1);
        let row = Fillable::<DARK>::new(classes, labels, y);
        if row.word(x / WORD) >> (x % WORD) & 1 == 0 {
            return None;
        }
        let (left, right) = run_within(&row, w0, w1 + 1, x);
        let left_closed = left > w0 * WORD || w0 == 0;
        let right_closed = right + 1 < (w1 + 1) * WORD || w1 + 1 == stride;
        if left_closed && right_closed {
            return Some((left, right));
        }
        reach = 4 * reach + 1;
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
    /// Sum of grey values, for the segment's mean brightness: left at
    /// zero by the fill, see [`Filler::grey_sum`].
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

/// Σ k² for k in `first..=last`: six times Σ k² up to n is n (n + 1)
/// (2n + 1), so the difference of the two products, divided once.
#[inline]
fn sum_squares(first: u64, last: u64) -> u64 {
    let six_times_up_to = |n: u64| n * (n + 1) * (2 * n + 1);
    let below = if first > 0 {
        six_times_up_to(first - 1)
    } else {
        0
    };
    (six_times_up_to(last) - below) / 6
}

impl Stats {
    /// Adds the run of pixels x0..=x1 on row y.
    #[inline]
    pub fn add_run(&mut self, y: u32, x0: u32, x1: u32, sum_i: u64) {
        let n = u64::from(x1 - x0 + 1);
        let su = (u64::from(x0) + u64::from(x1)) * n / 2;
        let suu = sum_squares(u64::from(x0), u64::from(x1));
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
    /// Runs of an earlier fill, set aside by [`Filler::keep_runs`].
    kept: Vec<(u32, u32, u32)>,
    classes: Classes,
    /// The box (min u, min v, max u, max v) of every fill since
    /// [`Filler::take_reach`], undone ones too.
    #[cfg(feature = "parallel")]
    reach: Option<[u32; 4]>,
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
        self.classes.select(image, map);
        // What the fill's unchecked reads of the labels' rows rest on.
        assert!(
            labels.width == image.width && labels.height == image.height,
            "labels begun for a {}x{} image, filling a {}x{} one",
            labels.width,
            labels.height,
            image.width,
            image.height
        );
        // A fill that classifies a few words at a time is its own copy, so
        // that the fills of a frame's scan keep their tighter loop.
        let result = match (mode, BY_RUNS_BUILT && self.classes.by_runs) {
            (Fill::Dark, false) => self.fill_as::<true, false>(image, map, labels, seed, mode),
            (Fill::Dark, true) => self.fill_as::<true, true>(image, map, labels, seed, mode),
            (Fill::White { .. }, false) => {
                self.fill_as::<false, false>(image, map, labels, seed, mode)
            }
            (Fill::White { .. }, true) => {
                self.fill_as::<false, true>(image, map, labels, seed, mode)
            }
        };
        #[cfg(feature = "parallel")]
        self.widen_reach(&result.stats);
        result
    }

    /// Widens the box of the fills since [`Filler::take_reach`] to the
    /// pixels of `stats`.
    #[cfg(feature = "parallel")]
    fn widen_reach(&mut self, stats: &Stats) {
        if stats.count > 0 {
            let area = [stats.min_u, stats.min_v, stats.max_u, stats.max_v];
            self.reach = Some(match self.reach {
                Some(r) => [
                    r[0].min(area[0]),
                    r[1].min(area[1]),
                    r[2].max(area[2]),
                    r[3].max(area[3]),
                ],
                None => area,
            });
        }
    }

    /// The box of every pixel the fills since the last call labelled (and
    /// then perhaps unlabelled), if they labelled any.
    #[cfg(feature = "parallel")]
    pub fn take_reach(&mut self) -> Option<[u32; 4]> {
        self.reach.take()
    }

    /// [`Filler::fill`] for one kind of fill, `DARK` when `mode` is
    /// [`Fill::Dark`].
    fn fill_as<const DARK: bool, const BY_RUNS: bool>(
        &mut self,
        image: Gray<'_>,
        map: &ThresholdMap,
        labels: &mut Labels,
        seed: (u32, u32),
        mode: Fill,
    ) -> FillResult {
        let width = image.width;
        let stride = words_per_row(width);
        // The moments are summed over the runs once the fill is done: the
        // loop keeps only the count, and fewer values in registers.
        let mut count = 0u64;
        self.stack.clear();
        self.runs.clear();
        let (bounds, max_count) = match mode {
            Fill::Dark => ([0, 0, u32::MAX, u32::MAX], u64::MAX),
            Fill::White { bounds, max_count } => (bounds, max_count),
        };
        let dark = DARK;
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
        let (sx, sy) = (seed.0 as usize, seed.1 as usize);
        if sx < x_lo || sx > x_hi || sy < y_lo || sy > y_hi {
            return FillResult {
                stats: Stats::default(),
                escaped: !dark,
            };
        }
        let classes = &mut self.classes;
        let held = map.held_rows();
        let has_floor = dark && map.has_floor();
        self.stack.push(seed);
        let mut escaped = false;
        while let Some((x, y)) = self.stack.pop() {
            let (x, y) = (x as usize, y as usize);
            // Past the rows of a band map the floor is unknown: a dark
            // segment that gets there is larger than any marker the band
            // was sized for, and following it would flood the floor
            // outside the band (most of a tracked frame's time on cards
            // lying on a grey floor).
            if dark && !held.contains(&y) {
                escaped = true;
                break;
            }
            let (left, right) = if !BY_RUNS {
                classes.ensure_row(image, map, y);
                // SAFETY: y lies within y_lo..=y_hi, rows of the image
                // the classes were selected for and the labels sized for.
                let row = unsafe { Fillable::<DARK>::in_frame(classes, labels, y) };
                if row.word(x / WORD) >> (x % WORD) & 1 == 0 {
                    continue;
                }
                run_through(&row, stride, x)
            } else {
                match run_in_runs::<DARK>(classes, image, map, labels, y, x) {
                    Some(run) => run,
                    None => continue,
                }
            };
            let (left, right) = (left.max(x_lo), right.min(x_hi));
            set_bits(labels.row_mut(y, dark), left, right, true);
            count += (right - left + 1) as u64;
            self.runs.push((y as u32, left as u32, right as u32));
            // Every pixel of a floor tile is dark, so a run touching one
            // belongs to the background floor, not to a marker. Filling the
            // rest of the segment first (to label it once) cost tracked
            // frames, whose band scan reached the whole floor's fringe.
            if has_floor && map.run_touches_floor(y, (left, right), (width, image.height)) {
                escaped = true;
                break;
            }
            if !dark
                && (left == x_lo || right == x_hi || y == y_lo || y == y_hi || count > max_count)
            {
                escaped = true;
                break;
            }
            // Seeds for the runs of the rows above and below that this run
            // touches, one at each run's first pixel within it, left to
            // right.
            for ny in [y.wrapping_sub(1), y + 1] {
                if ny < y_lo || ny > y_hi {
                    continue;
                }
                let (w0, w1) = (left / WORD, right / WORD);
                if BY_RUNS {
                    classes.ensure(image, map, ny, w0, w1);
                } else {
                    classes.ensure_row(image, map, ny);
                }
                // SAFETY: as for the run's own row.
                let row = unsafe { Fillable::<DARK>::in_frame(classes, labels, ny) };
                let mut carry = 0u64;
                for w in w0..=w1 {
                    let mut m = row.word(w);
                    if w == w0 {
                        m &= !0u64 << (left % WORD);
                    }
                    if w == w1 {
                        m &= !0u64 >> (WORD - 1 - right % WORD);
                    }
                    let mut starts = m & !((m << 1) | carry);
                    carry = m >> (WORD - 1);
                    while starts != 0 {
                        let bit = starts.trailing_zeros() as usize;
                        self.stack.push(((w * WORD + bit) as u32, ny as u32));
                        starts &= starts - 1;
                    }
                }
            }
        }
        let mut stats = Stats::default();
        for &(y, x0, x1) in &self.runs {
            stats.add_run(y, x0, x1, 0);
        }
        FillResult { stats, escaped }
    }

    /// Whether a fill (dark or white) from `at` would take that pixel at
    /// all: most of the white fill's probes of a blob land on ink.
    #[inline]
    pub fn takes(
        &mut self,
        image: Gray<'_>,
        map: &ThresholdMap,
        labels: &Labels,
        at: (u32, u32),
        dark: bool,
    ) -> bool {
        let (x, y) = (at.0 as usize, at.1 as usize);
        self.classes.select(image, map);
        self.classes.ensure(image, map, y, x / WORD, x / WORD);
        let word = if dark {
            Fillable::<true>::new(&self.classes, labels, y).word(x / WORD)
        } else {
            Fillable::<false>::new(&self.classes, labels, y).word(x / WORD)
        };
        word >> (x % WORD) & 1 == 1
    }

    /// Classifies `rows` of `image` under `map` at once, on the pool's
    /// threads, rather than as fills reach them: the same classes, sooner.
    /// `also` runs on each row as it is classified, with its number and
    /// its `per_row` items of `extra` (the scan finds its seeds there,
    /// reading the row's pixels while they are in the cache).
    pub fn classify_rows<T: Send>(
        &mut self,
        image: Gray<'_>,
        map: &ThresholdMap,
        rows: std::ops::Range<usize>,
        extra: (&mut [T], usize),
        also: impl Fn(usize, &mut [T]) + Sync,
    ) {
        self.classes.select(image, map);
        self.classes.classify_rows(image, map, rows, extra, also);
    }

    /// Sets the last fill's runs aside for [`Filler::kept_grey_sum`].
    pub fn keep_runs(&mut self) {
        std::mem::swap(&mut self.kept, &mut self.runs);
    }

    /// [`Filler::grey_sum`] of the runs set aside by [`Filler::keep_runs`].
    pub fn kept_grey_sum(&self, image: Gray<'_>) -> u64 {
        runs_grey_sum(&self.kept, image)
    }

    /// The sum of the grey values of the last fill's pixels. The fill
    /// leaves [`Stats::sum_i`] at zero: most segments of a cluttered frame
    /// fail a test that needs no brightness, so only those that get as far
    /// as the contrast test pay for reading their pixels again.
    pub fn grey_sum(&self, image: Gray<'_>) -> u64 {
        runs_grey_sum(&self.runs, image)
    }

    /// Forgets the labels of the last fill (a white region that turned out
    /// not to be a marker's inside may be another candidate's).
    pub fn undo_last(&self, labels: &mut Labels) {
        for &(y, x0, x1) in &self.runs {
            set_bits(
                labels.row_mut(y as usize, false),
                x0 as usize,
                x1 as usize,
                false,
            );
        }
    }
}

/// The sum of the grey values of `runs` (y, x0, x1).
fn runs_grey_sum(runs: &[(u32, u32, u32)], image: Gray<'_>) -> u64 {
    runs.iter()
        .map(|&(y, x0, x1)| {
            let row = y as usize * image.width;
            sum_bytes(&image.pixels[row + x0 as usize..=row + x1 as usize])
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Whether pixel (x, y) lies in a floor tile of `map`.
    fn is_floor(map: &ThresholdMap, x: usize, y: usize) -> bool {
        map.floor_row(y).is_some_and(|row| row[x >> map.shift()])
    }

    proptest::proptest! {
        /// The spread-level compare marks what the per-chunk one marks,
        /// at levels 0 and 255 too.
        #[test]
        fn below_levels_marks_the_pixels_below_word_marks(
            block in proptest::collection::vec(proptest::prelude::any::<u8>(), WORD),
            t in proptest::prelude::any::<[u8; 4]>(),
            flat in proptest::prelude::any::<bool>(),
        ) {
            // Flat blocks sit at or next to a level, where an off-by-one shows.
            let block: Vec<u8> = if flat {
                (0..WORD).map(|i| t[i / CHUNK].wrapping_add(block[i] % 3).wrapping_sub(1)).collect()
            } else {
                block
            };
            let mut levels = Vec::new();
            spread_levels(t, &mut levels);
            let expected = (0..WORD).fold(0u64, |m, i| m | u64::from(block[i] < t[i / CHUNK]) << i);
            proptest::prop_assert_eq!(below_levels(&block, &levels), expected);
            proptest::prop_assert_eq!(below_word(&block, t), expected);
        }
    }

    fn brute_stats(pixels: &[(u32, u32)]) -> Stats {
        let mut s = Stats::default();
        for &(x, y) in pixels {
            s.add_run(y, x, x, 0);
        }
        s
    }

    /// The 4-connected pixels below `t` from `seed`, found one by one.
    fn brute_component(px: &[u8], w: usize, h: usize, t: u8, seed: (usize, usize)) -> Stats {
        assert!(px[seed.1 * w + seed.0] < t, "{seed:?} is not dark");
        let mut seen = vec![false; w * h];
        let mut stack = vec![seed];
        let mut pixels = Vec::new();
        seen[seed.1 * w + seed.0] = true;
        while let Some((x, y)) = stack.pop() {
            pixels.push((x as u32, y as u32));
            let next = [
                (x.wrapping_sub(1), y),
                (x + 1, y),
                (x, y.wrapping_sub(1)),
                (x, y + 1),
            ];
            for (nx, ny) in next {
                if nx < w && ny < h && !seen[ny * w + nx] && px[ny * w + nx] < t {
                    seen[ny * w + nx] = true;
                    stack.push((nx, ny));
                }
            }
        }
        brute_stats(&pixels)
    }

    /// The white fill from `seed` within the bounding box of `ring`, a dark
    /// segment's statistics (as the scan fills a marker's inside).
    fn fill_within(
        filler: &mut Filler,
        image: Gray<'_>,
        map: &ThresholdMap,
        labels: &mut Labels,
        seed: (u32, u32),
        ring: &Stats,
        max_count: u64,
    ) -> FillResult {
        let bounds = [ring.min_u, ring.min_v, ring.max_u, ring.max_v];
        filler.fill(image, map, labels, seed, Fill::White { bounds, max_count })
    }

    /// How many pixels of a `w` x `h` image lie closer than the square
    /// root of `r2` to `centre`.
    fn pixels_within(w: usize, h: usize, centre: (i64, i64), r2: i64) -> u64 {
        (0..w * h)
            .filter(|&i| {
                ((i % w) as i64 - centre.0).pow(2) + ((i / w) as i64 - centre.1).pow(2) < r2
            })
            .count() as u64
    }

    /// Under one threshold on a frame wider than [`BY_RUNS_FROM_WORDS`]
    /// words, rows are classified a few words at a time as the fill
    /// reaches them: a bar across most of the width, a ring over the
    /// boundaries of those words and a snake through them fill as the
    /// pixels connect, and so does a second fill of the same image.
    #[test]
    fn a_fill_on_a_wide_frame_classifies_rows_in_runs_and_fills_whole() {
        let (w, h) = (64 * (BY_RUNS_FROM_WORDS + 9) + 13, 60usize);
        let mut px = vec![200u8; w * h];
        // A bar from near the left edge to near the right, two rows high,
        // with a stub down at the run boundary of 256 px.
        for y in 10..12 {
            px[y * w + 3..y * w + w - 5].fill(30);
        }
        for y in 12..20 {
            px[y * w + 255] = 30;
        }
        // A ring centred on a run boundary (512 px).
        for y in 25..55 {
            for x in 480..545 {
                let d2 = (x as i64 - 512).pow(2) + (y as i64 - 40).pow(2);
                if (100..=196).contains(&d2) {
                    px[y * w + x] = 30;
                }
            }
        }
        // A snake across four runs' boundaries, one pixel wide.
        for x in 700..1800 {
            let y = 30 + ((x / 97) % 2) * 20;
            px[y * w + x] = 30;
        }
        for x in (776..1800).step_by(97) {
            for y in 30..=50 {
                px[y * w + x] = 30;
            }
        }
        let image = Gray {
            pixels: &px,
            width: w,
            height: h,
        };
        let map = ThresholdMap::constant(100);
        let mut labels = Labels::default();
        let mut filler = Filler::default();
        for seed in [(2000, 11), (512, 27), (1700, 50), (3, 10)] {
            labels.begin(w, h);
            let filled = filler.fill(image, &map, &mut labels, seed, Fill::Dark);
            assert!(filler.classes.by_runs);
            let expected = brute_component(&px, w, h, 100, (seed.0 as usize, seed.1 as usize));
            assert_eq!(filled.stats, expected, "from {seed:?}");
        }
        // The white inside the ring, bounded by it.
        labels.begin(w, h);
        let ring = filler
            .fill(image, &map, &mut labels, (512, 27), Fill::Dark)
            .stats;
        let hole = fill_within(
            &mut filler,
            image,
            &map,
            &mut labels,
            (512, 40),
            &ring,
            10_000,
        );
        assert!(!hole.escaped);
        assert_eq!(hole.stats.count, pixels_within(w, h, (512, 40), 100));
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
        assert!(is_floor(&map, 5, 5) && is_floor(&map, w - 1, h - 1));
        assert!(!is_floor(&map, cx as usize - 20, cy as usize));
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
        assert!(
            is_floor(&band, 240, 300),
            "the pocket inside the U is floor"
        );
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
        assert!(!is_floor(&band, 120, 300));
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
        let hole = fill_within(&mut filler, image, &map, &mut labels, (20, 15), &s, 1000);
        assert!(!hole.escaped);
        assert_eq!(hole.stats.count, pixels_within(w, h, (20, 15), 25));
        // Outside the ring the white region reaches the bounds.
        let outside = fill_within(&mut filler, image, &map, &mut labels, (11, 6), &s, 1000);
        assert!(outside.escaped);
    }
}
