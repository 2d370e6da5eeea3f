//! Closest-hit and any-hit traversal, ordered near child first.
//!
//! `STATS` is a compile-time switch: with `false` the counters vanish from
//! the generated code, so the fast path pays nothing for the inspector.

use super::{Bvh, TraversalStats};
use crate::geometry::triangle::{intersect, RayShear};
use crate::geometry::Ray;
use glam::Vec3;

/// A closest hit: distance, barycentrics of vertices 1 and 2, and the
/// triangle's index in the scene geometry.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub u: f32,
    pub v: f32,
    pub prim: u32,
}

/// Enough for any tree the builders make (they fall back to median splits past depth 64).
const STACK: usize = 128;

impl Bvh {
    /// Nearest hit in `(0, ray.tmax]`.
    #[inline]
    pub fn intersect<const STATS: bool>(&self, ray: &Ray, st: &mut TraversalStats) -> Option<Hit> {
        if self.nodes.is_empty() {
            return None;
        }
        let shear = RayShear::new(ray.origin, ray.dir);
        let inv = ray.inv_dir();
        let o = ray.origin;
        let mut tmax = ray.tmax;
        let mut best: Option<(f32, f32, f32, u32)> = None;
        let mut stack = [0u32; STACK];
        let mut sp = 0;
        let mut node = &self.nodes[0];
        if STATS {
            st.nodes_visited += 1;
        }
        if node.bounds().hit(o, inv, tmax).is_none() {
            if STATS {
                st.boxes_missed += 1;
            }
            return None;
        }
        if STATS {
            st.boxes_hit += 1;
        }
        loop {
            if node.is_leaf() {
                if STATS {
                    st.leaves += 1;
                    st.triangle_tests += node.count;
                }
                let first = node.first as usize;
                for i in first..first + node.count as usize {
                    let t = &self.tris[i];
                    if let Some(h) = intersect(&shear, &t[0], &t[1], &t[2], tmax) {
                        tmax = h.t;
                        best = Some((h.t, h.u, h.v, i as u32));
                    }
                }
            } else {
                let c = node.first as usize;
                let (a, b) = (&self.nodes[c], &self.nodes[c + 1]);
                let ha = hit_box(a, o, inv, tmax);
                let hb = hit_box(b, o, inv, tmax);
                if STATS {
                    st.nodes_visited += 2;
                    let hits = ha.is_some() as u32 + hb.is_some() as u32;
                    st.boxes_hit += hits;
                    st.boxes_missed += 2 - hits;
                }
                match (ha, hb) {
                    (Some(da), Some(db)) => {
                        let (near, far) = if da <= db { (c, c + 1) } else { (c + 1, c) };
                        if sp < STACK {
                            stack[sp] = far as u32;
                            sp += 1;
                        }
                        node = &self.nodes[near];
                        continue;
                    }
                    (Some(_), None) => {
                        node = a;
                        continue;
                    }
                    (None, Some(_)) => {
                        node = b;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            // Pop, skipping nodes that now lie beyond the closest hit.
            loop {
                if sp == 0 {
                    return best.map(|(t, u, v, i)| Hit {
                        t,
                        u,
                        v,
                        prim: self.prim[i as usize],
                    });
                }
                sp -= 1;
                let n = &self.nodes[stack[sp] as usize];
                if hit_box(n, o, inv, tmax).is_some() {
                    node = n;
                    break;
                }
            }
        }
    }

    /// Whether anything lies in `(0, ray.tmax]`; stops at the first hit found.
    #[inline]
    pub fn occluded<const STATS: bool>(&self, ray: &Ray, st: &mut TraversalStats) -> Option<u32> {
        if self.nodes.is_empty() {
            return None;
        }
        let shear = RayShear::new(ray.origin, ray.dir);
        let inv = ray.inv_dir();
        let o = ray.origin;
        let tmax = ray.tmax;
        let mut stack = [0u32; STACK];
        let mut sp = 0;
        let root = &self.nodes[0];
        if STATS {
            st.nodes_visited += 1;
        }
        if root.bounds().hit(o, inv, tmax).is_none() {
            if STATS {
                st.boxes_missed += 1;
            }
            return None;
        }
        if STATS {
            st.boxes_hit += 1;
        }
        let mut node = root;
        loop {
            if node.is_leaf() {
                if STATS {
                    st.leaves += 1;
                }
                let first = node.first as usize;
                for i in first..first + node.count as usize {
                    if STATS {
                        st.triangle_tests += 1;
                    }
                    let t = &self.tris[i];
                    if intersect(&shear, &t[0], &t[1], &t[2], tmax).is_some() {
                        return Some(self.prim[i]);
                    }
                }
            } else {
                let c = node.first as usize;
                let (a, b) = (&self.nodes[c], &self.nodes[c + 1]);
                let ha = hit_box(a, o, inv, tmax);
                let hb = hit_box(b, o, inv, tmax);
                if STATS {
                    st.nodes_visited += 2;
                    let hits = ha.is_some() as u32 + hb.is_some() as u32;
                    st.boxes_hit += hits;
                    st.boxes_missed += 2 - hits;
                }
                match (ha, hb) {
                    (Some(da), Some(db)) => {
                        let (near, far) = if da <= db { (c, c + 1) } else { (c + 1, c) };
                        if sp < STACK {
                            stack[sp] = far as u32;
                            sp += 1;
                        }
                        node = &self.nodes[near];
                        continue;
                    }
                    (Some(_), None) => {
                        node = a;
                        continue;
                    }
                    (None, Some(_)) => {
                        node = b;
                        continue;
                    }
                    (None, None) => {}
                }
            }
            if sp == 0 {
                return None;
            }
            sp -= 1;
            node = &self.nodes[stack[sp] as usize];
        }
    }

    /// Closest hit by testing every triangle: the reference the BVH is checked
    /// against, and the "no BVH" column of the benchmark.
    pub fn intersect_brute(&self, ray: &Ray) -> Option<Hit> {
        let shear = RayShear::new(ray.origin, ray.dir);
        let mut tmax = ray.tmax;
        let mut best = None;
        for (i, t) in self.tris.iter().enumerate() {
            if let Some(h) = intersect(&shear, &t[0], &t[1], &t[2], tmax) {
                tmax = h.t;
                best = Some(Hit {
                    t: h.t,
                    u: h.u,
                    v: h.v,
                    prim: self.prim[i],
                });
            }
        }
        best
    }

    /// Any hit by testing every triangle.
    pub fn occluded_brute(&self, ray: &Ray) -> Option<u32> {
        let shear = RayShear::new(ray.origin, ray.dir);
        self.tris
            .iter()
            .position(|t| intersect(&shear, &t[0], &t[1], &t[2], ray.tmax).is_some())
            .map(|i| self.prim[i])
    }
}

#[inline(always)]
fn hit_box(n: &super::Node, o: Vec3, inv: Vec3, tmax: f32) -> Option<f32> {
    n.bounds().hit(o, inv, tmax)
}
