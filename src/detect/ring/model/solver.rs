//! The least-squares comparison of a ring's pixels with every member
//! rotation at every phase, and with a ring without angular structure:
//! the sums each fit needs are formed once per footprint and phase, a
//! rotation's from tables ([`PatternTables`]), and given a residual to
//! beat, a phase where no rotation can beat it is skipped
//! ([`unconstrained_residual`]).

use std::f64::consts::PI;

use super::footprint::{
    in_wedges, rendered_through_gaussian, MarkerFrame, PerPixel, RingPixels, Sampled,
    WEDGES_PER_SECTOR,
};
use super::{SmallRing, Thresholds, PHASE_STEPS};
use crate::family::{necklace, Family};

/// Most member rotations compared per ring (bounds the cost on families of
/// long codes, whose sectors are too narrow at these sizes anyway).
const MAX_MODELS: usize = 4096;

impl RingPixels {
    /// Compares the pixels with every member of `family` at every rotation.
    /// `None` when the family is too large to compare.
    pub(super) fn compare(&self, family: &Family, thresholds: Thresholds) -> Option<SmallRing> {
        self.compare_beating(family, thresholds, None)
    }

    /// [`RingPixels::compare`]; given `beat`, phases where no rotation can
    /// leave a residual under it are skipped (see [`unconstrained_residual`]).
    pub(super) fn compare_beating(
        &self,
        family: &Family,
        thresholds: Thresholds,
        beat: Option<f64>,
    ) -> Option<SmallRing> {
        let bits = family.bits();
        let members = family.len();
        if members == 0 || members * bits as usize > MAX_MODELS {
            return None;
        }
        let sectors = 2 * bits as usize;
        let sector = PI / f64::from(bits);
        let (pixels, sum_y, syy) = (&self.pixels, self.sum_y, self.syy);
        let count = pixels.len() as f64;
        let codes: Vec<u32> = (1..=members as u32)
            .filter_map(|id| family.code(id))
            .collect();
        // Every member rotation as the word seen, bit i (least significant
        // first) owning sectors 2i, 2i+1; a 1 is white then black.
        let patterns: Vec<(u32, u32, u64)> = codes
            .iter()
            .enumerate()
            .flat_map(|(k, &code)| {
                (0..bits).map(move |r| {
                    let word = necklace::rotl(code, bits, r);
                    let seen = (0..bits).fold(0u64, |seen, i| {
                        seen | u64::from(word >> (bits - 1 - i) & 1) << i
                    });
                    (k as u32 + 1, r, seen)
                })
            })
            .collect();
        let mut tables = PatternTables::new(bits as usize);
        struct Best {
            sse: f64,
            id: u32,
            rotation: u32,
            phase: f64,
        }
        let mut best: Option<Best> = None;
        // Best residual of every member (any rotation, phase and blur).
        let mut per_member = vec![f64::INFINITY; codes.len() + 1];
        let mut best_null = f64::INFINITY;
        // The Gaussians' coverage of the ring's wedges, binned once for all.
        let coverage = self
            .subsamples
            .as_ref()
            .map(|subsamples| subsamples.binned(sectors));
        for footprint in &self.footprints {
            // Per pixel: white weight outside the ring, and (wedge, weight) of
            // its footprint inside it.
            let (fixed_through, wedge_samples);
            let (fixed, ring_samples) = match footprint {
                Sampled::Gaussian(sigma) => {
                    let coverage = coverage.as_ref()?;
                    (fixed_through, wedge_samples) =
                        rendered_through_gaussian(pixels, *sigma, coverage);
                    (&fixed_through, &wedge_samples)
                }
                Sampled::Points(fixed, angles) => {
                    wedge_samples = in_wedges(angles, sectors);
                    (fixed, &wedge_samples)
                }
            };
            // Structureless ring: y ≈ α + β·fixed + γ·ring coverage.
            let coverage: Vec<f64> = ring_samples
                .runs()
                .map(|run| run.iter().map(|s| s.1).sum())
                .collect();
            best_null = best_null.min(residual_of_two(pixels, fixed, &coverage));
            let sum_fixed: f64 = fixed.iter().sum();
            let ff: f64 = fixed.iter().map(|f| f * f).sum();
            let yf: f64 = pixels.iter().zip(fixed).map(|(p, f)| p.2 * f).sum();
            // A phase a whole sector on reads every pixel's sectors one index
            // down: only the phases within the first sector are summed.
            let within: Vec<PhaseSums> = (0..WEDGES_PER_SECTOR)
                .map(|step| PhaseSums::of(pixels, fixed, ring_samples, sectors, step))
                .collect();
            // Phases where no rotation can leave a residual under `beat`.
            let ruled_out: Vec<bool> = within
                .iter()
                .map(|sums| {
                    beat.is_some_and(|beat| {
                        unconstrained_residual(sums, sum_fixed, ff, yf, count, sum_y, syy)
                            .is_some_and(|free| free > beat * (1.0 + BOUND_MARGIN))
                    })
                })
                .collect();
            for step in 0..PHASE_STEPS {
                // A sector on, the same sectors under other indices: the
                // same bound.
                if ruled_out[step % WEDGES_PER_SECTOR] {
                    continue;
                }
                let phase = 2.0 * sector * step as f64 / PHASE_STEPS as f64;
                let shifted;
                let sums = if step < WEDGES_PER_SECTOR {
                    &within[step]
                } else {
                    shifted = within[step - WEDGES_PER_SECTOR].next_sector();
                    &shifted
                };
                let PhaseSums {
                    gram,
                    w_sum,
                    w_fixed,
                    w_y,
                } = sums;
                tables.fill(gram, w_sum, w_fixed, w_y);
                for &(id, rotation, seen) in &patterns {
                    let (sm, smm, sym) = tables.sums(seen);
                    let (sm, smm, sym) = (sum_fixed + sm, ff + smm, yf + sym);
                    let sym_c = sym - sum_y * sm / count;
                    let smm_c = smm - sm * sm / count;
                    if sym_c <= 0.0 || smm_c <= 0.0 {
                        continue;
                    }
                    // The residual syy − sym_c²/smm_c beats the member's best
                    // so far only if sym_c² exceeds (syy − best)·smm_c: most
                    // rotations are refused without a division.
                    let slot = &mut per_member[id as usize];
                    if sym_c * sym_c <= (syy - *slot) * smm_c {
                        continue;
                    }
                    let sse = syy - sym_c * sym_c / smm_c;
                    *slot = slot.min(sse);
                    if best.as_ref().is_none_or(|b| sse < b.sse) {
                        best = Some(Best {
                            sse,
                            id,
                            rotation,
                            phase,
                        });
                    }
                }
            }
        }
        let best = best?;
        let runner_up = per_member
            .iter()
            .enumerate()
            .filter(|&(id, _)| id as u32 != best.id)
            .map(|(_, &sse)| sse)
            .fold(f64::INFINITY, f64::min);
        let floor = 1e-6 * syy;
        let margin = runner_up.max(floor) / best.sse.max(floor);
        let structure_ratio = best.sse / best_null.max(floor);
        let structured = structure_ratio <= thresholds.max_structure_ratio;
        let named = structured && margin >= thresholds.min_id_margin;
        let code = codes[best.id as usize - 1];
        // Sector 0 of the word seen sits at `phase`; the word is the code
        // rotated left by `rotation`, so the code's own bit 0 (the +x axis)
        // lies `rotation` bits earlier.
        let x_axis_t = best.phase - 2.0 * sector * f64::from(best.rotation);
        let (st, ct) = x_axis_t.sin_cos();
        let MarkerFrame {
            sin: s,
            cos: c,
            a,
            b,
            ..
        } = self.frame;
        let (ax, ay) = (a * ct * c + b * st * s, a * ct * s - b * st * c);
        Some(SmallRing {
            structured,
            id: if named { best.id } else { 0 },
            code,
            yaw: named.then(|| ay.atan2(ax)),
            margin,
            structure_ratio,
            residual: best.sse,
        })
    }
}

