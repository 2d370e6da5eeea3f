//! The one progressive loop: passes that each add samples to every pixel of
//! a [`Film`], until a [`Stop`] says enough. `render`, exports, `converge`,
//! `inspect`, the debug views, the benchmarks, the stability battery, the
//! TUI's worker and the tests all drive films through [`Progressive`].
//!
//! Results depend only on (pixel, sample index, seed), never on threads:
//! rows run in parallel, and a pass gives every pixel the same sample indices.

use std::sync::atomic::{AtomicU32, Ordering};
use std::sync::Arc;
use std::time::Instant;

use glam::Vec3;
use rayon::prelude::*;

use super::film::{BadSample, Film};
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
    /// between rows.
    pub seconds: Option<f64>,
    /// The film's estimated relative error, once the estimate is meaningful.
    pub error: Option<f64>,
}

impl Stop {
    pub fn spp(n: u32) -> Self {
        Stop {
            spp: Some(n),
            ..Stop::default()
        }
    }

    pub fn seconds(t: f64) -> Self {
        Stop {
            seconds: Some(t),
            ..Stop::default()
        }
    }
}

/// Which limit ended a render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Ended {
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
    /// Samples each pixel received.
    pub samples: u32,
    pub rays: u64,
    pub ms: f64,
}

impl PassStats {
    pub fn mrays_per_s(&self) -> f64 {
        self.rays as f64 / (self.ms.max(1e-6) * 1e3)
    }
}

/// A whole run of passes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Outcome {
    pub ended: Ended,
    pub passes: u32,
    pub rays: u64,
    pub seconds: f64,
}

/// A film and the passes that made it.
#[derive(Clone, Debug)]
pub struct Progressive {
    pub film: Film,
    /// Rays traced and seconds spent in passes so far.
    pub rays: u64,
    pub seconds: f64,
    /// Samples per pixel a pass adds (fewer when the stop leaves fewer);
    /// more than one keeps the per-pass overhead small on tiny images.
    pub samples_per_pass: u32,
    /// Counts the rows each pass finishes, for a progress readout.
    pub rows_done: Option<Arc<AtomicU32>>,
}

impl Progressive {
    pub fn new(width: u32, height: u32) -> Self {
        Self::resume(Film::new(width, height))
    }

    /// Continues a film that already has samples.
    pub fn resume(film: Film) -> Self {
        Self {
            film,
            rays: 0,
            seconds: 0.0,
            samples_per_pass: 1,
            rows_done: None,
        }
    }

    /// Runs one pass of up to `samples_per_pass` samples (never past the
    /// stop's spp); `None` when `cancel` stopped it between rows.
    pub fn pass(
        &mut self,
        tracer: &Tracer,
        stop: &Stop,
        cancel: &(dyn Fn() -> bool + Sync),
    ) -> Option<PassStats> {
        self.pass_with::<RayCounter>(tracer, stop, cancel)
            .map(|(p, _)| p)
    }

    /// As [`Progressive::pass`], with any counting recorder, whose counts of
    /// all rows are returned merged.
    pub fn pass_with<R: Recorder + Default + Send + Merge>(
        &mut self,
        tracer: &Tracer,
        stop: &Stop,
        cancel: &(dyn Fn() -> bool + Sync),
    ) -> Option<(PassStats, R)> {
        let left = stop
            .spp
            .map_or(u32::MAX, |n| n.saturating_sub(self.film.spp));
        let samples = self.samples_per_pass.clamp(1, left.max(1));
        let start = Instant::now();
        if let Some(r) = &self.rows_done {
            r.store(0, Ordering::Relaxed);
        }
        let rows = self.rows_done.as_deref();
        let rec: R = sample_rows(tracer, &mut self.film, samples, cancel, rows);
        let ms = start.elapsed().as_secs_f64() * 1e3;
        let rays = rec.rays();
        self.rays += rays;
        self.seconds += ms / 1e3;
        (!cancel()).then_some((PassStats { samples, rays, ms }, rec))
    }

    /// Which limit of `stop` the film has reached, if any; `elapsed` is the
    /// time the render has taken so far.
    pub fn finished(&self, plan: &Plan, stop: &Stop, elapsed: f64) -> Option<Ended> {
        let f = &self.film;
        if plan.deterministic && f.spp >= 1 {
            return Some(Ended::Exact);
        }
        if stop.spp.is_some_and(|n| f.spp >= n) {
            return Some(Ended::Spp);
        }
        if stop.seconds.is_some_and(|t| elapsed >= t) {
            return Some(Ended::Time);
        }
        if stop
            .error
            .is_some_and(|e| f.error_is_meaningful() && f.relative_error().is_some_and(|r| r < e))
        {
            return Some(Ended::Error);
        }
        None
    }

