//! The progressive film: per-pixel running mean and variance (Welford, f64),
//! and the error of each pixel's mean estimated from how its samples were
//! drawn. Non-finite samples are never averaged in; they are counted and
//! their first occurrences kept.
//!
//! Jittered pixel samples come in blocks of [`PIXEL_STRATA`] that visit
//! every sub-pixel stratum once: they are not independent, and treating them
//! so overstates the error (by 1.7x at 16 spp on `cornell-area`). Per pixel,
//! with `σ_w²` the mean variance within a stratum and `σ_b²` the variance of
//! the strata's means (`σ² = σ_w² + σ_b²`, one sample's variance), `n`
//! samples in complete blocks and groups of `r` strata drawn at random
//! without replacement (the block being filled, or one a dropped sample left
//! incomplete) give a mean whose variance is
//! `(n σ_w² + Σ r (16 - r) / 15 σ_b²) / n²`.
//! Each complete block gives two estimates of `σ_w²`: its mean against the
//! other blocks' (batch means), and its eight strata of one colour of a
//! checkerboard against the eight of the other (balanced halves: for a
//! stratum mean that varies linearly over the pixel they have equal means,
//! and for an edge nearly so; any difference only raises the estimate).
//! They are pooled; `σ_b²` is the rest of the sample variance. Before the
//! first block is complete nothing tells `σ_w²` from `σ_b²`: the estimate is
//! the geometric mean of the two extremes (all within: `s²/n`; all between:
//! `s² Σ r (16 - r) / (16 n²)`), off by at most `(16 / (16 - r))^¼` in error,
//! 1.19 at 8 spp. Independent samples give `s²/n`.
//!
//! Each quarter of a block visits the four quadrants of the pixel once
//! ([`Run`](crate::geometry::sampling::Run)), so the first `4q`
//! samples (`q` of 1 to 3) already stratify it 2x2. A quarter's contrast,
//! its two samples in black quadrants minus its two in white, has a square
//! whose mean is the four samples' variance within their quadrants, plus
//! the square of the quadrants' own contrast (zero for a linear change,
//! else it only raises the estimate): summed over the quarters, `Q`, it
//! gives `Q / n²`, exact for one quarter. For more, part of that variance
//! is between the strata within a quadrant, which drawing them without
//! replacement cancels by `(4 - q) / 3`; the estimate is the geometric mean
//! of the two extremes, `Q / n² √((4 - q) / 3)`, off by at most 1.11 in
//! error at 8 spp and 1.32 at 12. Statistics merged from parts keep no
//! quarters, and use the estimate before.
//!
//! Measured against the true error (docs/converge.md), the ratio stays
//! within 0.79 to 1.10 from 2 to 256 spp on `cornell-area`, `mirrors` and
//! area lights over a box, jittered and independent.

use std::ops::Range;
use std::sync::OnceLock;

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use crate::geometry::sampling::{quadrant_is_black, PIXEL_GRID, PIXEL_STRATA, QUARTER};

use crate::color::LUMA;
pub use crate::raster::metrics::REL_EPS;

/// How many non-finite samples are listed individually.
const MAX_LISTED: usize = 1000;

/// Why a summarised film cannot give statistics or take more samples.
const NO_STATISTICS: &str =
    "a summarised film keeps no statistics: it is made only for renders that read none";

/// One pixel's statistics: everything its error estimate needs, and
/// everything an exact merge of films over disjoint sample ranges needs.
/// The colour is summed exactly (fixed point, [`FIXED_ONE`]), so a film
/// merged from parts holds the very mean a single render computes; the
/// luminance statistics merge by Chan et al. (counts, means and M2 of the
/// samples and of the complete blocks' means; sums of the checkerboard
/// contrasts and of the incomplete blocks' terms), and the blocks a range
/// boundary cuts are kept as pieces (`head`, `tail`) that the neighbouring
/// range completes.
#[derive(Clone, Copy, Debug, Default, bytemuck::Zeroable)]
pub struct PixelStats {
    /// Sum of the samples per channel, in units of 1 / [`FIXED_ONE`].
    pub(crate) sum: [i128; 3],
    /// The mean colour: `sum / n`.
    pub mean: DVec3,
    /// Sum of squared deviations of the luminance (Welford's M2).
    pub m2: f64,
    pub n: u32,
    /// Complete blocks of strata.
    pub(crate) blocks: u32,
    /// Mean and M2 of the complete blocks' mean luminances.
    pub(crate) block_mean: f64,
    pub(crate) block_m2: f64,
    /// Sum over complete blocks of `(Σ black - Σ white)² / 16`, each an
    /// estimate of `σ_w²`.
    pub(crate) checker: f64,
    /// Sum of `r (16 - r)` over blocks left incomplete.
    pub(crate) open: u32,
    /// The first block seen, while incomplete: the one a range that starts
    /// inside a block shares with the range before it.
    pub(crate) head: BlockPart,
    /// The block being filled after the first.
    pub(crate) tail: BlockPart,
    /// Sum over the first block's complete quarters of the square of their
    /// contrast (black quadrants minus white); NaN once unknowable (a
    /// sample of the first block dropped, or statistics merged or read
    /// from a partial film, which do not keep it).
    pub(crate) quarters: f32,
    /// The contrast of the quarter being filled.
    pub(crate) quarter: f32,
}

/// A sample as a pass adds it to pixel `x` of a row: its index, colour
/// and sub-pixel stratum when jittered.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RowSample {
    pub(crate) x: u32,
    pub(crate) k: u32,
    pub(crate) c: Vec3,
    pub(crate) stratum: Option<u32>,
}

/// Samples [`PixelStats::add_run`] takes at a time.
const RUN: usize = 16;

/// Part of a block of strata: its index, samples, luminance sum and
/// checkerboard difference (black minus white).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Zeroable)]
pub(crate) struct BlockPart {
    pub(crate) block: u32,
    pub(crate) n: u32,
    pub(crate) sum: f64,
    pub(crate) diff: f64,
}

impl BlockPart {
    /// `r (16 - r)`: what an incomplete block adds to the variance.
    fn open(&self) -> u32 {
        self.n * (PIXEL_STRATA - self.n)
    }

    fn join(self, o: BlockPart) -> BlockPart {
        BlockPart {
            block: self.block,
            n: self.n + o.n,
            sum: self.sum + o.sum,
            diff: self.diff + o.diff,
        }
    }
}

/// One in the fixed point the colour sums are kept in: 2^64. A sample is
/// exact from 2^-41 up (below, its bits under 2^-64 are dropped) and
/// clamped to ±[`FIXED_MAX`], so a million samples cannot overflow.
pub(crate) const FIXED_ONE: f64 = 18_446_744_073_709_551_616.0;
/// The largest sample magnitude summed (2^41, about 2.2e12).
pub(crate) const FIXED_MAX: f32 = 2_199_023_255_552.0;

/// A sample channel in fixed point, and that value as f64 (exact: it has
/// at most 24 significant bits). The same as
/// `(x.clamp(-FIXED_MAX, FIXED_MAX) as f64 * FIXED_ONE) as i128`, without
/// the slow general i128 conversions: the product is the f32's 24-bit
/// significand shifted.
#[inline]
fn fixed(x: f32) -> (i128, f64) {
    let x = x.clamp(-FIXED_MAX, FIXED_MAX);
    let bits = x.to_bits();
    let exp = ((bits >> 23) & 0xff) as i32;
    // NaN, zero and subnormals (below 2^-64 once scaled) truncate to 0.
    if exp == 0 || exp == 0xff {
        return (0, 0.0);
    }
    let m = ((bits & 0x7f_ffff) | 0x80_0000) as i128;
    // x = m 2^(exp - 150), so x 2^64 = m 2^(exp - 86).
    let shift = exp - 86;
    let (q, value) = if shift >= 0 {
        (m << shift, x.abs() as f64)
    } else {
        let t = m.checked_shr((-shift) as u32).unwrap_or(0);
        (t, t as f64 / FIXED_ONE)
    };
    // A negative sample that truncates to 0 is +0, as the cast gives.
    if x < 0.0 && q != 0 {
        (-q, -value)
    } else {
        (q, value)
    }
}

/// `s as f64`, correctly rounded like the cast, in a few integer steps:
/// the top 63 bits with a sticky bit for the rest, converted and scaled.
#[inline]
fn to_f64(s: i128) -> f64 {
    let u = s.unsigned_abs();
    let v = if u >> 63 == 0 {
        u as i64 as f64
    } else {
        // The top 63 bits, and whether any below them is set (enough to
        // round to 53 bits as the cast does); the shifted value fits an
        // i64, whose conversion is one instruction.
        let shift = 65 - u.leading_zeros();
        let top = (u >> shift) as u64 | ((u & ((1u128 << shift) - 1)) != 0) as u64;
        top as i64 as f64 * f64::from_bits(((1023 + shift) as u64) << 52)
    };
    if s < 0 {
        -v
    } else {
        v
    }
}

