//! Deterministic random numbers and sampling helpers.
//!
//! Every sample draws from a PCG32 stream seeded by a hash of (pixel, sample
//! index, seed), so images do not depend on thread scheduling and any single
//! sample can be replayed on its own.

use glam::{Vec2, Vec3};

/// PCG32 (O'Neill), XSH-RR output.
#[derive(Clone, Debug)]
pub struct Rng {
    state: u64,
    inc: u64,
}

/// SplitMix64 finaliser: a good 64-bit mix for seeding.
fn mix64(mut z: u64) -> u64 {
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    z ^ (z >> 31)
}

/// A number in [0, 1) drawn from `words` alone: the same words, the same
/// number.
pub(crate) fn unit_hash(words: impl IntoIterator<Item = u32>) -> f32 {
    let h = words
        .into_iter()
        .fold(0x9e37_79b9_7f4a_7c15, |h: u64, w| mix64(h ^ w as u64));
    // The top 24 bits: every value exact in f32, below 1.
    (h >> 40) as f32 / (1u64 << 24) as f32
}

impl Rng {
    /// The stream for one sample of one pixel.
    pub fn for_sample(pixel: u64, sample: u64, seed: u64) -> Self {
        PixelStreams::new(pixel, seed).sample(sample)
    }

    /// A stream for a sample that draws nothing (every sample of an exact
    /// render): fixed, where seeding one per sample would cost a few hashes.
    pub(crate) const fn unseeded() -> Self {
        Rng { state: 0, inc: 1 }
    }

    #[inline]
    pub fn next_u32(&mut self) -> u32 {
        let old = self.state;
        self.state = old
            .wrapping_mul(6_364_136_223_846_793_005)
            .wrapping_add(self.inc);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        let rot = (old >> 59) as u32;
        xorshifted.rotate_right(rot)
    }

    /// Uniform in [0, 1).
    #[inline]
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / 16_777_216.0)
    }

    #[inline]
    pub fn next_vec2(&mut self) -> Vec2 {
        let x = self.next_f32();
        Vec2::new(x, self.next_f32())
    }
}

/// What [`Rng::for_sample`] draws from the pixel and seed alone, made once
/// for a run of the pixel's samples.
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct PixelStreams {
    key: u64,
    inc: u64,
}

impl PixelStreams {
    pub(crate) fn new(pixel: u64, seed: u64) -> Self {
        let key = mix64(pixel ^ mix64(seed.wrapping_add(0x9e37_79b9_7f4a_7c15)));
        PixelStreams {
            key,
            inc: (mix64(key ^ 0x632b_e59b_d9b4_e019) << 1) | 1,
        }
    }

    /// The stream of sample `sample`.
    #[inline]
    pub(crate) fn sample(&self, sample: u64) -> Rng {
        let b = mix64(sample.wrapping_add(self.key));
        let mut r = Rng {
            state: 0,
            inc: self.inc,
        };
        r.next_u32();
        r.state = r.state.wrapping_add(b);
        r.next_u32();
        r
    }
}

/// Sub-pixel strata per side when pixel samples are jittered.
pub(crate) const PIXEL_GRID: u32 = 4;
/// Strata per pixel: each run of this many consecutive samples of a pixel
/// (a block) visits every stratum once.
pub(crate) const PIXEL_STRATA: u32 = PIXEL_GRID * PIXEL_GRID;

/// Samples in a quarter of a block: one in each quadrant of the pixel.
pub(crate) const QUARTER: u32 = PIXEL_STRATA / 4;