    /// Adds passes until `stop` (or `cancel`); `on_pass` sees the film
    /// after each finished pass.
    pub fn run(
        &mut self,
        tracer: &Tracer,
        stop: &Stop,
        cancel: &(dyn Fn() -> bool + Sync),
        mut on_pass: impl FnMut(&Film, &PassStats),
    ) -> Outcome {
        let start = Instant::now();
        let (rays, seconds) = (self.rays, self.seconds);
        // A time too long for the clock is no deadline at all.
        let deadline = stop.seconds.and_then(|t| {
            std::time::Duration::try_from_secs_f64(t)
                .ok()
                .and_then(|d| start.checked_add(d))
        });
        let past = || deadline.is_some_and(|d| Instant::now() >= d);
        let stop_rows = || cancel() || past();
        let mut passes = 0;
        let ended = loop {
            if let Some(e) = self.finished(tracer.plan, stop, start.elapsed().as_secs_f64()) {
                break e;
            }
            let pass = self.pass(tracer, stop, &stop_rows);
            if cancel() {
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

    /// Runs to `spp` samples per pixel, uncancellable: for tests and tools.
    pub fn render(tracer: &Tracer, spp: u32) -> Film {
        let mut p = Progressive::new(tracer.width, tracer.height);
        p.run(tracer, &Stop::spp(spp), &|| false, |_, _| {});
        p.film
    }
}

/// Adds `samples` samples to every pixel of `film`, rows in parallel;
/// `cancel` is polled between rows and `rows_done` counts finished rows.
fn sample_rows<R: Recorder + Default + Send + Merge>(
    tracer: &Tracer,
    film: &mut Film,
    samples: u32,
    cancel: &(dyn Fn() -> bool + Sync),
    rows_done: Option<&AtomicU32>,
) -> R {
    let w = film.width as usize;
    let first = film.spp;
    let results: Vec<(R, Vec<BadSample>, bool)> = film
        .pixels
        .par_chunks_mut(w.max(1))
        .enumerate()
        .map(|(y, row)| {
            let mut rec = R::default();
            let mut bad = Vec::new();
            if cancel() {
                return (rec, bad, false);
            }
            for (x, px) in row.iter_mut().enumerate() {
                for k in first..first + samples {
                    let c: Vec3 = tracer.sample(x as u32, y as u32, k, &mut rec);
                    if c.is_finite() {
                        px.add(k, c, tracer.stratum(x as u32, y as u32, k));
                    } else {
                        bad.push(BadSample {
                            x: x as u32,
                            y: y as u32,
                            sample: k,
                        });
                    }
                }
            }
            if let Some(r) = rows_done {
                r.fetch_add(1, Ordering::Relaxed);
            }
            (rec, bad, true)
        })
        .collect();
    // A pass cut between rows leaves `spp` at what every pixel has.
    if results.iter().all(|r| r.2) {
        film.spp += samples;
    }
    let mut total = R::default();
    for (rec, bad, _) in results {
        total.merge(&rec);
        for b in bad {
            film.record_bad(b);
        }
    }
    total
}

/// Recorders that can be summed across rows.
pub trait Merge {
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
    use crate::render::Feature;

    fn session(off: &[Feature]) -> Session {
        let mut req = SceneRequest::new("cornell-area");
        req.size = Some((12, 8));
        req.features = req.features.without(off);
        Session::open(&req).unwrap().0
    }

    #[test]
    fn runs_to_the_spp_in_passes_of_the_asked_size() {
        let s = session(&[]);
        let t = s.tracer();
        let mut p = Progressive::new(12, 8);
        p.samples_per_pass = 3;
        let mut seen = Vec::new();
        let o = p.run(&t, &Stop::spp(7), &|| false, |f, pass| {
            seen.push((f.spp, pass.samples))
        });
        assert_eq!(seen, [(3, 3), (6, 3), (7, 1)]);
        assert_eq!((o.ended, o.passes, p.film.spp), (Ended::Spp, 3, 7));
        assert!(o.rays > 0 && o.rays == p.rays);
    }

    #[test]
    fn exact_scenes_stop_after_one_pass() {
        let s = session(&[Feature::Supersampling, Feature::SoftShadows]);
        let mut p = Progressive::new(12, 8);
        let o = p.run(&s.tracer(), &Stop::spp(50), &|| false, |_, _| {});
        assert_eq!((o.ended, p.film.spp), (Ended::Exact, 1));
    }

    #[test]
    fn time_and_cancel_end_a_run() {
        let s = session(&[]);
        let t = s.tracer();
        let mut p = Progressive::new(12, 8);
        let o = p.run(&t, &Stop::seconds(0.05), &|| false, |_, _| {});
        assert_eq!(o.ended, Ended::Time);
        assert!(o.seconds < 1.0, "{}", o.seconds);
        let o = p.run(&t, &Stop::default(), &|| true, |_, _| {});
        assert_eq!(o.ended, Ended::Cancelled);
    }

    #[test]
    fn the_same_samples_in_any_pass_size() {
        let s = session(&[]);
        let t = s.tracer();
        let one = Progressive::render(&t, 6);
        let mut p = Progressive::new(12, 8);
        p.samples_per_pass = 4;
        p.run(&t, &Stop::spp(6), &|| false, |_, _| {});
        assert_eq!(one.image(), p.film.image());
    }
}