/// The sums a member rotation's least-squares fit needs at one phase,
/// read from tables instead of summed sector by sector. A rotation is the
/// word seen, bit i white in sector 2i when set, else in 2i + 1. Its sums
/// over the sectors it whitens are linear per bit, except the model's
/// squared norm, a sum over pairs of bits of the Gram matrix. A pixel's
/// footprint covers a few neighbouring sectors, so bits further apart than
/// the Gram matrix's band never pair; the pairs of bit b with the next
/// `reach` bits are one entry of a table indexed by those reach + 1 bits.
/// A rotation then costs a lookup per bit, not one per pair of bits (the
/// neighbouring bit counts' thousand rotations made the pairs most of a
/// small ring's cost).
struct PatternTables {
    bits: usize,
    reach: usize,
    /// Per bit, 2^(reach + 1) entries: its pairs with the next `reach`
    /// bits (and its own square and linear norm term).
    pairs: Vec<f64>,
    /// Per group of [`LINEAR_GROUP`] bits, per value of the group: the sum
    /// of the whitened sectors' weights and of their weighted greys.
    linear: Vec<[f64; 2]>,
}

/// Bits per entry of [`PatternTables::linear`].
const LINEAR_GROUP: usize = 4;

impl PatternTables {
    fn new(bits: usize) -> PatternTables {
        PatternTables {
            bits,
            reach: 0,
            pairs: Vec::new(),
            linear: vec![[0.0; 2]; bits.div_ceil(LINEAR_GROUP) << LINEAR_GROUP],
        }
    }

