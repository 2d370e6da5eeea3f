//! The ray workload's checksum (`hits`, `occluded`, `sum_t` and the diffuse
//! set's `diffuse_hits`, `diffuse_sum_t`): the BVH against a brute-force loop
//! over every triangle, independence from the thread count, diffuse rays bit
//! for bit as the Embree harness makes them, and its reference checksums on
//! the shared meshes.

use crate::common;

use rayterm::bvh::{self, Simd, TraversalStats};
use rayterm::geometry::triangle::{intersect, RayShear};
use rayterm::geometry::Ray;
use rayterm::report::workload::{self, Checksum, HitImage, Workload};
use rayterm::scene::{self, Builder, Geometry};

/// The workload traced with the BVH on a pool of `threads` threads.
fn with_bvh(g: &Geometry, w: &Workload, builder: Builder, threads: usize) -> Checksum {
    let b = bvh::build(g, builder);
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .unwrap();
    let mut frame = HitImage::new(w);
    let closest = |r: &Ray| {
        b.intersect::<false>(r, &mut TraversalStats::default())
            .map(|h| (h.t, h.prim))
    };
    pool.install(|| {
        workload::trace_primary(w, &mut frame, workload::Rows::Make, closest);
        workload::trace_shadow(w, &mut frame, workload::Rows::Make, |r| {
            b.occluded::<false>(r, &mut TraversalStats::default())
                .is_some()
        });
        let rays = workload::diffuse_rays(w, &frame, g);
        workload::trace_diffuse(&mut frame, &rays, closest);
    });
    frame.checksum()
}

