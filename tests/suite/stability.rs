//! Every row of the stability battery as a test (at reduced sizes), and
//! controls showing that each measurement can fail: a hole lets rays escape,
//! a non-watertight intersector misses the rays aimed at edges and vertices,
//! a shrunken BVH box loses grazing hits, a shifted image differs.

use glam::{DVec3, Vec3};
use rayterm::bvh::{self, Bvh};
use rayterm::geometry::sampling::Rng;
use rayterm::geometry::Ray;
use rayterm::report::stability::scale::{
    aimed_leaks, image_difference, interior_lost, interior_lost_within, own_surface, place,
    probe_render, shadow_edge_allowance, transform_rows, Transform, TRANSFORMS,
};
use rayterm::report::stability::topology::{Crossing, Topology};
use rayterm::report::stability::watertight::{aimed_rays, random_rays, sphere, teapot};
use rayterm::report::stability::{self as st, grazing, hygiene, Options, Row};
use rayterm::scene::{self, Builder, Geometry};

fn small() -> Options {
    Options {
        width: 32,
        height: 32,
        rays: 2000,
        teapot_segments: 4,
        seed: 3,
    }
}

fn all_pass(rows: &[Row]) {
    assert!(!rows.is_empty());
    let failed: Vec<&Row> = rows.iter().filter(|r| !r.pass).collect();
    assert!(failed.is_empty(), "{}", st::format_table(rows));
}

#[test]
fn scale_and_offset_rows_pass() {
    let scene = scene::load::open("cornell", &Default::default())
        .unwrap()
        .scene;
    let rows = st::scale_offset(&scene, &small()).unwrap();
    all_pass(&rows);
    // Acne, shadows and leaks for every transform, and an image row for all but the identity.
    assert_eq!(rows.len(), 4 * TRANSFORMS.len() - 1);
}

#[test]
fn scale_cases_measure_something() {
    // The probe sees shadow rays from lit surfaces at every scale, and a
    // transformed render that is plainly the same picture.
    let base = scene::load::open("cornell", &Default::default())
        .unwrap()
        .scene;
    let b = bvh::build(&base.geometry, Builder::Sah);
    let reference = probe_render(&base, &b, 24, 24, 1);
    assert!(reference.lit > 24 * 24 / 2, "{}", reference.lit);
    assert!(
        reference.primary.iter().all(|&h| h),
        "the box fills the view"
    );
    let (umbra, _) = interior_lost(&reference.shadowed, &reference.shadowed, 24, 24);
    assert!(umbra >= 4, "{umbra} pixels inside the blocks' shadows");
    for t in TRANSFORMS {
        let s = place(&base, t).0;
        let b = bvh::build(&s.geometry, Builder::Sah);
        let p = probe_render(&s, &b, 24, 24, 1);
        assert_eq!(p.acne, 0, "{}", t.label());
        assert!(p.lit > 24 * 24 / 2, "{}: {}", t.label(), p.lit);
        let (aimed, missed) = aimed_leaks(&s, &b, 200, 1);
        assert!(aimed > 200, "{}: {aimed}", t.label());
        assert_eq!(missed, 0, "{}", t.label());
    }
}

#[test]
fn image_difference_forgives_one_pixel_edges_only() {
    // A vertical edge; moving it by one pixel is forgiven, by three is not.
    let img: Vec<Vec3> = (0..64)
        .map(|i| Vec3::splat((i % 8 >= 4) as u8 as f32))
        .collect();
    assert_eq!(image_difference(&img, &img, 8, 8), 0.0);
    let shift = |by: usize| -> Vec<Vec3> {
        (0..64)
            .map(|i| img[i / 8 * 8 + (i % 8 + by).min(7)])
            .collect()
    };
    assert_eq!(image_difference(&img, &shift(1), 8, 8), 0.0);
    assert_eq!(image_difference(&img, &shift(3), 8, 8), 3.0 / 8.0);
    let mut nan = img.clone();
    nan[5] = Vec3::NAN;
    assert_eq!(image_difference(&img, &nan, 8, 8), 1.0 / 64.0);
    let mut darker = img.clone();
    darker[20] *= 0.5;
    assert_eq!(image_difference(&img, &darker, 8, 8), 1.0 / 64.0);
}