    /// Tables of the sums over pixels of the sector weights `w_sum`, their
    /// products with the white outside the ring `w_fixed` and with the
    /// grey `w_y`, and of products of sector weights `gram` (2n × 2n).
    fn fill(&mut self, gram: &[f64], w_sum: &[f64], w_fixed: &[f64], w_y: &[f64]) {
        let n = self.bits;
        let sectors = 2 * n;
        let sector = |bit: usize, set: usize| 2 * (bit % n) + 1 - set;
        // Widest cyclic distance between two sectors one pixel covers; bits
        // b and b + d own sectors at least 2d - 1 apart.
        let mut band = 0;
        for i in 0..sectors {
            for j in i + 1..sectors {
                if gram[i * sectors + j] != 0.0 {
                    band = band.max((j - i).min(sectors - (j - i)));
                }
            }
        }
        self.reach = (band.div_ceil(2)).min(n / 2);
        let size = 1usize << (self.reach + 1);
        self.pairs.clear();
        self.pairs.resize(n * size, 0.0);
        // Each unordered pair once: twice its entry, except the pair of
        // opposite bits of an even count, which both of its bits reach.
        let factor = |d: usize| if 2 * d == n { 1.0 } else { 2.0 };
        for b in 0..n {
            let table = &mut self.pairs[b * size..(b + 1) * size];
            for own in 0..2 {
                let s = sector(b, own);
                let row = &gram[s * sectors..(s + 1) * sectors];
                // Every further bit clear, then each one set in turn.
                let mut clear = row[s] + 2.0 * w_fixed[s];
                let mut step = [0.0; 32];
                for d in 1..=self.reach {
                    let f = factor(d);
                    clear += f * row[sector(b + d, 0)];
                    step[d] = f * (row[sector(b + d, 1)] - row[sector(b + d, 0)]);
                }
                table[own] = clear;
                for further in 1..size >> 1 {
                    let lowest = further & further.wrapping_neg();
                    let d = lowest.trailing_zeros() as usize + 1;
                    table[own | further << 1] = table[own | (further ^ lowest) << 1] + step[d];
                }
            }
        }
        for (group, table) in self.linear.chunks_mut(1 << LINEAR_GROUP).enumerate() {
            let first = group * LINEAR_GROUP;
            for (value, entry) in table.iter_mut().enumerate() {
                *entry = [0.0; 2];
                for bit in first..(first + LINEAR_GROUP).min(n) {
                    let s = sector(bit, value >> (bit - first) & 1);
                    entry[0] += w_sum[s];
                    entry[1] += w_y[s];
                }
            }
        }
    }

    /// The ring's part of the rotation `seen`'s sums over the pixels: of
    /// its model, of its model squared, and of its model times the grey
    /// (the white outside the ring adds its own terms to each).
    fn sums(&self, seen: u64) -> (f64, f64, f64) {
        let n = self.bits;
        let size = 1usize << (self.reach + 1);
        let mask = (size - 1) as u64;
        let twice = seen | seen << n;
        let mut norm = 0.0;
        for (b, table) in self.pairs.chunks_exact(size).enumerate() {
            norm += table[(twice >> b & mask) as usize];
        }
        let (mut sum, mut grey) = (0.0, 0.0);
        for (group, table) in self.linear.chunks_exact(1 << LINEAR_GROUP).enumerate() {
            let entry =
                table[(seen >> (group * LINEAR_GROUP)) as usize & ((1 << LINEAR_GROUP) - 1)];
            sum += entry[0];
            grey += entry[1];
        }
        (sum, norm, grey)
    }
}

/// Relative margin by which [`unconstrained_residual`] must exceed a
/// residual to rule a phase out (the solve's rounding stays far below).
const BOUND_MARGIN: f64 = 0.01;

