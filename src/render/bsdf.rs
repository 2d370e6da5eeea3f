//! How a surface scatters light along a path: the path tracer's view of a
//! material. A metallic-roughness material is its BRDF ([`Brdf`]): a
//! diffuse lobe and a GGX lobe (or a Fresnel mirror when smooth). A Phong
//! material becomes the energy-based reading of its parameters: a
//! Lambertian lobe of albedo `kd` and a normalised Phong lobe of
//! reflectance `ks` and exponent `Ns`, a mirror at
//! [`GLOSSY_MAX_NS`](crate::scene::material::GLOSSY_MAX_NS) and above.
//! Either may let light through (`dissolve`).
//!
//! A sample picks one lobe at random (in proportion to an estimate of what
//! it reflects) and draws a direction from it; its density is the mixture's,
//! so a direction reachable by both rough lobes has one density, the one
//! multiple importance sampling weighs light samples against.

use std::f32::consts::{FRAC_1_PI, TAU};

use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};

use super::brdf::Brdf;
use crate::geometry::sampling::{onb, phong_lobe};

/// The lobe a path's bounce was drawn from.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub(crate) enum Lobe {
    Diffuse,
    /// A rough specular lobe (GGX or Phong).
    Glossy,
    /// A mirror: one direction, no density.
    Mirror,
    /// Straight through a partly transparent surface.
    Through,
}

impl Lobe {
    pub(crate) fn name(self) -> &'static str {
        match self {
            Lobe::Diffuse => "diffuse",
            Lobe::Glossy => "glossy",
            Lobe::Mirror => "mirror",
            Lobe::Through => "through",
        }
    }
}

/// A drawn direction.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Scattered {
    pub(crate) dir: Vec3,
    /// BSDF times cosine over the density (and over the chance of the
    /// lobe): the path's throughput factor.
    pub(crate) weight: Vec3,
    /// The density per solid angle of the whole mixture at `dir`; `None`
    /// for a mirror or a pass through, which light sampling cannot reach.
    pub(crate) pdf: Option<f32>,
    pub(crate) lobe: Lobe,
}

/// The specular part of a Phong material.
#[derive(Clone, Copy, Debug, PartialEq)]
struct PhongLobe {
    ks: Vec3,
    ns: f32,
    mirror: bool,
}

/// The scattering at one shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Bsdf {
    model: Model,
    /// The chance a sample passes straight through (MTL `1 - d`).
    through: f32,
}

#[derive(Clone, Copy, Debug, PartialEq)]
enum Model {
    Pbr(Brdf),
    Phong { kd: Vec3, spec: Option<PhongLobe> },
}

fn luminance(c: Vec3) -> f32 {
    c.dot(crate::color::LUMA).max(0.0)
}

/// The share of samples given to the specular lobe, from what each lobe
/// reflects; never below a tenth of the samples while both lobes reflect,
/// so neither is starved.
fn specular_share(diffuse: f32, specular: f32) -> f32 {
    match (diffuse > 0.0, specular > 0.0) {
        (false, false) => 0.0,
        (false, true) => 1.0,
        (true, false) => 0.0,
        (true, true) => (specular / (diffuse + specular)).clamp(0.1, 0.9),
    }
}

/// A cosine-weighted direction about `n` and its density.
fn cosine_hemisphere(n: Vec3, u: Vec2) -> (Vec3, f32) {
    let r = u.x.sqrt();
    let phi = TAU * u.y;
    let z = (1.0 - u.x).max(0.0).sqrt();
    let (t, b) = onb(n);
    let d = (t * (r * phi.cos()) + b * (r * phi.sin()) + n * z).normalize();
    (d, z * FRAC_1_PI)
}

impl Bsdf {
    /// A metallic-roughness surface's scattering.
    pub(crate) fn pbr(brdf: Brdf, dissolve: f32) -> Self {
        Self {
            model: Model::Pbr(brdf),
            through: (1.0 - dissolve).clamp(0.0, 1.0),
        }
    }

