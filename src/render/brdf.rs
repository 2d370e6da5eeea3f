//! glTF 2.0's metallic-roughness BRDF, as its specification's Appendix B
//! defines it: a Lambertian diffuse lobe and a GGX (Trowbridge-Reitz)
//! specular lobe with the height-correlated Smith visibility term and
//! Schlick's Fresnel; F0 is 0.04 for dielectrics and the base colour for
//! metals, `metallic` mixing the two. The specular lobe is sampled from
//! its distribution of visible normals (Heitz 2018), whose weight is
//! Fresnel times the ratio of the two masking terms.

use std::f32::consts::{FRAC_1_PI, PI};

use glam::{Vec2, Vec3};

use crate::geometry::sampling::onb;

/// Below this GGX alpha (roughness 0.0316) the specular lobe is a mirror:
/// its highlight from a point light would be a spot smaller than a pixel
/// with values past f32's comfort, and its reflection rays all but
/// parallel.
pub(crate) const MIRROR_ALPHA: f32 = 1e-3;

/// F0 of a dielectric of index of refraction 1.5.
#[cfg(test)]
const DIELECTRIC_F0: f32 = 0.04;

/// The BRDF of one shading point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Brdf {
    /// Diffuse albedo: the base colour's dielectric share.
    pub(crate) c_diff: Vec3,
    /// Reflectance at normal incidence.
    pub(crate) f0: Vec3,
    /// Reflectance at grazing incidence: 1, less for a dielectric whose
    /// `KHR_materials_specular` weight is below 1.
    pub(crate) f90: Vec3,
    /// GGX alpha: roughness squared.
    pub(crate) alpha: f32,
}

/// A light direction's reflected share, split by lobe (each already times
/// the cosine at the surface).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Lobes {
    pub(crate) diffuse: Vec3,
    pub(crate) specular: Vec3,
}

/// A sampled specular direction and its weight: BRDF times cosine over
/// the direction's density.
#[derive(Clone, Copy, Debug)]
pub(crate) struct SpecularSample {
    pub(crate) dir: Vec3,
    pub(crate) weight: Vec3,
}

/// Schlick's Fresnel.
#[inline]
fn schlick(f0: Vec3, f90: Vec3, cos: f32) -> Vec3 {
    let m = (1.0 - cos.clamp(0.0, 1.0)).powi(5);
    f0 + (f90 - f0) * m
}

/// GGX's normal distribution at `cos_h`, the cosine between the normal
/// and the half vector.
#[inline]
pub(crate) fn ggx_d(alpha: f32, cos_h: f32) -> f32 {
    if cos_h <= 0.0 {
        return 0.0;
    }
    let a2 = alpha * alpha;
    let d = cos_h * cos_h * (a2 - 1.0) + 1.0;
    a2 / (PI * d * d)
}

/// Smith's Λ for GGX at a direction whose cosine with the normal is `cos`.
#[inline]
fn lambda(alpha: f32, cos: f32) -> f32 {
    let c2 = (cos * cos).max(1e-12);
    let tan2 = (1.0 - c2).max(0.0) / c2;
    0.5 * ((1.0 + alpha * alpha * tan2).sqrt() - 1.0)
}

/// The height-correlated visibility term `G2 / (4 cos_l cos_v)`, as the
/// specification writes it.
#[inline]
fn visibility(alpha: f32, cos_l: f32, cos_v: f32) -> f32 {
    let a2 = alpha * alpha;
    let gv = cos_l * (cos_v * cos_v * (1.0 - a2) + a2).sqrt();
    let gl = cos_v * (cos_l * cos_l * (1.0 - a2) + a2).sqrt();
    let s = gv + gl;
    if s > 0.0 {
        0.5 / s
    } else {
        0.0
    }
}

impl Brdf {
    /// [`Brdf::with_f0`] with glTF's default dielectric reflectance.
    #[cfg(test)]
    pub(crate) fn new(base: Vec3, metallic: f32, roughness: f32) -> Self {
        Self::with_f0(base, metallic, roughness, DIELECTRIC_F0)
    }

    /// The BRDF of a base colour (linear), metalness and perceptual
    /// roughness, each clamped to 0..1, for a dielectric that reflects
    /// `dielectric_f0` at normal incidence (0.04, or what
    /// `KHR_materials_ior` says).
    #[cfg(test)]
    pub(crate) fn with_f0(base: Vec3, metallic: f32, roughness: f32, dielectric_f0: f32) -> Self {
        Self::with_specular(base, metallic, roughness, Vec3::splat(dielectric_f0), 1.0)
    }

