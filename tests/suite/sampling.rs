//! Sampled effects against independently known values: area lights by
//! quadrature, the film's standard error, stratification, determinism
//! across thread counts, glossy reflection's mirror limit, and an
//! environment light's importance sampling by quadrature.

use crate::common::*;
use crate::exact::*;
use glam::{DVec3, Vec3};
use rayterm::bvh;
use rayterm::render::{Feature, Features, Plan, PlanPolicy};
use rayterm::scene::{self, Builder, Camera, Light, Projection, Scene};

/// Renders `s` with `light_samples` per hit, jittered or independent.
fn render_lights(
    s: &Scene,
    w: u32,
    h: u32,
    spp: u32,
    light_samples: u32,
    stratify: bool,
) -> Rendered {
    let mut s = s.clone();
    s.settings.light_samples = light_samples;
    s.settings.stratify = stratify;
    render(&s, w, h, spp, features(), Builder::Sah, 7)
}

#[test]
fn converged_area_lights_match_quadrature_within_four_standard_errors() {
    for light in [parallelogram(), segment()] {
        let s = plane_under(light.clone());
        let (w, h) = (6, 6);
        let exact = exact_image(&s, w, h);
        let r = render_lights(&s, w, h, 128, 16, true);
        for (i, (px, e)) in r.film.pixels().iter().zip(&exact).enumerate() {
            let got = px.mean.dot(rayterm::color::LUMA.as_dvec3());
            let se = px.std_error();
            assert!(se > 0.0, "{} pixel {i}: no variance", light.kind());
            assert!(
                (got - lum(*e)).abs() <= 4.0 * se,
                "{} pixel {i}: {got} vs exact {} (se {se})",
                light.kind(),
                lum(*e)
            );
        }
        // Colour too, not only luminance: every channel within 1 %.
        for (got, e) in r.image.iter().zip(&exact) {
            assert!(
                ((*got - *e).abs() / *e).max_element() < 0.01,
                "{got} vs {e}"
            );
        }
    }
}

#[test]
fn standard_error_is_calibrated() {
    let s = plane_under(parallelogram());
    let (w, h) = (32, 32);
    let exact = exact_image(&s, w, h);
    let r = render_lights(&s, w, h, 32, 1, false);
    let within = r
        .film
        .pixels()
        .iter()
        .zip(&exact)
        .filter(|(px, e)| {
            let got = px.mean.dot(rayterm::color::LUMA.as_dvec3());
            (got - lum(**e)).abs() <= 2.0 * px.std_error()
        })
        .count();
    let frac = within as f64 / exact.len() as f64;
    assert!(
        (0.90..=0.99).contains(&frac),
        "{:.1} % within 2 se",
        frac * 100.0
    );
}

fn rms_error(img: &[Vec3], exact: &[Vec3]) -> f64 {
    let sum: f64 = img
        .iter()
        .zip(exact)
        .map(|(a, b)| (lum(*a) - lum(*b)).powi(2))
        .sum();
    (sum / img.len() as f64).sqrt()
}

#[test]
fn jittered_light_samples_beat_independent_ones_at_equal_count() {
    for light in [parallelogram(), segment()] {
        let s = plane_under(light.clone());
        let (w, h) = (12, 12);
        let exact = exact_image(&s, w, h);
        let jit = rms_error(&render_lights(&s, w, h, 4, 16, true).image, &exact);
        let ind = rms_error(&render_lights(&s, w, h, 4, 16, false).image, &exact);
        assert!(
            jit < 0.6 * ind,
            "{}: jittered {jit} vs independent {ind}",
            light.kind()
        );
    }
}

/// The film of `spec` rendered in a pool of `threads` threads.
fn film_with_threads(spec: &str, threads: usize) -> anyhow::Result<Vec<(u64, u64, u32)>> {
    let s = scene::load::open(spec, &Default::default())?.scene;
    let bvh = bvh::build(&s.geometry, s.settings.builder);
    let plan = Plan::new(&s, Features::all(), PlanPolicy::Prune);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()?;
    let r = pool.install(|| render_with(&s, &bvh, &plan, 20, 16, 3, 99));
    Ok(r.film
        .pixels()
        .iter()
        .map(|p| {
            let bits = p.mean.x.to_bits()
                ^ p.mean.y.to_bits().rotate_left(21)
                ^ p.mean.z.to_bits().rotate_left(42);
            (bits, p.m2.to_bits(), p.n)
        })
        .collect())
}

#[test]
fn same_seed_gives_bit_identical_films_on_one_and_two_threads() -> anyhow::Result<()> {
    // Area light with soft shadows and supersampling; glossy reflection.
    for spec in ["cornell-area", "mirrors"] {
        let one = film_with_threads(spec, 1)?;
        let two = film_with_threads(spec, 2)?;
        assert!(one.iter().any(|p| p.1 != 0), "{spec}: nothing was sampled");
        assert_eq!(one, two, "{spec}");
    }
    Ok(())
}

/// A reflective floor under a lit ceiling; the floor's Ns is `ns`.
fn floor_under_ceiling(ns: f32) -> Scene {
    let (fp, ft) = quad_y(-30.0, -30.0, 30.0, 30.0, 0.0);
    let (cp, ct) = quad_y(-30.0, -30.0, 30.0, 30.0, 2.0);
    let mut s = scene(
        &[
            (fp, ft, material(Vec3::ZERO, Vec3::splat(0.9), ns)),
            (cp, ct, material(Vec3::new(0.8, 0.7, 0.6), Vec3::ZERO, 1.0)),
        ],
        vec![Light::Point {
            position: Vec3::new(0.3, 0.5, -0.2),
            color: Vec3::ONE,
        }],
        Camera {
            eye: Vec3::new(0.0, 1.2, 1.5),
            target: Vec3::new(0.0, 0.0, 0.0),
            up: Vec3::Y,
            projection: Projection::perspective(30.0),
        },
    );
    s.settings.ambient = Vec3::ZERO;
    s.settings.max_depth = 1;
    s
}

