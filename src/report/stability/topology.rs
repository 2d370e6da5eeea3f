//! Triangles welded by exact position, and the points a ray aimed from a
//! given origin must hit: points on shared edges and around closed vertex
//! fans that the ray crosses transversally, and interior points of
//! triangles it does not graze. A miss on any of them is a crack.

use std::collections::BTreeMap;

use glam::{DVec3, Vec3};

use crate::geometry::sampling::Rng;
use crate::geometry::Ray;

/// A position's bit pattern, with -0 folded into +0.
type Key = [u32; 3];

fn key(p: Vec3) -> Key {
    (p + Vec3::ZERO).to_array().map(f32::to_bits)
}

/// Rays closer than this cosine to a surface's plane are ambiguous (a grazing
/// ray may legitimately slip past) and are not aimed at.
const MIN_COS: f64 = 0.01;

/// A triangle soup welded by exact vertex position.
pub struct Topology {
    pub(crate) tris: Vec<[Vec3; 3]>,
    normals: Vec<DVec3>,
    /// Edge (sorted keys) to its triangles, each with whether it walks the
    /// edge from the smaller key to the larger. Ordered maps: random points
    /// are drawn edge by edge, so the order makes the battery's rays.
    edges: BTreeMap<(Key, Key), Vec<(u32, bool)>>,
    /// Vertex to the edges that meet there.
    vertex_edges: BTreeMap<Key, Vec<(Key, Key)>>,
}

/// Where a ray must cross the surface.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Crossing {
    Vertex,
    Edge,
    Surface,
}

impl Topology {
    pub fn new(tris: Vec<[Vec3; 3]>) -> Self {
        let normals = tris
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|p| p.as_dvec3());
                (b - a).cross(c - a).normalize_or_zero()
            })
            .collect();
        let mut edges: BTreeMap<(Key, Key), Vec<(u32, bool)>> = BTreeMap::new();
        let mut vertex_edges: BTreeMap<Key, Vec<(Key, Key)>> = BTreeMap::new();
        for (i, t) in tris.iter().enumerate() {
            for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                let (ka, kb) = (key(a), key(b));
                if ka == kb {
                    continue;
                }
                let e = if ka < kb { (ka, kb) } else { (kb, ka) };
                let list = edges.entry(e).or_default();
                if list.is_empty() {
                    vertex_edges.entry(e.0).or_default().push(e);
                    vertex_edges.entry(e.1).or_default().push(e);
                }
                list.push((i as u32, ka < kb));
            }
        }
        Self {
            tris,
            normals,
            edges,
            vertex_edges,
        }
    }

    /// Edges used by one triangle only: openings of the surface.
    pub fn boundary_edges(&self) -> Vec<(Vec3, Vec3)> {
        self.edges
            .iter()
            .filter(|(_, t)| t.len() == 1)
            .map(|(e, _)| (from_key(e.0), from_key(e.1)))
            .collect()
    }

    /// Boundary edges that another boundary edge matches within `tol` at
    /// both ends: hairline cracks that exact welding leaves open.
    pub fn hairline_cracks(&self, tol: f32) -> usize {
        let b = self.boundary_edges();
        let near = |p: Vec3, q: Vec3| (p - q).abs().max_element() <= tol;
        (0..b.len())
            .filter(|&i| {
                (0..b.len()).any(|j| {
                    j != i
                        && ((near(b[i].0, b[j].0) && near(b[i].1, b[j].1))
                            || (near(b[i].0, b[j].1) && near(b[i].1, b[j].0)))
                })
            })
            .count()
    }

    /// Whether a ray along `d` crosses the surface at the shared edge `e`:
    /// two consistently oriented triangles both facing the same way.
    fn edge_crosses(&self, e: &(Key, Key), d: DVec3) -> bool {
        let Some(t) = self.edges.get(e) else {
            return false;
        };
        let [(t0, f0), (t1, f1)] = t[..] else {
            return false;
        };
        let n0 = self.normals[t0 as usize];
        let mut n1 = self.normals[t1 as usize];
        if f0 == f1 {
            n1 = -n1;
        }
        let (c0, c1) = (n0.dot(d), n1.dot(d));
        c0.abs() >= MIN_COS && c1.abs() >= MIN_COS && (c0 > 0.0) == (c1 > 0.0)
    }

    /// Whether a ray along `d` crosses the surface at vertex `v`: every edge
    /// there is shared by two consistently oriented triangles, all facing the
    /// same way.
    fn vertex_crosses(&self, v: &Key, d: DVec3) -> bool {
        let Some(es) = self.vertex_edges.get(v) else {
            return false;
        };
        let mut sign = None;
        for e in es {
            let Some(t) = self.edges.get(e) else {
                return false;
            };
            let [(t0, f0), (t1, f1)] = t[..] else {
                return false;
            };
            if f0 == f1 {
                return false;
            }
            for tri in [t0, t1] {
                let c = self.normals[tri as usize].dot(d);
                if c.abs() < MIN_COS || *sign.get_or_insert(c > 0.0) != (c > 0.0) {
                    return false;
                }
            }
        }
        sign.is_some()
    }

    /// Points that a ray from `origin` aimed at them must hit (something at
    /// or before the point): all crossing vertices, `per_edge` random points
    /// on every crossing edge, or `count` random interior points.
    pub(crate) fn targets(
        &self,
        origin: Vec3,
        kind: Crossing,
        per_edge: u32,
        count: u32,
        rng: &mut Rng,
    ) -> Vec<DVec3> {
        let o = origin.as_dvec3();
        let unit = |p: DVec3| (p - o).normalize_or_zero();
        match kind {
            Crossing::Vertex => self
                .vertex_edges
                .keys()
                .map(|v| (v, from_key(*v).as_dvec3()))
                .filter(|(v, p)| self.vertex_crosses(v, unit(*p)))
                .map(|(_, p)| p)
                .collect(),
            Crossing::Edge => {
                let mut out = Vec::new();
                for e in self.edges.keys() {
                    let (a, b) = (from_key(e.0).as_dvec3(), from_key(e.1).as_dvec3());
                    for _ in 0..per_edge {
                        let p = a.lerp(b, 0.02 + 0.96 * rng.next_f32() as f64);
                        if self.edge_crosses(e, unit(p)) {
                            out.push(p);
                        }
                    }
                }
                out
            }
            Crossing::Surface => {
                let mut out = Vec::new();
                if self.tris.is_empty() {
                    return out;
                }
                for _ in 0..count {
                    let i = rng.next_u32() as usize % self.tris.len();
                    // Uniform on the triangle, kept off its edges by a hair so
                    // the point is inside whatever the rounding.
                    let (r1, r2) = (rng.next_f32() as f64, rng.next_f32() as f64);
                    let s = r1.sqrt();
                    let b = [1.0 - s, s * (1.0 - r2), s * r2].map(|x| 1e-3 + x * (1.0 - 3e-3));
                    let [p0, p1, p2] = self.tris[i].map(|p| p.as_dvec3());
                    let p = p0 * b[0] + p1 * b[1] + p2 * b[2];
                    if self.normals[i].dot(unit(p)).abs() >= MIN_COS {
                        out.push(p);
                    }
                }
                out
            }
        }
    }
}

