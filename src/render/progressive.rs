//! The one progressive loop: passes that each add samples to the pixels of
//! a [`Film`], until a [`Stop`] says enough. `render`, exports, `converge`,
//! `inspect`, the debug views, the benchmarks, the stability battery, the
//! TUI's worker and the tests all drive films through [`Progressive`].
//!
//! What the passes are for (the stop, the samples, what is read of the
//! film) is a [`Job`]'s, decided before the first: it makes the film, and
//! nothing here changes how the film keeps its pixels.
//!
//! A uniform pass gives every pixel the same sample indices. An adaptive
//! one ([`Job::adaptive`]), once every pixel has [`MIN_SPP`], raises
//! the mean spp and shares the samples in proportion to each pixel's
//! weight, predicted once from its neighbours' first quarters
//! ([`Allocation::weigh`]); each pixel's next sample index is its own
//! count. Either way results depend only on (pixel, sample index, seed),
//! never on threads: rows run in parallel, and what a pass gives a pixel is
//! decided before it starts.

use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;
use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;

use super::film::{Allocation, BadSample, Film, PixelStats, RowSample, Samples};
use super::integrator::SamplePoint;
use super::job::Job;
use crate::geometry::sampling::{Run, PIXEL_STRATA, QUARTER};
use crate::interrupt::Cancel;

/// Samples every pixel of an adaptive film gets before any decision: one
/// quarter of a block, a sample in each quadrant of the pixel, which also
/// makes every pixel's error estimate rest on its samples alone.
pub const MIN_SPP: u32 = QUARTER;
use super::recorder::{RayCounter, Recorder, WorkCounter};
use super::{Plan, Tracer};

/// When a progressive render ends: at whichever limit comes first. With
/// none set it runs until cancelled. A scene where nothing is sampled ends
/// after one pass whatever the limits, since that pass is exact.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Stop {
    /// Samples per pixel.
    pub spp: Option<u32>,
    /// Seconds of rendering; the pass in flight at the deadline stops there,
    /// between rows, except the first, which always completes.
    pub seconds: Option<f64>,
    /// The film's estimated relative error, once the estimate is meaningful.
    pub error: Option<f64>,
}

impl Stop {
    pub(crate) fn spp(n: u32) -> Self {
        Stop {
            spp: Some(n),
            ..Stop::default()
        }
    }

    pub(crate) fn seconds(t: f64) -> Self {
        Stop {
            seconds: Some(t),
            ..Stop::default()
        }
    }
}

/// Which limit ended a render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Ended {
    Spp,
    Time,
    Error,
    /// Nothing is sampled: one pass is the exact image.
    Exact,
    Cancelled,
}

/// One finished pass.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PassStats {
    /// Samples each pixel given any received.
    pub(crate) samples: u32,
    /// Pixels that received samples.
    pub(crate) pixels: u64,
    pub(crate) rays: u64,
    pub(crate) ms: f64,
}

impl PassStats {
    pub(crate) fn mrays_per_s(&self) -> f64 {
        self.rays as f64 / (self.ms.max(1e-6) * 1e3)
    }
}

/// A whole run of passes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outcome {
    pub(crate) ended: Ended,
    pub(crate) passes: u32,
    pub(crate) rays: u64,
    pub(crate) seconds: f64,
}

/// A film and the passes that made it, as its [`Job`] decided them.
#[derive(Clone, Debug)]
pub struct Progressive {
    film: Film,
    /// Rays traced and seconds spent in passes so far.
    rays: u64,
    seconds: f64,
    stop: Stop,
    /// Samples per pixel a pass adds (fewer when the stop leaves fewer);
    /// more than one keeps the per-pass overhead small on tiny images.
    samples_per_pass: u32,
    /// Counts the rows each pass finishes, for a progress readout.
    rows_done: Option<Arc<AtomicU32>>,
    /// Whether a uniform pass cut short (cancelled, or at the deadline) is
    /// undone, so that the film holds whole passes only: every pixel the
    /// same samples, as a checkpoint must. Each row is copied before it is
    /// sampled, which needs the film's statistics twice over.
    whole_passes: bool,
    /// Whether passes grow: after each pass, `samples_per_pass` becomes the
    /// film's mean samples per pixel (so the film doubles with each pass),
    /// at most `pass_cap`. The first passes stay short, for an early
    /// picture; later ones give a pixel enough samples to trace them in a
    /// packet ([`PACKET_SAMPLES`]) and spread the work each pass repeats
    /// (the image, the error estimate, the adaptive weights) over more
    /// samples. One sample per pixel per pass ran at half the rays per
    /// second of a one-pass render. To an error, once the estimate is
    /// meaningful, the pass is sized from it instead
    /// ([`Progressive::step_to_error`]).
    growing: bool,
    /// The most samples per pixel a growing pass gives: at most
    /// [`MAX_PASS_SPP`], less where a caller wants passes short (the TUI).
    pass_cap: u32,
    /// Whether the next pass was sized to the stop's error
    /// ([`Progressive::step_to_error`]).
    sized_to_error: bool,
    /// The mean an adaptive pass cut short was raising the film to: the
    /// next pass finishes it before raising it further, so that passes cut
    /// again and again (a key held down in the TUI) still reach the rows
    /// below, where each started the rows above anew.
    unfinished: Option<f64>,
}

/// What a render to an error aims its passes at, of the target: a little
/// under it, so that an estimate a little high after the pass does not
/// cost another.
const ERROR_AIM: f64 = 0.95;

/// The most pixels a pass sized to an error is predicted from: evenly
/// spaced through the film.
const PREDICTED_PIXELS: usize = 1 << 16;

/// No film yet: 0 x 0 pixels, before the first job.
impl Default for Progressive {
    fn default() -> Self {
        Self::of(
            Film::new(0, 0),
            (0, 0.0),
            Stop::default(),
            1,
            None,
            false,
            false,
        )
    }
}

/// The most samples per pixel a render read only for its image takes in
/// one pass (see [`Job::passes_for_stop`]): beyond, a row would keep a
/// cancel waiting too long.
pub(crate) const ONE_PASS_SPP: u32 = 256;

/// What a pass gives the pixels.
enum Give {
    /// `n` samples to every pixel, from the film's `spp`.
    All(u32),
    /// Samples to each pixel, from its own count.
    Each(Vec<u32>),
}

impl Progressive {
    /// The passes of `job`, into the film it made.
    pub(super) fn of(
        film: Film,
        (rays, seconds): (u64, f64),
        stop: Stop,
        samples_per_pass: u32,
        rows_done: Option<Arc<AtomicU32>>,
        whole_passes: bool,
        growing: bool,
    ) -> Self {
        Self {
            film,
            rays,
            seconds,
            stop,
            samples_per_pass,
            rows_done,
            whole_passes,
            growing,
            pass_cap: MAX_PASS_SPP,
            sized_to_error: false,
            unfinished: None,
        }
    }

