//! `rayterm bench scaling`: how build and trace cost grow with the number of
//! triangles, on the teapot tessellated from ~1k to ~4M triangles (~16M with
//! `--max-n 512`).

use std::time::Instant;

use anyhow::Result;
use serde::Serialize;

use super::stats::{fit_line, median};
use super::workload::{self, HitImage, Workload};
use super::{Machine, Progress};
use crate::bvh::{self, TraversalStats};
use crate::scene::{self, Builder, Geometry};

#[derive(Clone, Debug)]
pub(crate) struct ScalingOptions {
    /// Segments per patch edge, smallest and largest (doubling in between).
    pub(crate) min_n: u32,
    pub(crate) max_n: u32,
    pub(crate) width: u32,
    pub(crate) height: u32,
    pub(crate) builder: Builder,
}

impl Default for ScalingOptions {
    fn default() -> Self {
        ScalingOptions {
            min_n: 4,
            max_n: 256,
            width: 512,
            height: 384,
            builder: Builder::Sah,
        }
    }
}

#[derive(Clone, Debug, Serialize)]
pub(crate) struct ScalingRow {
    pub(crate) segments: u32,
    pub(crate) triangles: usize,
    pub(crate) build_ms: f64,
    pub(crate) build_mtris_s: f64,
    pub(crate) levels: usize,
    pub(crate) sah_cost: f64,
    pub(crate) primary_mrays_s: f64,
    pub(crate) shadow_mrays_s: f64,
    /// Wall time per primary ray times the threads: the cost of one ray.
    pub(crate) ns_per_ray: f64,
    pub(crate) bvh_bytes_per_tri: f64,
    pub(crate) mesh_bytes_per_tri: f64,
}

#[derive(Clone, Debug, Serialize)]
pub(crate) struct ScalingReport {
    pub(crate) machine: Machine,
    pub(crate) builder: String,
    pub(crate) rays: String,
    pub(crate) rows: Vec<ScalingRow>,
    /// Log-log slope of build time against triangles (1 is linear; n log n
    /// over these sizes fits a slope a little above 1).
    pub(crate) build_exponent: Option<f64>,
    /// Slope of the time per primary ray against log2(triangles): ns per
    /// doubling of the mesh (a BVH makes it grow like log n).
    pub(crate) trace_ns_per_doubling: Option<f64>,
    pub(crate) trace_fit_r2: Option<f64>,
}

/// The teapot's own triangles at `n` segments per patch edge (the scene's
/// floor left out, so the auto camera frames the teapot).
pub fn teapot(n: u32) -> Result<Geometry> {
    let mut g = scene::load::open(&format!("teapot:{n}"), &Default::default())?
        .scene
        .geometry;
    let keep: Vec<bool> = g.tri_mesh.iter().map(|&m| m == 0).collect();
    let mut k = keep.iter();
    g.indices.retain(|_| *k.next().unwrap_or(&false));
    let mut k = keep.iter();
    g.tri_material.retain(|_| *k.next().unwrap_or(&false));
    g.tri_mesh.retain(|&m| m == 0);
    Ok(g)
}

fn mesh_bytes(g: &Geometry) -> usize {
    use std::mem::size_of_val;
    size_of_val(&g.positions[..])
        + size_of_val(&g.normals[..])
        + size_of_val(&g.uvs[..])
        + size_of_val(&g.indices[..])
        + size_of_val(&g.tri_material[..])
        + size_of_val(&g.tri_mesh[..])
}

