//! The path tracer against what is known exactly: furnaces (a closed
//! world of uniform light, where every surface that reflects all it
//! receives disappears), direct light where there is nothing to bounce
//! off, multiple importance sampling's densities agreeing both ways, and
//! long paths that stay finite.

use crate::common::*;
use glam::Vec3;
use rayterm::inspect::tree::{inspect_pixel, RayNode};
use rayterm::render::{Feature, Features, RayCounter, SceneRequest, Session};
use rayterm::scene::{
    Builder, Camera, EnvLight, Environment, Integrator, Light, Material, Pbr, Projection, Scene,
};

/// A sphere of `rings` x `2 rings` flat facets, radius `r` about `c`.
fn sphere(c: Vec3, r: f32, rings: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let segs = 2 * rings;
    let mut p = Vec::new();
    for i in 0..=rings {
        let th = std::f32::consts::PI * i as f32 / rings as f32;
        for j in 0..segs {
            let ph = std::f32::consts::TAU * j as f32 / segs as f32;
            p.push(c + r * Vec3::new(th.sin() * ph.cos(), th.cos(), th.sin() * ph.sin()));
        }
    }
    let mut t = Vec::new();
    for i in 0..rings {
        for j in 0..segs {
            let a = i * segs + j;
            let b = i * segs + (j + 1) % segs;
            let (c2, d) = (a + segs, b + segs);
            t.push([a, b, d]);
            t.push([a, d, c2]);
        }
    }
    (p, t)
}

fn pbr(base: f32, metallic: f32, roughness: f32) -> Material {
    Material {
        kd: Vec3::splat(base),
        pbr: Some(Pbr {
            metallic,
            roughness,
            ..Pbr::default()
        }),
        ..Material::default()
    }
}