    /// The film so far.
    pub fn film(&self) -> &Film {
        &self.film
    }

    /// The film, once its passes are done.
    pub fn into_film(self) -> Film {
        self.film
    }

    /// Rays traced in passes so far (a resumed film's included).
    pub(crate) fn rays(&self) -> u64 {
        self.rays
    }

    /// Seconds spent in passes so far (a resumed film's included).
    pub(crate) fn seconds(&self) -> f64 {
        self.seconds
    }

    /// Samples per pixel the next pass gives at most.
    pub(crate) fn samples_per_pass(&self) -> u32 {
        self.samples_per_pass
    }

    /// Caps the samples per pixel of the growing passes from here
    /// ([`Job::growing`]): the TUI keeps each pass within a frame's time at
    /// the last pass's pace.
    pub(crate) fn cap_passes(&mut self, cap: u32) {
        self.pass_cap = cap;
    }

    /// What the next pass gives each pixel; `None` when no pixel needs more.
    /// With it, the mean an adaptive pass raises the film to.
    fn give(&self) -> Option<(Give, Option<f64>)> {
        let cap = self.stop.spp.unwrap_or(u32::MAX);
        let f = &self.film;
        let Some(a) = &f.adaptive else {
            let n = uniform_pass(self.samples_per_pass, cap.saturating_sub(f.spp));
            return Some((Give::All(n), None));
        };
        if f.spp < MIN_SPP.min(cap) {
            let upto = MIN_SPP
                .min(cap)
                .min(f.spp.saturating_add(self.samples_per_pass.max(1)));
            let give = a.spp.iter().map(|&n| upto.saturating_sub(n)).collect();
            return Some((Give::Each(give), None));
        }
        let to = |mean: f64| {
            let counts = share(&a.weight, &a.ascending, mean, cap)?;
            let give: Vec<u32> = counts
                .iter()
                .zip(&a.spp)
                .map(|(&want, &has)| want.saturating_sub(has))
                .collect();
            give.iter().any(|&n| n > 0).then_some(give)
        };
        // A pass cut short is finished first: its rows done get nothing.
        if let Some(give) = self.unfinished.and_then(to) {
            return Some((Give::Each(give), self.unfinished));
        }
        // Each pass raises the mean by at least one sample, shared in
        // proportion to the weights.
        let step = self.samples_per_pass.max(1) as f64;
        let mut mean = f.spp_range().1;
        loop {
            mean = (mean + step).min(cap as f64);
            if let Some(give) = to(mean) {
                return Some((Give::Each(give), Some(mean)));
            }
            if mean >= cap as f64 || a.weight.is_empty() {
                return None;
            }
        }
    }

    /// Runs one pass of up to `samples_per_pass` samples (never past the
    /// stop's spp); `None` when `cancel` stopped it between rows.
    pub fn pass(&mut self, tracer: &Tracer, cancel: Cancel) -> Option<PassStats> {
        self.pass_with::<RayCounter>(tracer, cancel).map(|(p, _)| p)
    }

    /// As [`Progressive::pass`], with any counting recorder, whose counts of
    /// all rows are returned merged.
    pub(crate) fn pass_with<R: Recorder + Default + Send + Merge>(
        &mut self,
        tracer: &Tracer,
        cancel: Cancel,
    ) -> Option<(PassStats, R)> {
        let start = Instant::now();
        let (give, target) = self.give().unzip();
        let (samples, pixels) = match &give {
            Some(Give::All(n)) => (*n, self.film.pixels_len() as u64),
            Some(Give::Each(g)) => (
                g.iter().copied().max().unwrap_or(0),
                g.iter().filter(|&&n| n > 0).count() as u64,
            ),
            None => (0, 0),
        };
        if let Some(r) = &self.rows_done {
            r.store(0, Ordering::Relaxed);
        }
        let rows = self.rows_done.as_deref();
        let whole = self.whole_passes;
        let rec: R = match &give {
            Some(g) => sample_rows(tracer, &mut self.film, g, cancel, rows, whole),
            None => R::default(),
        };
        self.unfinished = target.flatten().filter(|_| cancel.is_set());
        if self.growing {
            let cap = self.pass_cap.clamp(1, MAX_PASS_SPP);
            let to_error = self.stop.error.and_then(|e| self.step_to_error(e, cap));
            self.sized_to_error = to_error.is_some();
            let mean = self.film.spp_range().1 as u32;
            self.samples_per_pass = to_error.unwrap_or(mean.clamp(1, cap));
        }
        let ms = start.elapsed().as_secs_f64() * 1e3;
        let rays = rec.rays();
        self.rays += rays;
        self.seconds += ms / 1e3;
        let stats = PassStats {
            samples,
            pixels,
            rays,
            ms,
        };
        (!cancel.is_set()).then_some((stats, rec))
    }

    /// Which limit of the stop the film has reached, if any; `elapsed` is
    /// the time the render has taken so far.
    pub(crate) fn finished(&self, plan: &Plan, elapsed: f64) -> Option<Ended> {
        let (f, stop) = (&self.film, &self.stop);
        if plan.deterministic && f.spp >= 1 {
            return Some(Ended::Exact);
        }
        if stop.spp.is_some_and(|n| f.spp >= n) {
            return Some(Ended::Spp);
        }
        // However short the time, the film gets one full pass: an image of
        // no samples is no render.
        if f.spp >= 1 && stop.seconds.is_some_and(|t| elapsed >= t) {
            return Some(Ended::Time);
        }
        // An adaptive film's error counts once every pixel has its first
        // blocks: they are what the later passes are decided on.
        let decided = f.adaptive.is_none() || f.spp >= MIN_SPP;
        if decided
            && stop.error.is_some_and(|e| {
                f.error_is_meaningful() && f.relative_error().is_some_and(|r| r < e)
            })
        {
            return Some(Ended::Error);
        }
        // An adaptive film with nothing to share by: its weights are made
        // by its own passes (every pixel at the cap ended it above).
        if f.spp >= MIN_SPP && f.adaptive.as_ref().is_some_and(|a| a.weight.is_empty()) {
            return Some(Ended::Spp);
        }
        None
    }