    /// A Phong surface's scattering: `kd` its diffuse albedo; a specular
    /// lobe where `ks` is not black (`reflect` says whether reflection
    /// runs), a mirror unless `glossy`.
    pub(crate) fn phong(kd: Vec3, ks: Vec3, ns: f32, glossy: bool, dissolve: f32) -> Self {
        let spec = (ks.max_element() > 0.0).then_some(PhongLobe {
            ks: ks.max(Vec3::ZERO),
            ns: ns.max(0.0),
            mirror: !glossy,
        });
        Self {
            model: Model::Phong {
                kd: kd.max(Vec3::ZERO),
                spec,
            },
            through: (1.0 - dissolve).clamp(0.0, 1.0),
        }
    }

    /// The scattering with its specular lobe at least as rough as a GGX
    /// alpha of `alpha` (a mirror's included; a Phong lobe through the
    /// alpha of its exponent, `Ns = 2 / α² - 2`): path regularization
    /// ([`regularizing_alpha`]).
    pub(crate) fn regularized(mut self, alpha: f32) -> Self {
        if alpha <= 0.0 {
            return self;
        }
        match &mut self.model {
            Model::Pbr(b) => b.alpha = b.alpha.max(alpha),
            Model::Phong { spec: Some(s), .. } => {
                let own = if s.mirror {
                    0.0
                } else {
                    (2.0 / (s.ns + 2.0)).sqrt()
                };
                if own < alpha {
                    s.ns = 2.0 / (alpha * alpha) - 2.0;
                    s.mirror = false;
                }
            }
            Model::Phong { spec: None, .. } => {}
        }
        self
    }

    /// The chance of the specular lobe among the reflecting ones, seen
    /// from `cos_v`.
    fn share(&self, cos_v: f32) -> f32 {
        match &self.model {
            Model::Pbr(b) => {
                let f = b.fresnel(cos_v);
                specular_share(luminance((Vec3::ONE - f) * b.c_diff), luminance(f))
            }
            Model::Phong { kd, spec } => {
                specular_share(luminance(*kd), spec.map_or(0.0, |s| luminance(s.ks)))
            }
        }
    }

    /// BSDF times `n·l` for light from `l` seen from `v` (unit vectors
    /// away from the surface), the rough lobes only: a mirror reflects no
    /// light sample. Scaled by the share of light that does not pass
    /// through.
    pub(crate) fn eval(&self, n: Vec3, v: Vec3, l: Vec3) -> Vec3 {
        let keep = 1.0 - self.through;
        match &self.model {
            Model::Pbr(b) => {
                let lobes = b.eval(n, v, l);
                (lobes.diffuse + lobes.specular) * keep
            }
            Model::Phong { kd, spec } => {
                let (cos_l, cos_v) = (n.dot(l), n.dot(v));
                if cos_l <= 0.0 || cos_v <= 0.0 {
                    return Vec3::ZERO;
                }
                let mut f = *kd * FRAC_1_PI;
                if let Some(s) = spec.filter(|s| !s.mirror) {
                    let r = 2.0 * cos_v * n - v;
                    let c = r.dot(l).max(0.0);
                    f += s.ks * ((s.ns + 2.0) / TAU * c.powf(s.ns));
                }
                f * cos_l * keep
            }
        }
    }

    /// The density with which [`Bsdf::sample`] draws `l` for `v`: what
    /// multiple importance sampling weighs a light sample against.
    pub(crate) fn pdf(&self, n: Vec3, v: Vec3, l: Vec3) -> f32 {
        let (cos_l, cos_v) = (n.dot(l), n.dot(v));
        if cos_l <= 0.0 || cos_v <= 0.0 {
            return 0.0;
        }
        let keep = 1.0 - self.through;
        let share = self.share(cos_v);
        let diffuse = (1.0 - share) * cos_l * FRAC_1_PI;
        let specular = match &self.model {
            Model::Pbr(b) if !b.is_mirror() => share * b.specular_pdf(n, v, l),
            Model::Phong {
                spec: Some(s),
                kd: _,
            } if !s.mirror => {
                let r = 2.0 * cos_v * n - v;
                let c = r.dot(l).max(0.0);
                share * (s.ns + 1.0) / TAU * c.powf(s.ns)
            }
            _ => 0.0,
        };
        keep * (diffuse + specular)
    }