/// The mean colour of `n` samples whose fixed-point sums are `sum`.
#[inline(always)]
fn mean_of(sum: &[i128; 3], n: u32) -> DVec3 {
    if n == 0 {
        return DVec3::ZERO;
    }
    let n = n as f64;
    let [r, g, b] = sum;
    // Times 2^-64 is the division by FIXED_ONE, exactly, and cheaper.
    let mean = |s: &i128| to_f64(*s) * (1.0 / FIXED_ONE) / n;
    DVec3::new(mean(r), mean(g), mean(b))
}

/// Whether the samples of `run` all have the same colour, bit for bit.
#[inline]
fn is_one_colour(run: &[RowSample]) -> bool {
    let bits = |s: &RowSample| s.c.to_array().map(f32::to_bits);
    run.first()
        .is_some_and(|a| run.iter().all(|s| bits(s) == bits(a)))
}

/// `lum` on a black square of a checkerboard, `-lum` on a white one, the
/// sign set without a branch on the square's colour, which is random.
#[inline(always)]
fn signed(lum: f64, black: bool) -> f64 {
    f64::from_bits(lum.to_bits() ^ ((!black as u64) << 63))
}

/// Merges counts, means and M2 of two sets of values (Chan et al.).
fn chan(a: (u32, f64, f64), b: (u32, f64, f64)) -> (u32, f64, f64) {
    match (a.0, b.0) {
        (_, 0) => a,
        (0, _) => b,
        (na, nb) => {
            let n = na + nb;
            let d = b.1 - a.1;
            let w = na as f64 * nb as f64 / n as f64;
            (n, a.1 + d * nb as f64 / n as f64, a.2 + b.2 + d * d * w)
        }
    }
}

impl PixelStats {
    /// `n` pixels with no samples, without writing them: see
    /// [`crate::memory::zeroed`].
    pub(crate) fn zeroed(n: usize) -> Vec<PixelStats> {
        crate::memory::zeroed(n)
    }

    /// A pixel of the one sample `c` (sample 0, not jittered), or of none
    /// where `c` is not finite.
    pub(crate) fn of_sample(c: Vec3) -> PixelStats {
        let mut p = PixelStats::default();
        if c.is_finite() {
            p.add(0, c, None);
        }
        p
    }

    /// Adds sample `k` with colour `c`, drawn in sub-pixel `stratum` when
    /// pixel samples are jittered.
    #[inline]
    pub(crate) fn add(&mut self, k: u32, c: Vec3, stratum: Option<u32>) {
        self.add_run(&[RowSample {
            x: 0,
            k,
            c,
            stratum,
        }]);
    }

    /// Adds this pixel's finite samples `run`, in order (their `x` is not
    /// read): what adding them one at a time gives, bit for bit. The mean
    /// after each sample is made first, in one loop, then the running
    /// statistics in another: the means' conversions and divisions depend
    /// on one another only through the sums, so those of several samples
    /// overlap where one at a time each waits for the last.
    #[inline]
    pub(crate) fn add_run(&mut self, run: &[RowSample]) {
        let one_colour = self.n == 0 && self.sum == [0; 3] && is_one_colour(run);
        for run in run.chunks(RUN) {
            let mut lum = [0.0; RUN];
            let mut lum_mean = [0.0; RUN];
            let (mut sum, mut mean) = (self.sum, self.mean);
            if one_colour {
                // A fresh pixel's samples of one colour (a background's):
                // the sum after `i` of them is `i` times one sample's, a
                // value of at most 29 significant bits, so each mean is
                // exactly the sample's fixed-point value and its luminance
                // the sample's. The same values without the conversions and
                // divisions of every sample.
                let q = [fixed(run[0].c.x), fixed(run[0].c.y), fixed(run[0].c.z)];
                let n = self.n + run.len() as u32;
                sum = q.map(|q| q.0 * n as i128);
                mean = mean_of(&sum, n);
                let l = DVec3::from_array(q.map(|v| v.1)).dot(LUMA.as_dvec3());
                lum = [l; RUN];
                lum_mean = [l; RUN];
            } else {
                for (i, s) in run.iter().enumerate() {
                    let q = [fixed(s.c.x), fixed(s.c.y), fixed(s.c.z)];
                    for (s, q) in sum.iter_mut().zip(q) {
                        *s += q.0;
                    }
                    mean = mean_of(&sum, self.n + i as u32 + 1);
                    lum_mean[i] = mean.dot(LUMA.as_dvec3());
                    lum[i] = DVec3::from_array(q.map(|v| v.1)).dot(LUMA.as_dvec3());
                }
            }
            let mut lum_old = self.mean.dot(LUMA.as_dvec3());
            for (i, s) in run.iter().enumerate() {
                self.n += 1;
                // Welford's update.
                self.m2 += (lum[i] - lum_old) * (lum[i] - lum_mean[i]);
                lum_old = lum_mean[i];
                if let Some(stratum) = s.stratum {
                    self.add_stratified(s.k / PIXEL_STRATA, lum[i], stratum);
                    self.add_quartered(s.k, lum[i], stratum);
                }
            }
            (self.sum, self.mean) = (sum, mean);
        }
    }

    /// Counts sample `k` in its quarter of the first block, if it is one.
    fn add_quartered(&mut self, k: u32, lum: f64, stratum: u32) {
        if k >= PIXEL_STRATA {
            return;
        }
        // Samples 0..k all here, in order: else the quarters are unknown.
        if k + 1 != self.n {
            self.quarters = f32::NAN;
            return;
        }
        self.quarter += signed(lum, quadrant_is_black(stratum)) as f32;
        if k % QUARTER == QUARTER - 1 {
            self.quarters += self.quarter * self.quarter;
            self.quarter = 0.0;
        }
    }

    /// The sum of the samples' luminances, from the exact sums to within
    /// a few ulps: what merging the error statistics needs, for less than
    /// the mean colour.
    #[inline]
    fn luminance_sum(&self) -> f64 {
        // Each sum as its high word plus its low word's top 53 bits, in two
        // conversions of i64s.
        let f = |s: i128| {
            (s >> 64) as i64 as f64 * FIXED_ONE + ((s as u64) >> 11) as i64 as f64 * 2048.0
        };
        let [r, g, b] = &self.sum;
        let l = LUMA.as_dvec3();
        (f(*r) * l.x + f(*g) * l.y + f(*b) * l.z) * (1.0 / FIXED_ONE)
    }

    /// The mean colour the exact sums give.
    #[inline]
    pub(crate) fn mean_of_sum(&self) -> DVec3 {
        mean_of(&self.sum, self.n)
    }

    fn add_stratified(&mut self, block: u32, lum: f64, stratum: u32) {
        let black = (stratum % PIXEL_GRID + stratum / PIXEL_GRID).is_multiple_of(2);
        let first = self.n == 1;
        let piece = if first || (self.head.n > 0 && self.head.block == block) {
            &mut self.head
        } else {
            if self.tail.n > 0 && block != self.tail.block {
                // A sample of the block being filled was dropped (not finite).
                self.open += self.tail.open();
                self.tail = BlockPart::default();
            }
            &mut self.tail
        };
        if piece.n == 0 {
            *piece = BlockPart {
                block,
                ..BlockPart::default()
            };
        }
        piece.n += 1;
        piece.sum += lum;
        piece.diff += signed(lum, black);
        if piece.n == PIXEL_STRATA {
            let p = std::mem::take(piece);
            self.close_block(p);
        }
    }

    /// Counts a complete block.
    fn close_block(&mut self, p: BlockPart) {
        let m = p.sum / PIXEL_STRATA as f64;
        (self.blocks, self.block_mean, self.block_m2) =
            chan((self.blocks, self.block_mean, self.block_m2), (1, m, 0.0));
        self.checker += p.diff * p.diff / PIXEL_STRATA as f64;
    }

    /// Whether the only block piece is the first, incomplete one.
    fn only_head(&self) -> bool {
        self.head.n > 0 && self.tail.n == 0 && self.blocks == 0 && self.open == 0
    }

    /// Appends `b`'s samples, whose indices all come after this pixel's:
    /// the colour sums exactly, the rest as the sequential sums up to
    /// rounding. The `mean` fields are neither read nor updated: set this
    /// pixel's to [`PixelStats::mean_of_sum`] after the last part.
    #[inline]
    pub(crate) fn merge_stats(&mut self, b: &PixelStats) {
        if b.n == 0 {
            return;
        }
        if self.n == 0 {
            *self = *b;
            return;
        }
        // Merged statistics keep no quarters (docs/adaptive.md).
        self.quarters = f32::NAN;
        // Chan et al.'s M2 term, d² na nb / n for d the difference of the
        // mean luminances, from the luminance sums in one division.
        let (na, nb) = (self.n as f64, b.n as f64);
        let e = b.luminance_sum() * na - self.luminance_sum() * nb;
        let m2 = self.m2 + b.m2 + e * e / (na * nb * (na + nb));
        for (s, t) in self.sum.iter_mut().zip(b.sum) {
            *s += t;
        }
        (self.n, self.m2) = (self.n + b.n, m2);
        // This pixel's last piece and b's first one may be halves of one
        // block.
        let last_is_head = self.only_head();
        let last = if self.tail.n > 0 {
            Some(std::mem::take(&mut self.tail))
        } else if last_is_head {
            Some(std::mem::take(&mut self.head))
        } else {
            None
        };
        let first = (b.head.n > 0).then_some(b.head);
        let b_only_head = b.only_head();
        let place = |out: &mut PixelStats, p: BlockPart, is_first: bool, is_last: bool| {
            if p.n == PIXEL_STRATA {
                out.close_block(p);
            } else if is_first {
                out.head = p;
            } else if is_last {
                out.tail = p;
            } else {
                out.open += p.open();
            }
        };
        match (last, first) {
            (Some(l), Some(f)) if l.block == f.block => {
                place(self, l.join(f), last_is_head, b_only_head);
            }
            (l, f) => {
                if let Some(l) = l {
                    place(self, l, last_is_head, false);
                }
                if let Some(f) = f {
                    place(self, f, false, b_only_head);
                }
            }
        }
        (self.blocks, self.block_mean, self.block_m2) = chan(
            (self.blocks, self.block_mean, self.block_m2),
            (b.blocks, b.block_mean, b.block_m2),
        );
        self.checker += b.checker;
        self.open += b.open;
        if b.tail.n > 0 {
            self.tail = b.tail;
        }
    }

