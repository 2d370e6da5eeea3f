//! Whitted shading against hand-computed values: Phong, shadows, reflection.

mod common;

use common::*;
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
            vfov: 10.0,
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
            vfov: 1.0,
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
