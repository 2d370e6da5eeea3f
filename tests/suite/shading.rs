//! Whitted shading against hand-computed values: Phong, shadows, reflection.

use crate::common::*;
use glam::Vec3;
use rayterm::render::{Feature, Features};
use rayterm::scene::{Builder, Light};

fn no_sampling() -> Features {
    Features::all().without(&[Feature::Supersampling, Feature::Bloom])
}

#[test]
fn phong_diffuse_and_specular_match_hand_computation() {
    let (p, t) = quad_y(-10.0, -10.0, 10.0, 10.0, 0.0);
    let kd = Vec3::new(0.5, 0.4, 0.3);
    let ks = Vec3::new(0.2, 0.2, 0.2);
    let ns = 8.0;
    let light_pos = Vec3::new(1.0, 2.0, 0.5);
    let light_col = Vec3::new(0.9, 0.8, 0.7);
    let mut s = scene(
        &[(p, t, material(kd, ks, ns))],
        vec![Light::Point {
            position: light_pos,
            color: light_col,
        }],
        top_camera(3.0),
    );
    s.settings.max_depth = 0; // no reflection: only the local Phong terms
    let r = render(&s, 9, 9, 1, no_sampling(), Builder::Sah, 1);
    // The centre pixel's ray goes straight down to the origin.
    let got = r.image[4 * 9 + 4];
    let pnt = Vec3::ZERO;
    let n = Vec3::Y;
    let l = (light_pos - pnt).normalize();
    let v = Vec3::Y;
    let refl = 2.0 * n.dot(l) * n - l;
    let expected = kd * n.dot(l) * light_col + ks * refl.dot(v).max(0.0).powf(ns) * light_col;
    assert!(
        (got - expected).abs().max_element() < 1e-5,
        "got {got}, expected {expected}"
    );
}

#[test]
fn occluded_light_contributes_nothing() {
    let (p, t) = quad_y(-10.0, -10.0, 10.0, 10.0, 0.0);
    let (bp, bt) = quad_y(-0.5, -0.5, 0.5, 0.5, 1.0); // blocker between light and floor
    let kd = Vec3::splat(0.5);
    let mut s = scene(
        &[
            (p, t, material(kd, Vec3::ZERO, 1.0)),
            (bp, bt, material(kd, Vec3::ZERO, 1.0)),
        ],
        vec![Light::Point {
            position: Vec3::new(0.0, 2.0, 0.0),
            color: Vec3::ONE,
        }],
        // Looking at the floor beside the blocker, the shadowed point is (0.6, 0, 0)?
        // Simpler: camera below the blocker's level, aimed at the floor centre from the side.
        rayterm::scene::Camera {
            eye: Vec3::new(3.0, 0.5, 0.0),
            target: Vec3::ZERO,
            up: Vec3::Y,
            projection: rayterm::scene::Projection::perspective(10.0),
        },
    );
    s.settings.ambient = Vec3::splat(0.1);
    let r = render(&s, 5, 5, 1, no_sampling(), Builder::Sah, 1);
    let centre = r.image[2 * 5 + 2];
    assert!(
        (centre - kd * 0.1).abs().max_element() < 1e-6,
        "shadowed: {centre}"
    );
    let lit = render(
        &s,
        5,
        5,
        1,
        no_sampling().without(&[Feature::Shadows]),
        Builder::Sah,
        1,
    )
    .image[12];
    assert!(lit.x > 0.4, "without shadows the point is lit: {lit}");
}