    /// Sample variance of the luminance.
    pub(crate) fn variance(&self) -> f64 {
        if self.n < 2 {
            0.0
        } else {
            self.m2 / (self.n - 1) as f64
        }
    }

    /// The variance of the mean luminance, estimated from how the samples
    /// were drawn (see the module comment); `None` below two samples.
    pub fn mean_variance(&self) -> Option<f64> {
        if self.n < 2 {
            return None;
        }
        let (n, s2) = (self.n as f64, self.variance());
        let strata = PIXEL_STRATA as f64;
        // Σ r (16 - r) over the groups of strata drawn without replacement.
        let g = (self.open + self.head.open() + self.tail.open()) as f64;
        if self.blocks == 0 {
            if let Some(v) = self.quartered_variance() {
                return Some(v);
            }
            if g == 0.0 {
                // Independent samples.
                return Some(s2 / n);
            }
            return Some(s2 / n * (g / (strata * n)).sqrt());
        }
        let b = self.blocks as f64;
        let within = (self.checker + strata * self.block_m2) / (2.0 * b - 1.0);
        let between = (s2 - within).max(0.0);
        Some((n * within + g / (strata - 1.0) * between) / (n * n))
    }

    /// The variance of the mean of a pixel whose samples are the first `4q`
    /// of its first block, `q` of 1 to 3 (see the module comment); `None`
    /// for any other.
    fn quartered_variance(&self) -> Option<f64> {
        let q = self.n / QUARTER;
        let whole = self.n.is_multiple_of(QUARTER) && (1..4).contains(&q);
        if !whole || !self.quarters.is_finite() || !self.only_head() || self.head.block != 0 {
            return None;
        }
        let n = self.n as f64;
        let q = q as f64;
        Some(self.quarters as f64 / (n * n) * ((4.0 - q) / 3.0).sqrt())
    }

    /// The estimated variance of the mean luminance over `lum^2 + REL_EPS`:
    /// this pixel's term of [`Film::estimated_rel_mse`].
    pub(crate) fn rel_variance(&self) -> Option<f64> {
        let lum = self.mean.dot(LUMA.as_dvec3());
        Some(self.mean_variance()? / (lum * lum + REL_EPS))
    }

    /// The estimated relative error of the mean: its standard error over
    /// `√(lum² + ε)`, as the film's relMSE counts it; `None` below two
    /// samples.
    pub(crate) fn relative_error(&self) -> Option<f64> {
        self.rel_variance().map(f64::sqrt)
    }

    /// Standard error of the mean luminance (0 below two samples).
    pub fn std_error(&self) -> f64 {
        self.mean_variance().unwrap_or(0.0).sqrt()
    }

    /// Whether the error estimate rests on the samples alone: a complete
    /// block of strata when jittered, as many independent samples otherwise
    /// (below that a jittered estimate assumes how the variance splits, and
    /// a few independent ones can all miss a small bright feature).
    pub(crate) fn estimate_is_design_based(&self) -> bool {
        let jittered = self.blocks > 0 || self.head.n > 0 || self.tail.n > 0 || self.open > 0;
        self.quartered_variance().is_some()
            || self.n >= PIXEL_STRATA && (self.blocks > 0 || !jittered)
    }
}

/// What a film that is read only for its image and error estimate keeps
/// of a pixel (see [`Film::new_summary`]): 24 bytes where statistics are 176.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Zeroable)]
pub(crate) struct PixelSummary {
    /// [`PixelStats::mean`], as the image takes it.
    mean: Vec3,
    /// [`PixelSummary::KNOWN`] and [`PixelSummary::DESIGN_BASED`].
    flags: u32,
    /// [`PixelStats::rel_variance`] where known.
    rel: f64,
}

impl PixelSummary {
    /// The pixel's relative variance is known (two samples or more).
    const KNOWN: u32 = 1;
    /// [`PixelStats::estimate_is_design_based`].
    const DESIGN_BASED: u32 = 2;

    fn of(p: &PixelStats) -> Self {
        let rel = p.rel_variance();
        let design = p.estimate_is_design_based();
        PixelSummary {
            mean: p.mean.as_vec3(),
            flags: rel.is_some() as u32 * Self::KNOWN + design as u32 * Self::DESIGN_BASED,
            rel: rel.unwrap_or(0.0),
        }
    }

    fn rel_variance(&self) -> Option<f64> {
        (self.flags & Self::KNOWN != 0).then_some(self.rel)
    }
}

/// A row of a summarised film as a pass fills it: the statistics of the
/// pixel being sampled are kept here, on the stack, and summarised when
/// the pass moves on to the next pixel.
pub(crate) struct SummaryRow<'a> {
    pixels: &'a mut [PixelSummary],
    /// The pixel being sampled (`u32::MAX` before the first).
    x: u32,
    open: PixelStats,
}

impl<'a> SummaryRow<'a> {
    fn new(pixels: &'a mut [PixelSummary]) -> Self {
        SummaryRow {
            pixels,
            x: u32::MAX,
            open: PixelStats::default(),
        }
    }

    /// Summarises the pixel being sampled.
    fn close(&mut self) {
        if let Some(px) = self.pixels.get_mut(self.x as usize) {
            *px = PixelSummary::of(&self.open);
            self.open = PixelStats::default();
        }
        self.x = u32::MAX;
    }
}