#[test]
fn lost_shadows_count_inside_shadows_only() {
    // A 6x6 shadow in an 8x8 image: its 4x4 interior is checked; a lit
    // pixel on its edge (rounding moving the edge) is not a loss, a lit
    // pixel inside is.
    let shadow: Vec<bool> = (0..64)
        .map(|i| (1..7).contains(&(i % 8)) && (1..7).contains(&(i / 8)))
        .collect();
    assert_eq!(interior_lost(&shadow, &shadow, 8, 8), (16, 0));
    let mut edge = shadow.clone();
    edge[8 + 3] = false;
    assert_eq!(interior_lost(&shadow, &edge, 8, 8), (16, 0));
    let mut inside = shadow.clone();
    inside[3 * 8 + 3] = false;
    assert_eq!(interior_lost(&shadow, &inside, 8, 8), (16, 1));
    assert_eq!(interior_lost(&shadow, &[false; 64], 8, 8), (16, 16));
    // Edges allowed to move by 2 pixels: the 2x2 centre is checked, a lit
    // pixel there is still a loss, one a pixel inside the edge is not.
    assert_eq!(interior_lost_within(&shadow, &shadow, 8, 8, 2), (4, 0));
    assert_eq!(interior_lost_within(&shadow, &inside, 8, 8, 2), (4, 1));
    let mut near_edge = shadow.clone();
    near_edge[2 * 8 + 2] = false;
    assert_eq!(interior_lost(&shadow, &near_edge, 8, 8), (16, 1));
    assert_eq!(interior_lost_within(&shadow, &near_edge, 8, 8, 2), (4, 0));
}

#[test]
fn far_shadow_edges_move_within_their_error_bound_at_high_resolution() {
    // Cornell at 1e4 sizes from the origin, rendered out there: shadow-ray
    // origins are 5 f32 steps (0.0049) above the floor, which moves the far
    // edge of the short box's shadow by 2 pixels at 1024x1024. Counted
    // against its 8 neighbours, 18 umbra pixels were lost; the allowance is
    // the origins' error bound in pixels, 1 at the default size.
    let scene = scene::load::open("cornell", &Default::default())
        .unwrap()
        .scene;
    let t = Transform::new(1.0, 1e4);
    let moved = place(&scene, t).0;
    assert_eq!(shadow_edge_allowance(&moved, 96, 96), 1);
    assert_eq!(shadow_edge_allowance(&moved, 1024, 1024), 9);
    assert_eq!(shadow_edge_allowance(&scene, 1024, 1024), 1);
    let near = place(&scene, Transform::new(1.0, 1e3)).0;
    assert_eq!(shadow_edge_allowance(&near, 1024, 1024), 1);
    let o = Options {
        width: 1024,
        height: 1024,
        ..Options::default()
    };
    let b = bvh::build(&scene.geometry, Builder::Sah);
    let reference = probe_render(&scene, &b, o.width, o.height, o.seed);
    let rows = transform_rows(&scene, t, &reference, &o);
    let shadows = rows.iter().find(|r| r.case.ends_with("shadows")).unwrap();
    assert!(shadows.pass, "{shadows:?}");
    assert!(shadows.detail.contains("within 9 pixels"), "{shadows:?}");
}

#[test]
fn own_surface_is_the_triangle_or_its_plane() {
    let s = scene::load::open("cornell", &Default::default())
        .unwrap()
        .scene;
    let g = &s.geometry;
    // Triangles 0 and 1 are the two halves of the floor, 2 and 3 the
    // ceiling, 10.. the short box, 30 and 31 the light panel under the ceiling.
    let (u, v) = (0.3, 0.3);
    assert!(own_surface(g, 0, 0, u, v));
    assert!(own_surface(g, 0, 1, u, v));
    assert!(!own_surface(g, 0, 10, u, v));
    assert!(
        !own_surface(g, 0, 2, u, v),
        "the ceiling is parallel, not the same plane"
    );
    // Far out, the panel 0.005 under the ceiling is still another surface.
    let mut far = s.clone();
    far.transform(1.0, Vec3::new(1e4, -5e3, 7.5e3));
    assert!(own_surface(&far.geometry, 2, 3, u, v));
    assert!(!own_surface(&far.geometry, 2, 30, u, v));
}

#[test]
fn watertight_rows_pass() {
    all_pass(&st::watertight(&small()).unwrap());
}

#[test]
fn a_hole_lets_rays_escape() {
    let mut tris = sphere().unwrap();
    let closed = bvh::build(&Geometry::from_triangles(&tris), Builder::Sah);
    let mut rng = Rng::for_sample(0, 0, 9);
    let rays = random_rays(Vec3::new(0.01, -0.02, 0.03), 20_000, &mut rng);
    assert_eq!(st::escapes(&closed, &rays).escaped, 0);
    tris.swap_remove(700);
    let holed = bvh::build(&Geometry::from_triangles(&tris), Builder::Sah);
    assert!(st::escapes(&holed, &rays).escaped > 0);
}

