//! The same scene at any scale and distance from the origin: shadows stay
//! where they are (shadow rays used to pass through occluders in tiny
//! scenes, when the triangle test's bound on the rounding error of `t`
//! mixed units).

use crate::common::*;
use glam::Vec3;
use rayterm::bvh;
use rayterm::report::stability::scale::{image_difference, interior_lost, probe_render, Probed};
use rayterm::scene::{Camera, Light, Projection, Scene};

/// A box standing on a plane, lit by a point light from the side: a shadow
/// on the plane and on the box's far faces.
fn box_on_plane() -> Scene {
    let (pp, pt) = quad_y(-2.0, -2.0, 2.0, 2.0, 0.0);
    let (c, e) = (Vec3::new(0.1, 0.45, 0.0), 0.35);
    let corner = |i: u32| {
        c + e * Vec3::new(
            if i & 1 == 0 { -1.0 } else { 1.0 },
            if i & 2 == 0 { -1.0 } else { 1.0 },
            if i & 4 == 0 { -1.0 } else { 1.0 },
        )
    };
    let bp: Vec<Vec3> = (0..8).map(corner).collect();
    let bt = vec![
        [0, 1, 3],
        [0, 3, 2],
        [4, 6, 7],
        [4, 7, 5],
        [0, 4, 5],
        [0, 5, 1],
        [2, 3, 7],
        [2, 7, 6],
        [0, 2, 6],
        [0, 6, 4],
        [1, 5, 7],
        [1, 7, 3],
    ];
    let grey = material(Vec3::splat(0.7), Vec3::ZERO, 1.0);
    let mut s = scene(
        &[(pp, pt, grey.clone()), (bp, bt, grey)],
        vec![Light::Point {
            position: Vec3::new(1.2, 2.5, 0.9),
            color: Vec3::ONE,
        }],
        Camera {
            eye: Vec3::new(0.3, 2.2, 3.0),
            target: Vec3::new(0.0, 0.2, 0.0),
            up: Vec3::Y,
            projection: Projection::perspective(45.0),
        },
    );
    s.settings.ambient = Vec3::splat(0.1);
    s
}

fn probe(s: &Scene, w: u32, h: u32) -> Probed {
    let b = bvh::build(&s.geometry, s.settings.builder);
    probe_render(s, &b, w, h, 1)
}

fn shadowed(p: &Probed) -> usize {
    p.shadowed.iter().filter(|&&s| s).count()
}

#[test]
fn a_tiny_copy_of_a_scene_has_exactly_the_same_shadows() {
    let (w, h) = (64, 64);
    let unit = probe(&box_on_plane(), w, h);
    assert!(shadowed(&unit) > 100, "{} shadowed pixels", shadowed(&unit));
    for scale in [1e-6, 1e-8, (2.0f32).powi(-20)] {
        let mut s = box_on_plane();
        s.transform(scale, Vec3::ZERO);
        let small = probe(&s, w, h);
        let differ: Vec<usize> = (0..unit.shadowed.len())
            .filter(|&i| unit.shadowed[i] != small.shadowed[i])
            .collect();
        assert!(
            differ.is_empty(),
            "scale {scale:e}: {} of {} shadowed pixels differ, e.g. pixel {:?}",
            differ.len(),
            shadowed(&unit),
            differ.first().map(|i| (i % w as usize, i / w as usize))
        );
    }
}

#[test]
fn shadows_stay_from_1e_minus_8_to_1e8_and_far_from_the_origin() {
    let (w, h) = (48, 48);
    let unit = probe(&box_on_plane(), w, h);
    for (scale, offset) in [
        (1e-8, 0.0),
        (1e-4, 0.0),
        (1e4, 0.0),
        (1e8, 0.0),
        (1.0, 1e3),
        (1e-6, 1e-2),
        (1e4, 1e9),
    ] {
        let mut s = box_on_plane();
        s.transform(scale, Vec3::new(1.0, -0.5, 0.75) * offset);
        let p = probe(&s, w, h);
        let (n, lost) = interior_lost(&unit.shadowed, &p.shadowed, w, h);
        assert!(n > 20, "{n} interior shadow pixels");
        assert_eq!(
            lost, 0,
            "scale {scale:e}, offset {offset:e}: {lost} of {n} shadow pixels lit"
        );
    }
}

#[test]
fn the_monkey_keeps_its_shadows_at_1e_minus_5() -> anyhow::Result<()> {
    let Some(dir) = shared_meshes() else {
        return Ok(());
    };
    let mut s = rayterm::scene::load::open(
        &dir.join("monkey.obj").to_string_lossy(),
        &Default::default(),
    )?
    .scene;
    s.settings.ambient = Vec3::splat(0.1);
    let (w, h) = (64, 64);
    let unit = probe(&s, w, h);
    assert!(shadowed(&unit) > 20, "{} shadowed pixels", shadowed(&unit));
    for scale in [1e-5, 1e-6] {
        let mut small = s.clone();
        small.transform(scale, Vec3::ZERO);
        let p = probe(&small, w, h);
        let lit = (0..unit.shadowed.len())
            .filter(|&i| unit.shadowed[i] && !p.shadowed[i])
            .count();
        assert_eq!(
            lit,
            0,
            "scale {scale:e}: {lit} of {} shadowed pixels lit",
            shadowed(&unit)
        );
    }
    Ok(())
}

#[test]
fn huge_scenes_render_like_unit_ones_or_are_refused() {
    let (w, h) = (48, 48);
    let unit = probe(&box_on_plane(), w, h);
    assert!(unit.primary.iter().any(|&p| p));
    // 1e13 used to render black: t's numerator (length² · t) overflowed f32.
    for scale in [1e12, 1e13, 1e15, 1e17] {
        let mut s = box_on_plane();
        s.transform(scale, Vec3::ZERO);
        rayterm::scene::check_reach(&s).expect("within reach");
        let p = probe(&s, w, h);
        let diff = image_difference(&p.image, &unit.image, w, h);
        assert!(diff < 0.01, "scale {scale:e}: {diff} of the pixels differ");
        assert_eq!(p.shadowed, unit.shadowed, "scale {scale:e}");
    }
    for scale in [1e19, 1e25, 1e30, f32::MAX] {
        let mut s = box_on_plane();
        s.transform(scale, Vec3::ZERO);
        let e = rayterm::scene::check_reach(&s).unwrap_err();
        assert!(
            e.to_string().contains("renders coordinates up to 1e18"),
            "{e}"
        );
    }
}

#[test]
fn a_huge_obj_renders_like_a_small_one() -> anyhow::Result<()> {
    let dir = std::env::temp_dir().join(format!("rayterm-scale-{}", std::process::id()));
    std::fs::create_dir_all(&dir)?;
    let load = |size: &str| {
        let path = dir.join(format!("t{size}.obj"));
        std::fs::write(
            &path,
            format!("v 0 0 0\nv {size} 0 0\nv 0 {size} 0\nf 1 2 3\n"),
        )?;
        rayterm::scene::load::open(&path.to_string_lossy(), &Default::default()).map(|o| o.scene)
    };
    let (w, h) = (32, 32);
    let small = probe(&load("1")?, w, h);
    assert!(small.primary.iter().filter(|&&p| p).count() > 100);
    for size in ["1e12", "1e13", "1e16"] {
        let big = probe(&load(size)?, w, h);
        assert_eq!(big.primary, small.primary, "{size}");
        assert!(
            image_difference(&big.image, &small.image, w, h) < 0.01,
            "{size}"
        );
    }
    std::fs::remove_dir_all(&dir)?;
    Ok(())
}