/// Runs the sizes from `o.min_n` to `o.max_n` on the current rayon pool.
pub(crate) fn run(
    o: &ScalingOptions,
    threads: usize,
    progress: &dyn Progress,
) -> Result<ScalingReport> {
    let mut sizes = Vec::new();
    let mut n = o.min_n.max(1);
    while n <= o.max_n.min(1024) {
        sizes.push(n);
        n *= 2;
    }
    progress.begin(Some(sizes.len() as u64));
    let mut rows = Vec::new();
    for &n in &sizes {
        progress.doing(&format!("teapot:{n}"));
        let g = teapot(n)?;
        let tris = g.triangle_count();
        // Fewer repetitions for the big sizes keep the run to a minute or two.
        let reps = if tris > 1_000_000 { 1 } else { 3 };
        let mut ms = Vec::new();
        let mut last = None;
        for _ in 0..reps {
            let start = Instant::now();
            let b = bvh::build(&g, o.builder);
            ms.push(start.elapsed().as_secs_f64() * 1e3);
            last = Some(b);
        }
        let Some(b) = last else { continue };
        let build_ms = median(&mut ms);
        let w = Workload::auto(&g.bounds(), o.width, o.height);
        let mut frame = HitImage::new(&w);
        let (mut p, mut s) = (Vec::new(), Vec::new());
        for _ in 0..3 {
            p.push(workload::trace_primary(
                &w,
                &mut frame,
                workload::Rows::Make,
                |r| {
                    b.intersect::<false>(r, &mut TraversalStats::default())
                        .map(|h| (h.t, h.prim))
                },
            ));
            s.push(workload::trace_shadow(
                &w,
                &mut frame,
                workload::Rows::Make,
                |r| {
                    b.occluded::<false>(r, &mut TraversalStats::default())
                        .is_some()
                },
            ));
        }
        let (p, s) = (median(&mut p), median(&mut s));
        let primary = o.width as f64 * o.height as f64;
        let hits = frame.checksum().hits as f64;
        rows.push(ScalingRow {
            segments: n,
            triangles: tris,
            build_ms,
            build_mtris_s: tris as f64 / build_ms.max(1e-9) / 1e3,
            levels: b.stats.depth,
            sah_cost: b.stats.sah_cost,
            primary_mrays_s: primary / p.max(1e-12) / 1e6,
            shadow_mrays_s: hits / s.max(1e-12) / 1e6,
            ns_per_ray: p * 1e9 * threads as f64 / primary,
            bvh_bytes_per_tri: b.memory_bytes() as f64 / tris.max(1) as f64,
            mesh_bytes_per_tri: mesh_bytes(&g) as f64 / tris.max(1) as f64,
        });
        progress.step();
    }
    progress.end();
    let ln_n: Vec<f64> = rows.iter().map(|r| (r.triangles as f64).ln()).collect();
    let ln_b: Vec<f64> = rows.iter().map(|r| r.build_ms.ln()).collect();
    let log2_n: Vec<f64> = rows.iter().map(|r| (r.triangles as f64).log2()).collect();
    let ns: Vec<f64> = rows.iter().map(|r| r.ns_per_ray).collect();
    let trace = fit_line(&log2_n, &ns);
    Ok(ScalingReport {
        machine: Machine::current(threads),
        builder: o.builder.to_string(),
        rays: format!(
            "workload primary+shadow at {}x{} (auto camera on the teapot)",
            o.width, o.height
        ),
        rows,
        build_exponent: fit_line(&ln_n, &ln_b).map(|f| f.0),
        trace_ns_per_doubling: trace.map(|f| f.0),
        trace_fit_r2: trace.map(|f| f.2),
    })
}

pub(crate) fn to_text(r: &ScalingReport) -> String {
    use std::fmt::Write;
    let mut s = String::new();
    let _ = writeln!(s, "rayterm bench scaling: {}", r.machine);
    let _ = writeln!(s, "teapot:N, {} builder; rays: {}\n", r.builder, r.rays);
    let _ = writeln!(
        s,
        "{:>4} {:>9} {:>10} {:>9} {:>6} {:>8} {:>9} {:>9} {:>8} {:>9} {:>9}",
        "N",
        "triangles",
        "build ms",
        "Mtris/s",
        "levels",
        "SAH",
        "prim Mr/s",
        "shad Mr/s",
        "ns/ray",
        "BVH B/tri",
        "mesh B/tri"
    );
    for x in &r.rows {
        let _ = writeln!(
            s,
            "{:>4} {:>9} {:>10.2} {:>9.2} {:>6} {:>8.2} {:>9.2} {:>9.2} {:>8.1} {:>9.1} {:>9.1}",
            x.segments,
            x.triangles,
            x.build_ms,
            x.build_mtris_s,
            x.levels,
            x.sah_cost,
            x.primary_mrays_s,
            x.shadow_mrays_s,
            x.ns_per_ray,
            x.bvh_bytes_per_tri,
            x.mesh_bytes_per_tri
        );
    }
    if let Some(e) = r.build_exponent {
        let _ = writeln!(
            s,
            "\nbuild time grows as n^{e:.2} (log-log slope; n log n over this range fits about 1.1, \
             so ~1 means n log n or better)"
        );
    }
    if let (Some(b), Some(r2)) = (r.trace_ns_per_doubling, r.trace_fit_r2) {
        let change = if b >= 0.0 { "grows" } else { "falls" };
        let _ = writeln!(
            s,
            "time per primary ray {change} by {:.1} ns per doubling of n (fit against log2 n, \
             r\u{b2} {r2:.2}; a BVH makes it ~log n)",
            b.abs()
        );
    }
    s
}
