//! Hot paths of the tracer: triangle and box tests, closest-hit and any-hit
//! traversal, the SAH build. Generated meshes (the tessellated teapot), and
//! the shared bunny when `../shared/data/meshes` is present.

use std::hint::black_box;
use std::path::Path;
use std::time::Duration;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::Vec3;
use rayterm::bvh::{self, TraversalStats};
use rayterm::geometry::triangle::{intersect, intersect8, RayShear};
use rayterm::geometry::{Aabb, Ray};
use rayterm::report::workload::Workload;
use rayterm::scene::{self, Builder, Geometry};

fn meshes() -> Vec<(String, Geometry)> {
    let mut v = vec![(
        "teapot:16".to_string(),
        scene::load::open("teapot:16", &Default::default())
            .unwrap()
            .scene
            .geometry,
    )];
    let bunny = Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/meshes/bunny.obj");
    match scene::load::open(bunny.to_str().unwrap_or_default(), &Default::default())
        .map(|o| o.scene)
    {
        Ok(s) => v.push(("bunny".to_string(), s.geometry)),
        Err(_) => eprintln!(
            "bunny skipped: ../shared/data/meshes/bunny.obj not found (optional: see BENCHMARKS.md)"
        ),
    }
    v
}

fn primitives(c: &mut Criterion) {
    let tri = [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
    let hit = RayShear::new(Vec3::new(0.25, 0.25, 1.0), Vec3::new(0.01, 0.02, -1.0));
    let miss = RayShear::new(Vec3::new(0.75, 0.75, 1.0), Vec3::new(0.01, 0.02, -1.0));
    c.bench_function("triangle/hit", |b| {
        b.iter(|| intersect(black_box(&hit), &tri[0], &tri[1], &tri[2], f32::INFINITY))
    });
    c.bench_function("triangle/miss", |b| {
        b.iter(|| intersect(black_box(&miss), &tri[0], &tri[1], &tri[2], f32::INFINITY))
    });
    // Eight triangles at once, as the leaves hold them (the portable two
    // four-lane runs; traversal uses AVX where the CPU has it).
    let p8: [[[f32; 8]; 3]; 3] =
        tri.map(|v| v.map(|x| std::array::from_fn(|lane| x + lane as f32 * 0.01)));
    let ray = RayShear::new(Vec3::new(0.25, 0.25, 1.0), Vec3::new(0.01, 0.02, -1.0));
    c.bench_function("triangle/packet8", |b| {
        b.iter(|| intersect8::<true>(black_box(&ray), &p8, f32::INFINITY))
    });
    // The scalar slab test that the eight-box test in traversal reproduces.
    let bx = Aabb {
        min: Vec3::ZERO,
        max: Vec3::ONE,
    };
    let ray = Ray::new(Vec3::new(-1.0, 0.3, 0.4), Vec3::new(1.0, 0.1, 0.05));
    let inv: Vec3 = ray.inv_dir().into();
    c.bench_function("box/hit", |b| {
        b.iter(|| black_box(&bx).hit(black_box(ray.origin), inv, f32::INFINITY))
    });
}

/// The workload's rays at 256x192 that hit the mesh's bounds, and shadow rays for the hits.
fn rays(g: &Geometry) -> (Vec<Ray>, Vec<Ray>) {
    let w = Workload::auto(&g.bounds(), 256, 192);
    let b = bvh::build(g, Builder::Sah);
    let mut primary = Vec::new();
    let mut shadow = Vec::new();
    for y in 0..w.height {
        for x in 0..w.width {
            let r = w.primary(x, y);
            if let Some(h) = b.intersect::<false>(&r, &mut TraversalStats::default()) {
                shadow.push(w.shadow(&r, h.t));
            }
            primary.push(r);
        }
    }
    (primary, shadow)
}

fn traversal(c: &mut Criterion) {
    let mut g = c.benchmark_group("traverse");
    for (name, geom) in meshes() {
        let b = bvh::build(&geom, Builder::Sah);
        let (primary, shadow) = rays(&geom);
        g.throughput(Throughput::Elements(primary.len() as u64));
        g.bench_with_input(BenchmarkId::new("closest", &name), &primary, |bn, rs| {
            bn.iter(|| {
                rs.iter()
                    .filter(|r| {
                        b.intersect::<false>(r, &mut TraversalStats::default())
                            .is_some()
                    })
                    .count()
            })
        });
        g.throughput(Throughput::Elements(shadow.len() as u64));
        g.bench_with_input(BenchmarkId::new("any", &name), &shadow, |bn, rs| {
            bn.iter(|| {
                rs.iter()
                    .filter(|r| {
                        b.occluded::<false>(r, &mut TraversalStats::default())
                            .is_some()
                    })
                    .count()
            })
        });
    }
    g.finish();
}

fn build(c: &mut Criterion) {
    let mut g = c.benchmark_group("build");
    for (name, geom) in meshes() {
        g.throughput(Throughput::Elements(geom.triangle_count() as u64));
        for builder in [Builder::Sah, Builder::Median] {
            g.bench_with_input(
                BenchmarkId::new(builder.to_string(), &name),
                &geom,
                |bn, geom| bn.iter(|| bvh::build(geom, builder)),
            );
        }
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
        .sample_size(20);
    targets = primitives, traversal, build
}
criterion_main!(benches);