    /// Adds passes until the stop (or `cancel`); `on_pass` sees the film
    /// after each finished pass.
    pub fn run(
        &mut self,
        tracer: &Tracer,
        cancel: Cancel,
        mut on_pass: impl FnMut(&Film, &PassStats),
    ) -> Outcome {
        let start = Instant::now();
        let (rays, seconds) = (self.rays, self.seconds);
        // A time too long for the clock is no deadline at all.
        let deadline = self.stop.seconds.and_then(|t| {
            std::time::Duration::try_from_secs_f64(t)
                .ok()
                .and_then(|d| start.checked_add(d))
        });
        let past = || deadline.is_some_and(|d| Instant::now() >= d);
        let mut passes = 0;
        let ended = loop {
            if let Some(e) = self.finished(tracer.plan, start.elapsed().as_secs_f64()) {
                break e;
            }
            // The deadline never cuts the first pass (see `finished`).
            let first = self.film.spp == 0;
            if let Some(d) = deadline.filter(|_| self.growing && !first) {
                self.fill_half(d.saturating_duration_since(Instant::now()).as_secs_f64());
            }
            let stop_rows = || cancel.is_set() || (!first && past());
            let pass = self.pass(tracer, Cancel::When(&stop_rows));
            if cancel.is_set() {
                break Ended::Cancelled;
            }
            passes += 1;
            match pass {
                Some(p) => on_pass(&self.film, &p),
                None => break Ended::Time,
            }
        };
        Outcome {
            ended,
            passes,
            rays: self.rays - rays,
            seconds: self.seconds - seconds,
        }
    }

    /// Before a deadline `left` seconds away, lets the next growing pass
    /// take up to half that time at the pace so far, if that is more than
    /// doubling gives: fewer, larger passes trace a pixel's samples
    /// together, and a pass the deadline cuts keeps the rows it traced.
    fn fill_half(&mut self, left: f64) {
        let mean = self.film.spp_range().1;
        // A pass sized to the error already takes what the stop needs.
        if mean <= 0.0 || self.seconds <= 0.0 || self.sized_to_error {
            return;
        }
        let fit = (0.5 * left / (self.seconds / mean)).floor();
        let cap = self.pass_cap.clamp(1, MAX_PASS_SPP);
        self.samples_per_pass = self
            .samples_per_pass
            .max((fit.min(cap as f64)) as u32)
            .max(1);
    }