    /// A direction for the path to go on, drawn with `pick` (which lobe)
    /// and `u` (where in it), seen from `v` on a surface of shading normal
    /// `n` and geometric normal `ng` (on `v`'s side); `None` where the
    /// drawn direction leaves below the surface (the path ends: it
    /// carries no light).
    pub(crate) fn sample(
        &self,
        n: Vec3,
        ng: Vec3,
        v: Vec3,
        pick: f32,
        u: Vec2,
    ) -> Option<Scattered> {
        if pick < self.through {
            return Some(Scattered {
                dir: -v,
                weight: Vec3::ONE,
                pdf: None,
                lobe: Lobe::Through,
            });
        }
        let keep = 1.0 - self.through;
        // Reuse what is left of `pick` for the lobe.
        let pick = if keep > 0.0 {
            ((pick - self.through) / keep).min(1.0)
        } else {
            pick
        };
        let cos_v = n.dot(v);
        if cos_v <= 0.0 {
            return None;
        }
        let share = self.share(cos_v);
        let specular = pick < share;
        let mirror = match &self.model {
            Model::Pbr(b) => b.is_mirror(),
            Model::Phong { spec, .. } => spec.is_some_and(|s| s.mirror),
        };
        if specular && mirror {
            let dir = 2.0 * cos_v * n - v;
            if dir.dot(ng) <= 0.0 {
                return None;
            }
            let f = match &self.model {
                Model::Pbr(b) => b.fresnel(cos_v),
                Model::Phong { spec, .. } => spec.map_or(Vec3::ZERO, |s| s.ks),
            };
            return Some(Scattered {
                dir,
                weight: f / share,
                pdf: None,
                lobe: Lobe::Mirror,
            });
        }
        let (dir, lobe) = if specular {
            let dir = match &self.model {
                Model::Pbr(b) => b.sample_specular(n, v, u)?.dir,
                Model::Phong { spec, .. } => {
                    let s = spec.as_ref()?;
                    phong_lobe(2.0 * cos_v * n - v, s.ns, u).0
                }
            };
            (dir, Lobe::Glossy)
        } else {
            (cosine_hemisphere(n, u).0, Lobe::Diffuse)
        };
        if dir.dot(ng) <= 0.0 || n.dot(dir) <= 0.0 || !dir.is_finite() {
            return None;
        }
        let pdf = self.pdf(n, v, dir);
        if pdf <= 0.0 || !pdf.is_finite() {
            return None;
        }
        // With a mirror beside it, the diffuse lobe is all the density has.
        let f = self.eval(n, v, dir);
        Some(Scattered {
            dir,
            weight: f / pdf,
            pdf: Some(pdf),
            lobe,
        })
    }
}

/// The power heuristic (exponent 2) weight of a strategy of density `a`
/// against one of density `b`.
pub(crate) fn power_heuristic(a: f32, b: f32) -> f32 {
    let (a2, b2) = (a * a, b * b);
    if a2 + b2 > 0.0 && (a2 + b2).is_finite() {
        a2 / (a2 + b2)
    } else if a.is_infinite() {
        1.0
    } else {
        0.0
    }
}

