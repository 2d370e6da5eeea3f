//! A render job: what a run of progressive passes is for, said once before
//! the first: its size and plan, when it stops, the samples it starts from
//! (a sample range, or a resumed film), what is read of its film, whether
//! its passes are adaptive and how large they are. From that the job
//! chooses how the film keeps its pixels ([`Storage`]) and makes it, so the
//! memory it checks ([`Job::bytes_per_pixel`]) is what it allocates, and
//! no pass ever changes it; [`Job::start`] hands the film to the one
//! progressive loop ([`Progressive`]).

use std::sync::atomic::AtomicU32;
use std::sync::Arc;

use super::film::Film;
use super::progressive::{uniform_pass, ONE_PASS_SPP};
use super::{Plan, Progressive, Stop, Tracer, MIN_SPP};
use crate::geometry::sampling::PIXEL_STRATA;

/// What is read of a job's film once its passes are done.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) enum Needs {
    /// Each pixel's statistics: a part of a split render, tools, tests.
    #[default]
    Statistics,
    /// The image and its error estimate only: a render to an image file.
    Image,
    /// Statistics of whole passes only, every pixel the same samples, as a
    /// checkpoint needs: a pass cut short is undone.
    WholePasses,
}

/// How large a job's passes are.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Passes {
    /// This many samples per pixel each.
    Of(u32),
    /// Sized for the stop (see [`Job::passes_for_stop`]).
    ForStop,
    /// Growing with the film (see [`Job::growing`]).
    Growing,
}

/// How a film keeps its pixels.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Storage {
    /// Each pixel's one sample ([`Film::new_exact`]).
    Exact,
    /// Each pixel's mean and error term ([`Film::new_summary`]).
    Summary,
    /// Each pixel's statistics.
    Stats,
}

/// A render to be made: a builder, then [`Job::start`].
#[derive(Clone, Debug)]
pub struct Job {
    width: u32,
    height: u32,
    deterministic: bool,
    stop: Stop,
    start: u32,
    /// A film with samples already, and the rays and seconds they took.
    resumed: Option<(Film, u64, f64)>,
    needs: Needs,
    adaptive: bool,
    passes: Passes,
    rows_done: Option<Arc<AtomicU32>>,
}

impl Job {
    /// A `width` x `height` render of `plan` until `stop`: uniform passes
    /// of one sample into a blank film of statistics, unless told more.
    pub(crate) fn new(width: u32, height: u32, plan: &Plan, stop: Stop) -> Self {
        Self {
            width,
            height,
            deterministic: plan.deterministic,
            stop,
            start: 0,
            resumed: None,
            needs: Needs::default(),
            adaptive: false,
            passes: Passes::Of(1),
            rows_done: None,
        }
    }

    /// A render of `tracer`'s image until `stop`.
    pub fn of(tracer: &Tracer, stop: Stop) -> Self {
        Self::new(tracer.width, tracer.height, tracer.plan, stop)
    }

    /// Starts at sample index `start` (a part of a split render).
    pub(crate) fn samples_from(self, start: u32) -> Self {
        Self { start, ..self }
    }

    /// Goes on from `film`, whose samples took `rays` and `seconds`.
    pub(crate) fn resume(self, film: Film, rays: u64, seconds: f64) -> Self {
        Self {
            resumed: Some((film, rays, seconds)),
            ..self
        }
    }

    pub(crate) fn needs(self, needs: Needs) -> Self {
        Self { needs, ..self }
    }

    /// Whether passes after [`MIN_SPP`](super::MIN_SPP) go to the pixels
    /// with the highest predicted error; a blank film only, and never where
    /// nothing is sampled.
    pub fn adaptive(self, adaptive: bool) -> Self {
        Self { adaptive, ..self }
    }

    /// Passes of `n` samples per pixel.
    pub(crate) fn passes_of(self, n: u32) -> Self {
        Self {
            passes: Passes::Of(n),
            ..self
        }
    }

    /// Passes sized for the stop, as `render` and exports take them. To a
    /// fixed spp, a block of strata per pass: the same samples as passes
    /// of one (a sample depends only on its pixel, index and seed) with
    /// each pixel's statistics brought through the cache once a block
    /// rather than once a sample; a render read only for its image takes
    /// all its samples in one pass up to [`ONE_PASS_SPP`], so that its film
    /// keeps no statistics. To a time, growing passes; to an error alone,
    /// a first pass of [`MIN_SPP`], the fewest that make the estimate
    /// meaningful, then passes sized from it. Passes of one sample between
    /// checkpoints (a pass cut short is undone), and for an exact render's
    /// one pass.
    pub(crate) fn passes_for_stop(self) -> Self {
        Self {
            passes: Passes::ForStop,
            ..self
        }
    }