#[test]
fn mirror_reflects_the_coloured_wall_weighted_by_ks() {
    // A mirror floor, a red wall behind the camera is seen in it.
    let (fp, ft) = quad_y(-10.0, -10.0, 10.0, 10.0, 0.0);
    let wall_p = vec![
        Vec3::new(-10.0, 4.0, -10.0),
        Vec3::new(10.0, 4.0, -10.0),
        Vec3::new(10.0, 4.0, 10.0),
        Vec3::new(-10.0, 4.0, 10.0),
    ];
    let wall_t = vec![[0, 1, 2], [0, 2, 3]];
    let ks = Vec3::splat(0.8);
    let mut s = scene(
        &[
            (fp, ft, material(Vec3::ZERO, ks, 1e6)),
            (
                wall_p,
                wall_t,
                material(Vec3::new(1.0, 0.0, 0.0), Vec3::ZERO, 1.0),
            ),
        ],
        vec![],
        top_camera(2.0),
    );
    s.settings.ambient = Vec3::ONE; // the ceiling shows its kd
    let on = render(&s, 3, 3, 1, no_sampling(), Builder::Sah, 1).image[4];
    assert!(
        (on - Vec3::new(0.8, 0.0, 0.0)).abs().max_element() < 1e-6,
        "{on}"
    );
    let off = render(
        &s,
        3,
        3,
        1,
        no_sampling().without(&[Feature::Reflections]),
        Builder::Sah,
        1,
    )
    .image[4];
    assert_eq!(off, Vec3::ZERO);
}

#[test]
fn reflection_depth_is_limited() {
    // Two parallel mirrors facing each other: the number of reflection
    // generations equals max_depth.
    let (a, at) = quad_y(-50.0, -50.0, 50.0, 50.0, 0.0);
    let (b, bt) = quad_y(-50.0, -50.0, 50.0, 50.0, 1.0);
    let mut s = scene(
        &[
            (a, at, material(Vec3::splat(0.1), Vec3::splat(0.5), 1e6)),
            (b, bt, material(Vec3::splat(0.1), Vec3::splat(0.5), 1e6)),
        ],
        vec![],
        rayterm::scene::Camera {
            eye: Vec3::new(0.0, 0.5, 0.0),
            target: Vec3::new(0.1, 0.0, 0.0),
            up: Vec3::Z,
            projection: rayterm::scene::Projection::perspective(1.0),
        },
    );
    s.settings.ambient = Vec3::ONE;
    for depth in [0, 1, 5] {
        s.settings.max_depth = depth;
        let got = render(&s, 1, 1, 1, no_sampling(), Builder::Sah, 1).image[0].x;
        // 0.1 * (1 + 0.5 + 0.25 + ...) over depth + 1 hits.
        let expected: f32 = (0..=depth).map(|i| 0.1 * 0.5f32.powi(i as i32)).sum();
        assert!(
            (got - expected).abs() < 1e-6,
            "depth {depth}: {got} vs {expected}"
        );
    }
}

/// A session on `scene` at 1x1 without jitter or bloom.
fn one_pixel(scene: &rayterm::scene::Scene) -> rayterm::render::Session {
    let req = rayterm::render::SceneRequest {
        size: Some((1, 1)),
        features: no_sampling(),
        ..rayterm::render::SceneRequest::new(&scene.name)
    };
    rayterm::render::Session::with_scene(scene.clone(), &req).0
}

/// Every ray of a tree.
fn count(n: &rayterm::inspect::tree::RayNode) -> usize {
    1 + n.children.iter().map(count).sum::<usize>()
}

/// Camera between two horizontal planes, looking along them at a slant.
fn between_planes() -> rayterm::scene::Camera {
    rayterm::scene::Camera {
        eye: Vec3::new(0.0, 0.5, 0.0),
        target: Vec3::new(1.0, 0.2, 0.0),
        up: Vec3::Y,
        projection: rayterm::scene::Projection::perspective(1.0),
    }
}