    /// [`Brdf::with_f0`] for a dielectric reflecting `dielectric_f0` (a
    /// colour) at normal incidence and `weight` at grazing incidence:
    /// `KHR_materials_specular`, whose weight scales the dielectric's
    /// whole Fresnel term (the diffuse share is what that leaves, per
    /// channel, where the extension takes the largest channel's).
    pub(crate) fn with_specular(
        base: Vec3,
        metallic: f32,
        roughness: f32,
        dielectric_f0: Vec3,
        weight: f32,
    ) -> Self {
        let m = if metallic.is_nan() {
            1.0
        } else {
            metallic.clamp(0.0, 1.0)
        };
        let r = if roughness.is_nan() {
            1.0
        } else {
            roughness.clamp(0.0, 1.0)
        };
        let base = base.max(Vec3::ZERO);
        Self {
            c_diff: base * (1.0 - m),
            f0: dielectric_f0.clamp(Vec3::ZERO, Vec3::ONE).lerp(base, m),
            f90: Vec3::splat(weight.clamp(0.0, 1.0)).lerp(Vec3::ONE, m),
            alpha: r * r,
        }
    }

    /// Whether the specular lobe is a mirror ([`MIRROR_ALPHA`]).
    #[inline]
    pub(crate) fn is_mirror(&self) -> bool {
        self.alpha < MIRROR_ALPHA
    }

    /// BRDF times `n·l` for light arriving from `l`, seen from `v` (both
    /// unit, pointing away from the surface). Zero below the surface. A
    /// mirror's specular lobe is zero here: only its reflection ray sees
    /// light.
    pub(crate) fn eval(&self, n: Vec3, v: Vec3, l: Vec3) -> Lobes {
        let (cos_l, cos_v) = (n.dot(l), n.dot(v));
        if cos_l <= 0.0 || cos_v <= 0.0 {
            return Lobes::default();
        }
        let h = (v + l).normalize_or_zero();
        let f = schlick(self.f0, self.f90, v.dot(h));
        let diffuse = (Vec3::ONE - f) * self.c_diff * (FRAC_1_PI * cos_l);
        if self.is_mirror() {
            return Lobes {
                diffuse,
                specular: Vec3::ZERO,
            };
        }
        let spec = ggx_d(self.alpha, n.dot(h)) * visibility(self.alpha, cos_l, cos_v) * cos_l;
        Lobes {
            diffuse,
            specular: f * spec,
        }
    }

    /// The specular lobe's reflection direction for `v` and its weight:
    /// the mirror direction with Fresnel for a mirror, else a direction
    /// drawn from the visible normals with `u`. `None` when the drawn
    /// direction falls below the surface (it carries no light).
    pub(crate) fn sample_specular(&self, n: Vec3, v: Vec3, u: Vec2) -> Option<SpecularSample> {
        let cos_v = n.dot(v);
        if cos_v <= 0.0 {
            return None;
        }
        if self.is_mirror() {
            let dir = 2.0 * cos_v * n - v;
            return Some(SpecularSample {
                dir,
                weight: schlick(self.f0, self.f90, cos_v),
            });
        }
        let (t, b) = onb(n);
        let local = Vec3::new(v.dot(t), v.dot(b), cos_v);
        let hl = sample_visible_normal(local, self.alpha, u);
        let h = t * hl.x + b * hl.y + n * hl.z;
        let dir = (2.0 * v.dot(h) * h - v).normalize_or_zero();
        let cos_l = n.dot(dir);
        if cos_l <= 0.0 || !dir.is_finite() {
            return None;
        }
        let (lv, ll) = (lambda(self.alpha, cos_v), lambda(self.alpha, cos_l));
        let g2_over_g1 = (1.0 + lv) / (1.0 + lv + ll);
        Some(SpecularSample {
            dir,
            weight: schlick(self.f0, self.f90, v.dot(h)) * g2_over_g1,
        })
    }

    /// Schlick's Fresnel seen from `cos_v`: what a mirror reflects.
    #[inline]
    pub(crate) fn fresnel(&self, cos_v: f32) -> Vec3 {
        schlick(self.f0, self.f90, cos_v)
    }