/// The pixels a pass samples into (all or a row).
pub(crate) enum Samples<'a> {
    Stats(&'a mut [PixelStats]),
    /// A lean film's samples.
    Exact(&'a mut [Vec3]),
    /// A summarised film's pixels.
    Summary(SummaryRow<'a>),
}

impl<'a> Samples<'a> {
    /// Rows of `width` pixels.
    pub(crate) fn rows(self, width: usize) -> Vec<Samples<'a>> {
        match self {
            Samples::Stats(p) => p.chunks_mut(width).map(Samples::Stats).collect(),
            Samples::Exact(p) => p.chunks_mut(width).map(Samples::Exact).collect(),
            Samples::Summary(r) => r
                .pixels
                .chunks_mut(width)
                .map(|p| Samples::Summary(SummaryRow::new(p)))
                .collect(),
        }
    }

    pub(crate) fn len(&self) -> usize {
        match self {
            Samples::Stats(p) => p.len(),
            Samples::Exact(p) => p.len(),
            Samples::Summary(r) => r.pixels.len(),
        }
    }

    /// Adds `samples` of this row's pixels, dropping those not finite; a
    /// lean film's pixels take one each (not jittered: exact renders are
    /// not), and keep a dropped one, which means none. Each pixel's run of
    /// samples goes in at once ([`PixelStats::add_run`]).
    #[inline]
    pub(crate) fn add(&mut self, samples: &[RowSample]) {
        match self {
            Samples::Stats(p) => {
                for run in samples.chunk_by(|a, b| a.x == b.x) {
                    let px = &mut p[run[0].x as usize];
                    for finite in run.split(|s| !s.c.is_finite()) {
                        px.add_run(finite);
                    }
                }
            }
            Samples::Exact(p) => {
                for s in samples {
                    debug_assert!(s.k == 0 && s.stratum.is_none());
                    p[s.x as usize] = s.c;
                }
            }
            Samples::Summary(row) => {
                for run in samples.chunk_by(|a, b| a.x == b.x) {
                    if run[0].x != row.x {
                        row.close();
                        row.x = run[0].x;
                    }
                    for finite in run.split(|s| !s.c.is_finite()) {
                        row.open.add_run(finite);
                    }
                }
            }
        }
    }

    /// Ends a row's pass: a summarised film's last pixel is summarised.
    pub(crate) fn finish(&mut self) {
        if let Samples::Summary(row) = self {
            row.close();
        }
    }

    /// Marks pixels of a lean film that a pass left out as having no
    /// sample (its pass writes every other pixel).
    pub(crate) fn skipped(&mut self) {
        if let Samples::Exact(p) = self {
            p.fill(Vec3::NAN);
        }
    }
}

/// A sample that was NaN or infinite.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize)]
pub(crate) struct BadSample {
    pub(crate) x: u32,
    pub(crate) y: u32,
    pub(crate) sample: u32,
}

/// Where an adaptive film's samples go. Every pixel first gets the same
/// [`QUARTER`] samples (a quarter of a block: one in each quadrant); from
/// then on a pixel's share follows its weight, a prediction made from its
/// neighbours' first quarters and never from its own samples: given the weights, each pixel's
/// samples are independent draws in a number fixed without them, so its
/// mean is unbiased and its error estimate as calibrated as a uniform
/// film's (docs/adaptive.md).
#[derive(Clone, Debug)]
pub struct Allocation {
    /// Samples attempted per pixel: the index of each pixel's next sample.
    pub spp: Vec<u32>,
    /// Each pixel's predicted relative standard deviation of one sample
    /// over the square root of its predicted rays per sample; empty until
    /// every pixel has its first quarter.
    pub weight: Vec<f32>,
    /// The weights in ascending order, which a pass's share is found from.
    pub(crate) ascending: Vec<f32>,
    /// Rays each pixel's samples traced until the weights were made (then
    /// emptied).
    pub(crate) rays: Vec<u32>,
}

/// How far a pixel's two predictions look: the neighbours within one pixel,
/// and those within this many (its own samples excluded).
const WEIGHT_RADIUS: usize = 3;
/// The least weight, as a fraction of the mean: a defence against
/// neighbours' quarters that missed what a pixel holds (measured, a tenth
/// left `cornell` at 64x64 slower to 1 % than uniform sampling; 0.4 and 0.5
/// reached it with about half the samples).
const WEIGHT_FLOOR: f64 = 0.4;

impl Allocation {
    /// The weights from `pixels` (a `width`-wide film whose pixels have
    /// their first quarter and nothing more, which traced `rays`): pixel
    /// `i`'s is the root of its neighbours' mean relative variance of one
    /// sample, `s² / (lum² + ε)` with `s²` the sample variance, over their
    /// mean rays per sample. Counts in proportion to it minimise the film's
    /// relMSE for the rays traced, where counts in proportion to the
    /// deviation alone would for the samples: a glossy or mirrored pixel's
    /// samples cost several times a diffuse one's. Variance is smooth
    /// across an image, so neighbours' quarters give a firmer prediction
    /// than a pixel's own four samples, and leaving the pixel out keeps its
    /// mean free of the decision. The sample variance has 3 degrees of
    /// freedom a quarter where the design-based estimate has one, and it
    /// measured best (docs/adaptive.md). The weight is the mean of two
    /// predictions, from the 8 neighbours within one pixel (sharp noisy
    /// features) and from the 48 within [`WEIGHT_RADIUS`] (broad soft
    /// shadows). A pixel with no estimable neighbour gets the highest
    /// weight, and none less than [`WEIGHT_FLOOR`] of the mean.
    pub(crate) fn weigh(pixels: &[PixelStats], rays: &[u32], width: u32) -> Vec<f32> {
        let w = width.max(1) as usize;
        let h = pixels.len() / w;
        // Relative variance, rays per sample and 1 for an estimable pixel;
        // zeros for one that is not.
        let rel = |i: usize| {
            let p = &pixels[i];
            let lum = p.mean.dot(LUMA.as_dvec3());
            let v = p.variance() / (lum * lum + REL_EPS);
            let per_sample = rays[i] as f64 / p.n.max(1) as f64;
            if p.n >= 2 && v.is_finite() {
                [v, per_sample, 1.0]
            } else {
                [0.0; 3]
            }
        };
        // The neighbours' root mean relative variance over their mean rays
        // per sample (at least one): the window's sums less the pixel's own.
        let predict = |sum: [f64; 3], own: [f64; 3]| {
            let [v, t, n] = [0, 1, 2].map(|k| (sum[k] - own[k]).max(0.0));
            (n >= 0.5).then(|| (v / t.max(n)).sqrt())
        };
        // Bands of rows in parallel, each summing the rows it reads into
        // buffers its thread reuses (whole-film arrays of sums were 95 MB
        // of fresh memory at 1024x768). Each sum is made in the same order
        // whatever the bands, and as it was made over the whole film.
        let mut weight = vec![0.0f64; pixels.len()];
        weight
            .par_chunks_mut(WEIGH_BAND * w)
            .enumerate()
            .for_each_init(<[Vec<[f64; 3]>; 5]>::default, |bufs, (b, out)| {
                let [own, near, far, near_y, far_y] = bufs;
                let (y0, y1) = (b * WEIGH_BAND, ((b + 1) * WEIGH_BAND).min(h));
                let rows = y0.saturating_sub(WEIGHT_RADIUS)..(y1 + WEIGHT_RADIUS).min(h);
                own.clear();
                own.extend((rows.start * w..rows.end * w).map(rel));
                row_sums(own, w, 1, near);
                row_sums(own, w, WEIGHT_RADIUS, far);
                // A row's window sums: its rows' sums added in row order, a
                // whole row at a time.
                let column = |sums: &[[f64; 3]], y: usize, r: usize, into: &mut Vec<[f64; 3]>| {
                    into.clear();
                    into.resize(w, [0.0; 3]);
                    for ny in window(y, h, r) {
                        let row = &sums[(ny - rows.start) * w..][..w];
                        for (a, b) in into.iter_mut().zip(row) {
                            *a = add3(*a, b);
                        }
                    }
                };
                for (y, out) in (y0..y1).zip(out.chunks_mut(w)) {
                    column(near, y, 1, near_y);
                    column(far, y, WEIGHT_RADIUS, far_y);
                    for (x, out) in out.iter_mut().enumerate() {
                        let mine = own[(y - rows.start) * w + x];
                        let (a, b) = (predict(near_y[x], mine), predict(far_y[x], mine));
                        // NaN: no estimable neighbour.
                        *out = match (a, b) {
                            (Some(a), Some(b)) => 0.5 * (a + b),
                            (a, b) => a.or(b).unwrap_or(f64::NAN),
                        };
                    }
                }
            });
        let top = weight
            .iter()
            .copied()
            .filter(|v| !v.is_nan())
            .fold(0.0, f64::max);
        let or_top = |v: f64| if v.is_nan() { top } else { v };
        let mean = weight.iter().map(|&v| or_top(v)).sum::<f64>() / weight.len() as f64;
        // A floor, so that pixels whose neighbours' first blocks all missed
        // a rare path still gain samples; all equal on a film with no
        // variance at all.
        let floor = if mean > 0.0 { WEIGHT_FLOOR * mean } else { 1.0 };
        weight
            .iter()
            .map(|&v| or_top(v).max(floor) as f32)
            .collect()
    }
}

/// Rows of output a band of [`Allocation::weigh`] makes.
const WEIGH_BAND: usize = 64;

/// The rows within `r` of row (or column) `i` of `n`, cut at the edges.
fn window(i: usize, n: usize, r: usize) -> Range<usize> {
    i.saturating_sub(r)..(i + r + 1).min(n)
}

#[inline(always)]
fn add3(a: [f64; 3], b: &[f64; 3]) -> [f64; 3] {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

/// Each value's sum of `v` over the values within `r` of it in its row of
/// `w` (cut at the row's ends), into `sums`.
fn row_sums(v: &[[f64; 3]], w: usize, r: usize, sums: &mut Vec<[f64; 3]>) {
    sums.clear();
    for src in v.chunks(w) {
        sums.extend((0..src.len()).map(|x| src[window(x, w, r)].iter().fold([0.0; 3], add3)));
    }
}

#[derive(Clone, Debug)]
pub struct Film {
    pub(crate) width: u32,
    pub(crate) height: u32,
    /// Each pixel's statistics, or an exact film's one sample each.
    pixels: Pixels,
    /// Samples per pixel attempted so far on a uniform film (the next
    /// pass's first index is `start + spp`), the fewest any pixel has on an
    /// adaptive one.
    pub(crate) spp: u32,
    /// The first sample index of a uniform film: 0, except for a part of a
    /// split render (`render --samples A..B`), which starts at A.
    pub(crate) start: u32,
    /// Per-pixel counts and weights of an adaptive film.
    pub(crate) adaptive: Option<Allocation>,
    pub(crate) bad_count: u64,
    pub(crate) bad: Vec<BadSample>,
}

/// What a film holds of its pixels.
#[derive(Clone, Debug)]
enum Pixels {
    /// Every pixel's statistics.
    Stats(Vec<PixelStats>),
    /// The one sample of each pixel of an exact render (not finite where
    /// it has none), which is everything its statistics say: a lean film,
    /// 12 bytes a pixel where statistics are 176, which a frame would
    /// otherwise spend much of its time bringing into memory. The
    /// statistics are made from the samples when something asks for them.
    Exact {
        samples: Vec<Vec3>,
        stats: OnceLock<Vec<PixelStats>>,
    },
    /// Each pixel's mean and error term, all a render that writes an image
    /// reads of its film: made by a pass that gives a blank film all its
    /// samples, each pixel's statistics kept on the stack while it is
    /// sampled (see [`Film::new_summary`]).
    Summary(Vec<PixelSummary>),
}

impl Pixels {
    fn exact_stats(samples: &[Vec3]) -> Vec<PixelStats> {
        samples.iter().map(|&c| PixelStats::of_sample(c)).collect()
    }
}

/// The mean a pixel of one sample `c` has: `c` as the fixed point sums
/// hold it (the same as [`PixelStats::of_sample`]'s mean), black where `c`
/// is not finite (never added).
#[inline]
fn one_sample_mean(c: Vec3) -> Vec3 {
    if c.is_finite() {
        Vec3::new(
            fixed(c.x).1 as f32,
            fixed(c.y).1 as f32,
            fixed(c.z).1 as f32,
        )
    } else {
        Vec3::ZERO
    }
}

/// Memory per pixel of the images made from a film: the linear, bloomed
/// and displayed copies, and the 8-bit picture.
const IMAGES: u64 = 3 * 12 + 3;

/// An adaptive film's per-pixel sample counts and rays traced, as a pass
/// writes them.
pub(crate) type Counts<'a> = (&'a mut [u32], &'a mut [u32]);

impl Film {
    /// Samples per pixel so far: on a uniform film, every pixel's (the next
    /// pass's first index is `start + spp`); on an adaptive one, the fewest.
    pub fn spp(&self) -> u32 {
        self.spp
    }

    /// Per-pixel counts and weights of an adaptive film.
    pub fn adaptive(&self) -> Option<&Allocation> {
        self.adaptive.as_ref()
    }

    /// Samples that were NaN or infinite (left out of the pixels).
    pub fn bad_count(&self) -> u64 {
        self.bad_count
    }

    /// Memory a render needs per pixel: the statistics (with an adaptive
    /// film's count, weight and rays, or a lean film's sample they were
    /// made from), and the linear, bloomed and displayed copies of the
    /// image made from them.
    pub(crate) const BYTES_PER_PIXEL: u64 = std::mem::size_of::<PixelStats>() as u64 + 12 + IMAGES;
    /// The same for a summarised film ([`Film::new_summary`]).
    pub(crate) const SUMMARY_BYTES_PER_PIXEL: u64 =
        std::mem::size_of::<PixelSummary>() as u64 + IMAGES;
    /// The same for a lean film ([`Film::new_exact`]).
    pub(crate) const EXACT_BYTES_PER_PIXEL: u64 = 12 + IMAGES;

    pub(crate) fn new(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self::with(width, height, Pixels::Stats(PixelStats::zeroed(n)))
    }

    /// A film of `pixels`' statistics.
    pub(crate) fn of_stats(width: u32, height: u32, pixels: Vec<PixelStats>) -> Self {
        assert_eq!(pixels.len(), width as usize * height as usize);
        Self::with(width, height, Pixels::Stats(pixels))
    }

    /// A lean film for the one pass of an exact render, which only keeps
    /// each pixel's sample (see [`Film::pixels`]). Its samples start as
    /// zero bytes, which fresh memory already holds, so nothing writes
    /// them twice: the pass writes every pixel, a sample or a non-finite
    /// value (none), and marks a row it leaves out
    /// ([`Samples::skipped`]).
    pub(crate) fn new_exact(width: u32, height: u32) -> Self {
        let samples = crate::memory::zeroed(width as usize * height as usize);
        let pixels = Pixels::Exact {
            samples,
            stats: OnceLock::new(),
        };
        Self::with(width, height, pixels)
    }

    fn with(width: u32, height: u32, pixels: Pixels) -> Self {
        Self {
            width,
            height,
            pixels,
            spp: 0,
            start: 0,
            adaptive: None,
            bad_count: 0,
            bad: Vec::new(),
        }
    }

    /// A blank summarised film, which keeps of each pixel only its mean
    /// and its term of the error estimate, 24 bytes a pixel where
    /// statistics are 176: for a render whose one pass gives every pixel
    /// all its samples, and whose film is then read for nothing but
    /// [`Film::image`], [`Film::mean`] and [`Film::report`] (a render to an
    /// image file; its [`Job`](super::Job) decides). Its statistics are
    /// never made; asking for them ([`Film::pixels`]) or for another pass
    /// is a bug and panics.
    pub(crate) fn new_summary(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        // SAFETY: a summary of zero bytes is that of a pixel with no
        // sample, which a pass writes over.
        Self::with(width, height, Pixels::Summary(crate::memory::zeroed(n)))
    }

    /// The number of pixels.
    pub(crate) fn pixels_len(&self) -> usize {
        match &self.pixels {
            Pixels::Stats(p) => p.len(),
            Pixels::Exact { samples, .. } => samples.len(),
            Pixels::Summary(p) => p.len(),
        }
    }

    /// Whether this film keeps only each pixel's mean and error term.
    pub(crate) fn is_summary(&self) -> bool {
        matches!(self.pixels, Pixels::Summary(_))
    }

    /// Whether this is a lean film of one sample per pixel.
    pub(crate) fn is_exact(&self) -> bool {
        matches!(self.pixels, Pixels::Exact { .. })
    }

    /// Each pixel's statistics (made from the samples on first use for a
    /// lean film; a summarised film has none, see [`Film::new_summary`]).
    pub fn pixels(&self) -> &[PixelStats] {
        match &self.pixels {
            Pixels::Stats(p) => p,
            Pixels::Exact { samples, stats } => stats.get_or_init(|| Pixels::exact_stats(samples)),
            Pixels::Summary(_) => panic!("{NO_STATISTICS}"),
        }
    }

    /// Each pixel's statistics, to change: a lean film becomes a film of
    /// statistics.
    pub(crate) fn pixels_mut(&mut self) -> &mut [PixelStats] {
        if let Pixels::Exact { samples, stats } = &mut self.pixels {
            let p = stats.take().unwrap_or_else(|| Pixels::exact_stats(samples));
            self.pixels = Pixels::Stats(p);
        }
        match &mut self.pixels {
            Pixels::Stats(p) => p,
            Pixels::Exact { .. } => unreachable!("made statistics above"),
            Pixels::Summary(_) => panic!("{NO_STATISTICS}"),
        }
    }

    /// What a pass samples into: a lean film's samples or each pixel's
    /// statistics, and an adaptive film's sample counts.
    pub(crate) fn sample_into(&mut self) -> (Samples<'_>, Option<Counts<'_>>) {
        let pixels = match &mut self.pixels {
            Pixels::Stats(p) => Samples::Stats(p),
            Pixels::Exact { samples, stats } => {
                // Its job gives it one pass of one sample (again, where
                // that pass was cut short), never more.
                assert!(self.spp == 0, "an exact film holds one sample a pixel");
                // Statistics made before the samples came in are stale.
                stats.take();
                Samples::Exact(samples)
            }
            Pixels::Summary(p) => {
                // A summary holds all of a pixel's samples or none.
                assert!(self.spp == 0, "{NO_STATISTICS}");
                Samples::Summary(SummaryRow::new(p))
            }
        };
        let counts = self
            .adaptive
            .as_mut()
            .map(|a| (&mut a.spp[..], &mut a.rays[..]));
        (pixels, counts)
    }

    /// An empty film whose pixels each keep their own sample count.
    pub fn new_adaptive(width: u32, height: u32) -> Self {
        let n = width as usize * height as usize;
        Self {
            adaptive: Some(Allocation {
                spp: vec![0; n],
                weight: Vec::new(),
                ascending: Vec::new(),
                rays: vec![0; n],
            }),
            ..Self::new(width, height)
        }
    }

    /// Samples pixel `i` has had (its next sample index).
    pub fn pixel_spp(&self, i: usize) -> u32 {
        self.adaptive.as_ref().map_or(self.spp, |a| a.spp[i])
    }

    /// The fewest, mean and most samples per pixel.
    pub fn spp_range(&self) -> (u32, f64, u32) {
        match &self.adaptive {
            Some(a) if !a.spp.is_empty() => {
                let min = a.spp.iter().copied().min().unwrap_or(0);
                let max = a.spp.iter().copied().max().unwrap_or(0);
                let sum: u64 = a.spp.iter().map(|&n| n as u64).sum();
                (min, sum as f64 / a.spp.len() as f64, max)
            }
            _ => (self.spp, self.spp as f64, self.spp),
        }
    }

    /// The fraction of an adaptive film's pixels whose own estimated
    /// relative error is below `target` (`None` on a uniform film).
    pub(crate) fn converged(&self, target: f64) -> Option<f64> {
        self.adaptive.as_ref()?;
        let n = self.pixels().len().max(1);
        let below = self
            .pixels()
            .iter()
            .filter(|p| p.relative_error().is_some_and(|e| e < target))
            .count();
        Some(below as f64 / n as f64)
    }

    /// Adds sample `sample` (drawn in sub-pixel `stratum` when jittered),
    /// or records it as bad when not finite.
    pub fn add(&mut self, x: u32, y: u32, sample: u32, stratum: Option<u32>, c: Vec3) {
        let i = (y * self.width + x) as usize;
        if let Some(a) = &mut self.adaptive {
            a.spp[i] = a.spp[i].max(sample + 1);
        }
        if c.is_finite() {
            self.pixels_mut()[i].add(sample, c, stratum);
        } else {
            self.record_bad(BadSample { x, y, sample });
        }
    }

    pub(crate) fn record_bad(&mut self, b: BadSample) {
        self.bad_count += 1;
        if self.bad.len() < MAX_LISTED {
            self.bad.push(b);
        }
    }

    pub fn mean(&self, x: u32, y: u32) -> Vec3 {
        let i = (y * self.width + x) as usize;
        match &self.pixels {
            Pixels::Stats(p) => p[i].mean.as_vec3(),
            Pixels::Exact { samples, .. } => one_sample_mean(samples[i]),
            Pixels::Summary(p) => p[i].mean,
        }
    }

    /// Linear mean image, row-major.
    pub fn image(&self) -> Vec<Vec3> {
        match &self.pixels {
            Pixels::Stats(p) => p.iter().map(|p| p.mean.as_vec3()).collect(),
            Pixels::Exact { samples, .. } => samples.iter().map(|&c| one_sample_mean(c)).collect(),
            Pixels::Summary(p) => p.iter().map(|p| p.mean).collect(),
        }
    }

    /// The film's estimate of its relMSE: the mean over pixels of the
    /// estimated variance of the mean luminance over `lum^2 + REL_EPS`;
    /// `None` until every pixel has two samples.
    pub fn estimated_rel_mse(&self) -> Option<f64> {
        // The terms summed in pixel order, from statistics or summaries
        // alike; a lean film's pixels have one sample at most: no estimate.
        fn mean_of(terms: impl ExactSizeIterator<Item = Option<f64>>) -> Option<f64> {
            let n = terms.len();
            if n == 0 {
                return None;
            }
            let mut sum = 0.0;
            for t in terms {
                sum += t?;
            }
            Some(sum / n as f64)
        }
        match &self.pixels {
            Pixels::Stats(p) => mean_of(p.iter().map(PixelStats::rel_variance)),
            Pixels::Summary(p) => mean_of(p.iter().map(PixelSummary::rel_variance)),
            Pixels::Exact { .. } => None,
        }
    }

    /// The relative error shown everywhere (TUI, `--target-error`,
    /// `converge`): the square root of [`Film::estimated_rel_mse`]; `None`
    /// (unknown) until every pixel has two samples.
    pub(crate) fn relative_error(&self) -> Option<f64> {
        self.estimated_rel_mse().map(f64::sqrt)
    }

    /// What a render's closing line says of this film.
    pub(crate) fn report(&self) -> Report {
        Report {
            spp: self.spp_range(),
            adaptive: self.adaptive.is_some(),
            samples: self.start..self.start + self.spp,
            relative_error: self.relative_error(),
            bad_count: self.bad_count,
        }
    }

    /// Whether the estimate is firm enough to stop on
    /// (`--target-error`): every pixel's rests on its samples alone
    /// ([`PixelStats::estimate_is_design_based`]: 16 samples).
    pub(crate) fn error_is_meaningful(&self) -> bool {
        match &self.pixels {
            Pixels::Stats(p) => !p.is_empty() && p.iter().all(PixelStats::estimate_is_design_based),
            Pixels::Summary(p) => {
                !p.is_empty() && p.iter().all(|p| p.flags & PixelSummary::DESIGN_BASED != 0)
            }
            // A lean film's pixels have one sample at most.
            Pixels::Exact { .. } => false,
        }
    }
}

/// What a render's or merge's closing line says of its film, which a merge
/// measures band by band without holding the film.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Report {
    /// The fewest, mean and most samples per pixel.
    pub(crate) spp: (u32, f64, u32),
    pub(crate) adaptive: bool,
    /// The sample indices every pixel of a uniform film holds.
    pub(crate) samples: Range<u32>,
    /// [`Film::relative_error`].
    pub(crate) relative_error: Option<f64>,
    pub(crate) bad_count: u64,
}

/// What makes a pixel the worst of a film.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Worst {
    Nan,
    Variance,
    Brightest,
}

