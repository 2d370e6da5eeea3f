//! glTF alpha for every ray: a hit on a surface that is not there (a
//! `MASK` texel below its cutoff, a `BLEND` texel passed by chance) is
//! stepped past, and the ray goes on in the same direction to the next
//! hit. Camera, bounce and shadow rays alike, so cut-out leaves cast
//! leaf-shaped shadows. Only scenes with such materials pay: the plan's
//! `alpha` is off elsewhere.

use glam::Vec3;

use super::integrator::{lookup, Tracer, Uvs};
use super::recorder::Recorder;
use crate::bvh::Hit;
use crate::geometry::offset::{geometric_normal, hit_point, offset_origin};
use crate::geometry::Ray;

/// The most surfaces a ray steps past before it stops at the next: a
/// bound on the work of a stack of cut-outs (foliage seen edge-on).
const MAX_PASSED: u32 = 64;

impl Tracer<'_> {
    /// How much of the surface is there at `hit` (glTF alpha), where its
    /// material tests it.
    fn coverage(&self, hit: &Hit) -> Option<(f32, Option<f32>)> {
        let geo = &self.scene.geometry;
        let prim = hit.prim as usize;
        let a = self.scene.materials[geo.tri_material[prim] as usize].alpha?;
        let mut alpha = a.factor;
        if let (Some(id), true) = (a.texture, self.plan.textures) {
            let uvs = Uvs::at(
                self.scene,
                prim,
                Vec3::new(1.0 - hit.u - hit.v, hit.u, hit.v),
            );
            if let Some(t) = lookup(&self.scene.textures[id as usize], &uvs, self.plan.bilinear) {
                alpha *= t.x;
            }
        }
        Some((alpha, a.cutoff))
    }

    /// Whether `ray` passes the surface at `hit`: below `MASK`'s cutoff, or
    /// past `BLEND`'s alpha by a number drawn from the ray and the
    /// triangle, so that the same ray always decides the same way (a
    /// sample depends only on its pixel, index and seed).
    fn passes(&self, ray: &Ray, hit: &Hit) -> bool {
        match self.coverage(hit) {
            None => false,
            Some((alpha, Some(cutoff))) => alpha < cutoff,
            Some((alpha, None)) => {
                let words = [ray.origin, ray.dir].map(|v| v.to_array().map(f32::to_bits));
                let u = crate::geometry::sampling::unit_hash(
                    words.iter().flatten().copied().chain([hit.prim]),
                );
                u >= alpha
            }
        }
    }

    /// The rest of `ray` beyond the surface at `hit`: from just past it
    /// (the offset reflection rays start from), in the same direction, to
    /// the same end.
    fn beyond(&self, ray: &Ray, hit: &Hit) -> Ray {
        let geo = &self.scene.geometry;
        let verts = geo.indices[hit.prim as usize].map(|i| geo.positions[i as usize]);
        let (p, err) = hit_point(verts, hit.u, hit.v);
        let o = offset_origin(p, err, geometric_normal(verts), ray.dir);
        match ray.tmax.is_finite() {
            true => Ray::segment(o, ray.at(ray.tmax) - o, 1.0),
            false => Ray::new(o, ray.dir),
        }
    }

    /// `ray` and its closest hit `hit`, or the ray's rest beyond every
    /// surface it passes and the hit that stops it. The hit's distance is
    /// along the ray returned.
    pub(super) fn past_cutouts<R: Recorder>(
        &self,
        ray: &Ray,
        hit: Option<Hit>,
        rec: &mut R,
    ) -> (Ray, Option<Hit>) {
        let (mut ray, mut hit) = (*ray, hit);
        for _ in 0..MAX_PASSED {
            match hit {
                Some(h) if self.passes(&ray, &h) => {
                    ray = self.beyond(&ray, &h);
                    hit = self.nearest(&ray, rec);
                }
                _ => break,
            }
        }
        (ray, hit)
    }

    /// The triangle that blocks the shadow ray `ray`, passing what is not
    /// there: hits nearest first, as any hit could be one to pass. Each
    /// step past a surface is a shadow ray of its own in the counts.
    pub(super) fn blocked_past_cutouts<R: Recorder>(&self, ray: &Ray, rec: &mut R) -> Option<u32> {
        let mut ray = *ray;
        for _ in 0..MAX_PASSED {
            let h = self.nearest(&ray, rec)?;
            if !self.passes(&ray, &h) {
                return Some(h.prim);
            }
            ray = self.beyond(&ray, &h);
            rec.shadow_ray();
        }
        None
    }
}