/// The stratum (`i + PIXEL_GRID * j`) of sample `k` of `pixel`: each block
/// of [`PIXEL_STRATA`] samples visits the strata once, and each quarter of
/// a block (samples `4q..4q + 4`) visits the pixel's four quadrants once, in
/// random orders per pixel and block. So any prefix is spread over the
/// pixel, and the first four samples already stratify it 2x2, which is what
/// lets a pixel's error be estimated from four samples (`render::film`).
/// The integrator and the film's error estimate read it through [`Run`];
/// this one-sample form is the definition the tests hold `Run` to.
#[cfg(test)]
pub(crate) fn pixel_stratum(pixel: u64, k: u32, seed: u64) -> u32 {
    stratum_of(block_order(pixel, k / PIXEL_STRATA, seed), k % PIXEL_STRATA)
}

/// What a run of samples of one pixel, under one seed, share: the
/// pixel's [`PixelStreams`] and the strata of its current block
/// (`pixel_stratum`), drawn once for the run, not once a sample.
#[derive(Clone, Copy, Debug, Default)]
pub struct Run {
    pixel: Option<u64>,
    streams: PixelStreams,
    /// The block of `order` and `strata`.
    block: Option<u32>,
    order: u32,
    /// The block's strata, drawn once a second of its samples asks: a pass
    /// of one sample per pixel draws only each sample's own.
    strata: Option<[u8; PIXEL_STRATA as usize]>,
}

impl Run {
    #[inline]
    fn at(&mut self, pixel: u64, seed: u64) {
        if self.pixel != Some(pixel) {
            *self = Run {
                pixel: Some(pixel),
                streams: PixelStreams::new(pixel, seed),
                ..Run::default()
            };
        }
    }

    /// [`Rng::for_sample`].
    #[inline]
    pub(crate) fn rng(&mut self, pixel: u64, k: u32, seed: u64) -> Rng {
        self.at(pixel, seed);
        self.streams.sample(k as u64)
    }

    /// `pixel_stratum`.
    #[inline]
    pub(crate) fn stratum(&mut self, pixel: u64, k: u32, seed: u64) -> u32 {
        self.at(pixel, seed);
        let (block, i) = (k / PIXEL_STRATA, k % PIXEL_STRATA);
        if self.block != Some(block) {
            self.block = Some(block);
            self.order = block_order(pixel, block, seed);
            self.strata = None;
            return stratum_of(self.order, i);
        }
        let order = self.order;
        self.strata.get_or_insert_with(|| block_strata(order))[i as usize] as u32
    }
}

/// The random order block `block` of `pixel`'s samples visits the strata
/// in.
fn block_order(pixel: u64, block: u32, seed: u64) -> u32 {
    Rng::for_sample(pixel, block as u64, seed ^ 0x5bd1_e995).next_u32()
}

/// The strata a block whose order is `order` visits, sample by sample:
/// each slot of a quarter visits a quadrant, in an order drawn per
/// quarter, and each quarter takes one of that quadrant's four strata, in
/// an order drawn per quadrant, so the block visits every stratum once.
fn block_strata(order: u32) -> [u8; PIXEL_STRATA as usize] {
    let quadrants: [[u8; 4]; 4] = std::array::from_fn(|quarter| draw4(order, quarter as u32));
    let subs: [[u8; 4]; 4] = std::array::from_fn(|quadrant| draw4(order, quadrant as u32 + 4));
    std::array::from_fn(|k| {
        let quarter = k / QUARTER as usize;
        let quadrant = quadrants[quarter][k % QUARTER as usize];
        in_quadrant(quadrant, subs[quadrant as usize][quarter]) as u8
    })
}

/// Entry `k` of [`block_strata`], drawing only the two permutations it
/// reads.
fn stratum_of(order: u32, k: u32) -> u32 {
    let quarter = k / QUARTER;
    let quadrant = draw4(order, quarter)[(k % QUARTER) as usize];
    in_quadrant(
        quadrant,
        draw4(order, quadrant as u32 + 4)[quarter as usize],
    )
}

/// Permutation `i` of a block whose order is `order`: slots `0..4` give
/// each quarter's quadrants, `4..8` each quadrant's strata.
#[inline]
fn draw4(order: u32, i: u32) -> [u8; 4] {
    permutation4(order ^ i.wrapping_mul(0x9e37_79b9))
}