/// Möller-Trumbore with strict inequalities and an epsilon: the classic
/// non-watertight test, which misses rays through edges and vertices.
fn naive_hit(r: &Ray, t: &[Vec3; 3]) -> bool {
    let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
    let p = r.dir.cross(e2);
    let det = e1.dot(p);
    if det.abs() < 1e-7 {
        return false;
    }
    let s = r.origin - t[0];
    let u = s.dot(p) / det;
    let q = s.cross(e1);
    let v = r.dir.dot(q) / det;
    u > 0.0 && v > 0.0 && u + v < 1.0 && e2.dot(q) / det > 1e-6
}

#[test]
fn aimed_rays_graze_edges_and_vertices() {
    // Aimed at vertices and edges from inside the sphere, every ray hits the
    // watertight BVH, and a naive intersector loses some of them.
    let tris = sphere().unwrap();
    let topo = Topology::new(tris.clone());
    let b = bvh::build(&Geometry::from_triangles(&tris), Builder::Sah);
    let mut rng = Rng::for_sample(0, 0, 4);
    let inside = [Vec3::new(0.01, -0.02, 0.03)];
    for kind in [Crossing::Vertex, Crossing::Edge] {
        let rays = aimed_rays(&topo, &inside, kind, 0, &mut rng);
        assert!(rays.len() > 500, "{kind:?}: {}", rays.len());
        assert_eq!(st::escapes(&b, &rays).escaped, 0, "{kind:?}");
        let naive_misses = rays
            .iter()
            .filter(|r| !tris.iter().any(|t| naive_hit(r, t)))
            .count();
        assert!(naive_misses > 0, "{kind:?}: the targets are not on edges");
    }
}

#[test]
fn a_hole_in_the_teapot_is_not_taken_for_its_lid_gap() {
    use rayterm::report::stability::watertight::through_lid_gap;
    let mut pot = teapot(4).unwrap();
    let inside = Vec3::new(0.013, 0.6, -0.021);
    let mut rng = Rng::for_sample(0, 0, 6);
    let rays = random_rays(inside, 20_000, &mut rng);
    let elsewhere = |pot: &[[Vec3; 3]]| {
        let b = bvh::build(&Geometry::from_triangles(pot), Builder::Sah);
        rays.iter()
            .filter(|r| b.intersect_brute(r).is_none() && !through_lid_gap(r))
            .count()
    };
    assert_eq!(elsewhere(&pot), 0);
    // Punch out the body triangle nearest (0, 0.5, 1), away from spout and handle.
    let centre = |t: &[Vec3; 3]| (t[0] + t[1] + t[2]) / 3.0;
    let i = (0..pot.len())
        .min_by(|&a, &b| {
            let d = |i: usize| centre(&pot[i]).distance(Vec3::new(0.0, 0.5, 1.0));
            d(a).total_cmp(&d(b))
        })
        .unwrap();
    pot.swap_remove(i);
    assert!(elsewhere(&pot) > 0);
}

#[test]
fn teapot_seams_are_closed_and_its_openings_are_the_datas() {
    for n in [2, 3, 8] {
        let topo = Topology::new(teapot(n).unwrap());
        assert_eq!(topo.hairline_cracks(1e-5), 0, "N = {n}");
        assert_eq!(topo.boundary_edges().len(), 16 * n as usize, "N = {n}");
    }
}

#[test]
fn grazing_rows_pass() {
    all_pass(&st::grazing(&small()).unwrap());
}

/// Rays along the lattice's integer planes (its outer faces among them), in
/// every grazing direction.
fn lattice_rays() -> Vec<Ray> {
    let mut rays = Vec::new();
    for d in grazing::grazing_directions() {
        let a = d.abs().max_position();
        for (p, q) in [
            (0.0, 0.0),
            (0.0, 1.0),
            (3.0, 1.0),
            (1.0, 3.0),
            (3.0, 3.0),
            (1.0, 2.0),
        ] {
            let mut o = Vec3::splat(p);
            o[(a + 1) % 3] = p;
            o[(a + 2) % 3] = q;
            o[a] = if d[a] > 0.0 { -1.0 } else { 4.0 };
            rays.push(Ray::new(o, d));
        }
    }
    rays
}

#[test]
fn a_shrunken_box_loses_grazing_hits() {
    let g = Geometry::from_triangles(&grazing::lattice());
    let rays = lattice_rays();
    for builder in [Builder::Sah, Builder::Median] {
        let mut b: Bvh = bvh::build(&g, builder);
        let anc = grazing::ancestors(&b);
        let ok = grazing::check_rays(&b, &anc, &rays);
        assert_eq!((ok.nan, ok.disagree, ok.box_misses), (0, 0, 0), "{ok:?}");
        // Pull every box's faces in by one ulp: rays along them are lost.
        b.edit_nodes(|n| {
            n.max = n.max.map(f32::next_down);
            n.min = n.min.map(f32::next_up);
        });
        let bad = grazing::check_rays(&b, &anc, &rays);
        assert!(bad.box_misses > 0 && bad.disagree > 0, "{bad:?}");
    }
}