fn front_camera() -> Camera {
    Camera {
        eye: Vec3::new(0.0, 0.0, 4.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        projection: Projection::perspective(25.0),
    }
}

fn path(mut s: Scene) -> Scene {
    s.settings.integrator = Some(Integrator::Path);
    s
}

fn no_bloom() -> Features {
    Features::all().without(&[Feature::Bloom])
}

/// A sphere in a uniform environment of radiance 1: the mean of its
/// pixels (a quarter of the image's middle, all on the sphere).
fn furnace(m: Material, spp: u32) -> (f32, Vec<f32>) {
    let (p, t) = sphere(Vec3::ZERO, 1.0, 24);
    let mut s = path(scene(&[(p, t, m)], vec![], front_camera()));
    s.environment = Environment::Light(Box::new(EnvLight::constant(Vec3::ONE)));
    s.settings.max_depth = 8;
    let r = render(&s, 16, 16, spp, no_bloom(), Builder::Sah, 1);
    let mut px = Vec::new();
    for y in 5..11 {
        for x in 5..11 {
            px.push(r.image[y * 16 + x].x);
        }
    }
    (px.iter().sum::<f32>() / px.len() as f32, px)
}

/// A white Lambertian sphere and a white mirror vanish in a furnace; a
/// rough white metal loses what single-scattering GGX loses: at roughness
/// 0.5 (alpha 0.25) its directional albedo is 0.916 at normal incidence and
/// 0.907 at 25 degrees (quadrature of the specification's D and V), the
/// range of the pixels measured.
#[test]
fn a_furnace_hides_what_reflects_everything() {
    let (lambert, px) = furnace(material(Vec3::ONE, Vec3::ZERO, 1.0), 256);
    assert!((lambert - 1.0).abs() < 0.01, "Lambertian: {lambert}");
    assert!(
        px.iter().all(|v| (v - 1.0).abs() < 0.05),
        "Lambertian pixels {px:?}"
    );
    let (mirror, px) = furnace(pbr(1.0, 1.0, 0.0), 4);
    assert!((mirror - 1.0).abs() < 1e-4, "mirror: {mirror} {px:?}");
    let (rough, _) = furnace(pbr(1.0, 1.0, 0.5), 256);
    assert!((0.900..0.922).contains(&rough), "rough metal: {rough}");
    // A grey Lambertian sphere shows its albedo.
    let (grey, _) = furnace(material(Vec3::splat(0.5), Vec3::ZERO, 1.0), 256);
    assert!((grey - 0.5).abs() < 0.01, "grey: {grey}");
}

/// Where nothing bounces back (a lone floor under a point light in
/// candela, a black world), the path tracer gives what the direct-light
/// integrator gives, which the shading tests hold to the specification.
#[test]
fn a_lone_floor_gets_direct_light_only() {
    let (p, t) = quad_y(-50.0, -50.0, 50.0, 50.0, 0.0);
    for (base, metallic, roughness) in [(0.5f32, 0.0f32, 1.0f32), (0.5, 0.0, 0.5), (0.8, 1.0, 0.7)]
    {
        let mut s = scene(
            &[(p.clone(), t.clone(), pbr(base, metallic, roughness))],
            vec![Light::Photometric {
                position: Vec3::new(0.7, 3.0, 0.2),
                intensity: Vec3::splat(90.0),
                range: None,
                cone: None,
            }],
            top_camera(3.0),
        );
        let features = no_bloom().without(&[Feature::Supersampling]);
        let whitted = render(&s, 9, 9, 1, features, Builder::Sah, 1).image;
        s.settings.integrator = Some(Integrator::Path);
        let traced = render(&s, 9, 9, 16, features, Builder::Sah, 1).image;
        for (a, b) in whitted.iter().zip(&traced) {
            assert!(
                (*a - *b).abs().max_element() <= 0.005 * a.max_element(),
                "{base} {metallic} {roughness}: whitted {a} path {b}"
            );
        }
    }
}

/// An emissive square above a grey Lambertian floor: the floor under its
/// middle gets the irradiance of a uniform rectangle (the form factor of a
/// parallel rectangle, by quadrants), found by sampling the emitter and
/// by bounces that hit it, weighed together.
#[test]
fn an_emissive_square_lights_by_its_form_factor() {
    let (fp, ft) = quad_y(-50.0, -50.0, 50.0, 50.0, 0.0);
    // The emitter faces down: the same quad, its winding reversed.
    let (ep, et) = quad_y(-0.5, -0.5, 0.5, 0.5, 1.0);
    let et: Vec<[u32; 3]> = et.iter().map(|t| [t[0], t[2], t[1]]).collect();
    let radiance = 3.0;
    let emitter = Material {
        kd: Vec3::ZERO,
        pbr: Some(Pbr {
            metallic: 0.0,
            roughness: 1.0,
            emissive: Vec3::splat(radiance),
            ..Pbr::default()
        }),
        ..Material::default()
    };
    let kd = 0.5;
    let camera = Camera {
        eye: Vec3::new(0.0, 0.5, 3.0),
        target: Vec3::ZERO,
        up: Vec3::Y,
        projection: Projection::perspective(2.0),
    };
    let mut s = path(scene(
        &[
            (fp, ft, material(Vec3::splat(kd), Vec3::ZERO, 1.0)),
            (ep, et, emitter),
        ],
        vec![],
        camera,
    ));
    // One bounce: light sampling and the bounce both reach the emitter,
    // and nothing comes back from it.
    s.settings.max_depth = 1;
    let r = render(&s, 5, 5, 1024, no_bloom(), Builder::Sah, 1);
    let got = r.image[2 * 5 + 2].x;
    // A quarter of the square, corner above the point: a = b = 0.5, h = 1.
    let (a, b, h) = (0.5f64, 0.5f64, 1.0f64);
    let (x, y) = (a / h, b / h);
    let f = (x / (1.0 + x * x).sqrt() * (y / (1.0 + x * x).sqrt()).atan()
        + y / (1.0 + y * y).sqrt() * (x / (1.0 + y * y).sqrt()).atan())
        / (2.0 * std::f64::consts::PI);
    let e = 4.0 * f * std::f64::consts::PI * radiance as f64;
    let want = (kd as f64 / std::f64::consts::PI * e) as f32;
    assert!((got - want).abs() < 0.01 * want, "{got}, want {want}");
    // Either strategy alone is right too: with emission off nothing
    // lights the floor.
    let off = render(
        &s,
        5,
        5,
        4,
        no_bloom().without(&[Feature::Emission]),
        Builder::Sah,
        1,
    );
    assert_eq!(off.image[12], Vec3::ZERO);
}

/// Every arrival weighed both ways uses the same two densities: the
/// bounce's density is the one its light samples were weighed against,
/// and the environment's density of a direction a bounce found is the one
/// light sampling would have had. Both weights sum to 1.
#[test]
fn mis_densities_agree_both_ways() {
    let (p, t) = sphere(Vec3::ZERO, 1.0, 12);
    let (fp, ft) = quad_y(-5.0, -5.0, 5.0, 5.0, -1.0);
    let mut s = path(scene(
        &[(p, t, pbr(0.7, 0.0, 0.4)), (fp, ft, pbr(0.5, 0.0, 0.9))],
        vec![],
        front_camera(),
    ));
    let env = EnvLight::constant(Vec3::new(0.3, 0.5, 0.9));
    s.environment = Environment::Light(Box::new(env.clone()));
    s.settings.max_depth = 6;
    let req = SceneRequest {
        size: Some((8, 8)),
        features: no_bloom(),
        ..SceneRequest::new("test")
    };
    let (session, _) = Session::with_scene(s, &req);
    let tracer = session.tracer();
    let mut checked = (0, 0);
    fn walk(n: &RayNode, env: &EnvLight, checked: &mut (u32, u32)) {
        for l in &n.lights {
            for s in &l.samples {
                if let Some(m) = s.mis {
                    assert!((m.light_weight + m.bsdf_weight - 1.0).abs() < 1e-6);
                    checked.0 += 1;
                }
            }
        }
        if let (Some(b), Some(c)) = (&n.bounce, n.children.first()) {
            if let Some(m) = c.miss.as_ref().and_then(|m| m.mis) {
                assert_eq!(Some(m.bsdf_pdf), b.pdf);
                let want = env.pdf(c.dir);
                assert!((m.light_pdf - want).abs() <= 1e-6 * want, "{m:?} {want}");
                assert!((m.light_weight + m.bsdf_weight - 1.0).abs() < 1e-6);
                checked.1 += 1;
            }
        }
        for c in &n.children {
            walk(c, env, checked);
        }
    }
    for y in 0..8 {
        for x in 0..8 {
            for k in 0..4 {
                let tree = inspect_pixel(&tracer, x, y, k);
                // The tree's colour is the pixel's sample, bit for bit.
                let colour = tracer.sample(x, y, k, &mut RayCounter::default());
                assert_eq!(tree.color.to_array(), colour.to_array());
                walk(&tree.root, &env, &mut checked);
            }
        }
    }
    assert!(checked.0 > 50 && checked.1 > 20, "{checked:?}");
}

/// Inside a closed white box lit from within, paths go on until Russian
/// roulette ends them: 64 bounces allowed, every sample finite and
/// positive, and the chance a path lived never turns a weight large.
#[test]
fn long_paths_stay_finite() {
    let mut meshes = Vec::new();
    let white = material(Vec3::splat(0.99), Vec3::ZERO, 1.0);
    // Six faces of a box [-2, 2]^3, facing in.
    for (axis, sign) in [
        (0, 1.0f32),
        (0, -1.0),
        (1, 1.0),
        (1, -1.0),
        (2, 1.0),
        (2, -1.0),
    ] {
        let (p, t) = quad_y(-2.0, -2.0, 2.0, 2.0, 0.0);
        let p: Vec<Vec3> = p
            .iter()
            .map(|q| {
                let v = Vec3::new(q.x, -2.0 * sign, q.z);
                match axis {
                    0 => Vec3::new(v.y, v.x, v.z),
                    1 => v,
                    _ => Vec3::new(v.x, v.z, v.y),
                }
            })
            .collect();
        meshes.push((p, t, white.clone()));
    }
    let mut s = path(scene(
        &meshes,
        vec![Light::Point {
            position: Vec3::new(0.3, 1.0, -0.2),
            color: Vec3::ONE,
        }],
        Camera {
            eye: Vec3::new(0.0, 0.0, 1.5),
            target: Vec3::ZERO,
            up: Vec3::Y,
            projection: Projection::perspective(90.0),
        },
    ));
    // Faces see each other from both sides: the closed box has no way out.
    s.settings.max_depth = 64;
    let r = render(&s, 12, 12, 32, no_bloom(), Builder::Sah, 7);
    for v in &r.image {
        assert!(v.is_finite() && v.min_element() > 0.0, "{v}");
    }
    let (session, _) = Session::with_scene(
        s,
        &SceneRequest {
            size: Some((12, 12)),
            features: no_bloom(),
            ..SceneRequest::new("test")
        },
    );
    let tracer = session.tracer();
    let mut deepest = 0;
    for k in 0..64 {
        let tree = inspect_pixel(&tracer, 6, 6, k);
        let (mut n, mut depth) = (&tree.root, 0);
        while let Some(c) = n.children.first() {
            if let Some(b) = &n.bounce {
                let w = b.factor / b.survival;
                assert!(
                    w.is_finite() && c.weight.max_element() <= 1.01,
                    "{b:?} {}",
                    c.weight
                );
            }
            n = c;
            depth += 1;
        }
        deepest = deepest.max(depth);
    }
    assert!(deepest > 5, "paths end early: {deepest}");
}

/// `--explain` says which integrator runs and why: the scene file's
/// `integrator`, overridden by `--integrator`; Phong scenes default to
/// Whitted's.
#[test]
fn the_plan_says_which_integrator_runs_and_why() {
    let dir = std::env::temp_dir().join(format!("rayterm-path-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let scene = dir.join("s.toml");
    std::fs::write(dir.join("q.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    std::fs::write(
        &scene,
        "[[mesh]]\nfile = \"q.obj\"\n[render]\nintegrator = \"path\"\n",
    )
    .unwrap();
    let explain = |args: &[&str]| {
        let out = dir.join("x.png");
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_rayterm"))
            .args(["render", "--size", "8x8", "--spp", "1", "--explain", "-o"])
            .arg(&out)
            .args(args)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let err = String::from_utf8_lossy(&o.stderr).to_string();
        err.lines()
            .find(|l| l.contains("path tracing (indirect light)"))
            .unwrap_or_else(|| panic!("{err}"))
            .to_string()
    };
    let s = scene.to_str().unwrap();
    assert!(explain(&[s]).contains("on   on: asked for"));
    let forced = explain(&[s, "--integrator", "whitted"]);
    assert!(
        forced.contains("off  not needed: the Whitted integrator was asked for"),
        "{forced}"
    );
    let cornell = explain(&["cornell"]);
    assert!(
        cornell.contains("not needed: Phong materials only"),
        "{cornell}"
    );
    let off = explain(&["cornell", "--integrator", "path", "--no", "indirect"]);
    assert!(off.contains("off: direct light only"), "{off}");
}

/// A path-traced render split into parts merges into the single render to
/// the byte, and one resumed from its checkpoint is the uninterrupted one.
#[test]
fn path_traced_parts_and_checkpoints_make_the_single_render() {
    let dir = std::env::temp_dir().join(format!("rayterm-path-split-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let run = |args: &[&str]| {
        let o = std::process::Command::new(env!("CARGO_BIN_EXE_rayterm"))
            .current_dir(&dir)
            .args(args)
            .output()
            .unwrap();
        assert!(
            o.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
    };
    let base = [
        "render",
        "cornell-area",
        "--integrator",
        "path",
        "--size",
        "24x18",
    ];
    let with = |more: &[&'static str]| -> Vec<&'static str> {
        let mut v = base.to_vec();
        v.extend_from_slice(more);
        v
    };
    run(&with(&["--spp", "12", "-o", "single.png"]));
    run(&with(&["--samples", "0..5", "-o", "a.exr"]));
    run(&with(&["--samples", "5..12", "-o", "b.exr"]));
    run(&["merge", "b.exr", "a.exr", "-o", "merged.png"]);
    let read = |f: &str| std::fs::read(dir.join(f)).unwrap();
    assert!(
        read("single.png") == read("merged.png"),
        "the merge differs"
    );
    run(&with(&[
        "--spp",
        "5",
        "--checkpoint",
        "c.exr",
        "-o",
        "early.png",
    ]));
    run(&with(&[
        "--spp",
        "12",
        "--resume",
        "c.exr",
        "-o",
        "resumed.png",
    ]));
    assert!(
        read("single.png") == read("resumed.png"),
        "the resumed render differs"
    );
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A smooth metal sphere on a grey floor under a point light, seen from
/// above: light reaches the floor by way of the sphere (a caustic) through
/// rare bounces that leave single bright pixels. Regularization makes the
/// sphere rougher for paths that bounced off the floor, so light sampling
/// finds that light instead: no pixel of the floor stands out, and the
/// floor keeps its brightness.
#[test]
fn regularization_takes_the_fireflies_out_of_a_caustic() {
    let (fp, ft) = quad_y(-6.0, -6.0, 6.0, 6.0, 0.0);
    let (sp, st) = sphere(Vec3::new(0.0, 1.0, 0.0), 1.0, 24);
    let mut s = path(scene(
        &[(fp, ft, pbr(0.5, 0.0, 1.0)), (sp, st, pbr(0.9, 1.0, 0.15))],
        vec![Light::Photometric {
            position: Vec3::new(-1.5, 4.0, 1.5),
            intensity: Vec3::splat(200.0),
            range: None,
            cone: None,
        }],
        Camera {
            eye: Vec3::new(0.0, 7.0, 0.01),
            target: Vec3::ZERO,
            up: Vec3::NEG_Z,
            projection: Projection::perspective(51.6),
        },
    ));
    s.settings.max_depth = 4;
    // The floor around the sphere: pixels over 0.3 of the width from the
    // middle. Its mean, median, brightest, and pixels over 3x the median.
    let floor = |features: Features| {
        let r = render(&s, 32, 32, 64, features, Builder::Sah, 1);
        let mut px: Vec<f32> = (0..32 * 32)
            .filter(|i| {
                let (x, y) = ((i % 32) as f32 - 15.5, (i / 32) as f32 - 15.5);
                x.hypot(y) > 0.3 * 32.0
            })
            .map(|i| r.image[i].x)
            .collect();
        px.sort_by(f32::total_cmp);
        let mean = px.iter().sum::<f32>() / px.len() as f32;
        let median = px[px.len() / 2];
        let over = px.iter().filter(|&&v| v > 3.0 * median).count();
        (mean, median, px[px.len() - 1], over)
    };
    let (mean_off, median_off, max_off, over_off) =
        floor(no_bloom().without(&[Feature::Regularize]));
    assert!(
        over_off > 0,
        "no firefly to take out: brightest {max_off}, median {median_off}"
    );
    let (mean_on, median_on, max_on, over_on) = floor(no_bloom());
    assert_eq!(
        over_on, 0,
        "regularized: brightest {max_on}, median {median_on}"
    );
    assert!(
        (mean_on - mean_off).abs() < 0.1 * mean_off,
        "means {mean_on} and {mean_off}"
    );
}
