//! What adaptive sampling can gain on a scene: rays per pixel to a relMSE
//! target (1e-4, 1 % error) for uniform sampling, for the counts an
//! adaptive film gives from its weights, and for counts that know each
//! pixel's true variance (docs/adaptive.md, "What it can gain").
//!
//! `cargo run --release --example allocation_bound -- mirrors [SIZE] [TARGET]`
//!
//! Every pixel's first 64 samples are traced once. A count's error is the
//! variance of the mean of the pixel's first 4, 8 or 12 samples of a block
//! (over its blocks' quarters, halves or first three quarters) or of whole
//! blocks, relative as the film's relMSE counts it; a count's cost is its
//! samples times the pixel's mean rays per sample.

use rayon::prelude::*;
use rayterm::color::LUMA;
use rayterm::interrupt::Cancel;
use rayterm::render::film::REL_EPS;
use rayterm::render::{Job, RayCounter, SceneRequest, Session, Stop, MIN_SPP};

fn main() -> anyhow::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    let scene = args.get(1).map_or("mirrors", String::as_str);
    let size: u32 = args.get(2).map_or(Ok(256), |s| s.parse())?;
    let target: f64 = args.get(3).map_or(Ok(1e-4), |s| s.parse())?;
    let mut req = SceneRequest::new(scene);
    req.size = Some((size, size));
    let (session, _) = Session::open(&req)?;
    let t = session.tracer();
    let w = t.width;
    let traced: Vec<(Vec<f64>, f64)> = (0..t.width * t.height)
        .into_par_iter()
        .map(|i| {
            let mut rec = RayCounter::default();
            let l = (0..64)
                .map(|k| t.sample(i % w, i / w, k, &mut rec).dot(LUMA) as f64)
                .collect();
            (l, rec.rays as f64 / 64.0)
        })
        .collect();
    let pixels: Vec<Pixel> = traced
        .iter()
        .map(|(l, rays)| Pixel::new(l, *rays))
        .collect();
    let n = pixels.len() as f64;
    // relMSE, rays per pixel and mean spp of one count per pixel.
    let price = |counts: &mut dyn Iterator<Item = u32>| {
        let (mut err, mut rays, mut spp) = (0.0, 0.0, 0.0);
        for (p, k) in pixels.iter().zip(counts) {
            err += p.error(k);
            rays += k as f64 * p.rays;
            spp += k as f64;
        }
        (err / n, rays / n, spp / n)
    };
    for k in [4, 8, 12, 16, 32] {
        let (err, rays, _) = price(&mut std::iter::repeat(k));
        println!("uniform {k:2} spp: relMSE {err:.3e}, {rays:.1} rays/px");
    }
    // The film's own weights, made after its first quarter.
    let mut p = Job::of(&t, Stop::default()).adaptive(true).start();
    while p.film().spp() < MIN_SPP {
        p.pass(&t, Cancel::Never);
    }
    let weights = p
        .into_film()
        .adaptive()
        .map(|a| a.weight.clone())
        .unwrap_or_default();
    let known: Vec<f64> = pixels
        .iter()
        .map(|p| (4.0 * p.err[0] / p.rays.max(1.0)).sqrt())
        .collect();
    for (name, weight) in [
        (
            "weights from neighbours' quarters",
            weights.iter().map(|&w| w as f64).collect(),
        ),
        ("each pixel's own variance, known", known),
    ] {
        // The scale whose counts reach the target, by bisection.
        let at = |c: f64| price(&mut weight.iter().map(|&w| count(c * w)));
        let (mut a, mut b) = (-64.0f64, 64.0f64);
        for _ in 0..60 {
            let m = 0.5 * (a + b);
            if at(m.exp2()).0 > target {
                a = m;
            } else {
                b = m;
            }
        }
        let (err, rays, spp) = at(b.exp2());
        println!("{name}: relMSE {err:.3e}, {spp:.2} spp, {rays:.1} rays/px");
    }
    Ok(())
}

/// A count for weight times scale `x`, as an adaptive film rounds it.
fn count(x: f64) -> u32 {
    let unit = if x <= 16.0 { 4.0 } else { 16.0 };
    ((x / unit).ceil() * unit).clamp(MIN_SPP as f64, f64::from(1 << 20)) as u32
}

struct Pixel {
    /// Relative variance of the mean of 4, 8 and 12 samples of a block and
    /// of one whole block.
    err: [f64; 4],
    rays: f64,
}

impl Pixel {
    fn new(l: &[f64], rays: f64) -> Self {
        let mean = l.iter().sum::<f64>() / l.len() as f64;
        let d = mean * mean + REL_EPS;
        let spread = |reps: Vec<f64>| {
            let m = reps.iter().sum::<f64>() / reps.len() as f64;
            reps.iter().map(|a| (a - m) * (a - m)).sum::<f64>() / (reps.len() - 1) as f64 / d
        };
        let avg = |s: &[f64]| s.iter().sum::<f64>() / s.len() as f64;
        let blocks = || l.chunks(16);
        Self {
            err: [
                spread(blocks().flat_map(|b| b.chunks(4).map(avg)).collect()),
                spread(blocks().flat_map(|b| b.chunks(8).map(avg)).collect()),
                spread(blocks().map(|b| avg(&b[..12])).collect()),
                spread(blocks().map(avg).collect()),
            ],
            rays,
        }
    }

    /// Relative variance of the mean of the first `k` samples.
    fn error(&self, k: u32) -> f64 {
        match k {
            4 => self.err[0],
            8 => self.err[1],
            12 => self.err[2],
            _ => self.err[3] * 16.0 / k as f64,
        }
    }
}
