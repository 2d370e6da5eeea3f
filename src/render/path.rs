//! Path tracing: the integrator's other way of following light, where the
//! plan says so (`--integrator path`). At each hit, a path adds the light
//! the surface gives off, samples every light (next-event estimation), then
//! goes on in one direction drawn from the surface's BSDF ([`Bsdf`]).
//! Lights that a bounce can also find (the environment light and emissive
//! triangles) are weighed by multiple importance sampling with the power
//! heuristic, both ways; point, spot, directional and the seed's area
//! lights are found by light sampling only. Russian roulette ends paths
//! whose throughput has faded.
//!
//! The same `trace` and `shade` as Whitted's rays, the same recorder
//! hooks: a path's ray tree is one branch deep at each hit, and its colour
//! is the pixel's sample.

use std::f32::consts::PI;

use glam::{Vec2, Vec3};

use super::bsdf::{regularizing_alpha, Bsdf, Lobe};
use super::integrator::{Depth, Surface, Tracer, Uvs};
use super::recorder::{Bounce, Emission, LightSample, Mis, RayKind, Recorder};
use crate::geometry::offset::{offset_origin, SHADOW_EPSILON};
use crate::geometry::sampling::Rng;
use crate::geometry::Ray;
use crate::scene::light::{Arriving, From};
use crate::scene::{Environment, Light};

/// Bounces before Russian roulette may end a path: the first few carry
/// most of the light, and ending them early only adds noise.
const ROULETTE_AFTER: u32 = 3;

/// The index the ray tree gives the emissive triangles, after the
/// scene's lights and the environment.
fn emitters_index(lights: usize) -> usize {
    lights + 1
}

