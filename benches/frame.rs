//! A full frame: 400x400, 1 spp, shadows and reflections, all cores.

use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use rayterm::bvh;
use rayterm::render::{pass, Film, Plan, Tracer};
use rayterm::report::bench::frame_features;
use rayterm::scene;

fn frame(c: &mut Criterion) {
    let mut g = c.benchmark_group("frame");
    for name in ["cornell", "teapot", "mirrors"] {
        let s = scene::load(name).unwrap();
        let b = bvh::build(&s.geometry, s.settings.builder);
        let plan = Plan::new(&s, frame_features());
        let tracer = Tracer::new(&s, &b, &plan, 400, 400, 1);
        g.bench_function(name, |bn| {
            bn.iter(|| {
                let mut film = Film::new(400, 400);
                pass::render_pass(&tracer, &mut film, 1, &|| false)
            })
        });
    }
    g.finish();
}

criterion_group! {
    name = benches;
    config = Criterion::default()
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(2))
        .sample_size(20);
    targets = frame
}
criterion_main!(benches);