#[test]
fn glossy_splits_stop_at_the_most_paths_a_tree_may_have() {
    // Two glossy planes facing each other, 256 lobe samples a hit, 64
    // bounces: split at every hit, 256^64 rays. The tree splits at the
    // first hit only, and each of its 256 paths goes on with one sample.
    use rayterm::render::integrator::MAX_PATHS;
    let glossy = material(Vec3::splat(0.1), Vec3::splat(0.5), 200.0);
    let (a, at) = quad_y(-1e4, -1e4, 1e4, 1e4, 0.0);
    let (b, bt) = quad_y(-1e4, -1e4, 1e4, 1e4, 1.0);
    let mut s = scene(
        &[(a, at, glossy.clone()), (b, bt, glossy)],
        vec![],
        between_planes(),
    );
    s.settings.ambient = Vec3::ONE;
    s.settings.max_depth = 64;
    s.settings.glossy_samples = MAX_PATHS;
    let session = one_pixel(&s);
    let tree = rayterm::inspect::tree::inspect_pixel(&session.tracer(), 0, 0, 0);
    let first = &tree.root.children;
    assert_eq!(first.len(), MAX_PATHS as usize, "the first hit splits");
    // The most children of any ray below `n`, `n` included.
    fn widest(n: &rayterm::inspect::tree::RayNode) -> usize {
        n.children
            .iter()
            .map(widest)
            .fold(n.children.len(), usize::max)
    }
    assert!(first.iter().all(|c| widest(c) <= 1), "later hits do not");
    let rays = count(&tree.root);
    assert!(rays <= 1 + 64 * MAX_PATHS as usize, "{rays} rays");
    assert!(rays > 10 * MAX_PATHS as usize, "paths go on: {rays} rays");
}

