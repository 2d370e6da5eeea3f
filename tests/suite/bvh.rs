//! BVH invariants, agreement with brute force, watertightness.

use glam::Vec3;
use rayterm::bvh::{self, Bvh, TraversalStats};
use rayterm::geometry::sampling::Rng;
use rayterm::geometry::{Aabb, Ray};
use rayterm::scene::{self, Builder, Geometry};

fn random_soup(n: usize, seed: u64) -> Geometry {
    let mut r = Rng::for_sample(0, 0, seed);
    let tris: Vec<[Vec3; 3]> = (0..n)
        .map(|_| {
            let c = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 10.0;
            [(); 3].map(|_| c + (Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) - 0.5) * 0.8)
        })
        .collect();
    Geometry::from_triangles(&tris)
}

fn check_invariants(g: &Geometry, b: &Bvh) {
    // Every triangle in exactly one leaf.
    let mut seen = vec![0u32; g.indices().len()];
    let mut stack = vec![(0usize, 1usize)];
    let mut max_depth = 0;
    while let Some((i, depth)) = stack.pop() {
        max_depth = max_depth.max(depth);
        let n = &b.nodes()[i];
        let nb = n.bounds();
        if n.is_leaf() {
            for k in n.first..n.first + n.count {
                let prim = b.prims()[k as usize] as usize;
                seen[prim] += 1;
                let tb = Aabb::from_points(&g.triangle(prim));
                assert!(nb.contains(&tb), "triangle {prim} outside its leaf");
            }
        } else {
            for c in [n.first as usize, n.first as usize + 1] {
                assert!(
                    nb.contains(&b.nodes()[c].bounds()),
                    "child {c} outside parent {i}"
                );
                stack.push((c, depth + 1));
            }
        }
    }
    assert!(
        seen.iter().all(|&s| s == 1),
        "a triangle is missing or duplicated"
    );
    assert_eq!(max_depth, b.stats().depth);
    assert_eq!(b.stats().triangles, g.indices().len());
}

#[test]
fn invariants_hold_for_both_builders() {
    for n in [1, 2, 7, 1000, 5000] {
        let g = random_soup(n, n as u64);
        for builder in [Builder::Sah, Builder::Median] {
            let b = bvh::build(&g, builder);
            check_invariants(&g, &b);
            assert!(b.stats().sah_cost > 0.0);
        }
    }
}

/// A tree as bits: nodes (boxes and links), leaf order, and the triangles
/// as traversal tests them.
type TreeBits = (Vec<[u32; 8]>, Vec<u32>, Vec<[[u32; 3]; 3]>);

fn tree_bits(b: &Bvh) -> TreeBits {
    let nodes = b
        .nodes()
        .iter()
        .map(|n| {
            let [x, y, z] = n.min.map(f32::to_bits);
            let [u, v, w] = n.max.map(f32::to_bits);
            [x, y, z, n.first, u, v, w, n.count]
        })
        .collect();
    let tris = (0..b.triangle_count())
        .map(|i| b.triangle(i).map(|v| v.map(f32::to_bits)))
        .collect();
    (nodes, b.prims().to_vec(), tris)
}

#[test]
fn the_tree_is_the_same_on_any_number_of_threads() {
    // Large enough that the root's bins are filled in parallel and the
    // subtrees, compaction and packets are spread over the pool.
    let g = random_soup(150_000, 5);
    for builder in [Builder::Sah, Builder::Median] {
        let on = |threads| {
            let pool = rayon::ThreadPoolBuilder::new()
                .num_threads(threads)
                .build()
                .unwrap();
            pool.install(|| bvh::build(&g, builder))
        };
        let one = on(1);
        check_invariants(&g, &one);
        let want = tree_bits(&one);
        for threads in [2, 3] {
            let b = on(threads);
            assert!(tree_bits(&b) == want, "{builder}: {threads} threads");
            assert_eq!(b.stats().depth, one.stats().depth);
            assert_eq!(b.stats().sah_cost, one.stats().sah_cost);
        }
    }
}

#[test]
fn binned_sah_is_within_five_percent_of_a_full_sweep() {
    let scenes = ["cornell", "teapot:6", "mirrors"].map(|n| {
        (
            n.to_string(),
            scene::load::open(n, &Default::default())
                .unwrap()
                .scene
                .geometry,
        )
    });
    for (name, g) in scenes
        .into_iter()
        .chain([("soup".to_string(), random_soup(4000, 11))])
    {
        let binned = bvh::build(&g, Builder::Sah);
        let sweep = bvh::build_full_sweep(&g);
        check_invariants(&g, &sweep);
        let (b, s) = (binned.packet_sah_cost(), sweep.packet_sah_cost());
        assert!(
            b <= 1.05 * s,
            "{name}: binned SAH cost {b} vs full sweep {s}"
        );
    }
}

#[test]
fn bvh_agrees_with_brute_force() {
    let g = random_soup(3000, 7);
    let mut r = Rng::for_sample(1, 2, 3);
    for builder in [Builder::Sah, Builder::Median] {
        let b = bvh::build(&g, builder);
        for _ in 0..3000 {
            let o = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) * 14.0 - 2.0;
            let d = Vec3::new(r.next_f32(), r.next_f32(), r.next_f32()) - 0.5;
            let ray = Ray::new(o, d);
            let mut st = TraversalStats::default();
            let fast = b.intersect::<true>(&ray, &mut st);
            let slow = b.intersect_brute(&ray);
            assert_eq!(fast.map(|h| h.t), slow.map(|h| h.t));
            let seg = Ray::segment(o, d, 3.0);
            assert_eq!(
                b.occluded::<false>(&seg, &mut st).is_some(),
                b.occluded_brute(&seg).is_some()
            );
        }
    }
}

#[test]
fn empty_geometry_never_hits() {
    let b = bvh::build(&Geometry::default(), Builder::Sah);
    assert!(b
        .intersect::<false>(
            &Ray::new(Vec3::ZERO, Vec3::X),
            &mut TraversalStats::default()
        )
        .is_none());
}

/// Rays from inside a closed mesh never escape: the watertight test leaves no cracks.
fn no_escapes(spec: &str, centre: Vec3, rays: u32) {
    let s = scene::load::open(spec, &Default::default()).unwrap().scene;
    let b = bvh::build(&s.geometry, Builder::Sah);
    let mut r = Rng::for_sample(5, 5, 5);
    let mut escapes = 0;
    // Random directions, plus rays aimed exactly at vertices.
    for i in 0..rays {
        let d = if i % 4 == 0 {
            let v = s.geometry.positions()[(r.next_u32() as usize) % s.geometry.positions().len()];
            v - centre
        } else {
            let z = 2.0 * r.next_f32() - 1.0;
            let phi = std::f32::consts::TAU * r.next_f32();
            let s = (1.0 - z * z).max(0.0).sqrt();
            Vec3::new(s * phi.cos(), s * phi.sin(), z)
        };
        if b.intersect::<false>(&Ray::new(centre, d), &mut TraversalStats::default())
            .is_none()
        {
            escapes += 1;
        }
    }
    assert_eq!(escapes, 0, "{escapes} of {rays} rays escaped {spec}");
}

#[test]
fn rays_never_escape_a_closed_sphere() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("data/meshes/sphere.obj");
    no_escapes(dir.to_str().unwrap(), Vec3::new(0.01, -0.02, 0.03), 100_000);
}