impl crate::choice::Choice for Worst {
    const ALL: &'static [Self] = &[Worst::Nan, Worst::Variance, Worst::Brightest];

    fn choice(self) -> (&'static str, &'static str) {
        match self {
            Worst::Nan => ("nan", "The first pixel with a NaN or infinite sample"),
            Worst::Variance => ("variance", "The pixel whose samples vary most"),
            Worst::Brightest => ("brightest", "The brightest pixel"),
        }
    }
}

/// A pixel and the sample of it worth replaying.
pub(crate) type PixelSample = (u32, u32, u32);

/// The worst pixel of a film by each measure.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct WorstPixels {
    pub(crate) nan: Option<PixelSample>,
    pub(crate) variance: Option<PixelSample>,
    pub(crate) brightest: Option<PixelSample>,
}

impl WorstPixels {
    pub(crate) fn get(&self, w: Worst) -> Option<PixelSample> {
        match w {
            Worst::Nan => self.nan,
            Worst::Variance => self.variance,
            Worst::Brightest => self.brightest,
        }
    }
}

impl Film {
    /// The worst pixel by `w`, with the sample to replay: the first NaN/Inf
    /// sample; the pixel of highest variance (none while no pixel varies);
    /// the brightest pixel (none on an empty film).
    pub(crate) fn worst(&self, w: Worst) -> Option<PixelSample> {
        let at = |i: usize| (i as u32 % self.width, i as u32 / self.width, 0);
        let lum = |p: &PixelStats| p.mean.dot(LUMA.as_dvec3());
        let top = |key: &dyn Fn(&PixelStats) -> f64| {
            self.pixels()
                .iter()
                .enumerate()
                .map(|(i, p)| (i, key(p)))
                .filter(|(_, v)| v.is_finite())
                .max_by(|a, b| a.1.total_cmp(&b.1))
        };
        match w {
            Worst::Nan => self.bad.first().map(|b| (b.x, b.y, b.sample)),
            Worst::Variance => top(&PixelStats::variance)
                .filter(|(_, v)| *v > 0.0)
                .map(|(i, _)| at(i)),
            Worst::Brightest => top(&lum).map(|(i, _)| at(i)),
        }
    }