#[test]
fn degenerate_rows_pass() {
    all_pass(&st::degenerate(&small()).unwrap());
}

#[test]
fn stiff_shading_rows_pass() {
    all_pass(&st::stiff_shading(&small()).unwrap());
}

#[test]
fn stiff_bound_scales_with_the_light() {
    use rayterm::report::stability::stiff::{bound, stage};
    let a = bound(&stage(30.0, Vec3::Y * 4.0, 1.0, false).unwrap());
    let b = bound(&stage(30.0, Vec3::Y * 4.0, 2.0, false).unwrap());
    assert!(b > 1.9 * a && b < 2.1 * a, "{a} {b}");
}

#[test]
fn reintersection_rows_pass() {
    all_pass(&st::reintersection(&small()).unwrap());
}

#[test]
fn reintersection_spawns_from_every_scale() {
    let r = st::reintersect::random_triangles(500, 5);
    assert!(r.spawned > 1000, "{r:?}");
    assert_eq!(r.rehits, 0);
    // Without the offset a ray leaving the surface often hits it again: the
    // test would see it.
    use rayterm::geometry::triangle::{intersect, RayShear};
    let tri = [
        Vec3::new(1e5, 0.0, 0.0),
        Vec3::new(1e5 + 1.0, 0.3, 0.1),
        Vec3::new(1e5, 1.0, 0.7),
    ];
    let t = tri.map(|p| p.to_array());
    let mut rng = Rng::for_sample(0, 0, 2);
    let rehits = (0..1000)
        .filter(|_| {
            let (u, v) = (rng.next_f32() * 0.5, rng.next_f32() * 0.5);
            let p = tri[0] * (1.0 - u - v) + tri[1] * u + tri[2] * v;
            let w = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) - 0.5;
            intersect(&RayShear::new(p, w), &t[0], &t[1], &t[2], f32::INFINITY).is_some()
        })
        .count();
    assert!(rehits > 0);
}

#[test]
fn hygiene_rows_pass_and_probes_can_fail() {
    all_pass(&st::hygiene().unwrap());
    for (name, src, entry, expect) in hygiene::probes() {
        assert!(hygiene::check(&src, entry, expect).is_ok(), "{name}");
        // The same expectation on a clean file fails.
        let clean = rayterm::scene::load::source::Memory::default()
            .with("m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
        if entry == "m.obj" {
            assert!(hygiene::check(&clean, entry, expect).is_err(), "{name}");
        }
    }
}

#[test]
fn far_scenes_are_recentred_exactly() {
    let base = scene::load::open("cornell", &Default::default())
        .unwrap()
        .scene;
    let mut far = base.clone();
    let off = Vec3::new(1e6, -5e5, 7.5e5);
    far.transform(1.0, off);
    let stored = far.geometry.positions().to_vec();
    let shift = far.recentre().expect("a scene a million units out is far");
    assert!(far
        .warnings
        .iter()
        .any(|w| w.contains("far from the origin")));
    for (p, q) in far.geometry.positions().iter().zip(&stored) {
        assert_eq!(
            p.as_dvec3(),
            q.as_dvec3() - shift.as_dvec3(),
            "moved exactly"
        );
    }
    // Near scenes stay where they are.
    let mut near = base.clone();
    assert!(near.recentre().is_none());
    assert_eq!(near.geometry.positions(), base.geometry.positions());
    // Aimed rays still find the recentred geometry.
    let b = bvh::build(&far.geometry, Builder::Sah);
    let target = DVec3::new(0.0, 1.0, -0.5) + (off - shift).as_dvec3();
    let r = rayterm::report::stability::topology::aimed(far.camera.eye, target).unwrap();
    assert!(b.intersect_brute(&r).is_some());
}

#[test]
fn battery_runs_on_other_scenes() {
    let o = Options {
        width: 32,
        height: 32,
        rays: 400,
        teapot_segments: 2,
        seed: 1,
    };
    let rows = st::run_battery("teapot:2", &o).unwrap();
    all_pass(&rows);
    let table = st::format_table(&rows);
    assert!(table.starts_with("case"));
    assert_eq!(table.lines().count(), rows.len() + 1);
    assert!(st::run_battery("no-such-scene", &o).is_err());
}

#[test]
fn cli_prints_the_table_and_exits_zero() {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_rayterm"))
        .args(["stability", "--size", "16x16", "--json"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let rows: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let rows = rows.as_array().unwrap();
    assert!(rows.len() > 40);
    assert!(rows.iter().all(|r| r["pass"] == true));
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_rayterm"))
        .args(["stability", "nowhere.obj"])
        .output()
        .unwrap();
    assert!(!out.status.success());
}