fn from_key(k: Key) -> Vec3 {
    Vec3::from_array(k.map(f32::from_bits))
}

/// The ray from `origin` toward `target`, its direction computed in f64 so
/// the only rounding is that of the final f32 direction.
pub fn aimed(origin: Vec3, target: DVec3) -> Option<Ray> {
    let d = (target - origin.as_dvec3()).normalize_or_zero();
    (d != DVec3::ZERO).then(|| Ray::new(origin, d.as_vec3()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube() -> Vec<[Vec3; 3]> {
        // Unit cube, outward counter-clockwise.
        let v = |x: f32, y: f32, z: f32| Vec3::new(x, y, z);
        let q = |a, b, c, d| [[a, b, c], [a, c, d]];
        [
            q(v(0., 0., 0.), v(0., 1., 0.), v(1., 1., 0.), v(1., 0., 0.)),
            q(v(0., 0., 1.), v(1., 0., 1.), v(1., 1., 1.), v(0., 1., 1.)),
            q(v(0., 0., 0.), v(1., 0., 0.), v(1., 0., 1.), v(0., 0., 1.)),
            q(v(0., 1., 0.), v(0., 1., 1.), v(1., 1., 1.), v(1., 1., 0.)),
            q(v(0., 0., 0.), v(0., 0., 1.), v(0., 1., 1.), v(0., 1., 0.)),
            q(v(1., 0., 0.), v(1., 1., 0.), v(1., 1., 1.), v(1., 0., 1.)),
        ]
        .concat()
    }

    #[test]
    fn closed_cube_has_no_boundary_and_every_target_from_inside() {
        let t = Topology::new(cube());
        assert!(t.boundary_edges().is_empty());
        let mut rng = Rng::for_sample(0, 0, 1);
        let o = Vec3::splat(0.4);
        assert_eq!(t.targets(o, Crossing::Vertex, 0, 0, &mut rng).len(), 8);
        // 18 edges (12 cube edges and 6 diagonals), one point each.
        assert_eq!(t.targets(o, Crossing::Edge, 1, 0, &mut rng).len(), 18);
    }

    #[test]
    fn silhouettes_and_openings_are_not_targets() {
        let mut tris = cube();
        tris.truncate(10); // drop the +x face: an opening
        let t = Topology::new(tris);
        assert_eq!(t.boundary_edges().len(), 4);
        let mut rng = Rng::for_sample(0, 0, 1);
        // From outside, looking at the open side: the cube's far-side edges
        // are crossed, its silhouette edges (toward the eye) are not.
        let eye = Vec3::new(5.0, 0.5, 0.5);
        let verts = t.targets(eye, Crossing::Vertex, 0, 0, &mut rng);
        assert_eq!(verts.len(), 4);
        assert!(verts.iter().all(|p| p.x == 0.0), "{verts:?}");
    }

    /// The same soup and seed give the same targets: the battery's rays
    /// do not change from run to run.
    #[test]
    fn targets_are_the_same_every_time() {
        let o = Vec3::new(0.4, 0.55, 0.3);
        let draw = |kind| {
            let mut rng = Rng::for_sample(3, 1, 4);
            Topology::new(cube()).targets(o, kind, 3, 50, &mut rng)
        };
        for kind in [Crossing::Vertex, Crossing::Edge, Crossing::Surface] {
            let first = draw(kind);
            assert!(!first.is_empty(), "{kind:?}");
            for _ in 0..4 {
                assert_eq!(draw(kind), first, "{kind:?}");
            }
        }
    }

    #[test]
    fn hairline_cracks_are_found() {
        let mut tris = cube();
        assert_eq!(Topology::new(tris.clone()).hairline_cracks(1e-4), 0);
        // Nudge one corner of one triangle: its two edges there open up.
        tris[0][1].y += 1e-6;
        let t = Topology::new(tris);
        assert!(t.hairline_cracks(1e-4) >= 2);
        assert_eq!(t.hairline_cracks(1e-9), 0);
    }
}