/// The workload by testing every triangle of the geometry, written out here
/// so it shares nothing with the BVH or the report code but the rays.
fn brute_force(g: &Geometry, w: &Workload) -> Checksum {
    let tris: Vec<[[f32; 3]; 3]> = (0..g.triangle_count())
        .map(|i| g.triangle(i).map(|v| v.to_array()))
        .collect();
    // The nearest hit, the lowest triangle index on a tie (as the BVH).
    let closest = |r: &Ray| {
        let s = RayShear::new(r.origin, r.dir);
        let mut tmax = r.tmax;
        let mut hit: Option<(f32, usize)> = None;
        for (i, t) in tris.iter().enumerate() {
            if let Some(h) = intersect(&s, &t[0], &t[1], &t[2], tmax) {
                if hit.is_none_or(|(b, _)| h.t < b) {
                    tmax = h.t;
                    hit = Some((h.t, i));
                }
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
        let (mut d_hits, mut d_sum_t) = (0, 0.0);
        for x in 0..w.width {
            let p = w.primary(x, y);
            if let Some((t, tri)) = closest(&p) {
                hits += 1;
                sum_t += t as f64;
                occ += any(&w.shadow(&p, t)) as u64;
                let d = w.diffuse(&p, t, g.triangle(tri), y * w.width + x);
                if let Some((dt, _)) = closest(&d) {
                    d_hits += 1;
                    d_sum_t += dt as f64;
                }
            }
        }
        c.hits += hits;
        c.occluded += occ;
        c.sum_t += sum_t;
        c.diffuse_hits += d_hits;
        c.diffuse_sum_t += d_sum_t;
    }
    c
}

fn check_against_brute_force(spec: &str, width: u32, height: u32) {
    let s = scene::load::open(spec, &Default::default()).unwrap().scene;
    let g = &s.geometry;
    let w = Workload::auto(&g.bounds(), width, height);
    let want = brute_force(g, &w);
    assert!(want.hits > 0, "{spec}: no primary ray hits");
    assert!(
        want.occluded > 0 && want.occluded < want.hits,
        "{spec}: shadow rays are all occluded or all free"
    );
    assert!(
        want.diffuse_hits > 0 && want.diffuse_hits < want.hits,
        "{spec}: diffuse rays all hit or all miss"
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

/// Rays made before the timer (the tinybvh harness's way) are the rays made
/// in the timed loop, and rays traced in packets find what single rays
/// find, with every SIMD level this CPU has: the report's checksums agree
/// with brute force every way (the frame's 62x45 pixels leave tiles cut
/// short at two edges), and the report says how it made and traced them.
#[test]
fn rays_made_first_or_traced_in_packets_are_the_same_rays() {
    let s = scene::load::open("teapot:3", &Default::default())
        .unwrap()
        .scene;
    let g = &s.geometry;
    let w = Workload::auto(&g.bounds(), 62, 45);
    let want = brute_force(g, &w);
    let ways = [(false, false), (true, false), (false, true), (true, true)];
    let levels = Simd::available();
    if !levels.contains(&Simd::Avx512) {
        eprintln!("note: this CPU has no AVX-512: its kernels are not tested here");
    }
    for ((rays_first, packets), simd) in ways
        .into_iter()
        .flat_map(|w| levels.iter().map(move |&l| (w, l)))
    {
        let o = workload::RaysOptions {
            width: 62,
            height: 45,
            threads: 2,
            builder: Builder::Sah,
            reps: 2,
            rays_first,
            packets,
            simd,
        };
        let r = workload::run("teapot:3", g, &o);
        let got = (r.hits, r.occluded, r.sum_t, r.diffuse_hits, r.diffuse_sum_t);
        let brute = (
            want.hits,
            want.occluded,
            want.sum_t,
            want.diffuse_hits,
            want.diffuse_sum_t,
        );
        assert_eq!(
            got, brute,
            "rays first: {rays_first}, packets: {packets}, {simd}"
        );
        assert_eq!(r.simd, simd);
        let label = if rays_first { "untimed" } else { "timed" };
        assert_eq!(r.ray_generation, label);
        let traced = if packets {
            "packets of 8x8 tiles"
        } else {
            "single"
        };
        assert_eq!((r.primary_traversal, r.shadow_traversal), (traced, traced));
        assert_eq!(r.diffuse_traversal, "single");
    }
}

#[test]
fn shadow_rays_start_at_the_light_and_stop_short_of_the_hit() {
    let s = scene::load::open("cornell", &Default::default())
        .unwrap()
        .scene;
    let w = Workload::auto(&s.geometry.bounds(), 64, 48);
    let p = w.primary(32, 24);
    let sh = w.shadow(&p, 2.0);
    assert_eq!(sh.tmax, (1.0 - 1e-4) as f32);
    // The shadow ray ends (at t = 1) on the primary hit point.
    let hit = p.origin + 2.0 * p.dir;
    assert!((sh.at(1.0) - hit).length() < 1e-4 * hit.length().max(1.0));
}

/// Reference checksums of the Embree harness (its README, AVX2 kernels),
/// 1024x768, auto camera: hits, occluded, sum_t, diffuse_hits, diffuse_sum_t.
const REFERENCES: &[(&str, u64, u64, f64, u64, f64)] = &[
    (
        "CornellBox-Mirror-Rotated.obj",
        315368,
        76497,
        1126480.807359457,
        0,
        0.0,
    ),
    (
        "monkey.obj",
        111838,
        28181,
        369065.2519431114,
        6065,
        1581.3571641052476,
    ),
    (
        "teapot.obj",
        100933,
        24032,
        22172399.526657104,
        5498,
        84301.63337991014,
    ),
    (
        "bunny.obj",
        145161,
        42059,
        532713.8997080326,
        11583,
        2992.9647487031907,
    ),
];

/// The specification's tolerance on a count: a few grazing rays, well
/// under 0.01 %.
fn near(a: u64, b: u64) -> bool {
    a.abs_diff(b) as f64 <= (1e-4 * b as f64).max(1.0)
}

/// 1e-5 relative, plus one mean hit distance for each grazing ray that one
/// tracer hits and the other misses.
fn near_sum(got: (u64, f64), want: (u64, f64)) -> bool {
    let mean_t = if want.0 == 0 {
        0.0
    } else {
        want.1 / want.0 as f64
    };
    (got.1 - want.1).abs() <= 1e-5 * want.1 + got.0.abs_diff(want.0) as f64 * mean_t
}

#[test]
fn checksum_agrees_with_the_embree_harness_on_shared_meshes() {
    let Some(dir) = common::shared_meshes() else {
        return;
    };
    for &(name, hits, occluded, sum_t, d_hits, d_sum_t) in REFERENCES {
        let path = dir.join(name);
        if !path.exists() {
            eprintln!("skipping {name}: not in {}", dir.display());
            continue;
        }
        let s = scene::load::open(path.to_str().unwrap(), &Default::default())
            .unwrap()
            .scene;
        let w = Workload::auto(&s.geometry.bounds(), 1024, 768);
        let got = with_bvh(&s.geometry, &w, Builder::Sah, 2);
        assert!(near(got.hits, hits), "{name}: hits {} vs {hits}", got.hits);
        assert!(
            near(got.occluded, occluded),
            "{name}: occluded {} vs {occluded}",
            got.occluded
        );
        assert!(
            near_sum((got.hits, got.sum_t), (hits, sum_t)),
            "{name}: sum_t {} vs {sum_t}",
            got.sum_t
        );
        assert!(
            near(got.diffuse_hits, d_hits),
            "{name}: diffuse_hits {} vs {d_hits}",
            got.diffuse_hits
        );
        assert!(
            near_sum((got.diffuse_hits, got.diffuse_sum_t), (d_hits, d_sum_t)),
            "{name}: diffuse_sum_t {} vs {d_sum_t}",
            got.diffuse_sum_t
        );
    }
}

/// A diffuse ray as the Embree harness writes it (`--dump-diffuse`): pixel,
/// triangle and primary `t` in, then the ray's origin and direction out, as
/// f32 bits.
type Dumped = (u32, usize, u32, [u32; 3], [u32; 3]);

/// Diffuse rays of the bunny from the harness.
const DUMPED: &[Dumped] = &[
    (
        144921,
        10935,
        0x407da1f9,
        [0xbc5b2679, 0x3f7da17b, 0xbe68bee2],
        [0x3f4a18d9, 0x3f1a6924, 0x3de940ed],
    ),
    (
        158175,
        27416,
        0x4095e125,
        [0xbf1b5d23, 0x3f602d26, 0xbf33b5a7],
        [0x3f5c7f7a, 0x3edd3b1e, 0xbe88d571],
    ),
    (
        396565,
        63274,
        0x40761f38,
        [0xbf31243d, 0x3d809ae5, 0x3f2e042e],
        [0x3ea93656, 0xbf6dff02, 0xbe26a4f6],
    ),
    (
        689687,
        63908,
        0x407185cd,
        [0x3ee26af0, 0xbf7248d7, 0x3f0f3c87],
        [0x3ef4c35a, 0xbf600882, 0xbd997090],
    ),
];

#[test]
fn diffuse_rays_are_the_harness_rays_bit_for_bit() {
    let Some(dir) = common::shared_meshes() else {
        return;
    };
    let path = dir.join("bunny.obj");
    if !path.exists() {
        eprintln!("skipping: bunny.obj not in {}", dir.display());
        return;
    }
    let s = scene::load::open(path.to_str().unwrap(), &Default::default())
        .unwrap()
        .scene;
    let w = Workload::auto(&s.geometry.bounds(), 1024, 768);
    for &(pixel, tri, t, origin, dir) in DUMPED {
        let p = w.primary(pixel % 1024, pixel / 1024);
        let r = w.diffuse(&p, f32::from_bits(t), s.geometry.triangle(tri), pixel);
        assert_eq!(
            r.origin.to_array().map(f32::to_bits),
            origin,
            "pixel {pixel}"
        );
        assert_eq!(r.dir.to_array().map(f32::to_bits), dir, "pixel {pixel}");
    }
}

/// `--simd` picks the walk the report names, and asking for more than the
/// CPU has is an error that says what it has, with no report.
#[test]
fn simd_level_is_chosen_and_named() {
    let run = |simd: &str| {
        std::process::Command::new(env!("CARGO_BIN_EXE_rayterm"))
            .args([
                "bench", "rays", "teapot:2", "--size", "16x12", "--reps", "1",
            ])
            .args(["--simd", simd])
            .output()
            .unwrap()
    };
    for level in Simd::available() {
        let o = run(level.name());
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
        let json: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
        assert_eq!(json["simd"], level.name());
    }
    if Simd::detect() < Simd::Avx512 {
        let o = run("avx512");
        assert_eq!(o.status.code(), Some(1));
        assert!(o.stdout.is_empty());
        let err = String::from_utf8_lossy(&o.stderr);
        let most = Simd::detect();
        assert!(
            err.contains(&format!(
                "this CPU has no avx512 (the widest it has is {most})"
            )),
            "{err}"
        );
    } else {
        eprintln!("note: this CPU has AVX-512: no level above it to refuse");
    }
}
