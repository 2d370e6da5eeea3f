//! BVH builders: binned SAH (Wald 2007) and object median on the largest axis.

use std::time::Instant;

use glam::Vec3;

use super::{BuildStats, Bvh, Node};
use crate::geometry::Aabb;
use crate::scene::{Builder, Geometry};

/// Bins per axis for the SAH; 32 keeps the cost within a few percent of a full sweep.
const BINS: usize = 32;
/// The SAH builder splits any node with more triangles than this.
const MAX_LEAF: usize = 8;
/// The median builder stops splitting at this many triangles.
const MEDIAN_LEAF: usize = 4;
/// Cost of one node traversal relative to one triangle test, for the SAH.
const TRAVERSAL_COST: f32 = 1.0;

#[derive(Clone, Copy)]
struct PrimRef {
    bounds: Aabb,
    centroid: Vec3,
    index: u32,
}

struct Task {
    node: usize,
    start: usize,
    end: usize,
    depth: usize,
}

/// Builds a BVH over every triangle of `geom`.
pub fn build(geom: &Geometry, builder: Builder) -> Bvh {
    let start_time = Instant::now();
    let n = geom.indices.len();
    let mut refs: Vec<PrimRef> = (0..n)
        .map(|i| {
            let b = Aabb::from_points(&geom.triangle(i));
            PrimRef {
                bounds: b,
                centroid: b.center(),
                index: i as u32,
            }
        })
        .collect();
    let mut nodes = Vec::with_capacity(2 * n);
    let mut stack = Vec::new();
    if n > 0 {
        nodes.push(Node::default());
        stack.push(Task {
            node: 0,
            start: 0,
            end: n,
            depth: 1,
        });
    }
    let mut depth = n.min(1);
    while let Some(t) = stack.pop() {
        depth = depth.max(t.depth);
        let slice = &mut refs[t.start..t.end];
        let (bounds, cbounds) = slice.iter().fold((Aabb::EMPTY, Aabb::EMPTY), |(b, c), r| {
            (b.union(r.bounds), c.grow(r.centroid))
        });
        nodes[t.node].set_bounds(&bounds);
        // Past depth 64 only balanced splits, so traversal stacks stay bounded.
        let mid = match builder {
            Builder::Sah if t.depth <= 64 => split_sah(slice, &bounds, &cbounds),
            _ => split_median(slice, &cbounds),
        };
        match mid {
            Some(m) => {
                let left = nodes.len();
                nodes.push(Node::default());
                nodes.push(Node::default());
                nodes[t.node].first = left as u32;
                nodes[t.node].count = 0;
                stack.push(Task {
                    node: left + 1,
                    start: t.start + m,
                    end: t.end,
                    depth: t.depth + 1,
                });
                stack.push(Task {
                    node: left,
                    start: t.start,
                    end: t.start + m,
                    depth: t.depth + 1,
                });
            }
            None => {
                nodes[t.node].first = t.start as u32;
                nodes[t.node].count = (t.end - t.start) as u32;
            }
        }
    }
    let tris = refs
        .iter()
        .map(|r| geom.triangle(r.index as usize).map(|v| v.to_array()))
        .collect();
    let prim = refs.iter().map(|r| r.index).collect();
    let build_ms = start_time.elapsed().as_secs_f64() * 1e3;
    let stats = stats(&nodes, n, depth, builder, build_ms);
    Bvh {
        nodes,
        tris,
        prim,
        stats,
    }
}