/// Stratum `sub` (`0..4`) of quadrant `quadrant`, as a stratum of the pixel.
#[inline]
fn in_quadrant(quadrant: u8, sub: u8) -> u32 {
    let (quadrant, sub, half) = (quadrant as u32, sub as u32, PIXEL_GRID / 2);
    let i = (quadrant % 2) * half + sub % half;
    let j = (quadrant / 2) * half + sub / half;
    i + PIXEL_GRID * j
}

/// One of the 24 permutations of `0..4`, chosen by a hash of `seed`.
#[inline]
fn permutation4(seed: u32) -> [u8; 4] {
    // The finaliser of MurmurHash3: every bit of the seed moves the choice.
    let mut h = seed;
    h ^= h >> 16;
    h = h.wrapping_mul(0x85eb_ca6b);
    h ^= h >> 13;
    h = h.wrapping_mul(0xc2b2_ae35);
    h ^= h >> 16;
    PERMUTATIONS_OF_4[(h % 24) as usize]
}

/// The 24 permutations of `0..4`, permutation `c` the one whose Lehmer
/// code is `c` (its digits, least significant first, pick from what is
/// left).
const PERMUTATIONS_OF_4: [[u8; 4]; 24] = {
    let mut table = [[0u8; 4]; 24];
    let mut c = 0;
    while c < 24 {
        let mut left = [0u8, 1, 2, 3];
        let (mut code, mut len, mut i) = (c, 4, 0);
        while i < 4 {
            let d = code % len;
            code /= len;
            table[c][i] = left[d];
            let mut j = d;
            while j + 1 < len {
                left[j] = left[j + 1];
                j += 1;
            }
            len -= 1;
            i += 1;
        }
        c += 1;
    }
    table
};

/// The colour of stratum `s` on a checkerboard of the pixel's quadrants:
/// black (`true`) top-left and bottom-right.
pub(crate) fn quadrant_is_black(s: u32) -> bool {
    let half = PIXEL_GRID / 2;
    ((s % PIXEL_GRID) / half + (s / PIXEL_GRID) / half).is_multiple_of(2)
}

/// Stratum `k` of an `n x n` grid, jittered with `r`, in [0, 1)^2.
#[inline]
pub(crate) fn jittered(k: u32, n: u32, r: Vec2) -> Vec2 {
    let (i, j) = (k % n, k / n);
    ((Vec2::new(i as f32, j as f32) + r) / n as f32).min(Vec2::splat(1.0 - f32::EPSILON))
}