    /// Passes that grow with the film (see [`Progressive::cap_passes`]).
    pub(crate) fn growing(self) -> Self {
        Self {
            passes: Passes::Growing,
            ..self
        }
    }

    /// Counts the rows each pass finishes in `rows`, for a progress
    /// readout.
    pub(crate) fn rows_done(self, rows: Arc<AtomicU32>) -> Self {
        Self {
            rows_done: Some(rows),
            ..self
        }
    }

    /// Whether the stop is a number of samples only.
    fn fixed(&self) -> bool {
        self.stop.seconds.is_none() && self.stop.error.is_none()
    }

    /// Samples per pixel the first pass gives at most.
    pub(crate) fn samples_per_pass(&self) -> u32 {
        match self.passes {
            Passes::Of(n) => n,
            Passes::Growing => 1,
            Passes::ForStop if self.deterministic || self.needs == Needs::WholePasses => 1,
            // To an error alone, the samples its first estimate needs.
            Passes::ForStop if self.stop.error.is_some() && self.stop.seconds.is_none() => MIN_SPP,
            Passes::ForStop if !self.fixed() => 1,
            Passes::ForStop => match self.stop.spp {
                Some(n) if self.needs == Needs::Image && n <= ONE_PASS_SPP => n.max(PIXEL_STRATA),
                _ => PIXEL_STRATA,
            },
        }
    }

    fn grows(&self) -> bool {
        match self.passes {
            Passes::Of(_) => false,
            Passes::Growing => true,
            Passes::ForStop => !self.fixed() && self.needs != Needs::WholePasses,
        }
    }

    /// Whether a pass cut short is undone.
    pub(crate) fn whole_passes(&self) -> bool {
        self.needs == Needs::WholePasses
    }

    /// Whether the film is made adaptive.
    fn makes_adaptive(&self) -> bool {
        self.adaptive && !self.deterministic && self.resumed.is_none()
    }

    /// How the film keeps its pixels: a resumed film as it does; the one
    /// pass of an exact render, each pixel's sample; a pass that is all a
    /// film read only for its image gets, each pixel's mean and error (its
    /// statistics on the stack while it is sampled); else statistics.
    fn layout(&self) -> Storage {
        if let Some((f, ..)) = &self.resumed {
            return match (f.is_exact(), f.is_summary()) {
                (true, _) => Storage::Exact,
                (_, true) => Storage::Summary,
                _ => Storage::Stats,
            };
        }
        if self.makes_adaptive() || self.whole_passes() {
            return Storage::Stats;
        }
        let spp = self.stop.spp;
        let first = uniform_pass(self.samples_per_pass(), spp.unwrap_or(u32::MAX));
        if self.deterministic && first == 1 && self.start == 0 {
            Storage::Exact
        } else if self.needs == Needs::Image && spp.is_some_and(|s| first >= s) {
            Storage::Summary
        } else {
            Storage::Stats
        }
    }

    /// Bytes a pixel of this job's film takes (the film and the images made
    /// from it): what a caller checks against the memory available before
    /// [`Job::start`] allocates it.
    pub(crate) fn bytes_per_pixel(&self) -> u64 {
        match self.layout() {
            Storage::Exact => Film::EXACT_BYTES_PER_PIXEL,
            Storage::Summary => Film::SUMMARY_BYTES_PER_PIXEL,
            Storage::Stats => Film::BYTES_PER_PIXEL,
        }
    }

    /// Makes the film (or takes the resumed one) and the passes into it.
    pub fn start(self) -> Progressive {
        let (w, h) = (self.width, self.height);
        let (layout, per_pass, grows) = (self.layout(), self.samples_per_pass(), self.grows());
        let whole = self.whole_passes();
        let adaptive = self.makes_adaptive();
        let (film, work) = match self.resumed {
            Some((film, rays, seconds)) => (film, (rays, seconds)),
            None => {
                let mut film = match layout {
                    Storage::Exact => Film::new_exact(w, h),
                    Storage::Summary => Film::new_summary(w, h),
                    Storage::Stats if adaptive => Film::new_adaptive(w, h),
                    Storage::Stats => Film::new(w, h),
                };
                film.start = self.start;
                (film, (0, 0.0))
            }
        };
        Progressive::of(
            film,
            work,
            self.stop,
            per_pass,
            self.rows_done,
            whole,
            grows,
        )
    }
}