    /// The samples per pixel, in the mean, that the next pass adds to bring
    /// the film's estimated relative error to [`ERROR_AIM`] of `target`,
    /// were each pixel's variance of one sample what its estimate says now
    /// and the samples shared as [`Progressive::give`] shares them: at
    /// least one, at most `cap`; `None` until the estimate is meaningful
    /// (and on a summarised film, which takes no more passes). Doubling
    /// the film each pass instead took 1, 1, 2 and 4 samples per pixel
    /// where renders to an error end at 8, each pass a walk over the whole
    /// film, and overshot: the bunny at 1024x768 to 1 % ended at 0.33 %.
    fn step_to_error(&self, target: f64, cap: u32) -> Option<u32> {
        let f = &self.film;
        if f.is_summary() {
            return None;
        }
        // Each pixel's relative variance of one sample (of its mean, times
        // its samples) and its samples, of every `stride`th pixel, once
        // their estimates are meaningful: a prediction from all of a big
        // film's pixels took a tenth of the pass it sized.
        let len = f.pixels_len();
        let stride = len.div_ceil(PREDICTED_PIXELS).max(1);
        let has = |i: usize| f.adaptive.as_ref().map_or(f.spp, |a| a.spp[i]);
        let pixels = f.pixels();
        let one: Vec<(f64, u32, f32)> = (0..len)
            .step_by(stride)
            .map(|i| {
                let p = &pixels[i];
                let w = f.adaptive.as_ref().and_then(|a| a.weight.get(i)).copied();
                let n = has(i);
                let v = p.rel_variance().filter(|_| p.estimate_is_design_based());
                v.map(|v| (v * n as f64, n, w.unwrap_or(1.0)))
            })
            .collect::<Option<_>>()?;
        let n = one.len().max(1) as f64;
        let now: f64 = one
            .iter()
            .map(|&(v, h, _)| v / h.max(1) as f64)
            .sum::<f64>()
            / n;
        // Met already (where the whole film's estimate is not, a little
        // more).
        let goal = (ERROR_AIM * target).powi(2);
        if now <= goal {
            return Some(1);
        }
        let mean = f.spp_range().1;
        // An estimate from quarters of a block cannot see what a whole
        // block's strata gain: it foresaw twice the samples renders to an
        // error at 160x96 needed. So a film below a block goes to one first.
        let cap = if mean < PIXEL_STRATA as f64 {
            cap.min(PIXEL_STRATA - mean as u32)
        } else {
            cap
        };
        let limit = self.stop.spp.unwrap_or(u32::MAX);
        let weighted = f.adaptive.as_ref().is_some_and(|a| !a.weight.is_empty());
        // The estimated relMSE once the pass has added `step` in the mean.
        let after = |step: u32| -> f64 {
            let to = (mean + step as f64).min(limit as f64);
            let c = f
                .adaptive
                .as_ref()
                .and_then(|a| scale(&a.ascending, to, limit))
                .filter(|_| weighted);
            let sum: f64 = one
                .iter()
                .map(|&(v, h, w)| {
                    let k = c.map_or(to, |c| count(c, w, limit));
                    v / k.max(h as f64).max(1.0)
                })
                .sum();
            sum / n
        };
        if after(cap) > goal {
            return Some(cap);
        }
        // The fewest samples that reach the goal, by bisection.
        let (mut lo, mut hi) = (0, cap);
        while hi - lo > 1 {
            let mid = lo + (hi - lo) / 2;
            if after(mid) > goal {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(hi)
    }

    /// Traces the samples the film holds again from each pixel's `from`th
    /// on (0: all of them), in one pass into a scratch film that keeps
    /// what a one-shot render to an image keeps (each pixel's mean and
    /// error, [`Film::new_summary`]), each pixel's samples together, as
    /// `render --spp N` traces them: the rate the passes that took them are
    /// measured against. The samples, and so the rays, are the same; only
    /// the passes differ.
    pub(crate) fn retrace(&self, tracer: &Tracer, from: u32) -> PassStats {
        let f = &self.film;
        let give = match &f.adaptive {
            Some(a) => Give::Each(a.spp.iter().map(|&n| n.saturating_sub(from)).collect()),
            None => Give::All(f.spp.saturating_sub(from)),
        };
        let mut scratch = Film::new_summary(f.width, f.height);
        scratch.start = f.start + from;
        let start = Instant::now();
        let rec: RayCounter = sample_rows(tracer, &mut scratch, &give, Cancel::Never, None, false);
        PassStats {
            samples: f.spp_range().2.saturating_sub(from),
            pixels: f.pixels_len() as u64,
            rays: rec.rays(),
            ms: start.elapsed().as_secs_f64() * 1e3,
        }
    }

    /// Runs to `spp` samples per pixel, uncancellable: for tests and tools.
    pub fn render(tracer: &Tracer, spp: u32) -> Film {
        let mut p = Job::of(tracer, Stop::spp(spp)).start();
        p.run(tracer, Cancel::Never, |_, _| {});
        p.film
    }
}

/// The samples per pixel a uniform pass gives, of `per_pass` asked and
/// `left` before the stop's spp: at least one.
pub(super) fn uniform_pass(per_pass: u32, left: u32) -> u32 {
    per_pass.clamp(1, left.max(1))
}

/// Each pixel's sample count for a film of at least `mean` samples per
/// pixel that minimises its relMSE: counts in proportion to the weights (a
/// pixel's squared error is its weight² over its count), rounded up to
/// whole quarters of a block below a block and to whole blocks above, none
/// below [`MIN_SPP`] or above `cap` (so all at `cap` for a `mean` of
/// `cap`); `None` without weights. `ascending` holds the same weights in
/// ascending order.
fn share(weight: &[f32], ascending: &[f32], mean: f64, cap: u32) -> Option<Vec<u32>> {
    let c = scale(ascending, mean, cap)?;
    Some(weight.iter().map(|&w| count(c, w, cap) as u32).collect())
}

/// A pixel's count in [`share`] at scale `c`: `c` times its weight, rounded
/// up to whole quarters of a block below a block and to whole blocks
/// above (a quarter cut short keeps part of the variance between the
/// quadrants that a whole one cancels, and a block cut short part of that
/// between its strata), within [`MIN_SPP`] and `cap`.
fn count(c: f64, w: f32, cap: u32) -> f64 {
    let n = c * w as f64;
    let unit = if n <= PIXEL_STRATA as f64 {
        QUARTER
    } else {
        PIXEL_STRATA
    } as f64;
    ((n / unit).ceil() * unit).clamp(MIN_SPP.min(cap) as f64, cap as f64)
}

/// The scale at which the counts of [`share`] have the mean `mean`, from
/// the weights in ascending order; `None` without weights.
fn scale(ascending: &[f32], mean: f64, cap: u32) -> Option<f64> {
    let count = |c: f64, w: f32| count(c, w, cap);
    let (&heaviest, n) = (ascending.last()?, ascending.len() as f64);
    // The counts' mean: summed pixel by pixel, or, where there are fewer
    // distinct counts than pixels by far (a big image), one step per
    // distinct count: a count grows with the weight, so every pixel from the
    // lightest not yet counted up has at least that one's count. Both sum
    // the same whole numbers exactly.
    let mean_at = |c: f64| {
        let most = count(c, heaviest);
        let steps = QUARTER as f64 + (most - PIXEL_STRATA as f64).max(0.0) / PIXEL_STRATA as f64;
        if steps * n.log2() > n {
            return ascending.iter().map(|&w| count(c, w)).sum::<f64>() / n;
        }
        let (mut total, mut below, mut i) = (0.0, 0.0, 0);
        while let Some(&w) = ascending.get(i) {
            let k = count(c, w);
            total += (k - below) * (ascending.len() - i) as f64;
            below = k;
            i += ascending[i..].partition_point(|&w| count(c, w) <= k);
        }
        total / n
    };
    // The scale whose counts have the mean, by bisection on its exponent:
    // 24 steps find it to within 1e-5, finer than a block's rounding.
    let (mut a, mut b) = (-64.0f64, 64.0f64);
    for _ in 0..24 {
        let m = 0.5 * (a + b);
        if mean_at(m.exp2()) < mean {
            a = m;
        } else {
            b = m;
        }
    }
    Some(b.exp2())
}

/// Samples placed and their camera rays made ahead of tracing them (see
/// [`Tracer::place`]): enough to overlap their arithmetic and fill a
/// packet ([`crate::bvh::PACKET_RAYS`]), few enough to stay in the L1
/// cache.
const CAMERA_BATCH: usize = crate::bvh::PACKET_RAYS;

/// A pixel's camera rays walk the tree as one packet when a batch holds at
/// least this many of its samples (a block's worth), else one by one.
///
/// A packet's frustum is then one pixel wide. The rays of several pixels
/// (a pass of one sample per pixel puts 64 pixels of a row in a batch) make
/// a frustum wide enough to hold thousands of a dense mesh's triangles, and
/// its walk visits every leaf that any of its rays might reach: on a mesh of
/// 4.2 million triangles at 160x96 pixels, 130 thousand rays a second
/// against 2.6 million one by one. Within a pixel the rays share most
/// nodes: 16 or more of them walk faster together than alone where a pixel
/// holds a few triangles (1.1x to 1.2x the rays a second on the bunny),
/// and take 0.85x to 0.95x where it holds hundreds (`teapot:256` at
/// 160x96 and 16 spp) or where reflections are most of the rays
/// (`mirrors`); see BENCHMARKS.md.
pub(crate) const PACKET_SAMPLES: u32 = PIXEL_STRATA;

/// The most samples per pixel a growing pass gives ([`Job::growing`]):
/// four packets of one pixel's samples. A pixel's samples traced back to
/// back share what the caches hold of its part of the tree: on
/// `teapot:256` at 160x96, passes of 64 traced at 0.75x the rate of the
/// same samples in one pass, passes of 256 at 0.86x (BENCHMARKS.md).
pub(crate) const MAX_PASS_SPP: u32 = 4 * crate::bvh::PACKET_RAYS as u32;

/// One row of a film, with its sample counts when adaptive.
struct Row<'a> {
    y: usize,
    pixels: Samples<'a>,
    spp: Option<&'a mut [u32]>,
    /// Rays per pixel, while an adaptive film counts them.
    rays: Option<&'a mut [u32]>,
}

/// Adds what `give` says to the pixels of `film`, kept as the film keeps
/// them, rows in parallel; `cancel` is polled between rows and `rows_done`
/// counts finished rows. With `whole`, a pass cut short leaves a uniform
/// film as it was.
fn sample_rows<R: Recorder + Default + Send + Merge>(
    tracer: &Tracer,
    film: &mut Film,
    give: &Give,
    cancel: Cancel,
    rows_done: Option<&AtomicU32>,
    whole: bool,
) -> R {
    let whole = whole && film.adaptive.is_none();
    let tracer = &Tracer {
        cancel,
        ..tracer.clone()
    };
    let w = (film.width as usize).max(1);
    let first = film.start + film.spp;
    let (pixels, spp) = film.sample_into();
    let rows: Vec<Row> = match spp {
        None => pixels
            .rows(w)
            .into_iter()
            .enumerate()
            .map(|(y, pixels)| Row {
                y,
                pixels,
                spp: None,
                rays: None,
            })
            .collect(),
        Some((spp, rays)) => {
            // Rays are counted until the weights are made, then not kept.
            let rays = rays
                .chunks_mut(w)
                .map(Some)
                .chain(std::iter::repeat_with(|| None));
            pixels
                .rows(w)
                .into_iter()
                .zip(spp.chunks_mut(w))
                .zip(rays)
                .enumerate()
                .map(|(y, ((pixels, spp), rays))| Row {
                    y,
                    pixels,
                    spp: Some(spp),
                    rays,
                })
                .collect()
        }
    };
    let results: Vec<(R, Vec<BadSample>, bool, Vec<PixelStats>)> = rows
        .into_par_iter()
        // Rows one job each: rows through the scene cost many times those
        // of the background, and a run of rows that rayon no longer splits
        // once a thread has begun it left the other idle for up to a tenth
        // of a frame at the end.
        .with_max_len(1)
        .map(|mut row| {
            let mut rec = R::default();
            let mut bad = Vec::new();
            if cancel.is_set() {
                row.pixels.skipped();
                return (rec, bad, false, Vec::new());
            }
            // What a row cut short goes back to: kept for the film where
            // whole passes are undone, else in the thread's scratch (a new
            // row each time was a fresh, page-faulted allocation: a tenth of
            // a render to an error at 1024x768).
            let mut before = if whole {
                Vec::new()
            } else {
                ROW_SCRATCH.take()
            };
            before.clear();
            if let Samples::Stats(p) = &row.pixels {
                before.extend_from_slice(p);
            }
            let rays_before = row.rays.as_deref().map(<[u32]>::to_vec);
            let y = row.y as u32;
            let give_of = |x: usize| match give {
                Give::All(n) => (first, *n),
                Give::Each(g) => (row.spp.as_ref().map_or(first, |s| s[x]), g[row.y * w + x]),
            };
            let width = row.pixels.len();
            let pixels = &mut row.pixels;
            let mut ray_counts = row.rays.as_deref_mut();
            let mut rays = Vec::with_capacity(CAMERA_BATCH);
            // Camera rays share the eye: the plan has them traced in packets
            // where the recorder's traversal is the plain one, a pixel's
            // samples together (see `PACKET_SAMPLES`).
            let packets = tracer.plan.packets && R::PLAIN_TRAVERSAL;
            let mut hits = [None; CAMERA_BATCH];
            let mut packed = [false; CAMERA_BATCH];
            let mut colours = Vec::with_capacity(CAMERA_BATCH);
            let mut trace = |placed: &mut Vec<(u32, SamplePoint)>| {
                rays.clear();
                tracer.camera_rays(placed.iter().map(|(_, p)| p), &mut rays);
                let hits = &mut hits[..rays.len()];
                let packed = &mut packed[..rays.len()];
                packed.fill(false);
                let mut a = 0;
                while packets && a < rays.len() {
                    let x = placed[a].1.x;
                    let b = a + placed[a..].iter().take_while(|q| q.1.x == x).count();
                    if b - a >= PACKET_SAMPLES as usize {
                        tracer.bvh.intersect_packet(&rays[a..b], &mut hits[a..b]);
                        packed[a..b].fill(true);
                    }
                    a = b;
                }
                let each = placed
                    .drain(..)
                    .zip(&rays)
                    .zip(hits.iter().zip(packed.iter()));
                for (((k, p), ray), (hit, &packed)) in each {
                    let (x, stratum) = (p.x, p.stratum);
                    let traced = rec.rays();
                    let c: Vec3 = if packed {
                        tracer.sample_from_hit(p, ray, *hit, &mut rec)
                    } else {
                        tracer.sample_from(p, ray, &mut rec)
                    };
                    if let Some(r) = ray_counts.as_deref_mut() {
                        let n = (rec.rays() - traced).min(u32::MAX as u64) as u32;
                        r[x as usize] = r[x as usize].saturating_add(n);
                    }
                    if !c.is_finite() {
                        bad.push(BadSample { x, y, sample: k });
                    }
                    colours.push(RowSample { x, k, c, stratum });
                }
                pixels.add(&colours);
                colours.clear();
            };
            let mut placed = Vec::with_capacity(CAMERA_BATCH);
            let mut run = Run::default();
            // A row can hold all of a one-pass render's samples (up to
            // `ONE_PASS_SPP`), and a sample thousands of hits: too long to
            // make a cancel wait for. `cancel` is polled between pixels of
            // several samples, every 64 pixels of one (a poll a sample cost
            // an exact frame 3 %), and by the tracer within a sample; a row
            // it cuts goes back to what it was, a lean film's to no sample,
            // and nothing is read of a summarised one.
            let mut cut = false;
            for x in 0..width {
                let (k0, n) = give_of(x);
                if (n > 1 || x % 64 == 0) && cancel.is_set() {
                    cut = true;
                    break;
                }
                for k in k0..k0 + n {
                    placed.push((k, tracer.place(x as u32, y, k, &mut run)));
                    if placed.len() == CAMERA_BATCH {
                        trace(&mut placed);
                    }
                }
            }
            if !cut {
                trace(&mut placed);
            }
            if cut || cancel.is_set() {
                match &mut row.pixels {
                    Samples::Stats(p) => p.copy_from_slice(&before),
                    other => other.skipped(),
                }
                if let (Some(r), Some(b)) = (row.rays.as_deref_mut(), &rays_before) {
                    r.copy_from_slice(b);
                }
                return (rec, bad, false, Vec::new());
            }
            row.pixels.finish();
            if let (Some(s), Give::Each(g)) = (&mut row.spp, give) {
                for (x, s) in s.iter_mut().enumerate() {
                    *s += g[row.y * w + x];
                }
            }
            if let Some(r) = rows_done {
                r.fetch_add(1, Ordering::Relaxed);
            }
            if whole {
                return (rec, bad, true, before);
            }
            ROW_SCRATCH.set(before);
            (rec, bad, true, Vec::new())
        })
        .collect();
    let cut = results.iter().any(|r| !r.2);
    if whole && cut {
        for (row, r) in film.pixels_mut().chunks_mut(w).zip(&results) {
            if r.2 {
                row.copy_from_slice(&r.3);
            }
        }
    }
    match (&film.adaptive, give) {
        (Some(a), _) => {
            film.spp = a.spp.iter().copied().min().unwrap_or(0);
            // Weighed once, when every pixel has its first quarter and no
            // pixel anything more: no later sample ever moves a weight.
            if a.weight.is_empty() && film.spp >= MIN_SPP {
                let weight = Allocation::weigh(film.pixels(), &a.rays, film.width);
                if let Some(a) = &mut film.adaptive {
                    a.ascending = weight.clone();
                    a.ascending.sort_by(f32::total_cmp);
                    a.weight = weight;
                    a.rays = Vec::new();
                }
            }
        }
        // A pass cut between rows leaves `spp` at what every pixel has.
        (None, Give::All(n)) if !cut => film.spp += n,
        _ => {}
    }
    let mut total = R::default();
    for (rec, bad, ..) in results {
        total.merge(&rec);
        if whole && cut {
            continue;
        }
        for b in bad {
            film.record_bad(b);
        }
    }
    total
}

thread_local! {
    /// A row's statistics before its pass, reused from row to row.
    static ROW_SCRATCH: std::cell::Cell<Vec<PixelStats>> = const { std::cell::Cell::new(Vec::new()) };
}

/// Recorders that can be summed across rows.
pub(crate) trait Merge {
    fn merge(&mut self, other: &Self);
    fn rays(&self) -> u64;
}

impl Merge for RayCounter {
    fn merge(&mut self, o: &Self) {
        self.rays += o.rays;
    }
    fn rays(&self) -> u64 {
        self.rays
    }
}

impl Merge for WorkCounter {
    fn merge(&mut self, o: &Self) {
        self.rays += o.rays;
        self.work += o.work;
    }
    fn rays(&self) -> u64 {
        self.rays
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::session::{SceneRequest, Session};
    use crate::render::{Feature, Needs};

    fn session(off: &[Feature]) -> Session {
        session_of("cornell-area", off)
    }

    fn session_of(spec: &str, off: &[Feature]) -> Session {
        let mut req = SceneRequest::new(spec);
        req.size = Some((12, 8));
        req.features = req.features.without(off);
        Session::open(&req).unwrap().0
    }

    /// To a time, a growing pass may take half the time left at the pace
    /// so far (never less than doubling gives, never more than the cap).
    #[test]
    fn a_pass_to_a_time_takes_up_to_half_the_time_left() {
        let s = session(&[]);
        let t = s.tracer();
        let stop = Stop {
            seconds: Some(60.0),
            ..Stop::default()
        };
        let mut p = Job::of(&t, stop).growing().start();
        p.pass(&t, Cancel::Never).unwrap();
        assert_eq!((p.film.spp, p.samples_per_pass), (1, 1));
        // A pace of a tenth of a second a sample per pixel.
        p.seconds = 0.1;
        p.fill_half(2.0);
        assert_eq!(p.samples_per_pass, 10);
        // Less time left than doubling needs: doubling's size stays.
        p.fill_half(0.01);
        assert_eq!(p.samples_per_pass, 10);
        p.fill_half(1e6);
        assert_eq!(p.samples_per_pass, MAX_PASS_SPP);
    }

    /// To an error, the first pass gives every pixel the samples of a
    /// meaningful estimate, and the next is sized to bring the estimate to
    /// the target, as though each pixel's variance of one sample were
    /// what it is estimated to be.
    #[test]
    fn a_pass_to_an_error_is_sized_from_the_estimate() {
        let s = session(&[]);
        let t = s.tracer();
        let start = |target: f64| {
            let stop = Stop {
                error: Some(target),
                ..Stop::default()
            };
            let mut p = Job::of(&t, stop).passes_for_stop().start();
            p.pass(&t, Cancel::Never).unwrap();
            p
        };
        // A target about two and a half times the first pass's samples
        // away (the first pass is the same whatever the target).
        let e2 = start(1.0).film.estimated_rel_mse().unwrap();
        let target = 0.7 * e2.sqrt();
        let mut p = start(target);
        assert_eq!(p.film.spp, MIN_SPP);
        assert!(p.film.error_is_meaningful());
        // relMSE falls as 1 / spp on a uniform film: the fewest samples
        // that bring it under the aim.
        let aim = (ERROR_AIM * target).powi(2);
        let n = MIN_SPP as f64;
        let want = ((n * e2 / aim - n).ceil() as u32).clamp(1, MAX_PASS_SPP);
        let step = p.samples_per_pass;
        assert!(want.abs_diff(step) <= 1, "step {step}, predicted {want}");
        // The same when asked directly, and one sample once the aim is met.
        assert_eq!(p.step_to_error(target, MAX_PASS_SPP), Some(step));
        let met = e2.sqrt() * 1.01 / ERROR_AIM;
        assert_eq!(p.step_to_error(met, MAX_PASS_SPP), Some(1));
        // A target further than a block away: a block first.
        let far = 0.2 * e2.sqrt();
        assert_eq!(
            p.step_to_error(far, MAX_PASS_SPP),
            Some(PIXEL_STRATA - MIN_SPP)
        );
        let mut seen = Vec::new();
        let o = p.run(&t, Cancel::Never, |f, _| seen.push(f.spp));
        assert_eq!(o.ended, Ended::Error);
        assert!(p.film.relative_error().unwrap() < target);
        assert!(seen.len() <= 2, "passes after the first: {seen:?}");
        // An adaptive film's pass, shared by the weights, is predicted the
        // same way and reaches the target as soon.
        let stop = Stop {
            error: Some(target),
            ..Stop::default()
        };
        let mut p = Job::of(&t, stop).passes_for_stop().adaptive(true).start();
        let mut seen = Vec::new();
        let o = p.run(&t, Cancel::Never, |f, _| seen.push(f.spp_range()));
        assert_eq!(o.ended, Ended::Error);
        assert!(p.film.relative_error().unwrap() < target);
        assert!(seen.len() <= 3, "passes: {seen:?}");
        assert_eq!(seen[0].1, MIN_SPP as f64);
    }

    /// An adaptive pass cut short is finished by the next before the mean
    /// rises: the rows it did get nothing more, the others their share.
    #[test]
    fn a_cut_adaptive_pass_is_finished_before_the_mean_rises() {
        let s = session(&[]);
        let t = s.tracer();
        let done = std::sync::Arc::new(AtomicU32::new(0));
        let mut p = Job::of(&t, Stop::default())
            .adaptive(true)
            .passes_of(MIN_SPP)
            .rows_done(done.clone())
            .start();
        p.pass(&t, Cancel::Never).unwrap();
        let counts = |p: &Progressive| p.film.adaptive.as_ref().unwrap().spp.clone();
        let before = counts(&p);
        let cut = || done.load(Ordering::Relaxed) >= 2;
        assert!(p.pass(&t, Cancel::When(&cut)).is_none());
        let mid = counts(&p);
        p.pass(&t, Cancel::Never).unwrap();
        let after = counts(&p);
        let rows = |c: &[u32]| c.chunks(12).map(<[u32]>::to_vec).collect::<Vec<_>>();
        let (before, mid, after) = (rows(&before), rows(&mid), rows(&after));
        let cut_rows: Vec<usize> = (0..8).filter(|&y| mid[y] != before[y]).collect();
        assert!(!cut_rows.is_empty() && cut_rows.len() < 8, "{cut_rows:?}");
        let mut gained = 0;
        for y in 0..8 {
            if cut_rows.contains(&y) {
                assert_eq!(after[y], mid[y], "row {y} was done");
            } else {
                gained += after[y].iter().sum::<u32>() - mid[y].iter().sum::<u32>();
            }
        }
        assert!(gained > 0);
    }

    #[test]
    fn runs_to_the_spp_in_passes_of_the_asked_size() {
        let s = session(&[]);
        let t = s.tracer();
        let mut p = Job::of(&t, Stop::spp(7)).passes_of(3).start();
        let mut seen = Vec::new();
        let o = p.run(&t, Cancel::Never, |f, pass| {
            seen.push((f.spp, pass.samples))
        });
        assert_eq!(seen, [(3, 3), (6, 3), (7, 1)]);
        assert_eq!((o.ended, o.passes, p.film.spp), (Ended::Spp, 3, 7));
        assert!(o.rays > 0 && o.rays == p.rays);
    }

    #[test]
    fn exact_scenes_stop_after_one_pass() {
        let s = session(&[Feature::Supersampling, Feature::SoftShadows]);
        let t = s.tracer();
        let mut p = Job::of(&t, Stop::spp(50)).start();
        let o = p.run(&t, Cancel::Never, |_, _| {});
        assert_eq!((o.ended, p.film.spp), (Ended::Exact, 1));
    }

    /// The lean film of an exact render holds what a film of statistics
    /// would.
    #[test]
    fn an_exact_render_keeps_its_samples_and_nothing_is_lost() {
        let s = session(&[Feature::Supersampling, Feature::SoftShadows]);
        let t = s.tracer();
        let lean = Progressive::render(&t, 1);
        assert!(lean.is_exact());
        // A checkpointed render keeps statistics from the start.
        let mut full = Job::of(&t, Stop::spp(1)).needs(Needs::WholePasses).start();
        full.run(&t, Cancel::Never, |_, _| {});
        assert!(!full.film.is_exact());
        assert_eq!(lean.image(), full.film.image());
        assert_eq!(lean.report(), full.film.report());
        let stats = |f: &Film| format!("{:?}", f.pixels());
        assert_eq!(stats(&lean), stats(&full.film));
        assert_eq!(lean.mean(5, 3), full.film.mean(5, 3));
    }

    /// Rows a cancelled exact pass leaves out hold no sample, the others
    /// one each.
    #[test]
    fn rows_an_exact_pass_leaves_out_have_no_sample() {
        let s = session(&[Feature::Supersampling, Feature::SoftShadows]);
        let t = s.tracer();
        let done = std::sync::Arc::new(AtomicU32::new(0));
        let mut p = Job::of(&t, Stop::spp(1)).rows_done(done.clone()).start();
        let cancel = || done.load(Ordering::Relaxed) >= 2;
        assert!(p.pass(&t, Cancel::When(&cancel)).is_none());
        assert!(p.film.is_exact());
        let rows: Vec<u32> = p.film.pixels().chunks(12).map(|row| row[0].n).collect();
        for (row, &n) in p.film.pixels().chunks(12).zip(&rows) {
            assert!(row.iter().all(|px| px.n == n), "{rows:?}");
        }
        let sampled = rows.iter().filter(|&&n| n == 1).count();
        assert!(sampled > 0 && sampled < 8, "{rows:?}");
        assert!(rows.iter().all(|&n| n <= 1), "{rows:?}");
    }

    #[test]
    fn time_and_cancel_end_a_run() {
        let s = session(&[]);
        let t = s.tracer();
        let mut p = Job::of(&t, Stop::seconds(0.05)).start();
        let o = p.run(&t, Cancel::Never, |_, _| {});
        assert_eq!(o.ended, Ended::Time);
        assert!(o.seconds < 1.0, "{}", o.seconds);
        let mut p = Job::of(&t, Stop::default())
            .resume(p.into_film(), 0, 0.0)
            .start();
        let o = p.run(&t, Cancel::When(&|| true), |_, _| {});
        assert_eq!(o.ended, Ended::Cancelled);
        // A time too short for anything still gives one full pass.
        let mut p = Job::of(&t, Stop::seconds(1e-12)).start();
        let o = p.run(&t, Cancel::Never, |_, _| {});
        assert_eq!((o.ended, o.passes, p.film.spp), (Ended::Time, 1, 1));
        assert!(p.film.pixels().iter().all(|px| px.n == 1));
    }

    /// Under a cap that is no whole number of quarters, adaptive passes go on
    /// until every pixel has the cap, and the counts' mean grows by at
    /// least the step each pass.
    #[test]
    fn adaptive_passes_fill_up_to_the_cap() {
        let s = session(&[]);
        let t = s.tracer();
        let stop = Stop {
            spp: Some(42),
            seconds: Some(1e9),
            error: None,
        };
        let mut p = Job::of(&t, stop).adaptive(true).passes_of(16).start();
        let mut means = Vec::new();
        let o = p.run(&t, Cancel::Never, |f, _| means.push(f.spp_range().1));
        assert_eq!(o.ended, Ended::Spp);
        assert_eq!(p.film.spp_range(), (42, 42.0, 42));
        assert!(
            means.windows(2).all(|m| m[1] >= (m[0] + 16.0).min(42.0)),
            "{means:?}"
        );
    }

    /// A retrace traces the film's samples again, so the same rays, in
    /// one pass: for uniform and adaptive films, grown in passes; and from
    /// a later sample on, the rays of the passes after those samples.
    #[test]
    fn a_retrace_traces_the_same_rays_in_one_pass() {
        let s = session(&[]);
        let t = s.tracer();
        for adaptive in [false, true] {
            let stop = Stop {
                spp: Some(4096),
                seconds: Some(1e9),
                error: None,
            };
            let mut p = Job::of(&t, stop).adaptive(adaptive).growing().start();
            p.pass(&t, Cancel::Never).unwrap();
            let (first, first_rays) = (p.film.spp, p.rays);
            assert_eq!(first, 1);
            for _ in 0..5 {
                p.pass(&t, Cancel::Never).unwrap();
            }
            let (lo, _, hi) = p.film.spp_range();
            assert_eq!(lo < hi, adaptive);
            let again = p.retrace(&t, 0);
            assert_eq!(again.rays, p.rays, "adaptive: {adaptive}");
            let later = p.retrace(&t, first);
            assert_eq!(later.rays, p.rays - first_rays, "adaptive: {adaptive}");
        }
    }

    /// A share reaches the mean in whole quarters and blocks, heavier
    /// pixels never get fewer samples, and counting the mean one step per
    /// distinct count gives what summing every pixel's count gives.
    #[test]
    fn a_share_reaches_the_mean_in_whole_quarters_and_blocks() {
        let mut x = 7u32;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 17;
            x ^= x << 5;
            x as f32 / u32::MAX as f32
        };
        for case in 0..60 {
            let n = 1 + case * 37 % 500;
            // Weights spread over four orders of magnitude, some equal.
            let weight: Vec<f32> = (0..n)
                .map(|i| {
                    if i % 5 == 0 {
                        0.5
                    } else {
                        10f32.powf(4.0 * next() - 2.0)
                    }
                })
                .collect();
            let mut ascending = weight.clone();
            ascending.sort_by(f32::total_cmp);
            let cap = [5, 16, 42, 1000, u32::MAX][case as usize % 5];
            let mean = (MIN_SPP as f64 + 300.0 * next() as f64).min(cap as f64);
            let counts = share(&weight, &ascending, mean, cap).unwrap();
            let avg = |c: &[u32]| c.iter().map(|&k| k as f64).sum::<f64>() / c.len() as f64;
            assert!(
                avg(&counts) >= mean,
                "case {case}: {} < {mean}",
                avg(&counts)
            );
            assert!(counts
                .iter()
                .all(|&k| (MIN_SPP.min(cap)..=cap).contains(&k)));
            let whole =
                |k: u32| k == cap || (k <= 16 && k.is_multiple_of(4)) || k.is_multiple_of(16);
            assert!(counts.iter().all(|&k| whole(k)), "case {case}: {counts:?}");
            // Heavier pixels never get fewer samples.
            let mut pairs: Vec<(f32, u32)> =
                weight.iter().copied().zip(counts.iter().copied()).collect();
            pairs.sort_by(|a, b| a.0.total_cmp(&b.0));
            assert!(pairs.windows(2).all(|p| p[0].1 <= p[1].1), "case {case}");
            assert_eq!(counts, share_by_sum(&weight, mean, cap), "case {case}");
        }
    }