/// The least GGX alpha of a specular lobe at a path's hit after diffuse
/// bounces whose least density was `diffuse_pdf` (infinite for none):
/// `sqrt(1 - pdf) / 2`, as Cycles' Filter Glossy at its default of 1
/// blurs, so at least 0.41 (a diffuse bounce's density is at most 1/π).
/// Light that reaches a diffuse surface by way of a smooth reflection (a
/// caustic) then arrives blurred, found by light sampling, instead of by
/// rare bounces that leave single bright pixels. Unlike Cycles, glossy
/// bounces do not count: a point light here is found by light sampling
/// alone, and a lobe made only a little rougher turns a mirror's one
/// image of it into many bright pixels.
pub(crate) fn regularizing_alpha(diffuse_pdf: f32) -> f32 {
    if diffuse_pdf < 1.0 {
        0.5 * (1.0 - diffuse_pdf.max(0.0)).sqrt()
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::sampling::Rng;

    /// Regularization blurs by the path's least density as Cycles' Filter
    /// Glossy does, never below a lobe's own roughness; a mirror becomes
    /// glossy, with a density light sampling can weigh against, and a
    /// Phong lobe takes the exponent of that alpha.
    #[test]
    fn regularization_roughens_smooth_lobes_only() {
        assert_eq!(regularizing_alpha(f32::INFINITY), 0.0);
        assert_eq!(regularizing_alpha(1.0), 0.0);
        assert!((regularizing_alpha(FRAC_1_PI) - 0.41284).abs() < 1e-4);
        assert_eq!(regularizing_alpha(0.0), 0.5);
        let (n, v) = (Vec3::Z, dir(0.3, 0.0));
        let l = 2.0 * v.dot(n) * n - v;
        let mirror = Bsdf::pbr(Brdf::new(Vec3::ONE, 1.0, 0.0), 1.0);
        assert_eq!(mirror.pdf(n, v, l), 0.0);
        let blurred = mirror.regularized(0.41);
        assert!(blurred.pdf(n, v, l) > 0.0 && blurred.eval(n, v, l).x > 0.0);
        assert_eq!(mirror.regularized(0.0), mirror);
        let rough = Bsdf::pbr(Brdf::new(Vec3::ONE, 1.0, 0.8), 1.0);
        assert_eq!(rough.regularized(0.41), rough);
        let phong = Bsdf::phong(Vec3::ZERO, Vec3::ONE, 1000.0, false, 1.0);
        let Model::Phong { spec: Some(s), .. } = phong.regularized(0.5).model else {
            panic!("a Phong lobe stays Phong");
        };
        assert!(!s.mirror && (s.ns - 6.0).abs() < 1e-4, "{s:?}");
        let dull = Bsdf::phong(Vec3::ZERO, Vec3::ONE, 2.0, true, 1.0);
        assert_eq!(dull.regularized(0.5), dull);
    }

    fn dir(theta: f32, phi: f32) -> Vec3 {
        Vec3::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        )
    }

    fn bsdfs() -> Vec<(&'static str, Bsdf)> {
        vec![
            (
                "rough dielectric",
                Bsdf::pbr(Brdf::new(Vec3::new(0.8, 0.5, 0.2), 0.0, 0.6), 1.0),
            ),
            (
                "glossy metal",
                Bsdf::pbr(Brdf::new(Vec3::new(0.9, 0.7, 0.5), 1.0, 0.3), 1.0),
            ),
            (
                "half metal, half through",
                Bsdf::pbr(Brdf::new(Vec3::splat(0.7), 0.5, 0.45), 0.5),
            ),
            (
                "phong",
                Bsdf::phong(Vec3::splat(0.5), Vec3::splat(0.3), 20.0, true, 1.0),
            ),
            (
                "lambert",
                Bsdf::phong(Vec3::splat(0.9), Vec3::ZERO, 0.0, true, 1.0),
            ),
        ]
    }

    /// A sample's weight is the BSDF over the density it reports, and the
    /// density is what `pdf` says: what multiple importance sampling needs.
    #[test]
    fn samples_report_their_own_density() {
        let n = Vec3::Z;
        for (name, b) in bsdfs() {
            let v = dir(0.7, 0.3);
            let mut rng = Rng::for_sample(1, 2, 3);
            for _ in 0..2000 {
                let Some(s) = b.sample(n, n, v, rng.next_f32(), rng.next_vec2()) else {
                    continue;
                };
                let Some(pdf) = s.pdf else {
                    assert_eq!(s.lobe, Lobe::Through, "{name}");
                    continue;
                };
                let want = b.pdf(n, v, s.dir);
                assert!((pdf - want).abs() <= 1e-4 * want, "{name}: {pdf} vs {want}");
                let w = b.eval(n, v, s.dir) / pdf;
                assert!((s.weight - w).abs().max_element() <= 1e-4 * w.max_element().max(1e-3));
            }
        }
    }

    /// The density integrates to the share of samples the rough lobes
    /// take (quadrature over the hemisphere), and the sampled estimate of
    /// the albedo agrees with quadrature of `eval`: the sampler draws
    /// where its density says.
    #[test]
    fn density_integrates_and_sampling_estimates_the_albedo() {
        let n = Vec3::Z;
        for (name, b) in bsdfs() {
            let v = dir(0.5, 1.0);
            let (nt, np) = (400, 400);
            let (mut pdf_sum, mut albedo) = (0.0f64, Vec3::ZERO.as_dvec3());
            for i in 0..nt {
                let theta = (i as f32 + 0.5) / nt as f32 * std::f32::consts::FRAC_PI_2;
                for j in 0..np {
                    let phi = (j as f32 + 0.5) / np as f32 * TAU;
                    let l = dir(theta, phi);
                    let dw = theta.sin() as f64
                        * (std::f64::consts::FRAC_PI_2 / nt as f64)
                        * (std::f64::consts::TAU / np as f64);
                    pdf_sum += b.pdf(n, v, l) as f64 * dw;
                    albedo += b.eval(n, v, l).as_dvec3() * dw;
                }
            }
            let keep = 1.0 - b.through as f64;
            assert!(pdf_sum <= keep * 1.01, "{name}: density sums to {pdf_sum}");
            assert!(pdf_sum >= keep * 0.9, "{name}: density sums to {pdf_sum}");
            let mut rng = Rng::for_sample(4, 5, 6);
            let m = 200_000;
            let mut est = Vec3::ZERO.as_dvec3();
            for _ in 0..m {
                if let Some(s) = b.sample(n, n, v, rng.next_f32(), rng.next_vec2()) {
                    if s.pdf.is_some() {
                        est += s.weight.as_dvec3();
                    }
                }
            }
            est /= m as f64;
            let err = (est - albedo).abs().max_element();
            assert!(err < 0.01, "{name}: sampled {est} vs quadrature {albedo}");
        }
    }

    #[test]
    fn mirrors_and_passing_through_have_no_density() {
        let n = Vec3::Z;
        let v = dir(0.4, 0.0);
        let mirror = Bsdf::pbr(Brdf::new(Vec3::ONE, 1.0, 0.0), 1.0);
        let s = mirror.sample(n, n, v, 0.5, Vec2::splat(0.3)).unwrap();
        assert_eq!((s.lobe, s.pdf), (Lobe::Mirror, None));
        assert!((s.dir - Vec3::new(-v.x, -v.y, v.z)).length() < 1e-5);
        assert_eq!(mirror.eval(n, v, s.dir), Vec3::ZERO);
        let glass = Bsdf::phong(Vec3::ZERO, Vec3::ZERO, 0.0, false, 0.25);
        let s = glass.sample(n, n, v, 0.5, Vec2::splat(0.3)).unwrap();
        assert_eq!((s.lobe, s.pdf, s.dir), (Lobe::Through, None, -v));
    }

    #[test]
    fn power_heuristic_weights_sum_to_one() {
        for (a, b) in [(1.0, 1.0), (0.3, 7.0), (1e-20, 3.0), (5.0, 0.0)] {
            let s = power_heuristic(a, b) + power_heuristic(b, a);
            assert!((s - 1.0).abs() < 1e-6, "{a} {b}: {s}");
        }
        assert_eq!(power_heuristic(0.0, 0.0), 0.0);
    }
}