impl Tracer<'_> {
    /// A path's hit: `(triangle, distance, emitted radiance)` of the hit
    /// the ray from the previous vertex found; `weight` is the path's
    /// throughput to here.
    pub(super) fn path_vertex<R: Recorder>(
        &self,
        s: &Surface,
        (prim, dist, emitted): (u32, f32, Vec3),
        depth: Depth,
        weight: Vec3,
        rng: &mut Rng,
        rec: &mut R,
    ) -> Vec3 {
        let mut color = Vec3::ZERO;
        if emitted != Vec3::ZERO {
            // Light sampling could have found this point too, unless the
            // ray came from the camera, a mirror or a pass through.
            let mis = depth.pdf.map(|bsdf_pdf| {
                let area = self.scene.emitters().pdf_area(self.scene, prim);
                let cos = s.ng.dot(s.v).abs();
                let light_pdf = if cos > 0.0 {
                    area * dist * dist / cos
                } else {
                    0.0
                };
                Mis::new(light_pdf, bsdf_pdf)
            });
            let w = mis.map_or(1.0, |m| m.bsdf_weight);
            color += emitted * w;
            rec.emission(Emission {
                radiance: emitted,
                mis,
            });
        }
        let blur = match self.plan.regularize {
            true => regularizing_alpha(depth.diffuse_pdf),
            false => 0.0,
        };
        let own = self.bsdf(s);
        let bsdf = own.regularized(blur);
        let regularized = bsdf != own;
        for (i, light) in self.scene.lights.iter().enumerate() {
            color += self.path_light(s, &bsdf, i, light, rng, rec);
        }
        if let Environment::Light(env) = &self.scene.environment {
            if self.plan.environment {
                color += self.path_environment(s, &bsdf, env, rng, rec);
            }
        }
        if self.plan.emission && !self.scene.emitters().is_empty() {
            color += self.path_emitters(s, &bsdf, rng, rec);
        }
        if depth.bounces >= self.max_depth || self.cancelled() {
            return color;
        }
        let pick = rng.next_f32();
        let u = rng.next_vec2();
        let Some(b) = bsdf.sample(s.n, s.ng, s.v, pick, u) else {
            return color;
        };
        if b.lobe == Lobe::Mirror && !self.plan.reflections {
            return color;
        }
        let through = weight * b.weight;
        // Russian roulette: a path lives on in proportion to its
        // throughput, then counts for what the ended ones would have
        // brought. The throughput over the chance is at most 1 in every
        // channel, so a small chance never makes a large weight.
        let mut survival = 1.0;
        if depth.bounces >= ROULETTE_AFTER {
            survival = through.max_element().min(1.0);
            if survival.is_nan() || survival <= 0.0 || rng.next_f32() >= survival {
                rec.bounce(Bounce {
                    lobe: b.lobe,
                    regularized,
                    pdf: b.pdf,
                    factor: b.weight,
                    survival,
                });
                return color;
            }
        }
        let factor = b.weight / survival;
        rec.bounce(Bounce {
            lobe: b.lobe,
            regularized,
            pdf: b.pdf,
            factor: b.weight,
            survival,
        });
        let kind = match b.lobe {
            Lobe::Diffuse => RayKind::Diffuse,
            Lobe::Glossy => RayKind::Glossy,
            Lobe::Mirror => RayKind::Reflection,
            Lobe::Through => RayKind::Transmission,
        };
        let o = offset_origin(s.p, s.err, s.ng, b.dir);
        let ray = Ray::new(o, b.dir);
        let next = depth.bounce(b.pdf, b.lobe == Lobe::Diffuse);
        color + factor * self.trace(&ray, None, next, kind, weight * factor, rng, rec)
    }

    /// The surface's BSDF as the plan shades it.
    fn bsdf(&self, s: &Surface) -> Bsdf {
        let m = s.mat;
        match s.brdf {
            Some(b) => Bsdf::pbr(b, m.dissolve),
            None => {
                let ks = if self.plan.reflections {
                    m.ks
                } else {
                    Vec3::ZERO
                };
                Bsdf::phong(s.kd, ks, m.ns, self.plan.glossy && m.glossy(), m.dissolve)
            }
        }
    }

    /// A shadow ray from the surface toward `to` (a point, or a direction
    /// to infinity), and what blocks it, where shadows run.
    fn path_shadow<R: Recorder>(
        &self,
        s: &Surface,
        to: From,
        rec: &mut R,
    ) -> (Option<Ray>, Option<u32>) {
        if !self.plan.shadows {
            return (None, None);
        }
        let ray = match to {
            From::Point(q) => {
                let o = offset_origin(s.p, s.err, s.ng, q - s.p);
                Ray::segment(o, q - o, 1.0 - SHADOW_EPSILON)
            }
            From::Direction(l) => Ray::new(offset_origin(s.p, s.err, s.ng, l), l),
        };
        let occluder = self.blocked(&ray, rec);
        (Some(ray), occluder)
    }

    /// Records one light sample.
    #[allow(clippy::too_many_arguments)]
    fn record_sample<R: Recorder>(
        &self,
        rec: &mut R,
        point: Vec3,
        color: Vec3,
        (shadow_ray, occluder): (Option<Ray>, Option<u32>),
        visible: bool,
        value: Vec3,
        mis: Option<Mis>,
    ) {
        if R::ACTIVE {
            rec.light_sample(LightSample {
                point,
                color,
                shadow_ray,
                visible,
                occluder: occluder.map(|t| self.occluder(t)),
                diffuse: value,
                specular: Vec3::ZERO,
                mis,
            });
        }
    }

    /// One sample of one of the scene's lights: a point or direction the
    /// path's BSDF could never draw, so it counts whole.
    fn path_light<R: Recorder>(
        &self,
        s: &Surface,
        bsdf: &Bsdf,
        index: usize,
        light: &Light,
        rng: &mut Rng,
        rec: &mut R,
    ) -> Vec3 {
        rec.begin_light(index, light.kind());
        let st = match light {
            Light::Segment { .. } if self.plan.area_sampling => Vec2::new(rng.next_f32(), 0.0),
            Light::Parallelogram { .. } if self.plan.area_sampling => rng.next_vec2(),
            _ => Vec2::splat(0.5),
        };
        let Arriving {
            from,
            value,
            physical,
        } = light.arriving(s.p, st);
        let (point, l, facing) = match from {
            From::Point(q) => {
                let d = q - s.p;
                let len = d.length();
                (q, d / len, len > 0.0)
            }
            From::Direction(l) => (s.p + l, l, true),
        };
        let facing = facing && l.is_finite() && s.ng.dot(l) > 0.0 && s.n.dot(l) > 0.0;
        let f = if facing {
            bsdf.eval(s.n, s.v, l)
        } else {
            Vec3::ZERO
        };
        let mut out = Vec3::ZERO;
        let mut shadow = (None, None);
        if f != Vec3::ZERO {
            shadow = self.path_shadow(s, from, rec);
            if shadow.1.is_none() {
                // A Phong light's colour is what it gives a white Phong
                // surface facing it: an illuminance of π times it.
                let e = if physical { value } else { value * PI };
                out = f * e;
            }
        }
        let visible = facing && shadow.1.is_none();
        self.record_sample(rec, point, value, shadow, visible, out, None);
        rec.end_light(out, Vec3::ZERO);
        out
    }

    /// One sample of the environment light, weighed against the BSDF's
    /// chance of finding the same direction.
    fn path_environment<R: Recorder>(
        &self,
        s: &Surface,
        bsdf: &Bsdf,
        env: &crate::scene::EnvLight,
        rng: &mut Rng,
        rec: &mut R,
    ) -> Vec3 {
        rec.begin_light(self.scene.lights.len(), "environment");
        let e = env.sample(rng.next_vec2());
        let l = e.dir;
        let facing = e.pdf > 0.0 && l.is_finite() && s.ng.dot(l) > 0.0 && s.n.dot(l) > 0.0;
        let f = if facing {
            bsdf.eval(s.n, s.v, l)
        } else {
            Vec3::ZERO
        };
        let mut out = Vec3::ZERO;
        let (mut shadow, mut mis) = ((None, None), None);
        if f != Vec3::ZERO {
            let m = Mis::new(e.pdf, bsdf.pdf(s.n, s.v, l));
            mis = Some(m);
            shadow = self.path_shadow(s, From::Direction(l), rec);
            if shadow.1.is_none() {
                out = f * e.radiance * (m.light_weight / e.pdf);
            }
        }
        let visible = facing && shadow.1.is_none();
        self.record_sample(rec, s.p + l, e.radiance, shadow, visible, out, mis);
        rec.end_light(out, Vec3::ZERO);
        out
    }

    /// One point on the emissive triangles, drawn in proportion to their
    /// power, weighed against the BSDF's chance of finding it.
    fn path_emitters<R: Recorder>(
        &self,
        s: &Surface,
        bsdf: &Bsdf,
        rng: &mut Rng,
        rec: &mut R,
    ) -> Vec3 {
        let scene = self.scene;
        rec.begin_light(emitters_index(scene.lights.len()), "emissive triangles");
        let pick = rng.next_f32();
        let u = rng.next_vec2();
        let mut out = Vec3::ZERO;
        let Some((q, area_pdf)) = scene.emitters().sample(scene, pick, u) else {
            rec.end_light(out, out);
            return out;
        };
        let geo = &scene.geometry;
        let idx = geo.indices[q.prim as usize];
        let verts = idx.map(|i| geo.positions[i as usize]);
        let nl = crate::geometry::offset::geometric_normal(verts);
        let d = q.point - s.p;
        let dist2 = d.length_squared();
        let l = d / dist2.sqrt();
        let cos_light = nl.dot(l).abs();
        let facing = dist2 > 0.0
            && cos_light > 0.0
            && l.is_finite()
            && s.ng.dot(l) > 0.0
            && s.n.dot(l) > 0.0;
        let f = if facing {
            bsdf.eval(s.n, s.v, l)
        } else {
            Vec3::ZERO
        };
        let radiance = self.emitted_at(q.prim, q.uv);
        let (mut shadow, mut mis) = ((None, None), None);
        if f != Vec3::ZERO && radiance != Vec3::ZERO {
            let light_pdf = area_pdf * dist2 / cos_light;
            let m = Mis::new(light_pdf, bsdf.pdf(s.n, s.v, l));
            mis = Some(m);
            shadow = self.path_shadow(s, From::Point(q.point), rec);
            if shadow.1.is_none() {
                out = f * radiance * (m.light_weight / light_pdf);
            }
        }
        let visible = facing && shadow.1.is_none();
        self.record_sample(rec, q.point, radiance, shadow, visible, out, mis);
        rec.end_light(out, Vec3::ZERO);
        out
    }

    /// The light triangle `prim` gives off at barycentric `(u, v)`, as a
    /// hit there would see it.
    fn emitted_at(&self, prim: u32, uv: Vec2) -> Vec3 {
        let scene = self.scene;
        let geo = &scene.geometry;
        let mat = &scene.materials[geo.tri_material[prim as usize] as usize];
        let Some(pbr) = &mat.pbr else {
            return Vec3::ZERO;
        };
        let uvs = match self.plan.textures {
            true => Uvs::at(
                scene,
                prim as usize,
                Vec3::new(1.0 - uv.x - uv.y, uv.x, uv.y),
            ),
            false => Uvs::default(),
        };
        self.emitted(pbr, &uvs)
    }
}
