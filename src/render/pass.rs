//! Render passes: every pixel gets the next samples, rows in parallel.
//! Results depend only on (pixel, sample index, seed), never on threads.

use glam::Vec3;
use rayon::prelude::*;

use super::film::{BadSample, Film};
use super::recorder::{RayCounter, Recorder};
use super::Tracer;

/// Adds `samples` samples to every pixel of `film`; returns the rays traced.
/// `cancel` is polled between rows.
pub fn render_pass(
    tracer: &Tracer,
    film: &mut Film,
    samples: u32,
    cancel: &(dyn Fn() -> bool + Sync),
) -> u64 {
    let (rays, _) = render_pass_with::<RayCounter>(tracer, film, samples, cancel);
    rays
}

/// As [`render_pass`], with any counting recorder; returns the rays and the
/// recorders of all rows merged.
pub fn render_pass_with<R: Recorder + Default + Send + Merge>(
    tracer: &Tracer,
    film: &mut Film,
    samples: u32,
    cancel: &(dyn Fn() -> bool + Sync),
) -> (u64, R) {
    let w = film.width as usize;
    let first = film.spp;
    let results: Vec<(R, Vec<BadSample>)> = film
        .pixels
        .par_chunks_mut(w)
        .enumerate()
        .map(|(y, row)| {
            let mut rec = R::default();
            let mut bad = Vec::new();
            if cancel() {
                return (rec, bad);
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
            (rec, bad)
        })
        .collect();
    film.spp += samples;
    let mut total = R::default();
    for (rec, bad) in results {
        total.merge(&rec);
        for b in bad {
            film.record_bad(b);
        }
    }
    (total.rays(), total)
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

impl Merge for super::recorder::WorkCounter {
    fn merge(&mut self, o: &Self) {
        self.rays += o.rays;
        self.work += o.work;
    }
    fn rays(&self) -> u64 {
        self.rays
    }
}