/// Partitions `refs` by the best binned SAH split; `None` makes a leaf.
fn split_sah(refs: &mut [PrimRef], bounds: &Aabb, cbounds: &Aabb) -> Option<usize> {
    let n = refs.len();
    if n <= 1 {
        return None;
    }
    let ext = cbounds.extent();
    let scale = Vec3::splat(BINS as f32) / ext.max(Vec3::splat(f32::MIN_POSITIVE));
    let bin_of = |c: Vec3, axis: usize| -> usize {
        (((c[axis] - cbounds.min[axis]) * scale[axis]) as usize).min(BINS - 1)
    };
    let mut bins = [[(Aabb::EMPTY, 0u32); BINS]; 3];
    for r in refs.iter() {
        for (axis, axis_bins) in bins.iter_mut().enumerate() {
            let b = &mut axis_bins[bin_of(r.centroid, axis)];
            b.0 = b.0.union(r.bounds);
            b.1 += 1;
        }
    }
    let mut best: Option<(f32, usize, usize)> = None;
    for (axis, axis_bins) in bins.iter().enumerate() {
        if ext[axis] <= 0.0 {
            continue;
        }
        // Right-to-left sweep stores the suffix areas, left-to-right evaluates.
        let mut right_cost = [0.0f32; BINS];
        let (mut rb, mut rn) = (Aabb::EMPTY, 0u32);
        for i in (1..BINS).rev() {
            rb = rb.union(axis_bins[i].0);
            rn += axis_bins[i].1;
            right_cost[i] = rb.area() * rn as f32;
        }
        let (mut lb, mut ln) = (Aabb::EMPTY, 0u32);
        for i in 0..BINS - 1 {
            lb = lb.union(axis_bins[i].0);
            ln += axis_bins[i].1;
            if ln == 0 || ln as usize == n {
                continue;
            }
            let cost = lb.area() * ln as f32 + right_cost[i + 1];
            if best.is_none_or(|b| cost < b.0) {
                best = Some((cost, axis, i));
            }
        }
    }
    let leaf_cost = n as f32;
    let Some((cost, axis, bin)) = best else {
        // All centroids coincide: split by index so leaves stay bounded.
        return (n > MAX_LEAF).then_some(n / 2);
    };
    let split_cost = TRAVERSAL_COST + cost / bounds.area().max(f32::MIN_POSITIVE);
    if split_cost >= leaf_cost && n <= MAX_LEAF {
        return None;
    }
    let mid = partition(refs, |r| bin_of(r.centroid, axis) <= bin);
    (mid > 0 && mid < n).then_some(mid).or(Some(n / 2))
}

/// Splits at the object median of the largest centroid axis.
fn split_median(refs: &mut [PrimRef], cbounds: &Aabb) -> Option<usize> {
    let n = refs.len();
    if n <= MEDIAN_LEAF {
        return None;
    }
    let axis = cbounds.extent().max_position();
    let mid = n / 2;
    refs.select_nth_unstable_by(mid, |a, b| a.centroid[axis].total_cmp(&b.centroid[axis]));
    Some(mid)
}

/// In-place partition; returns the number of elements for which `pred` holds.
fn partition<T>(v: &mut [T], pred: impl Fn(&T) -> bool) -> usize {
    let mut i = 0;
    let mut j = v.len();
    while i < j {
        if pred(&v[i]) {
            i += 1;
        } else {
            j -= 1;
            v.swap(i, j);
        }
    }
    i
}

fn stats(
    nodes: &[Node],
    triangles: usize,
    depth: usize,
    builder: Builder,
    build_ms: f64,
) -> BuildStats {
    let root_area = nodes
        .first()
        .map_or(1.0, |r| r.bounds().area().max(f32::MIN_POSITIVE) as f64);
    let mut leaves = 0;
    let mut max_leaf = 0;
    let mut sah = 0.0;
    for node in nodes {
        let a = node.bounds().area() as f64 / root_area;
        if node.is_leaf() {
            leaves += 1;
            max_leaf = max_leaf.max(node.count as usize);
            sah += a * node.count as f64;
        } else {
            sah += a * TRAVERSAL_COST as f64;
        }
    }
    BuildStats {
        builder: builder.to_string(),
        triangles,
        nodes: nodes.len(),
        leaves,
        depth,
        max_leaf,
        mean_leaf: triangles as f64 / leaves.max(1) as f64,
        sah_cost: sah,
        build_ms,
    }
}