/// The least residual of any model whose sectors each take their own
/// grey at this phase (with its own weight for the white outside the ring
/// and an offset): a lower bound on every member rotation's residual,
/// each being such a model with sector greys 0 or 1. `None` when the
/// sums leave that fit undetermined.
fn unconstrained_residual(
    sums: &PhaseSums,
    sum_fixed: f64,
    ff: f64,
    yf: f64,
    count: f64,
    sum_y: f64,
    syy: f64,
) -> Option<f64> {
    let sectors = sums.w_sum.len();
    // Columns: the white outside the ring, then every sector that any
    // pixel sees (the others are all zero), centred.
    let columns: Vec<Option<usize>> = std::iter::once(None)
        .chain(
            (0..sectors)
                .filter(|&i| sums.gram[i * sectors + i] > 0.0)
                .map(Some),
        )
        .collect();
    let total = |c: Option<usize>| c.map_or(sum_fixed, |i| sums.w_sum[i]);
    let product = |a: Option<usize>, b: Option<usize>| match (a, b) {
        (None, None) => ff,
        (None, Some(i)) | (Some(i), None) => sums.w_fixed[i],
        (Some(i), Some(j)) => sums.gram[i * sectors + j],
    };
    let with_grey = |c: Option<usize>| c.map_or(yf, |i| sums.w_y[i]);
    let k = columns.len();
    let normal = nalgebra::DMatrix::from_fn(k, k, |r, c| {
        product(columns[r], columns[c]) - total(columns[r]) * total(columns[c]) / count
    });
    let right = nalgebra::DVector::from_fn(k, |r, _| {
        with_grey(columns[r]) - total(columns[r]) * sum_y / count
    });
    let solved = normal.cholesky()?.solve(&right);
    Some(syy - right.dot(&solved))
}

/// The sums over pixels a phase's comparison needs, sector by sector: of
/// each sector's weight in a pixel's model, of that weight times the
/// pixel's white outside the ring and times its grey, and of products of
/// two sectors' weights (the Gram matrix, `sectors` × `sectors`).
struct PhaseSums {
    gram: Vec<f64>,
    w_sum: Vec<f64>,
    w_fixed: Vec<f64>,
    w_y: Vec<f64>,
}

impl PhaseSums {
    /// At the phase `step` wedges on: wedge j lies in sector
    /// (j − step) / [`WEDGES_PER_SECTOR`], cyclically.
    fn of(
        pixels: &[(f64, f64, f64)],
        fixed: &[f64],
        ring_samples: &PerPixel<(usize, f64)>,
        sectors: usize,
        step: usize,
    ) -> PhaseSums {
        let wedges = sectors * WEDGES_PER_SECTOR;
        let sector_of: Vec<usize> = (0..wedges)
            .map(|j| (j + wedges - step) % wedges / WEDGES_PER_SECTOR)
            .collect();
        let mut sums = PhaseSums {
            gram: vec![0.0; sectors * sectors],
            w_sum: vec![0.0; sectors],
            w_fixed: vec![0.0; sectors],
            w_y: vec![0.0; sectors],
        };
        // The sectors a pixel's footprint covers, a few, with their weights.
        let mut touched: Vec<(usize, f64)> = Vec::with_capacity(sectors);
        for ((samples, &(_, _, y)), &white) in ring_samples.runs().zip(pixels).zip(fixed) {
            for &(wedge, w) in samples {
                let index = sector_of[wedge];
                // Wedges mostly come in order, a sector's together.
                match touched.last_mut() {
                    Some((last, sum)) if *last == index => *sum += w,
                    _ => match touched.iter_mut().find(|(i, _)| *i == index) {
                        Some((_, sum)) => *sum += w,
                        None => touched.push((index, w)),
                    },
                }
            }
            for &(i, wi) in &touched {
                sums.w_sum[i] += wi;
                sums.w_fixed[i] += wi * white;
                sums.w_y[i] += wi * y;
                let row = &mut sums.gram[i * sectors..(i + 1) * sectors];
                for &(j, wj) in &touched {
                    row[j] += wi * wj;
                }
            }
            touched.clear();
        }
        sums
    }