    pub(crate) fn worst_pixels(&self) -> WorstPixels {
        WorstPixels {
            nan: self.worst(Worst::Nan),
            variance: self.worst(Worst::Variance),
            brightest: self.worst(Worst::Brightest),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::sampling::{pixel_stratum, Rng};

    #[test]
    fn fixed_point_conversions_are_the_casts_bit_for_bit() {
        // A xorshift sequence of bit patterns: every exponent, both signs,
        // NaN, infinities and subnormals among them.
        let mut z = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            z ^= z << 13;
            z ^= z >> 7;
            z ^= z << 17;
            z
        };
        let specials = [
            0.0,
            -0.0,
            f32::NAN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            f32::MIN_POSITIVE,
        ];
        let xs = (0..200_000)
            .map(|_| f32::from_bits(next() as u32))
            .chain(specials);
        for x in xs {
            let q = (x.clamp(-FIXED_MAX, FIXED_MAX) as f64 * FIXED_ONE) as i128;
            let (fq, fv) = fixed(x);
            assert_eq!(fq, q, "{x:e}");
            assert_eq!(fv.to_bits(), (q as f64 / FIXED_ONE).to_bits(), "{x:e}");
        }
        for _ in 0..200_000 {
            // Sums of every size, with long runs of equal bits near the
            // rounding position.
            let wide = ((next() as i128) << 64 | next() as i128) >> (next() % 128);
            let tie = wide & !0x7ff | 0x400;
            for s in [wide, -wide, tie, -tie, wide >> 11 << 11] {
                assert_eq!(to_f64(s).to_bits(), (s as f64).to_bits(), "{s}");
            }
        }
    }

    #[test]
    fn a_lean_pixel_has_the_mean_of_its_statistics() {
        let mut z = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            z ^= z << 13;
            z ^= z >> 7;
            z ^= z << 17;
            f32::from_bits(z as u32)
        };
        let specials = [0.0, -0.0, f32::NAN, f32::INFINITY, 1e-30, 3e38, -5.0];
        let xs: Vec<f32> = (0..30_000).map(|_| next()).chain(specials).collect();
        for c in xs
            .chunks(3)
            .map(|c| Vec3::new(c[0], c[1 % c.len()], c[2 % c.len()]))
        {
            let p = PixelStats::of_sample(c);
            let want = p.mean.as_vec3();
            let got = one_sample_mean(c);
            assert_eq!(
                got.to_array().map(f32::to_bits),
                want.to_array().map(f32::to_bits),
                "{c}"
            );
        }
    }

    #[test]
    fn welford_matches_two_pass() {
        let xs = [0.1f32, 0.5, 0.25, 0.9, 0.3];
        let mut p = PixelStats::default();
        for (k, x) in xs.into_iter().enumerate() {
            p.add(k as u32, Vec3::splat(x), None);
        }
        let m: f64 = xs.iter().map(|&x| x as f64).sum::<f64>() / 5.0;
        let v: f64 = xs.iter().map(|&x| (x as f64 - m).powi(2)).sum::<f64>() / 4.0;
        assert!((p.mean.x - m).abs() < 1e-12);
        // Luminance of a grey is the grey (weights sum to 1 up to f32 rounding).
        assert!((p.variance() - v).abs() < 1e-6, "{} vs {v}", p.variance());
        assert!((p.mean_variance().unwrap() - v / 5.0).abs() < 1e-6);
    }

    #[test]
    fn zeroed_pixels_are_default_pixels() {
        let px = PixelStats::zeroed(100_000);
        assert_eq!(px.len(), 100_000);
        let d = format!("{:?}", PixelStats::default());
        assert!(px.iter().all(|p| format!("{p:?}") == d));
        assert!(PixelStats::zeroed(0).is_empty());
    }