/// Orthonormal basis around a unit vector (Duff et al., JCGT 2017).
pub(crate) fn onb(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1.0f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// Direction from the normalised Phong lobe `(n+1)/(2π) cos^n α` around `axis`.
/// Returns the direction and its pdf.
pub(crate) fn phong_lobe(axis: Vec3, exponent: f32, r: Vec2) -> (Vec3, f32) {
    let cos_a = r.x.powf(1.0 / (exponent + 1.0));
    let sin_a = (1.0 - cos_a * cos_a).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * r.y;
    let (t, b) = onb(axis);
    let d = (t * (phi.cos() * sin_a) + b * (phi.sin() * sin_a) + axis * cos_a).normalize();
    let pdf = (exponent + 1.0) / std::f32::consts::TAU * cos_a.powf(exponent);
    (d, pdf)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn streams_are_deterministic_and_distinct() {
        let a: Vec<u32> = (0..4)
            .map(|_| Rng::for_sample(7, 3, 1).next_u32())
            .collect();
        assert!(a.windows(2).all(|w| w[0] == w[1]));
        assert_ne!(
            Rng::for_sample(7, 3, 1).next_u32(),
            Rng::for_sample(7, 4, 1).next_u32()
        );
        assert_ne!(
            Rng::for_sample(7, 3, 1).next_u32(),
            Rng::for_sample(8, 3, 1).next_u32()
        );
        assert_ne!(
            Rng::for_sample(7, 3, 1).next_u32(),
            Rng::for_sample(7, 3, 2).next_u32()
        );
    }

    #[test]
    fn uniform_mean_is_one_half() {
        let mut r = Rng::for_sample(1, 2, 3);
        let m: f64 = (0..100_000).map(|_| r.next_f32() as f64).sum::<f64>() / 100_000.0;
        assert!((m - 0.5).abs() < 0.005);
    }

    /// A run gives each sample the stratum `pixel_stratum` gives it, one
    /// sample of a block at a time (a pass of one sample per pixel) or
    /// several, and the whole block's table the one entry's draws make.
    #[test]
    fn runs_give_the_strata_pixel_stratum_gives() {
        for order in (0..2000u32).map(|i| i.wrapping_mul(0x9e37_79b9)) {
            let table = block_strata(order);
            for k in 0..PIXEL_STRATA {
                assert_eq!(stratum_of(order, k), table[k as usize] as u32);
            }
        }
        for pixel in 0..50u64 {
            let want: Vec<u32> = (0..40).map(|k| pixel_stratum(pixel, k, 9)).collect();
            let mut run = Run::default();
            let together: Vec<u32> = (0..40).map(|k| run.stratum(pixel, k, 9)).collect();
            assert_eq!(together, want);
            let alone: Vec<u32> = (0..40)
                .map(|k| Run::default().stratum(pixel, k, 9))
                .collect();
            assert_eq!(alone, want);
        }
    }

    #[test]
    fn blocks_visit_every_stratum_and_quarters_every_quadrant() {
        let mut orders = std::collections::HashSet::new();
        for pixel in 0..200u64 {
            for block in 0..3 {
                let ks = block * PIXEL_STRATA..(block + 1) * PIXEL_STRATA;
                let s: Vec<u32> = ks.map(|k| pixel_stratum(pixel, k, 7)).collect();
                let mut sorted = s.clone();
                sorted.sort_unstable();
                assert_eq!(sorted, (0..PIXEL_STRATA).collect::<Vec<_>>(), "{s:?}");
                for q in s.chunks(QUARTER as usize) {
                    let mut quadrants: Vec<u32> =
                        q.iter().map(|&t| (t % 4) / 2 + 2 * ((t / 4) / 2)).collect();
                    quadrants.sort_unstable();
                    assert_eq!(quadrants, [0, 1, 2, 3], "{s:?}");
                    assert_eq!(q.iter().filter(|&&t| quadrant_is_black(t)).count(), 2);
                }
                orders.insert(s);
            }
        }
        // Random orders: 600 blocks, hardly any alike.
        assert!(orders.len() > 590, "{} distinct orders", orders.len());
    }

    #[test]
    fn onb_is_orthonormal() {
        for n in [
            Vec3::Z,
            Vec3::NEG_Z,
            Vec3::new(0.3, -0.5, 0.8).normalize(),
            Vec3::X,
        ] {
            let (t, b) = onb(n);
            assert!(t.dot(b).abs() < 1e-6 && t.dot(n).abs() < 1e-6 && b.dot(n).abs() < 1e-6);
            assert!((t.length() - 1.0).abs() < 1e-5 && (b.length() - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn phong_lobe_integrates_to_one() {
        // E[1/pdf] over the lobe equals the solid angle where pdf > 0 ... instead
        // check the mean cosine against the analytic (n+1)/(n+2).
        let n = 20.0;
        let mut r = Rng::for_sample(0, 0, 9);
        let m: f64 = (0..50_000)
            .map(|_| phong_lobe(Vec3::Z, n, r.next_vec2()).0.z as f64)
            .sum::<f64>()
            / 50_000.0;
        assert!((m - (n as f64 + 1.0) / (n as f64 + 2.0)).abs() < 2e-3);
    }
}
