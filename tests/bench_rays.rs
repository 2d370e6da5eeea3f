//! The ray workload's checksum (`hits`, `occluded`, `sum_t`): the BVH against
//! a brute-force loop over every triangle, independence from the thread
//! count, and the Embree harness's reference checksums on the shared meshes.

mod common;

use rayterm::bvh::{self, TraversalStats};
use rayterm::geometry::triangle::{intersect, RayShear};
use rayterm::geometry::Ray;
use rayterm::report::workload::{self, Checksum, Frame, Workload};
use rayterm::scene::{self, Builder, Geometry};

/// The workload traced with the BVH on a pool of `threads` threads.
fn with_bvh(g: &Geometry, w: &Workload, builder: Builder, threads: usize) -> Checksum {
    let b = bvh::build(g, builder);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let mut frame = Frame::new(w);
    pool.install(|| {
        workload::trace_primary(w, &mut frame, |r| {
            b.intersect::<false>(r, &mut TraversalStats::default())
                .map(|h| h.t)
        });
        workload::trace_shadow(w, &mut frame, |r| {
            b.occluded::<false>(r, &mut TraversalStats::default())
                .is_some()
        });
    });
    frame.checksum()
}

/// The workload by testing every triangle of the geometry, written out here
/// so it shares nothing with the BVH or the report code but the rays.
fn brute_force(g: &Geometry, w: &Workload) -> Checksum {
    let tris: Vec<[[f32; 3]; 3]> = (0..g.triangle_count())
        .map(|i| g.triangle(i).map(|v| v.to_array()))
        .collect();
    let closest = |r: &Ray| {
        let s = RayShear::new(r.origin, r.dir);
        let mut tmax = r.tmax;
        let mut hit = None;
        for t in &tris {
            if let Some(h) = intersect(&s, &t[0], &t[1], &t[2], tmax) {
                tmax = h.t;
                hit = Some(h.t);
            }
        }
        hit
    };
    let any = |r: &Ray| {
        let s = RayShear::new(r.origin, r.dir);
        tris.iter()
            .any(|t| intersect(&s, &t[0], &t[1], &t[2], r.tmax).is_some())
    };
    let mut c = Checksum::default();
    for y in 0..w.height {
        let (mut hits, mut occ, mut sum_t) = (0, 0, 0.0);
        for x in 0..w.width {
            let p = w.primary(x, y);
            if let Some(t) = closest(&p) {
                hits += 1;
                sum_t += t as f64;
                occ += any(&w.shadow(&p, t)) as u64;
            }
        }
        c.hits += hits;
        c.occluded += occ;
        c.sum_t += sum_t;
    }
    c
}

fn check_against_brute_force(spec: &str, width: u32, height: u32) {
    let s = scene::load(spec).unwrap();
    let g = &s.geometry;
    let w = Workload::auto(&g.bounds(), width, height);
    let want = brute_force(g, &w);
    assert!(want.hits > 0, "{spec}: no primary ray hits");
    assert!(
        want.occluded > 0 && want.occluded < want.hits,
        "{spec}: shadow rays are all occluded or all free"
    );
    for builder in [Builder::Sah, Builder::Median] {
        for threads in [1, 3] {
            let got = with_bvh(g, &w, builder, threads);
            assert_eq!(got, want, "{spec}, {builder} BVH, {threads} threads");
        }
    }
}

#[test]
fn checksum_matches_brute_force_on_cornell() {
    check_against_brute_force("cornell", 64, 48);
}

#[test]
fn checksum_matches_brute_force_on_a_tessellated_teapot() {
    check_against_brute_force("teapot:3", 64, 48);
}

#[test]
fn shadow_rays_start_at_the_light_and_stop_short_of_the_hit() {
    let s = scene::load("cornell").unwrap();
    let w = Workload::auto(&s.geometry.bounds(), 64, 48);
    let p = w.primary(32, 24);
    let sh = w.shadow(&p, 2.0);
    assert_eq!(sh.tmax, (1.0 - 1e-4) as f32);
    // The shadow ray ends (at t = 1) on the primary hit point.
    let hit = p.origin + 2.0 * p.dir;
    assert!((sh.at(1.0) - hit).length() < 1e-4 * hit.length().max(1.0));
}

/// Reference checksums of the Embree harness (its README), 1024x768, auto camera.
const REFERENCES: &[(&str, u64, u64, f64)] = &[
    (
        "CornellBox-Mirror-Rotated.obj",
        315368,
        76497,
        1126480.807359457,
    ),
    ("monkey.obj", 111838, 28181, 369065.2519431114),
    ("teapot.obj", 100933, 24032, 22172399.526657104),
    ("bunny.obj", 145161, 42059, 532713.8997080326),
];

#[test]
fn checksum_agrees_with_the_embree_harness_on_shared_meshes() {
    let Some(dir) = common::shared_meshes() else {
        return;
    };
    for &(name, hits, occluded, sum_t) in REFERENCES {
        let path = dir.join(name);
        if !path.exists() {
            eprintln!("skipping {name}: not in {}", dir.display());
            continue;
        }
        let s = scene::load(path.to_str().unwrap()).unwrap();
        let w = Workload::auto(&s.geometry.bounds(), 1024, 768);
        let got = with_bvh(&s.geometry, &w, Builder::Sah, 2);
        // The specification's tolerance: a few grazing rays, well under 0.01 %.
        let near = |a: u64, b: u64| a.abs_diff(b) as f64 <= (1e-4 * b as f64).max(1.0);
        assert!(near(got.hits, hits), "{name}: hits {} vs {hits}", got.hits);
        assert!(
            near(got.occluded, occluded),
            "{name}: occluded {} vs {occluded}",
            got.occluded
        );
        // 1e-5 relative, plus one mean hit distance for each grazing ray
        // that one tracer hits and the other misses.
        let mean_t = sum_t / hits as f64;
        let allowed = 1e-5 * sum_t + got.hits.abs_diff(hits) as f64 * mean_t;
        assert!(
            (got.sum_t - sum_t).abs() <= allowed,
            "{name}: sum_t {} vs {sum_t}",
            got.sum_t
        );
    }
}