fn max_diff(a: &[Vec3], b: &[Vec3]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).abs().max_element())
        .fold(0.0, f32::max)
}

#[test]
fn glossy_with_huge_ns_matches_the_mirror() {
    let (w, h) = (12, 9);
    let no_ss = Features::all().without(&[Feature::Supersampling, Feature::Bloom]);
    let render_ns = |ns: f32, features: Features, spp: u32| {
        render(
            &floor_under_ceiling(ns),
            w,
            h,
            spp,
            features,
            Builder::Sah,
            3,
        )
        .image
    };
    // Just below the glossy threshold (Ns < 1000), so the lobe is sampled.
    let glossy = render_ns(999.0, no_ss, 256);
    let mirror = render_ns(999.0, no_ss.without(&[Feature::Glossy]), 1);
    let dim = mirror
        .iter()
        .map(|c| c.max_element())
        .fold(f32::INFINITY, f32::min);
    assert!(
        dim > 0.05,
        "the ceiling is seen in the mirror everywhere: {dim} {mirror:?}"
    );
    let near = max_diff(&glossy, &mirror);
    assert!(near < 0.01, "Ns 999 differs from the mirror by {near}");
    // The tolerance means something: a broad lobe is visibly different.
    let broad = max_diff(&render_ns(20.0, no_ss, 64), &mirror);
    assert!(
        broad > 0.03,
        "Ns 20 differs from the mirror by only {broad}"
    );
}

/// An environment light's samples estimate its integral over the sphere
/// (the mean of radiance / pdf) as quadrature of its radiance finds it,
/// within four standard errors: a map of a sky and a sun two thousand
/// times brighter, read from a scene file.
#[test]
fn environment_light_samples_estimate_its_integral() {
    let dir = std::env::temp_dir().join(format!("rayterm-env-integral-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let (w, h) = (32u32, 16u32);
    let sky: Vec<image::Rgb<f32>> = (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| match (x, y) {
            (9, 4) => image::Rgb([2000.0, 1800.0, 1500.0]),
            _ => image::Rgb([0.2, 0.3, 0.6 - 0.03 * y as f32]),
        })
        .collect();
    let mut hdr = Vec::new();
    image::codecs::hdr::HdrEncoder::new(&mut hdr)
        .encode(&sky, w as usize, h as usize)
        .unwrap();
    std::fs::write(dir.join("sky.hdr"), hdr).unwrap();
    std::fs::write(dir.join("tri.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let toml = "[[mesh]]\nfile = \"tri.obj\"\n[environment]\nmap = \"sky.hdr\"\nrotate = 30\n";
    std::fs::write(dir.join("s.toml"), toml).unwrap();
    let s = scene::load::open(dir.join("s.toml").to_str().unwrap(), &Default::default())
        .unwrap()
        .scene;
    std::fs::remove_dir_all(&dir).ok();
    let scene::Environment::Light(env) = &s.environment else {
        panic!("no environment light: {:?}", s.environment);
    };
    // Quadrature: the midpoint rule, 40 x 40 steps a texel.
    let (nt, np) = (h as usize * 40, w as usize * 40);
    let (dt, dp) = (
        std::f64::consts::PI / nt as f64,
        std::f64::consts::TAU / np as f64,
    );
    let (mut exact, mut squared) = (DVec3::ZERO, 0.0);
    for i in 0..nt {
        let t = (i as f64 + 0.5) * dt;
        for j in 0..np {
            let p = (j as f64 + 0.5) * dp;
            let d = DVec3::new(t.sin() * p.cos(), t.cos(), t.sin() * p.sin());
            let l = env.eval(d.as_vec3()).as_dvec3();
            exact += l * t.sin() * dt * dp;
            squared += l.x * l.x * t.sin() * dt * dp;
        }
    }
    let n = 200_000;
    let mut rng = rayterm::geometry::sampling::Rng::for_sample(0, 0, 1);
    let (mut sum, mut squares) = (DVec3::ZERO, DVec3::ZERO);
    for _ in 0..n {
        let e = env.sample(rng.next_vec2());
        assert!(e.pdf > 0.0, "{e:?}");
        let x = e.radiance.as_dvec3() / e.pdf as f64;
        sum += x;
        squares += x * x;
    }
    let mean = sum / n as f64;
    let se = ((squares / n as f64 - mean * mean) / n as f64).map(f64::sqrt);
    for c in 0..3 {
        assert!(
            (mean[c] - exact[c]).abs() < 4.0 * se[c] + 1e-3 * exact[c],
            "channel {c}: {} against {} (standard error {})",
            mean[c],
            exact[c],
            se[c]
        );
    }
    // Importance sampling pays: the error is a tenth of uniform sampling's
    // or less (its variance is 4π ∫ L² dω - (∫ L dω)²).
    let four_pi = 4.0 * std::f64::consts::PI;
    let uniform = ((four_pi * squared - exact.x * exact.x) / n as f64).sqrt();
    assert!(se.x < uniform / 10.0, "{} against {uniform}", se.x);
}