    /// The density (per solid angle) with which [`Brdf::sample_specular`]
    /// draws `l` for `v`, for a rough lobe.
    pub(crate) fn specular_pdf(&self, n: Vec3, v: Vec3, l: Vec3) -> f32 {
        let (cos_v, cos_l) = (n.dot(v), n.dot(l));
        if cos_v <= 0.0 || cos_l <= 0.0 {
            return 0.0;
        }
        let h = (v + l).normalize();
        let g1 = 1.0 / (1.0 + lambda(self.alpha, cos_v));
        g1 * ggx_d(self.alpha, n.dot(h)) / (4.0 * cos_v)
    }
}

/// A visible normal of GGX with `alpha`, seen from `v` (local frame, +Z
/// the normal), drawn with `u`: Heitz's stretch, sample the projected
/// hemisphere, unstretch.
fn sample_visible_normal(v: Vec3, alpha: f32, u: Vec2) -> Vec3 {
    let vh = Vec3::new(alpha * v.x, alpha * v.y, v.z).normalize();
    let len2 = vh.x * vh.x + vh.y * vh.y;
    let t1 = if len2 > 0.0 {
        Vec3::new(-vh.y, vh.x, 0.0) / len2.sqrt()
    } else {
        Vec3::X
    };
    let t2 = vh.cross(t1);
    let r = u.x.sqrt();
    let phi = 2.0 * PI * u.y;
    let p1 = r * phi.cos();
    let s = 0.5 * (1.0 + vh.z);
    let p2 = (1.0 - s) * (1.0 - p1 * p1).max(0.0).sqrt() + s * r * phi.sin();
    let p3 = (1.0 - p1 * p1 - p2 * p2).max(0.0).sqrt();
    let nh = t1 * p1 + t2 * p2 + vh * p3;
    Vec3::new(alpha * nh.x, alpha * nh.y, nh.z.max(1e-6)).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::sampling::Rng;

    fn dir(theta: f32, phi: f32) -> Vec3 {
        Vec3::new(
            theta.sin() * phi.cos(),
            theta.sin() * phi.sin(),
            theta.cos(),
        )
    }

    /// The integral over the hemisphere of `f`, midpoint rule in (θ, φ):
    /// fine near the normal, where narrow lobes peak.
    fn hemisphere(f: impl Fn(Vec3) -> f64) -> f64 {
        let (nt, np) = (2048, 256);
        let dt = std::f64::consts::FRAC_PI_2 / nt as f64;
        let dp = std::f64::consts::TAU / np as f64;
        let mut sum = 0.0;
        for i in 0..nt {
            let theta = (i as f64 + 0.5) * dt;
            let mut ring = 0.0;
            for j in 0..np {
                let phi = (j as f64 + 0.5) * dp;
                ring += f(dir(theta as f32, phi as f32));
            }
            sum += ring * theta.sin();
        }
        sum * dt * dp
    }

    /// The microfacet normals' projected area is the surface's: the
    /// integral of D(h) cos θ_h over the hemisphere is 1.
    #[test]
    fn ggx_normals_project_to_the_surface() {
        for alpha in [0.05f32, 0.2, 0.5, 1.0] {
            let i = hemisphere(|h| (ggx_d(alpha, h.z) * h.z) as f64);
            assert!((i - 1.0).abs() < 2e-3, "alpha {alpha}: {i}");
        }
    }

    /// The sampled specular directions' density integrates to the share
    /// that lands above the surface (1 less what falls below), and the
    /// mean weight of the samples is the lobe's albedo computed by
    /// integrating `eval` (so sample and eval describe one lobe).
    #[test]
    fn specular_sampling_matches_evaluation() {
        let n = Vec3::Z;
        for (alpha, theta_v) in [(0.1f32, 0.3f32), (0.4, 1.0), (0.8, 1.4), (1.0, 0.0)] {
            let b = Brdf {
                c_diff: Vec3::ZERO,
                f0: Vec3::ONE,
                f90: Vec3::ONE,
                alpha,
            };
            let v = dir(theta_v, 0.7);
            let pdf_total = hemisphere(|l| b.specular_pdf(n, v, l) as f64);
            assert!(pdf_total <= 1.0 + 3e-3 && pdf_total > 0.3, "{pdf_total}");
            let albedo = hemisphere(|l| b.eval(n, v, l).specular.x as f64);
            let mut rng = Rng::for_sample(1, 2, 3);
            let m = 200_000;
            let mean: f64 = (0..m)
                .filter_map(|_| b.sample_specular(n, v, rng.next_vec2()))
                .map(|s| s.weight.x as f64)
                .sum::<f64>()
                / m as f64;
            assert!(
                (mean - albedo).abs() < 0.01 * albedo.max(0.1),
                "alpha {alpha} θv {theta_v}: sampled {mean}, integrated {albedo}"
            );
        }
    }

    /// Pearson's chi-square of sampled directions against the density,
    /// binned in (cos θ, φ), as pbrt and Mitsuba test their samplers.
    #[test]
    fn specular_samples_follow_their_density() {
        let n = Vec3::Z;
        let (nt, np) = (16usize, 32usize);
        for (alpha, theta_v) in [(0.15f32, 0.5f32), (0.6, 1.2)] {
            let b = Brdf {
                c_diff: Vec3::ZERO,
                f0: Vec3::ONE,
                f90: Vec3::ONE,
                alpha,
            };
            let v = dir(theta_v, 0.0);
            let m = 400_000usize;
            let mut observed = vec![0f64; nt * np];
            let mut rng = Rng::for_sample(4, 5, 6);
            for _ in 0..m {
                if let Some(s) = b.sample_specular(n, v, rng.next_vec2()) {
                    let c = s.dir.z.clamp(0.0, 0.999_999);
                    let phi = s.dir.y.atan2(s.dir.x).rem_euclid(std::f32::consts::TAU);
                    let i = (c * nt as f32) as usize;
                    let j = ((phi / std::f32::consts::TAU * np as f32) as usize).min(np - 1);
                    observed[i * np + j] += 1.0;
                }
            }
            // Expected counts: the density integrated over each bin.
            let sub = 8;
            let mut chi2 = 0.0;
            let mut dof = 0;
            for i in 0..nt {
                for j in 0..np {
                    let mut e = 0.0;
                    for a in 0..sub {
                        for c in 0..sub {
                            let cz = (i as f64 + (a as f64 + 0.5) / sub as f64) / nt as f64;
                            let ph = (j as f64 + (c as f64 + 0.5) / sub as f64) / np as f64
                                * std::f64::consts::TAU;
                            let l = dir(cz.acos() as f32, ph as f32);
                            e += b.specular_pdf(n, v, l) as f64;
                        }
                    }
                    let area = std::f64::consts::TAU / (nt * np) as f64;
                    let e = e / (sub * sub) as f64 * area * m as f64;
                    if e > 5.0 {
                        let o = observed[i * np + j];
                        chi2 += (o - e) * (o - e) / e;
                        dof += 1;
                    }
                }
            }
            // Past mean + 5 standard deviations of chi-square(dof): a
            // sampler that does not follow its density lands far beyond.
            let limit = dof as f64 + 5.0 * (2.0 * dof as f64).sqrt();
            assert!(dof > 50, "too few bins with counts: {dof}");
            assert!(chi2 < limit, "alpha {alpha}: chi2 {chi2} over {dof} bins");
        }
    }

    /// `KHR_materials_ior`'s reflectance takes the dielectric's 0.04 place:
    /// at 0.25 a white dielectric keeps 75 % as diffuse; a metal's F0 is
    /// its base colour whatever the index.
    #[test]
    fn the_dielectric_reflectance_is_the_index_of_refractions() {
        let n = Vec3::Z;
        let d = Brdf::with_f0(Vec3::ONE, 0.0, 0.5, 0.25);
        assert_eq!(d.f0, Vec3::splat(0.25));
        let e = d.eval(n, n, n);
        assert!((e.diffuse.x - 0.75 * FRAC_1_PI).abs() < 1e-6, "{e:?}");
        let gold = Vec3::new(1.0, 0.8, 0.3);
        assert_eq!(Brdf::with_f0(gold, 1.0, 0.5, 0.25).f0, gold);
    }

    /// `KHR_materials_specular`: a weight of 0 leaves a dielectric pure
    /// Lambert (no Fresnel at any angle, nothing taken from the diffuse);
    /// a coloured F0 reflects that colour head-on and the weight at
    /// grazing; a metal ignores both.
    #[test]
    fn the_specular_weight_and_colour_scale_the_dielectric_fresnel() {
        let n = Vec3::Z;
        let plain = Brdf::with_specular(Vec3::ONE, 0.0, 0.5, Vec3::ZERO, 0.0);
        for v in [n, dir(1.4, 0.0)] {
            let e = plain.eval(n, v, n);
            assert_eq!(e.specular, Vec3::ZERO);
            assert!((e.diffuse.x - FRAC_1_PI).abs() < 1e-6, "{e:?}");
        }
        let red = Brdf::with_specular(Vec3::ONE, 0.0, 0.5, Vec3::new(0.08, 0.0, 0.0), 0.5);
        assert_eq!(red.fresnel(1.0), Vec3::new(0.08, 0.0, 0.0));
        assert!((red.fresnel(0.0) - Vec3::splat(0.5)).abs().max_element() < 1e-6);
        let metal = Brdf::with_specular(Vec3::new(1.0, 0.8, 0.3), 1.0, 0.5, Vec3::ZERO, 0.0);
        assert_eq!((metal.f0, metal.f90), (Vec3::new(1.0, 0.8, 0.3), Vec3::ONE));
    }

    /// The spec's split: a dielectric keeps 96 % of a white base as
    /// diffuse at normal incidence, a metal none; a mirror's specular lobe
    /// only reflects, weighted by Fresnel.
    #[test]
    fn metallic_mixes_dielectric_and_metal() {
        let n = Vec3::Z;
        let white = Vec3::ONE;
        let d = Brdf::new(white, 0.0, 0.5).eval(n, n, n);
        assert!((d.diffuse.x - 0.96 * FRAC_1_PI).abs() < 1e-6, "{d:?}");
        let m = Brdf::new(white, 1.0, 0.5).eval(n, n, n);
        assert_eq!(m.diffuse, Vec3::ZERO);
        let mirror = Brdf::new(Vec3::new(1.0, 0.5, 0.25), 1.0, 0.0);
        assert!(mirror.is_mirror());
        assert_eq!(mirror.eval(n, n, n).specular, Vec3::ZERO);
        let s = mirror
            .sample_specular(n, dir(0.5, 0.0), Vec2::ZERO)
            .unwrap();
        assert!((s.dir - dir(0.5, std::f32::consts::PI)).length() < 1e-5);
        assert!(s.weight.y > 0.5 && s.weight.z > 0.25 && s.weight.x <= 1.0);
    }

    /// White furnace: a white metal never reflects more than arrives (a
    /// white dielectric may: the specification's diffuse weight
    /// `1 - F(v·h)` is not the specular lobe's complement, by 3 % seen
    /// from above and up to 30 % at grazing angles, as in every renderer
    /// that follows it),
    /// and nothing goes negative or NaN at grazing or back-facing
    /// directions.
    #[test]
    fn lobes_conserve_energy_and_stay_finite() {
        let n = Vec3::Z;
        for r in [0.0f32, 0.03, 0.3, 1.0] {
            for m in [0.0f32, 1.0] {
                let b = Brdf::new(Vec3::ONE, m, r);
                // Both sides of grazing, and from below.
                let grazing = std::f32::consts::FRAC_PI_2;
                for tv in [0.0f32, 1.0, 1.5, grazing - 1e-4, grazing + 1e-4, 2.0] {
                    let v = dir(tv, 0.3);
                    let total = hemisphere(|l| {
                        let e = b.eval(n, v, l);
                        assert!(e.diffuse.is_finite() && e.specular.is_finite());
                        assert!(e.diffuse.min_element() >= 0.0);
                        (e.diffuse + e.specular).x as f64
                    });
                    let limit = match (m, tv) {
                        (1.0, _) => 1.002,
                        (_, tv) if tv <= 1.0 => 1.03,
                        _ => 1.32,
                    };
                    assert!(total <= limit, "r {r} m {m} θv {tv}: {total}");
                    let mut rng = Rng::for_sample(0, 0, 1);
                    for _ in 0..100 {
                        if let Some(s) = b.sample_specular(n, v, rng.next_vec2()) {
                            assert!(s.dir.is_finite() && s.weight.is_finite());
                            assert!(s.weight.max_element() <= 1.0 + 1e-5);
                        }
                    }
                }
            }
        }
    }
}
