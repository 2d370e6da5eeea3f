//! A full frame: 400x400, 1 spp, shadows and reflections, all cores.

use std::time::Duration;

use criterion::{criterion_group, criterion_main, Criterion};
use rayterm::render::{Progressive, SceneRequest, Session};
use rayterm::report::bench::frame_features;

fn frame(c: &mut Criterion) {
    let mut g = c.benchmark_group("frame");
    for name in ["cornell", "teapot", "mirrors"] {
        let req = SceneRequest {
            size: Some((400, 400)),
            features: frame_features(),
            ..SceneRequest::new(name)
        };
        let (s, _) = Session::open(&req).unwrap();
        let tracer = s.tracer();
        g.bench_function(name, |bn| bn.iter(|| Progressive::render(&tracer, 1)));
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