    /// [`share`] as its definition says: the bisection's means summed over
    /// every pixel.
    fn share_by_sum(weight: &[f32], mean: f64, cap: u32) -> Vec<u32> {
        let count = |c: f64, w: f32| {
            let n = c * w as f64;
            let unit = if n <= 16.0 { 4.0 } else { 16.0 };
            ((n / unit).ceil() * unit).clamp(MIN_SPP.min(cap) as f64, cap as f64)
        };
        let mean_at =
            |c: f64| weight.iter().map(|&w| count(c, w)).sum::<f64>() / weight.len() as f64;
        let (mut a, mut b) = (-64.0f64, 64.0f64);
        for _ in 0..24 {
            let m = 0.5 * (a + b);
            if mean_at(m.exp2()) < mean {
                a = m;
            } else {
                b = m;
            }
        }
        weight.iter().map(|&w| count(b.exp2(), w) as u32).collect()
    }

    /// A render read only for its image summarises its film when one pass
    /// gives it every sample, and the image, error and report are those of
    /// the film of statistics; in more passes it keeps statistics.
    #[test]
    fn an_image_only_render_has_the_image_and_error_of_a_full_one() {
        for off in [&[][..], &[Feature::Supersampling]] {
            let s = session(off);
            let t = s.tracer();
            for (spp, per_pass) in [(1, 1), (3, 16), (16, 16), (16, 4), (21, 16)] {
                let run = |needs: Needs| {
                    let mut p = Job::of(&t, Stop::spp(spp))
                        .passes_of(per_pass)
                        .needs(needs)
                        .start();
                    let o = p.run(&t, Cancel::Never, |_, _| {});
                    (p.film, o.rays)
                };
                let (full, rays) = run(Needs::Statistics);
                let (only, only_rays) = run(Needs::Image);
                let what = format!("{off:?} {spp} spp in passes of {per_pass}");
                assert!(!full.is_summary(), "{what}");
                assert_eq!(only.is_summary(), per_pass >= spp, "{what}");
                assert_eq!(only.image(), full.image(), "{what}");
                assert_eq!(only.report(), full.report(), "{what}");
                assert_eq!(only.relative_error().is_some(), spp > 1, "{what}");
                assert_eq!(only_rays, rays, "{what}");
            }
        }
    }

