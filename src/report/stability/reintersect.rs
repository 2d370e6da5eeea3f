//! Reintersection (pbrt-v4's TestReintersectConvex idea): a ray hits a
//! triangle from a distance drawn log-uniformly from 1e-8 to 1e8; rays
//! spawned from the hit point with [`offset_origin`] in random directions
//! must never hit that triangle again. Checked on random triangles of
//! assorted sizes and positions, and through the BVH on the sphere mesh
//! placed at several scales and offsets.

use anyhow::Result;
use glam::{DVec3, Vec3};

use super::watertight::sphere;
use super::{Options, Row};
use crate::bvh::{self, TraversalStats};
use crate::geometry::offset::{geometric_normal, hit_point, offset_origin};
use crate::geometry::sampling::Rng;
use crate::geometry::triangle::{intersect, RayShear};
use crate::geometry::Ray;
use crate::scene::{Builder, Geometry};

/// Directions spawned from each hit.
const SPAWNED: u32 = 4;

fn log_uniform(rng: &mut Rng, lo: f64, hi: f64) -> f64 {
    (lo.ln() + (hi.ln() - lo.ln()) * rng.next_f32() as f64).exp()
}

fn unit(rng: &mut Rng) -> DVec3 {
    let z = 2.0 * rng.next_f32() as f64 - 1.0;
    let phi = std::f64::consts::TAU * rng.next_f32() as f64;
    let s = (1.0 - z * z).max(0.0).sqrt();
    DVec3::new(s * phi.cos(), s * phi.sin(), z)
}

fn point_on(t: &[Vec3; 3], rng: &mut Rng) -> DVec3 {
    let (r1, r2) = (rng.next_f32() as f64, rng.next_f32() as f64);
    let s = r1.sqrt();
    let [a, b, c] = t.map(|p| p.as_dvec3());
    a * (1.0 - s) + b * (s * (1.0 - r2)) + c * (s * r2)
}

/// A ray toward `target` from `dist` away in a random direction, or `None`
/// when the origin rounds onto the target.
fn incoming(target: DVec3, rng: &mut Rng) -> Option<Ray> {
    let dist = log_uniform(rng, 1e-8, 1e8);
    let o = (target + unit(rng) * dist).as_vec3();
    let d = (target - o.as_dvec3()).as_vec3();
    (d != Vec3::ZERO && d.is_finite()).then(|| Ray::new(o, d))
}

/// Spawned rays and those that hit their own triangle again.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Rehits {
    pub spawned: u64,
    pub rehits: u64,
}

/// Spawns rays from the hit of `ray` on `tri` and tests each against it.
fn spawn(
    tri: &[Vec3; 3],
    u: f32,
    v: f32,
    rng: &mut Rng,
    mut hits_own: impl FnMut(&Ray) -> bool,
) -> Rehits {
    let (p, err) = hit_point(*tri, u, v);
    let ng = geometric_normal(*tri);
    let mut r = Rehits::default();
    for _ in 0..SPAWNED {
        let w = unit(rng).as_vec3();
        let spawned = Ray::new(offset_origin(p, err, ng, w), w);
        r.spawned += 1;
        r.rehits += hits_own(&spawned) as u64;
    }
    r
}

/// Random triangles: centres 1e-4 .. 1e6 from the origin, sizes 1e-3 .. 1e3.
pub fn random_triangles(n: u32, seed: u64) -> Rehits {
    let mut rng = Rng::for_sample(0, 4, seed);
    let mut total = Rehits::default();
    let mut tries = 0;
    while total.spawned < (n * SPAWNED) as u64 && tries < 4 * n {
        tries += 1;
        let c = unit(&mut rng) * log_uniform(&mut rng, 1e-4, 1e6);
        let size = log_uniform(&mut rng, 1e-3, 1e3);
        let tri = [0, 1, 2].map(|_| (c + unit(&mut rng) * size).as_vec3());
        if (tri[1] - tri[0]).cross(tri[2] - tri[0]).length_squared() == 0.0 {
            continue;
        }
        let Some(ray) = incoming(point_on(&tri, &mut rng), &mut rng) else {
            continue;
        };
        let t = tri.map(|p| p.to_array());
        let s = RayShear::new(ray.origin, ray.dir);
        let Some(h) = intersect(&s, &t[0], &t[1], &t[2], f32::INFINITY) else {
            continue;
        };
        let r = spawn(&tri, h.u, h.v, &mut rng, |ray| {
            let s = RayShear::new(ray.origin, ray.dir);
            intersect(&s, &t[0], &t[1], &t[2], f32::INFINITY).is_some()
        });
        total.spawned += r.spawned;
        total.rehits += r.rehits;
    }
    total
}

/// The sphere mesh at `scale` and `offset`, hit from outside through the
/// BVH; a spawned ray re-hits when the BVH's closest hit is its own triangle.
pub(crate) fn sphere_mesh(n: u32, scale: f32, offset: Vec3, seed: u64) -> Result<Rehits> {
    let tris: Vec<[Vec3; 3]> = sphere()?
        .into_iter()
        .map(|t| t.map(|p| p * scale + offset))
        .collect();
    let b = bvh::build(&Geometry::from_triangles(&tris), Builder::Sah);
    let mut rng = Rng::for_sample(1, 4, seed);
    let mut total = Rehits::default();
    for _ in 0..n {
        let i = rng.next_u32() as usize % tris.len();
        let target = point_on(&tris[i], &mut rng);
        let Some(ray) = incoming(target, &mut rng) else {
            continue;
        };
        let Some(h) = b.intersect::<false>(&ray, &mut TraversalStats::default()) else {
            continue;
        };
        let tri = tris[h.prim as usize];
        let r = spawn(&tri, h.u, h.v, &mut rng, |ray| {
            b.intersect::<false>(ray, &mut TraversalStats::default())
                .is_some_and(|g| g.prim == h.prim)
        });
        total.spawned += r.spawned;
        total.rehits += r.rehits;
    }
    Ok(total)
}

/// The reintersection rows.
pub fn reintersection(o: &Options) -> Result<Vec<Row>> {
    let r = random_triangles(o.rays / SPAWNED, o.seed);
    let mut rows = vec![Row::zero(
        "reintersection: random triangles",
        r.rehits,
        format!(
            "{} of {} rays spawned from hits (distances 1e-8 .. 1e8) hit their own triangle",
            r.rehits, r.spawned
        ),
    )];
    let mut m = Rehits::default();
    for (scale, off) in [
        (1.0, Vec3::ZERO),
        (1e-3, Vec3::ZERO),
        (1e3, Vec3::new(1e6, -5e5, 7.5e5)),
    ] {
        let r = sphere_mesh(o.rays / SPAWNED / 3, scale, off, o.seed)?;
        m.spawned += r.spawned;
        m.rehits += r.rehits;
    }
    rows.push(Row::zero(
        "reintersection: sphere mesh (BVH)",
        m.rehits,
        format!(
            "{} of {} spawned rays hit their own triangle (sphere at scale 1, 1e-3, 1e3 offset 1e6)",
            m.rehits, m.spawned
        ),
    ));
    Ok(rows)
}