#[test]
fn surfaces_that_reflect_and_transmit_keep_the_mean_past_the_most_paths() {
    // A stack of half-transparent mirrors: every hit both reflects and lets
    // light through, so the tree doubles at each of 14 bounces (but for the
    // rays that leave the stack). Past 256 paths a hit follows one branch at
    // random; the mean over samples is the full tree's value.
    let mut m = material(Vec3::splat(0.2), Vec3::splat(0.6), 1e6);
    m.dissolve = 0.5;
    let planes: Vec<_> = (-6..=6)
        .map(|i| {
            let (p, t) = quad_y(-1e4, -1e4, 1e4, 1e4, i as f32);
            (p, t, m.clone())
        })
        .collect();
    let mut s = scene(&planes, vec![], between_planes());
    s.settings.ambient = Vec3::ONE;
    s.settings.max_depth = 14;
    let session = one_pixel(&s);
    let mut tracer = session.tracer();
    let sample = |t: &rayterm::render::Tracer, k| {
        let mut rec = rayterm::render::RayCounter::default();
        (t.sample(0, 0, k, &mut rec).x as f64, rec.rays)
    };
    tracer.max_paths = u32::MAX;
    let (exact, full) = sample(&tracer, 0);
    assert!(full > 2000, "the full tree: {full} rays");
    tracer.max_paths = rayterm::render::integrator::MAX_PATHS;
    let n = 4000;
    let got: Vec<(f64, u64)> = (0..n).map(|k| sample(&tracer, k)).collect();
    let most = got.iter().map(|g| g.1).max().unwrap();
    assert!(most < full, "{most} rays of {full}");
    let mean = got.iter().map(|g| g.0).sum::<f64>() / n as f64;
    let var = got.iter().map(|g| (g.0 - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
    let se = (var / n as f64).sqrt();
    assert!(var > 0.0, "branches are chosen at random");
    assert!(
        (mean - exact).abs() < 5.0 * se + 1e-6,
        "mean {mean} of {n} against the full tree's {exact} (standard error {se})"
    );
}

#[test]
fn a_tree_lists_a_bounded_number_of_light_samples() {
    // 256 glossy paths of 64 bounces, 64 samples of an area light at each
    // hit: about a million light samples, of which a tree lists 2^18.
    use rayterm::inspect::tree::LISTED_LIGHT_SAMPLES;
    let glossy = material(Vec3::splat(0.1), Vec3::splat(0.5), 200.0);
    let (a, at) = quad_y(-1e4, -1e4, 1e4, 1e4, 0.0);
    let (b, bt) = quad_y(-1e4, -1e4, 1e4, 1e4, 1.0);
    let light = Light::Parallelogram {
        corner: Vec3::new(-0.1, 0.9, -0.1),
        edge1: Vec3::new(0.2, 0.0, 0.0),
        edge2: Vec3::new(0.0, 0.0, 0.2),
        colors: [Vec3::ONE; 4],
    };
    let mut s = scene(
        &[(a, at, glossy.clone()), (b, bt, glossy)],
        vec![light],
        between_planes(),
    );
    s.settings.max_depth = 64;
    s.settings.glossy_samples = 256;
    s.settings.light_samples = 64;
    let session = one_pixel(&s);
    let tree = rayterm::inspect::tree::inspect_pixel(&session.tracer(), 0, 0, 0);
    fn listed(n: &rayterm::inspect::tree::RayNode) -> u64 {
        let here: usize = n.lights.iter().map(|l| l.samples.len()).sum();
        here as u64 + n.children.iter().map(listed).sum::<u64>()
    }
    assert_eq!(listed(&tree.root), LISTED_LIGHT_SAMPLES);
    assert!(
        tree.light_samples_not_listed > LISTED_LIGHT_SAMPLES,
        "{}",
        tree.light_samples_not_listed
    );
    let text = rayterm::inspect::to_text(&tree, false);
    assert!(
        text.contains("more light samples traced, not listed"),
        "{}",
        &text[text.len().saturating_sub(300)..]
    );
}

/// The centre pixel of a 9x9 exact render from straight above the
/// origin, with no ambient light and no reflection rays.
fn centre(meshes: &[TestMesh], lights: Vec<Light>) -> Vec3 {
    let mut s = scene(meshes, lights, top_camera(3.0));
    s.settings.max_depth = 0;
    let r = render(&s, 9, 9, 1, no_sampling(), Builder::Sah, 1);
    r.image[4 * 9 + 4]
}

fn floor(m: rayterm::scene::Material) -> Vec<TestMesh> {
    let (p, t) = quad_y(-10.0, -10.0, 10.0, 10.0, 0.0);
    vec![(p, t, m)]
}

fn candela(position: Vec3, intensity: f32) -> Light {
    Light::Photometric {
        position,
        intensity: Vec3::splat(intensity),
        range: None,
        cone: None,
    }
}

fn close(got: f32, want: f32, tolerance: f32) -> bool {
    (got - want).abs() <= tolerance * want.abs()
}

/// A diffuse surface under a point light of I candela at distance d has
/// radiance albedo/π · I cos θ / d², and a quarter of it at twice the
/// distance (half at 1.414 d).
#[test]
fn a_point_light_in_candela_falls_off_with_the_square_of_the_distance() {
    let albedo = 0.5;
    let lambert = || floor(material(Vec3::splat(albedo), Vec3::ZERO, 1.0));
    let i = 100.0;
    for (a, d) in [
        (0.0f32, 2.0f32),
        (1.5, 2.0),
        (0.0, 2.0 * 2f32.sqrt()),
        (3.0, 1.0),
    ] {
        let got = centre(&lambert(), vec![candela(Vec3::new(a, d, 0.0), i)]).x;
        let r2 = a * a + d * d;
        let want = albedo / std::f32::consts::PI * i * (d / r2.sqrt()) / r2;
        assert!(close(got, want, 0.005), "at ({a}, {d}): {got}, want {want}");
    }
    let near = centre(&lambert(), vec![candela(Vec3::new(0.0, 2.0, 0.0), i)]).x;
    let far = centre(
        &lambert(),
        vec![candela(Vec3::new(0.0, 2.0 * 2f32.sqrt(), 0.0), i)],
    )
    .x;
    assert!(close(far / near, 0.5, 0.005), "{far} / {near}");
}

/// A spot light's cone follows `KHR_lights_punctual`'s falloff: full
/// inside the inner angle, none outside the outer, the square of the
/// cosine's ramp between; a range windows the light to zero at it.
#[test]
fn spot_cones_and_ranges_follow_the_lights_extension() {
    use rayterm::scene::light::Cone;
    let lambert = || floor(material(Vec3::splat(1.0), Vec3::ZERO, 1.0));
    let (inner, outer) = (0.2f32, 0.6f32);
    let spot = |tilt: f32, range: Option<f32>| Light::Photometric {
        position: Vec3::new(0.0, 2.0, 0.0),
        intensity: Vec3::splat(40.0),
        range,
        cone: Some(Cone {
            axis: Vec3::new(tilt.sin(), -tilt.cos(), 0.0),
            cos_inner: inner.cos(),
            cos_outer: outer.cos(),
        }),
    };
    let full = 40.0 / std::f32::consts::PI / 4.0;
    for (tilt, share) in [
        (0.0f32, 1.0f32),
        (0.15, 1.0),
        (0.4, {
            let t = (0.4f32.cos() - outer.cos()) / (inner.cos() - outer.cos());
            t * t
        }),
        (0.7, 0.0),
    ] {
        let got = centre(&lambert(), vec![spot(tilt, None)]).x;
        let want = full * share;
        assert!(
            (got - want).abs() <= 0.005 * full,
            "tilt {tilt}: {got}, want {want}"
        );
    }
    // The window 1 - (d/range)^4: at half the range, 15/16.
    let got = centre(&lambert(), vec![spot(0.0, Some(4.0))]).x;
    assert!(close(got, full * 15.0 / 16.0, 0.005), "{got}");
    assert_eq!(centre(&lambert(), vec![spot(0.0, Some(1.9))]).x, 0.0);
}

/// A directional light of E lux gives albedo/π · E cos θ, wherever the
/// surface is, and its shadow rays reach to infinity.
#[test]
fn a_directional_light_in_lux_lights_by_the_cosine() {
    let albedo = 0.8;
    let theta = 0.5f32;
    let sun = Light::Directional {
        direction: Vec3::new(theta.sin(), -theta.cos(), 0.0),
        illuminance: Vec3::splat(3.0),
    };
    let got = centre(
        &floor(material(Vec3::splat(albedo), Vec3::ZERO, 1.0)),
        vec![sun.clone()],
    )
    .x;
    let want = albedo / std::f32::consts::PI * 3.0 * theta.cos();
    assert!(close(got, want, 0.005), "{got}, want {want}");
    // A far blocker on the light's way, off camera.
    let (bp, bt) = quad_y(-1e4, -1e4, 1e4, 1e4, 5e3);
    let mut meshes = floor(material(Vec3::splat(albedo), Vec3::ZERO, 1.0));
    meshes.push((bp, bt, material(Vec3::ONE, Vec3::ZERO, 1.0)));
    assert_eq!(centre(&meshes, vec![sun]).x, 0.0);
}

/// glTF's metallic-roughness BRDF, by hand from its specification at
/// normal incidence (light and viewer straight above): a dielectric
/// reflects (1 - 0.04) of its base colour diffusely, plus 0.04 D V with
/// D = 1/(π α²) and V = 1/4 at the normal; a metal only the specular
/// term with its base colour as F0. A Phong light lights it as one of π
/// times its colour in lux.
#[test]
fn metallic_roughness_matches_its_specification_at_normal_incidence() {
    use rayterm::scene::{Material, Pbr};
    let pi = std::f32::consts::PI;
    let pbr = |base: f32, metallic: f32, roughness: f32| Material {
        kd: Vec3::splat(base),
        pbr: Some(Pbr {
            metallic,
            roughness,
            ..Pbr::default()
        }),
        ..Material::default()
    };
    // The light just beside the camera's ray, both 3 above the floor:
    // light, view and normal agree to 1e-4.
    let light = |i: f32| candela(Vec3::new(1e-4, 3.0, 0.0), i);
    let e = 90.0 / 9.0;
    for (base, metallic, roughness) in [(0.5f32, 0.0f32, 1.0f32), (0.5, 0.0, 0.5), (0.8, 1.0, 0.7)]
    {
        let alpha = roughness * roughness;
        let d = 1.0 / (pi * alpha * alpha);
        let f0 = 0.04 * (1.0 - metallic) + base * metallic;
        let diffuse = (1.0 - f0) * base * (1.0 - metallic) / pi;
        let want = (diffuse + f0 * d * 0.25) * e;
        let got = centre(&floor(pbr(base, metallic, roughness)), vec![light(90.0)]).x;
        assert!(
            close(got, want, 0.005),
            "{base} {metallic} {roughness}: {got}, want {want}"
        );
    }
    let phong_light = Light::Point {
        position: Vec3::new(1e-4, 3.0, 0.0),
        color: Vec3::splat(e / pi),
    };
    let by_phong = centre(&floor(pbr(0.5, 0.0, 1.0)), vec![phong_light]).x;
    let by_candela = centre(&floor(pbr(0.5, 0.0, 1.0)), vec![light(90.0)]).x;
    assert!(close(by_phong, by_candela, 1e-5), "{by_phong} {by_candela}");
}

/// Lights from a millionth to a billion candela, mirror and fully rough
/// surfaces, grazing lights: the film stays finite and non-negative.
#[test]
fn extreme_lights_and_roughness_stay_finite() {
    use rayterm::scene::{Material, Pbr};
    for roughness in [0.0f32, 0.01, 1.0] {
        for metallic in [0.0f32, 1.0] {
            for i in [1e-6f32, 1.0, 1e9] {
                for light in [Vec3::new(0.0, 1e-3, 5.0), Vec3::new(0.0, 2.0, 0.0)] {
                    let m = Material {
                        kd: Vec3::ONE,
                        pbr: Some(Pbr {
                            metallic,
                            roughness,
                            ..Pbr::default()
                        }),
                        ..Material::default()
                    };
                    let got = centre(&floor(m), vec![candela(light, i)]);
                    assert!(
                        got.is_finite() && got.min_element() >= 0.0,
                        "r {roughness} m {metallic} i {i} at {light}: {got}"
                    );
                }
            }
        }
    }
}

/// A constant environment of radiance L lights an open floor with the
/// irradiance πL: a matte Phong floor of colour kd shows kd L, a white
/// matte metallic-roughness one its diffuse share; a roof cuts it off
/// (its shadow rays are blocked), and `--no environment` turns it off.
#[test]
fn an_environment_light_lights_by_its_irradiance() {
    use rayterm::scene::{EnvLight, Environment};
    let mean = |meshes: &[TestMesh], features: Features| {
        let mut s = scene(meshes, vec![], top_camera(3.0));
        s.environment = Environment::Light(Box::new(EnvLight::constant(Vec3::splat(2.0))));
        s.settings.max_depth = 0;
        let r = render(&s, 9, 9, 64, features, Builder::Sah, 1);
        // The middle 5x5 pixels, all on the floor.
        let mut sum = Vec3::ZERO;
        for y in 2..7 {
            for x in 2..7 {
                sum += r.image[y * 9 + x];
            }
        }
        sum / 25.0
    };
    let matte = floor(material(Vec3::splat(0.5), Vec3::ZERO, 1.0));
    let got = mean(&matte, Features::all().without(&[Feature::Bloom])).x;
    assert!(close(got, 1.0, 0.01), "{got}");
    let off = Features::all().without(&[Feature::Bloom, Feature::Environment]);
    assert_eq!(mean(&matte, off).x, 0.0);
    let mut roofed = matte.clone();
    let (rp, rt) = quad_y(-1e4, -1e4, 1e4, 1e4, 10.0);
    // The roof faces up: the camera below it sees the floor.
    roofed.push((rp, rt, material(Vec3::ONE, Vec3::ZERO, 1.0)));
    let got = mean(&roofed, Features::all().without(&[Feature::Bloom])).x;
    assert!(got < 0.01, "{got}");
}