    /// The memory a render's film will take, known before its first pass,
    /// is that of what its passes keep: each pixel's sample, summary or
    /// statistics.
    #[test]
    fn the_memory_a_film_will_take_is_known_before_its_first_pass() {
        let kept = |f: &Film| match (f.is_exact(), f.is_summary()) {
            (true, _) => Film::EXACT_BYTES_PER_PIXEL,
            (_, true) => Film::SUMMARY_BYTES_PER_PIXEL,
            _ => Film::BYTES_PER_PIXEL,
        };
        let error = Stop {
            error: Some(0.5),
            ..Stop::spp(40)
        };
        let mut seen = std::collections::BTreeSet::new();
        for (spec, off) in [
            ("cornell", &[Feature::Supersampling][..]),
            ("cornell-area", &[]),
        ] {
            let s = session_of(spec, off);
            let t = s.tracer();
            for stop in [Stop::spp(1), Stop::spp(16), Stop::spp(40), error] {
                for needs in [Needs::Statistics, Needs::Image, Needs::WholePasses] {
                    for adaptive in [false, true] {
                        let job = Job::of(&t, stop)
                            .passes_of(16)
                            .needs(needs)
                            .adaptive(adaptive);
                        let bytes = job.bytes_per_pixel();
                        let mut p = job.start();
                        p.run(&t, Cancel::Never, |_, _| {});
                        let what = format!("{spec} {stop:?} {needs:?}, adaptive {adaptive}");
                        assert_eq!(bytes, kept(&p.film), "{what}");
                        seen.insert(bytes);
                    }
                }
            }
        }
        assert_eq!(seen.len(), 3, "every layout is tried");
    }

    #[test]
    fn the_same_samples_in_any_pass_size() {
        let s = session(&[]);
        let t = s.tracer();
        let one = Progressive::render(&t, 6);
        let mut p = Job::of(&t, Stop::spp(6)).passes_of(4).start();
        p.run(&t, Cancel::Never, |_, _| {});
        assert_eq!(one.image(), p.film.image());
    }
}