    /// The sums a whole sector further on: every sector index one down.
    fn next_sector(&self) -> PhaseSums {
        let sectors = self.w_sum.len();
        let up = |i: usize| (i + 1) % sectors;
        PhaseSums {
            gram: (0..sectors * sectors)
                .map(|k| self.gram[up(k / sectors) * sectors + up(k % sectors)])
                .collect(),
            w_sum: (0..sectors).map(|i| self.w_sum[up(i)]).collect(),
            w_fixed: (0..sectors).map(|i| self.w_fixed[up(i)]).collect(),
            w_y: (0..sectors).map(|i| self.w_y[up(i)]).collect(),
        }
    }
}

/// Least-squares residual of y ≈ α + β·u + γ·v over the pixels.
fn residual_of_two(pixels: &[(f64, f64, f64)], u: &[f64], v: &[f64]) -> f64 {
    let n = pixels.len() as f64;
    let mean = |f: &dyn Fn(usize) -> f64| (0..pixels.len()).map(f).sum::<f64>() / n;
    let (my, mu, mv) = (mean(&|k| pixels[k].2), mean(&|k| u[k]), mean(&|k| v[k]));
    let (mut suu, mut svv, mut suv, mut syu, mut syv, mut syy) = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0);
    for k in 0..pixels.len() {
        let (y, a, b) = (pixels[k].2 - my, u[k] - mu, v[k] - mv);
        suu += a * a;
        svv += b * b;
        suv += a * b;
        syu += y * a;
        syv += y * b;
        syy += y * y;
    }
    let det = suu * svv - suv * suv;
    if det.abs() < 1e-12 {
        // Degenerate: fit the better single regressor.
        let one = |sxx: f64, syx: f64| if sxx > 0.0 { syx * syx / sxx } else { 0.0 };
        return syy - one(suu, syu).max(one(svv, syv));
    }
    let beta = (syu * svv - syv * suv) / det;
    let gamma = (syv * suu - syu * suv) / det;
    syy - beta * syu - gamma * syv
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The tables give every word the sums a sector-by-sector pass over
    /// its bits and pairs of bits gives, whatever the count and however
    /// many sectors a pixel's footprint spans (narrow bands read few
    /// pairs; a band past half the ring reads them all, opposite bits of
    /// an even count once).
    #[test]
    fn pattern_tables_sum_as_the_sectors_do() {
        let mut rng = crate::math::Pcg32::new(25, 3);
        for case in 0..400 {
            let n = 2 + case % 13;
            let sectors = 2 * n;
            let span = 1 + rng.next_u32() as usize % sectors;
            let mut gram = vec![0.0; sectors * sectors];
            let mut w_sum = vec![0.0; sectors];
            let mut w_fixed = vec![0.0; sectors];
            let mut w_y = vec![0.0; sectors];
            for _ in 0..20 {
                let first = rng.next_u32() as usize % sectors;
                let width = 1 + rng.next_u32() as usize % span;
                let touched: Vec<(usize, f64)> = (0..width)
                    .map(|k| ((first + k) % sectors, rng.range(0.01, 1.0)))
                    .collect();
                let (white, grey) = (rng.next_f64(), rng.range(0.0, 255.0));
                for &(i, wi) in &touched {
                    w_sum[i] += wi;
                    w_fixed[i] += wi * white;
                    w_y[i] += wi * grey;
                    for &(j, wj) in &touched {
                        gram[i * sectors + j] += wi * wj;
                    }
                }
            }
            let mut tables = PatternTables::new(n);
            tables.fill(&gram, &w_sum, &w_fixed, &w_y);
            for _ in 0..20 {
                let seen = u64::from(rng.next_u32()) & ((1 << n) - 1);
                let white: Vec<usize> = (0..n)
                    .map(|b| 2 * b + 1 - (seen >> b & 1) as usize)
                    .collect();
                let sum: f64 = white.iter().map(|&s| w_sum[s]).sum();
                let grey: f64 = white.iter().map(|&s| w_y[s]).sum();
                let norm: f64 = white.iter().map(|&s| 2.0 * w_fixed[s]).sum::<f64>()
                    + white
                        .iter()
                        .flat_map(|&s| white.iter().map(move |&t| (s, t)))
                        .map(|(s, t)| gram[s * sectors + t])
                        .sum::<f64>();
                let got = tables.sums(seen);
                for (a, b) in [(got.0, sum), (got.1, norm), (got.2, grey)] {
                    assert!(
                        (a - b).abs() <= 1e-9 * b.abs().max(1.0),
                        "n {n} span {span} word {seen:b}: {got:?} against {sum}, {norm}, {grey}"
                    );
                }
            }
        }
    }
}
