//! The scene plan: what each built-in scene needs, and that leaving stages
//! out never changes the image.

use crate::common::*;
use rayterm::render::{Feature, Features, Plan, PlanPolicy};
use rayterm::scene::{self, Builder};

/// (scene, textures, smooth normals, reflections, glossy, area sampling, environment)
const TABLE: &[(&str, bool, bool, bool, bool, bool, bool)] = &[
    ("cornell", false, false, true, false, false, false),
    ("cornell-area", false, false, true, false, true, false),
    ("cube-textured", true, true, false, false, false, false),
    ("mirrors", false, true, true, true, false, false),
    ("teapot", false, true, true, false, false, false),
    ("env", false, true, true, true, false, true),
];

#[test]
fn plan_of_each_builtin_follows_the_rules() {
    for &(name, tex, smooth, refl, glossy, area, env) in TABLE {
        let s = scene::load::open(name, &Default::default()).unwrap().scene;
        let p = Plan::new(&s, Features::all(), PlanPolicy::Prune);
        assert_eq!(p.textures, tex, "{name} textures");
        assert_eq!(p.smooth_normals, smooth, "{name} smooth normals");
        assert_eq!(p.reflections, refl, "{name} reflections");
        assert_eq!(p.specular, refl, "{name} specular term");
        assert_eq!(p.glossy, glossy, "{name} glossy");
        assert_eq!(p.area_sampling, area, "{name} area sampling");
        assert_eq!(p.environment, env, "{name} environment");
        assert!(p.shadows && p.bvh && p.supersampling);
        // Every stage that is off because of the scene says why.
        for (stage, on, reason) in p.rows() {
            assert!(
                on || reason.starts_with("not needed: ") || reason.starts_with("off"),
                "{stage}: {reason}"
            );
        }
        // Without supersampling, only area lights and glossy materials sample.
        let q = Plan::new(
            &s,
            Features::all().without(&[Feature::Supersampling]),
            PlanPolicy::Prune,
        );
        assert_eq!(q.deterministic, !(area || glossy), "{name} deterministic");
    }
}

#[test]
fn toggled_off_features_are_off_whatever_the_scene() {
    let s = scene::load::open("cube-textured", &Default::default())
        .unwrap()
        .scene;
    let p = Plan::new(
        &s,
        Features::all().without(&[Feature::Textures]),
        PlanPolicy::Prune,
    );
    assert!(!p.textures && !p.bilinear);
    let (_, on, reason) = p
        .rows()
        .into_iter()
        .find(|r| r.0.starts_with("bilinear"))
        .unwrap();
    assert_eq!((on, reason.as_str()), (false, "off: needs textures"));
}

#[test]
fn plan_on_and_off_give_identical_deterministic_images() {
    let f = Features::all().without(&[Feature::Supersampling, Feature::Bloom]);
    for name in ["cornell", "teapot", "cube-textured", "env"] {
        let s = scene::load::open(name, &Default::default()).unwrap().scene;
        let bvh = rayterm::bvh::build(&s.geometry, Builder::Sah);
        let with = render_with(&s, &bvh, &Plan::new(&s, f, PlanPolicy::Prune), 48, 36, 1, 1);
        let without = render_with(
            &s,
            &bvh,
            &Plan::new(&s, f, PlanPolicy::Everything),
            48,
            36,
            1,
            1,
        );
        for (a, b) in with.image.iter().zip(&without.image) {
            assert_eq!(
                a.to_array().map(f32::to_bits),
                b.to_array().map(f32::to_bits),
                "{name}"
            );
        }
    }
}

#[test]
fn plan_on_and_off_agree_on_sampled_scenes() {
    let s = scene::load::open("cornell-area", &Default::default())
        .unwrap()
        .scene;
    let bvh = rayterm::bvh::build(&s.geometry, Builder::Sah);
    let f = Features::all().without(&[Feature::Bloom]);
    let a = render_with(&s, &bvh, &Plan::new(&s, f, PlanPolicy::Prune), 24, 24, 8, 1);
    let b = render_with(
        &s,
        &bvh,
        &Plan::new(&s, f, PlanPolicy::Everything),
        24,
        24,
        8,
        2,
    );
    let mean =
        |r: &Rendered| r.image.iter().map(|c| c.x as f64).sum::<f64>() / r.image.len() as f64;
    let se = |r: &Rendered| {
        let v: f64 = r
            .film
            .pixels()
            .iter()
            .map(|p| p.std_error().powi(2))
            .sum::<f64>();
        v.sqrt() / r.image.len() as f64
    };
    let (ma, mb) = (mean(&a), mean(&b));
    assert!(
        (ma - mb).abs() < 4.0 * (se(&a).hypot(se(&b))) + 1e-6,
        "{ma} vs {mb}"
    );
}

#[test]
fn deterministic_scene_finishes_in_one_pass() {
    let dir = std::env::temp_dir().join(format!("rayterm-plan-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("c.png");
    let o = std::process::Command::new(env!("CARGO_BIN_EXE_rayterm"))
        .args([
            "render",
            "cornell",
            "--no",
            "supersampling",
            "--spp",
            "8",
            "--size",
            "32x32",
            "--explain",
        ])
        .arg("-o")
        .arg(&out)
        .output()
        .unwrap();
    assert!(o.status.success());
    let stdout = String::from_utf8_lossy(&o.stdout);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert!(
        stdout.contains(" 1 spp") && stdout.contains("error exact"),
        "{stdout}"
    );
    assert!(stderr.contains("one pass is exact"), "{stderr}");
    assert!(
        stderr.contains(
            "UV interpolation and texture lookups  off  not needed: no textures in scene"
        ),
        "{stderr}"
    );
    std::fs::remove_dir_all(&dir).ok();
}