    #[test]
    fn worst_pixels_by_each_measure() {
        let mut f = Film::new(3, 1);
        assert_eq!(f.worst(Worst::Variance), None);
        f.add(0, 0, 0, None, Vec3::ONE);
        f.add(1, 0, 0, None, Vec3::splat(0.2));
        f.add(1, 0, 1, None, Vec3::splat(0.4));
        f.add(2, 0, 0, None, Vec3::splat(0.5));
        f.add(2, 0, 1, None, Vec3::NAN);
        assert_eq!(
            f.worst_pixels(),
            WorstPixels {
                nan: Some((2, 0, 1)),
                variance: Some((1, 0, 0)),
                brightest: Some((0, 0, 0)),
            }
        );
    }

    #[test]
    fn bad_samples_are_not_averaged() {
        let mut f = Film::new(2, 1);
        f.add(0, 0, 0, None, Vec3::ONE);
        f.add(0, 0, 1, None, Vec3::NAN);
        f.add(1, 0, 0, None, Vec3::INFINITY);
        assert_eq!(f.mean(0, 0), Vec3::ONE);
        assert_eq!(f.bad_count, 2);
        assert_eq!(
            f.bad[1],
            BadSample {
                x: 1,
                y: 0,
                sample: 0
            }
        );
    }

    #[test]
    fn the_error_is_unknown_below_two_samples() {
        let mut f = Film::new(2, 1);
        f.add(0, 0, 0, Some(3), Vec3::ONE);
        f.add(1, 0, 0, Some(5), Vec3::ZERO);
        assert_eq!(f.relative_error(), None);
        f.add(0, 0, 1, Some(7), Vec3::ZERO);
        assert_eq!(f.relative_error(), None, "one pixel still has one sample");
        f.add(1, 0, 1, Some(9), Vec3::ONE);
        assert!(f.relative_error().is_some_and(|e| e > 0.0));
        assert!(!f.error_is_meaningful());
    }

    /// Sample `k` of replicate pixel `p`: a stratum mean that varies over
    /// the pixel (`between`: an edge through it, plus a gradient) and noise
    /// within the stratum (`within`).
    fn sample(p: u64, k: u32, between: f64, within: f64) -> (u32, f64) {
        let s = pixel_stratum(p, k, 3);
        let mut r = Rng::for_sample(p, k as u64, 3);
        let (i, j) = ((s % 4) as f64, (s / 4) as f64);
        let x = (i + r.next_f32() as f64) / 4.0;
        let y = (j + r.next_f32() as f64) / 4.0;
        let edge = if x + 0.4 * y > 0.55 + 0.1 * (p % 7) as f64 / 7.0 {
            1.0
        } else {
            0.0
        };
        let v = between * (edge + 0.3 * y) + within * r.next_f32() as f64;
        (s, v)
    }

    /// The estimated variance of the mean against the variance of the means
    /// of many independently drawn pixels, for every mix of variance within
    /// and between strata, jittered or with a sample dropped.
    #[test]
    fn the_estimate_of_jittered_pixels_is_calibrated() {
        let reps = 6000;
        for (between, within) in [(1.0, 0.0), (1.0, 1.0), (0.0, 1.0), (0.2, 1.0)] {
            for n in [2u32, 3, 4, 5, 8, 12, 14, 16, 24, 32, 48, 64] {
                let mut means = Vec::with_capacity(reps);
                let mut est = 0.0;
                for p in 0..reps as u64 {
                    let mut px = PixelStats::default();
                    for k in 0..n {
                        let (s, v) = sample(p, k, between, within);
                        px.add(k, Vec3::splat(v as f32), Some(s));
                    }
                    means.push(px.mean.x);
                    est += px.mean_variance().unwrap() / reps as f64;
                }
                // The seven edge positions have different true means: the
                // variance is pooled within each.
                let truth = (0..7)
                    .map(|kind| {
                        let g: Vec<f64> = means.iter().skip(kind).step_by(7).copied().collect();
                        let m = g.iter().sum::<f64>() / g.len() as f64;
                        g.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (g.len() - 1) as f64
                    })
                    .sum::<f64>()
                    / 7.0;
                let ratio = (est / truth).sqrt();
                // Whole quarters of the first block: within (3 / (4 - q))^¼
                // by construction, plus an edge's contrast and sampling
                // noise. Else below a complete block the split is unknown:
                // within (16 / (16 - n))^¼ for strata in random order, and
                // quadrant-balanced ones make an edge's true error smaller,
                // so the estimate may be higher by up to 1.5. Whole blocks
                // are exact up to noise, and a tail after them is as it
                // would be in random order, or higher.
                let q = n / 4;
                let (low, high) = if n < 16 && n % 4 == 0 {
                    let a = (3.0 / (4.0 - q as f64)).powf(0.25) * 1.15;
                    (1.0 / a, a)
                } else if n < 16 {
                    let a = (16.0 / (16.0 - n as f64)).powf(0.25) * 1.08;
                    (1.0 / a, a.max(1.5))
                } else if n % 16 == 0 {
                    (1.0 / 1.12, 1.12)
                } else {
                    (1.0 / 1.12, 1.5)
                };
                assert!(
                    ratio <= high && ratio >= low,
                    "between {between} within {within}, {n} spp: estimate / true {ratio:.3}"
                );
            }
        }
    }

    /// A pixel's samples `range`, jittered, with some dropped.
    fn stats(range: std::ops::Range<u32>, drop: &[u32]) -> PixelStats {
        let mut px = PixelStats::default();
        for k in range.filter(|k| !drop.contains(k)) {
            let (s, v) = sample(7, k, 1.0, 1.0);
            px.add(k, Vec3::new(v as f32, 0.5 * v as f32, 1e-30), Some(s));
        }
        px
    }

    #[test]
    fn merged_ranges_equal_one_range() {
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1e-300);
        for drop in [&[][..], &[0, 5, 20, 47], &[9, 10, 11, 12, 13, 14, 15]] {
            let whole = stats(0..70, drop);
            for cuts in [
                vec![35],
                vec![9, 16],
                vec![3, 7, 11, 50],
                vec![1, 2, 3, 4, 5, 6],
                vec![16, 32, 48, 64],
                vec![10, 20, 30, 40, 50, 60],
            ] {
                let mut bounds = vec![0];
                bounds.extend(&cuts);
                bounds.push(70);
                let mut m = PixelStats::default();
                for w in bounds.windows(2) {
                    m.merge_stats(&stats(w[0]..w[1], drop));
                    m.mean = m.mean_of_sum();
                }
                let what = format!("drop {drop:?} cuts {cuts:?}");
                assert_eq!(m.sum, whole.sum, "{what}");
                assert_eq!(m.mean.to_array(), whole.mean.to_array(), "{what}");
                assert_eq!(
                    (m.n, m.blocks, m.open, m.head.n, m.tail.n),
                    (
                        whole.n,
                        whole.blocks,
                        whole.open,
                        whole.head.n,
                        whole.tail.n
                    ),
                    "{what}"
                );
                for (a, b) in [
                    (m.m2, whole.m2),
                    (m.block_mean, whole.block_mean),
                    (m.block_m2, whole.block_m2),
                    (m.checker, whole.checker),
                    (m.mean_variance().unwrap(), whole.mean_variance().unwrap()),
                ] {
                    assert!(close(a, b), "{what}: {a} vs {b}");
                }
            }
        }
    }

    /// The mean and Welford's M2 after each sample as their definitions
    /// give them (the casts and one division a channel), bit for bit.
    #[test]
    fn means_and_m2_are_those_of_the_definitions() {
        let mut z = 0x1234_5678_9abc_def1u64;
        let mut next = || {
            z ^= z << 13;
            z ^= z >> 7;
            z ^= z << 17;
            z
        };
        for len in [1usize, 2, 3, 5, 16, 17, 40] {
            let c: Vec<Vec3> = (0..len)
                .map(|_| {
                    Vec3::from_array([0; 3].map(|_| {
                        let r = next();
                        // Every magnitude, clamped ones among them.
                        f32::from_bits(r as u32 & 0x7fff_ffff).min(1e13)
                            * [1.0, -1.0][r as usize >> 63]
                    }))
                })
                .map(|c| if c.is_finite() { c } else { Vec3::splat(0.25) })
                .collect();
            let run: Vec<RowSample> = (0..len)
                .map(|k| RowSample {
                    x: 0,
                    k: k as u32,
                    c: c[k],
                    stratum: None,
                })
                .collect();
            let mut px = PixelStats::default();
            px.add_run(&run);
            assert_as_defined(&px, &c, &format!("{len}"));
        }
    }

    /// Asserts that `px` has the sums, mean and M2 the definitions (the
    /// casts and one division a channel) give for samples `c`, bit for bit.
    fn assert_as_defined(px: &PixelStats, c: &[Vec3], what: &str) {
        let (mut sum, mut m2, mut old) = ([0i128; 3], 0.0, 0.0);
        let mut mean = DVec3::ZERO;
        for (k, c) in c.iter().enumerate() {
            let q = c
                .to_array()
                .map(|x| (x.clamp(-FIXED_MAX, FIXED_MAX) as f64 * FIXED_ONE) as i128);
            for (s, q) in sum.iter_mut().zip(q) {
                *s += q;
            }
            let n = (k + 1) as f64;
            mean = DVec3::from_array(sum.map(|s| s as f64 / FIXED_ONE / n));
            let lum = DVec3::from_array(q.map(|q| q as f64 / FIXED_ONE)).dot(LUMA.as_dvec3());
            let lum_mean = mean.dot(LUMA.as_dvec3());
            m2 += (lum - old) * (lum - lum_mean);
            old = lum_mean;
        }
        assert_eq!(px.sum, sum, "{what}");
        assert_eq!(
            px.mean.to_array().map(f64::to_bits),
            mean.to_array().map(f64::to_bits),
            "{what}"
        );
        assert_eq!(px.m2.to_bits(), m2.to_bits(), "{what}");
    }

    /// A pixel's samples added in runs of any length hold the statistics
    /// of the same samples added one at a time, bit for bit.
    #[test]
    fn runs_of_samples_add_as_single_samples() {
        let samples: Vec<RowSample> = (0..70)
            .map(|k| {
                let (stratum, v) = sample(11, k, 1.0, 1.0);
                let c = Vec3::new(v as f32, 0.3 + 2.0 * v as f32, 1e-9 * k as f32);
                RowSample {
                    x: 0,
                    k,
                    c,
                    stratum: Some(stratum),
                }
            })
            .collect();
        for skip in [None, Some(5), Some(33)] {
            let kept: Vec<RowSample> = samples
                .iter()
                .filter(|s| Some(s.k) != skip)
                .copied()
                .collect();
            let mut one = PixelStats::default();
            for s in &kept {
                one.add(s.k, s.c, s.stratum);
            }
            for len in [2, 3, 7, 16, 17, 40, 70] {
                let mut runs = PixelStats::default();
                for run in kept.chunks(len) {
                    runs.add_run(run);
                }
                assert_eq!(format!("{runs:?}"), format!("{one:?}"), "{len} {skip:?}");
            }
        }
    }

    /// A fresh pixel's samples of one colour, added in runs, hold the
    /// statistics of the same samples added one at a time, bit for bit:
    /// colours of every kind (zero, negative, tiny, clamped), jittered or
    /// not, with a sample dropped, and runs followed by other colours.
    #[test]
    fn runs_of_one_colour_add_as_single_samples() {
        let colours = [
            Vec3::new(0.1, 0.2, 0.3),
            Vec3::ZERO,
            Vec3::new(-0.0, 0.0, -1.5),
            Vec3::new(-3.7e-13, 1e-30, 7.0),
            Vec3::new(3e38, -1e13, 0.999_999_9),
            Vec3::splat(f32::MIN_POSITIVE),
        ];
        for c in colours {
            for jittered in [false, true] {
                for skip in [None, Some(3), Some(17)] {
                    let kept: Vec<RowSample> = (0..40)
                        .filter(|&k| Some(k) != skip)
                        .map(|k| RowSample {
                            x: 0,
                            k,
                            // Past 32 samples the colour changes.
                            c: if k < 32 { c } else { Vec3::splat(0.4) },
                            stratum: jittered.then(|| sample(5, k, 1.0, 1.0).0),
                        })
                        .collect();
                    let mut one = PixelStats::default();
                    for s in &kept {
                        one.add(s.k, s.c, s.stratum);
                    }
                    for len in [1, 2, 5, 16, 17, 31, 32, 40] {
                        let mut runs = PixelStats::default();
                        for run in kept.chunks(len) {
                            runs.add_run(run);
                        }
                        let what = format!("{c} {jittered} {skip:?} {len}");
                        assert_eq!(format!("{runs:?}"), format!("{one:?}"), "{what}");
                        let c: Vec<Vec3> = kept.iter().map(|s| s.c).collect();
                        assert_as_defined(&runs, &c, &what);
                    }
                }
            }
        }
    }

    /// A summarised film holds the image and error estimate a film of
    /// statistics holds for the same samples, bit for bit, whatever the
    /// batches they come in, with samples dropped and pixels left empty.
    #[test]
    fn a_summarised_film_has_the_image_and_error_of_its_statistics() {
        for empty in [false, true] {
            summarised_like_statistics(empty);
        }
        // A pixel with one sample leaves the error unknown, and a film
        // whose pixels all rest on whole blocks is meaningful.
        for n in [1, 16] {
            let mut films = [Film::new(2, 1), Film::new_summary(2, 1)];
            for f in &mut films {
                let mut pixels = f.sample_into().0;
                let row: Vec<RowSample> = (0..2)
                    .flat_map(|x| {
                        (0..n).map(move |k| {
                            let (stratum, v) = sample(x as u64, k, 1.0, 1.0);
                            RowSample {
                                x,
                                k,
                                c: Vec3::splat(v as f32),
                                stratum: Some(stratum),
                            }
                        })
                    })
                    .collect();
                pixels.add(&row);
                pixels.finish();
            }
            assert_eq!(films[1].relative_error(), films[0].relative_error());
            assert_eq!(films[1].relative_error().is_some(), n > 1);
            assert_eq!(films[1].error_is_meaningful(), n == 16);
            assert_eq!(films[0].error_is_meaningful(), n == 16);
        }
    }

    /// See [`a_summarised_film_has_the_image_and_error_of_its_statistics`];
    /// with `empty`, pixel 1 of row 0 has only non-finite samples.
    fn summarised_like_statistics(empty: bool) {
        let (w, h, spp) = (5usize, 3usize, 19u32);
        let mut samples = Vec::new();
        for y in 0..h {
            let mut row = Vec::new();
            for x in 0..w as u32 {
                let p = (y * w) as u64 + x as u64;
                for k in 0..spp {
                    let (stratum, v) = sample(p, k, 1.0, 0.5);
                    // A few samples are not finite.
                    let bad = (empty && y == 0 && x == 1) || (p * 31 + k as u64).is_multiple_of(23);
                    let c = if bad {
                        Vec3::NAN
                    } else {
                        Vec3::new(v as f32, 0.5 + v as f32, 1e-3 * k as f32)
                    };
                    let stratum = (x % 2 == 0).then_some(stratum);
                    row.push(RowSample { x, k, c, stratum });
                }
            }
            samples.push(row);
        }
        for batch in [1, 7, 32, 1000] {
            let (w32, h32) = (w as u32, h as u32);
            let mut films = [Film::new(w32, h32), Film::new_summary(w32, h32)];
            for f in &mut films {
                for (mut pixels, row) in f.sample_into().0.rows(w).into_iter().zip(&samples) {
                    for b in row.chunks(batch) {
                        pixels.add(b);
                    }
                    pixels.finish();
                }
            }
            let [stats, summary] = &films;
            assert!(summary.is_summary() && !stats.is_summary());
            let bits = |f: &Film| {
                f.image()
                    .iter()
                    .map(|c| c.to_array().map(f32::to_bits))
                    .collect::<Vec<_>>()
            };
            assert_eq!(bits(summary), bits(stats), "batch {batch}");
            assert_eq!(summary.mean(3, 2), stats.mean(3, 2));
            let err = stats.estimated_rel_mse();
            assert_eq!(err.is_none(), empty);
            assert!(err.is_none_or(|e| e > 0.0));
            assert_eq!(
                summary.estimated_rel_mse().map(f64::to_bits),
                err.map(f64::to_bits)
            );
            assert_eq!(summary.report(), stats.report());
            assert!(!stats.error_is_meaningful());
            assert_eq!(summary.error_is_meaningful(), stats.error_is_meaningful());
            for (p, s) in stats.pixels().iter().zip(summary_pixels(summary)) {
                assert_eq!(*s, PixelSummary::of(p));
            }
        }
    }

    fn summary_pixels(f: &Film) -> &[PixelSummary] {
        match &f.pixels {
            Pixels::Summary(p) => p,
            _ => panic!("not summarised"),
        }
    }

    #[test]
    #[should_panic(expected = "keeps no statistics")]
    fn a_summarised_film_gives_no_statistics() {
        Film::new_summary(2, 2).pixels();
    }

    #[test]
    fn colour_sums_are_exact_and_clamped() {
        let mut px = PixelStats::default();
        px.add(0, Vec3::new(0.1, 3.0e38, -1.0), None);
        px.add(1, Vec3::new(0.2, 1.0, -1.0), None);
        assert_eq!(px.mean.x, (0.1f32 as f64 + 0.2f32 as f64) / 2.0);
        assert_eq!(px.mean.y, (FIXED_MAX as f64 + 1.0) / 2.0);
        assert_eq!(px.mean.z, -1.0);
    }

    #[test]
    fn a_dropped_sample_leaves_its_block_incomplete_and_the_estimate_sound() {
        let mut px = PixelStats::default();
        for k in (0..40).filter(|&k| k != 20) {
            let (s, v) = sample(1, k, 1.0, 1.0);
            px.add(k, Vec3::splat(v as f32), Some(s));
        }
        assert_eq!((px.blocks, px.open), (1, 15));
        assert_eq!(px.n, 39);
        assert!(px.mean_variance().unwrap() > 0.0);
    }
}
