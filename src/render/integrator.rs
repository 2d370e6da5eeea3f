//! The one shading code path: Whitted ray tracing with Phong lights, hard or
//! sampled shadows, mirror and glossy reflection, textures and environment;
//! metallic-roughness materials ([`super::brdf`]) under the same lights and
//! glTF's lights in their units.
//!
//! Generic over a [`Recorder`]: the renderer passes a ray counter, the
//! inspector a tree builder. Both run exactly this code.

use std::f32::consts::{FRAC_1_PI, PI};

use glam::{Vec2, Vec3, Vec4};

use super::brdf::Brdf;
use super::plan::Plan;
use super::recorder::{HitInfo, LightSample, MissInfo, PbrInfo, RayKind, Recorder};
use crate::bvh::{Bvh, Hit};
use crate::geometry::offset::{geometric_normal, hit_point, offset_origin, SHADOW_EPSILON};
use crate::geometry::sampling::{jittered, phong_lobe, Rng, Run, PIXEL_GRID};
use crate::geometry::Ray;
use crate::interrupt::Cancel;
use crate::scene::camera::CameraFrame;
use crate::scene::envlight::LATLONG;
use crate::scene::light::{Arriving, From};
use crate::scene::texture::{cube_face_uv, FACE_NAMES};
use crate::scene::{EnvLight, Environment, Light, Material, Scene, Texture};

/// Tries to draw a glossy direction above the surface before using the mirror direction.
const GLOSSY_TRIES: u32 = 8;

/// The most paths a sample's ray tree splits into. Glossy lobes sampled
/// `glossy_samples` times at every bounce, or surfaces that both reflect
/// and let light through, split a tree exponentially with the depth
/// (`glossy_samples` 256 at `max_depth` 64 asked for 256^64 rays). A split
/// that would take the tree past this follows one branch: a glossy lobe
/// sampled once, or reflection or transmission chosen at random in
/// proportion to their weights and divided by the chance of choosing it.
/// Either estimate has the same mean, so the picture is the same on
/// average, and a sample's work grows with the depth, not exponentially.
pub const MAX_PATHS: u32 = 256;

/// A ray's place in its sample's tree: the bounces above it, and the paths
/// the tree had split into on the way.
#[derive(Clone, Copy, Debug)]
pub(super) struct Depth {
    pub(super) bounces: u32,
    paths: u32,
    /// On a path, the density (per solid angle) of the bounce that drew
    /// this ray, for weighing the light it finds against light sampling;
    /// `None` for the camera's rays, mirrors, passes through and Whitted's
    /// rays, which light sampling cannot stand in for.
    pub(super) pdf: Option<f32>,
    /// On a path, the least density of its diffuse bounces so far
    /// (infinite before any): how far a smooth lobe at the next hit is made
    /// rougher ([`Plan::regularize`]).
    pub(super) diffuse_pdf: f32,
}

impl Depth {
    const CAMERA: Depth = Depth {
        bounces: 0,
        paths: 1,
        pdf: None,
        diffuse_pdf: f32::INFINITY,
    };

    /// The next bounce, on one of `split` branches.
    fn next(self, split: u32) -> Depth {
        Depth {
            bounces: self.bounces + 1,
            paths: self.paths.saturating_mul(split),
            pdf: None,
            diffuse_pdf: self.diffuse_pdf,
        }
    }

    /// A path's next bounce, drawn with density `pdf`, from the diffuse
    /// lobe or not.
    pub(super) fn bounce(self, pdf: Option<f32>, diffuse: bool) -> Depth {
        Depth {
            bounces: self.bounces + 1,
            paths: self.paths,
            pdf,
            diffuse_pdf: match (diffuse, pdf) {
                (true, Some(p)) => self.diffuse_pdf.min(p),
                _ => self.diffuse_pdf,
            },
        }
    }

    /// Whether a tree of at most `max` paths may split `n` ways here.
    fn may_split(self, n: u32, max: u32) -> bool {
        self.paths.saturating_mul(n) <= max
    }

    /// How many directions a glossy lobe asked for `samples` draws here
    /// (one where that would take the tree past `max` paths), and the
    /// place of the rays drawn.
    fn glossy(self, samples: u32, max: u32) -> (u32, Depth) {
        let n = samples.max(1);
        let n = if self.may_split(n, max) { n } else { 1 };
        let next = Depth {
            paths: self.paths.saturating_mul(n),
            ..self
        };
        (n, next)
    }
}

/// Everything needed to shade samples of one image.
#[derive(Clone)]
pub struct Tracer<'a> {
    pub scene: &'a Scene,
    pub(crate) bvh: &'a Bvh,
    pub(crate) plan: &'a Plan,
    pub frame: CameraFrame,
    pub width: u32,
    pub height: u32,
    pub(crate) seed: u64,
    pub(crate) max_depth: u32,
    /// The most paths a sample's tree splits into: [`MAX_PATHS`].
    pub max_paths: u32,
    /// Polled before a hit's reflected and transmitted rays: once it says
    /// stop, a sample traces no more bounces. A sample's tree can hold
    /// thousands of hits, each with thousands of light samples, so the
    /// rows between which a pass polls could be minutes apart; a sample cut
    /// short is never kept (see `progressive::sample_rows`).
    pub(crate) cancel: Cancel<'a>,
}

/// The mirror direction of `dir` about the shading normal `n`, or about the
/// geometric normal `ng` where `n` would send it into the surface: the
/// reflection ray, and the axis of the glossy lobe.
pub(crate) fn mirror(dir: Vec3, n: Vec3, ng: Vec3) -> Vec3 {
    let d = dir.normalize();
    let r = d - 2.0 * d.dot(n) * n;
    if r.dot(ng) <= 0.0 {
        d - 2.0 * d.dot(ng) * ng
    } else {
        r
    }
}

/// Where one sample falls in its pixel `(x, y)`: its offset (0..1 on each
/// axis) and sub-pixel stratum when jittered, and the random numbers the
/// rest of the sample draws.
#[derive(Clone, Debug)]
pub(crate) struct SamplePoint {
    pub(crate) x: u32,
    pub(crate) y: u32,
    pub(crate) off: Vec2,
    pub(crate) stratum: Option<u32>,
    rng: Rng,
}

impl SamplePoint {
    /// The image position of the sample, in pixels.
    #[inline]
    fn position(&self) -> (f64, f64) {
        (
            self.x as f64 + self.off.x as f64,
            self.y as f64 + self.off.y as f64,
        )
    }
}

/// Shading point, as the lights and reflections need it.
pub(super) struct Surface<'m> {
    pub(super) p: Vec3,
    pub(super) err: Vec3,
    pub(super) ng: Vec3,
    pub(super) n: Vec3,
    pub(super) v: Vec3,
    pub(super) kd: Vec3,
    pub(super) mat: &'m Material,
    /// A metallic-roughness material's BRDF here, its textures read.
    pub(super) brdf: Option<Brdf>,
}

/// A hit's texture coordinates: each UV set its mesh has, interpolated
/// (none where the plan reads no textures).
#[derive(Clone, Copy, Debug, Default)]
pub(crate) struct Uvs(pub(crate) [Option<Vec2>; 2]);

impl Uvs {
    /// At barycentric coordinates `b` of triangle `prim`.
    #[inline]
    pub(crate) fn at(scene: &Scene, prim: usize, b: Vec3) -> Uvs {
        let geo = &scene.geometry;
        let mesh = &scene.meshes[geo.tri_mesh[prim] as usize];
        let at = |set| {
            geo.corner_uvs(mesh, prim, set)
                .map(|t| t[0] * b.x + t[1] * b.y + t[2] * b.z)
        };
        Uvs([at(0), at(1)])
    }
}

/// A texture's value at the coordinates it reads of `uvs`, filtered as
/// the plan says; `None` where the hit has not that UV set.
#[inline]
pub(crate) fn lookup(tex: &Texture, uvs: &Uvs, bilinear: bool) -> Option<Vec3> {
    let st = tex.uv.apply(uvs.0[tex.uv.set as usize]?);
    Some(if bilinear {
        tex.bilinear(st)
    } else {
        tex.nearest(st)
    })
}

/// The shading normal `n` tilted by a normal map's texel `t` (tangent
/// space, 0..1 a channel) scaled by `scale`: the tangent frame from the
/// triangle's positions and texture coordinates, made orthonormal about
/// `n`. `n` itself where the triangle spans no texture area, or where
/// the tilted normal would face away from the viewer `v` (a map that
/// tilts past the silhouette would shade the surface's back).
fn normal_mapped(verts: [Vec3; 3], uvs: [Vec2; 3], n: Vec3, v: Vec3, t: Vec3, scale: f32) -> Vec3 {
    let (e1, e2) = (verts[1] - verts[0], verts[2] - verts[0]);
    let (d1, d2) = (uvs[1] - uvs[0], uvs[2] - uvs[0]);
    let det = d1.x * d2.y - d2.x * d1.y;
    if det == 0.0 || !det.is_finite() {
        return n;
    }
    let tangent = (e1 * d2.y - e2 * d1.y) / det;
    let bitangent = (e2 * d1.x - e1 * d2.x) / det;
    let tt = (tangent - n * n.dot(tangent)).normalize_or_zero();
    if tt == Vec3::ZERO || !tt.is_finite() {
        return n;
    }
    // Mirrored texture coordinates flip the bitangent.
    let bt = n.cross(tt) * n.cross(tt).dot(bitangent).signum();
    let m = t * 2.0 - Vec3::ONE;
    let out = (tt * (m.x * scale) + bt * (m.y * scale) + n * m.z).normalize_or_zero();
    if out.dot(v) > 0.0 && out.is_finite() {
        out
    } else {
        n
    }
}

/// The normal `vn` tilted by a normal map's texel `t` scaled by `scale`,
/// in the vertex tangent frame of `tangents` at barycentric `b`: as
/// MikkTSpace's pixel shader does it, the interpolated normal and tangent
/// and the bitangent `w · vn × tangent` made from them, none normalised
/// first (the frame the map was baked in). `None` where the corners have
/// no tangent.
fn tangent_mapped(vn: Vec3, tangents: [Vec4; 3], b: Vec3, t: Vec3, scale: f32) -> Option<Vec3> {
    let [t0, t1, t2] = tangents;
    let vt = t0.truncate() * b.x + t1.truncate() * b.y + t2.truncate() * b.z;
    if !vt.is_finite() || vt.length_squared() <= 1e-12 {
        return None;
    }
    let w = if t0.w * b.x + t1.w * b.y + t2.w * b.z < 0.0 {
        -1.0
    } else {
        1.0
    };
    let vb = vn.cross(vt) * w;
    let m = t * 2.0 - Vec3::ONE;
    Some((vt * (m.x * scale) + vb * (m.y * scale) + vn * m.z).normalize_or_zero())
}

impl<'a> Tracer<'a> {
    /// Samples of the image `frame` was made for (its camera and size).
    pub fn new(
        scene: &'a Scene,
        bvh: &'a Bvh,
        plan: &'a Plan,
        frame: CameraFrame,
        seed: u64,
    ) -> Self {
        let (width, height) = frame.size();
        Self {
            scene,
            bvh,
            plan,
            frame: frame.lanes(bvh.simd() >= crate::bvh::Simd::Avx),
            width,
            height,
            seed,
            max_depth: plan.max_depth,
            max_paths: MAX_PATHS,
            cancel: Cancel::Never,
        }
    }

    /// Whether [`Tracer::cancel`] says stop.
    #[inline]
    pub(super) fn cancelled(&self) -> bool {
        self.cancel.is_set()
    }

    /// The sub-pixel stratum of sample `k` of pixel `(x, y)` when pixel
    /// samples are jittered ([`Run`](crate::geometry::sampling::Run)),
    /// else `None`.
    pub fn stratum(&self, x: u32, y: u32, k: u32) -> Option<u32> {
        self.stratum_in(x, y, k, &mut Run::default())
    }

    /// [`Tracer::stratum`], with what a run of samples shares kept in
    /// `run`.
    #[inline]
    fn stratum_in(&self, x: u32, y: u32, k: u32, run: &mut Run) -> Option<u32> {
        let pixel = y as u64 * self.width as u64 + x as u64;
        (self.plan.supersampling && self.scene.settings.stratify)
            .then(|| run.stratum(pixel, k, self.seed))
    }

    /// Sample `k` of pixel `(x, y)`: the same value whoever asks, in any order.
    pub fn sample<R: Recorder>(&self, x: u32, y: u32, k: u32, rec: &mut R) -> Vec3 {
        let placed = self.place(x, y, k, &mut Run::default());
        let ray = self.camera_ray(&placed);
        self.sample_from(placed, &ray, rec)
    }

    /// Where sample `k` of pixel `(x, y)` falls, with `run` keeping what a
    /// run of samples shares. A pass places a run of samples, makes their camera
    /// rays in one tight loop, then traces them: the f64 divisions and
    /// square roots of one ray overlap the next's, where behind each
    /// sample's chain of random numbers they would wait in front of every
    /// ray.
    #[inline(always)]
    pub(crate) fn place(&self, x: u32, y: u32, k: u32, run: &mut Run) -> SamplePoint {
        let pixel = y as u64 * self.width as u64 + x as u64;
        // Nothing an exact render does draws a random number (see
        // `Plan::deterministic`), so its samples need no seeded stream.
        let mut rng = if self.plan.deterministic {
            Rng::unseeded()
        } else {
            run.rng(pixel, k, self.seed)
        };
        let stratum = self.stratum_in(x, y, k, run);
        let off = if let Some(stratum) = stratum {
            jittered(stratum, PIXEL_GRID, rng.next_vec2())
        } else if self.plan.supersampling {
            rng.next_vec2()
        } else {
            Vec2::splat(0.5)
        };
        SamplePoint {
            x,
            y,
            off,
            stratum,
            rng,
        }
    }

    /// The camera ray of a placed sample.
    #[inline]
    pub(crate) fn camera_ray(&self, s: &SamplePoint) -> Ray {
        let (x, y) = s.position();
        self.frame.ray(x, y)
    }

    /// The camera rays of placed samples appended to `out`: those of
    /// [`Tracer::camera_ray`], made several at a time
    /// ([`CameraFrame::rays`](crate::scene::camera::CameraFrame::rays)).
    pub(crate) fn camera_rays<'p>(
        &self,
        placed: impl Iterator<Item = &'p SamplePoint>,
        out: &mut Vec<Ray>,
    ) {
        const BATCH: usize = 64;
        let (mut x, mut y) = ([0.0; BATCH], [0.0; BATCH]);
        let mut n = 0;
        for s in placed {
            (x[n], y[n]) = s.position();
            n += 1;
            if n == BATCH {
                self.frame.rays(&x, &y, out);
                n = 0;
            }
        }
        self.frame.rays(&x[..n], &y[..n], out);
    }

    /// The colour of the placed sample `s`, whose camera ray is `ray`.
    pub(crate) fn sample_from<R: Recorder>(&self, s: SamplePoint, ray: &Ray, rec: &mut R) -> Vec3 {
        self.camera_sample(s, ray, None, rec)
    }

    /// [`Tracer::sample_from`] with the camera ray's closest hit found
    /// ahead (in a packet, [`Bvh::intersect_packet`]): the same shading.
    /// Always inlined, so that a miss costs its caller no call.
    #[inline(always)]
    pub(crate) fn sample_from_hit<R: Recorder>(
        &self,
        s: SamplePoint,
        ray: &Ray,
        hit: Option<Hit>,
        rec: &mut R,
    ) -> Vec3 {
        debug_assert!(self.plan.bvh, "a hit found ahead needs the BVH");
        self.camera_sample(s, ray, Some(hit), rec)
    }

    /// A camera sample, its ray's closest hit `found` ahead or not.
    #[inline(always)]
    fn camera_sample<R: Recorder>(
        &self,
        s: SamplePoint,
        ray: &Ray,
        found: Option<Option<Hit>>,
        rec: &mut R,
    ) -> Vec3 {
        let mut rng = s.rng;
        rec.pixel_sample(s.off, s.stratum);
        let (kind, w) = (RayKind::Camera, Vec3::ONE);
        self.trace(ray, found, Depth::CAMERA, kind, w, &mut rng, rec)
    }

    /// The closest hit, with the BVH or without as the plan says.
    #[inline]
    pub(super) fn nearest<R: Recorder>(&self, ray: &Ray, rec: &mut R) -> Option<Hit> {
        if self.plan.bvh {
            rec.intersect(self.bvh, ray)
        } else {
            self.bvh.intersect_brute(ray)
        }
    }

    pub(super) fn blocked<R: Recorder>(&self, ray: &Ray, rec: &mut R) -> Option<u32> {
        rec.shadow_ray();
        if self.plan.alpha {
            return self.blocked_past_cutouts(ray, rec);
        }
        if self.plan.bvh {
            rec.occluded(self.bvh, ray)
        } else {
            self.bvh.occluded_brute(ray)
        }
    }

    /// Radiance along `ray`, whose closest hit is `found` when it was
    /// found ahead. `weight` is the ray's factor in the pixel colour.
    /// Always inlined: a camera ray whose hit was found ahead and missed
    /// then costs its caller no call, and the traversal is left out.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn trace<R: Recorder>(
        &self,
        ray: &Ray,
        found: Option<Option<Hit>>,
        depth: Depth,
        kind: RayKind,
        weight: Vec3,
        rng: &mut Rng,
        rec: &mut R,
    ) -> Vec3 {
        rec.begin_ray(kind, ray, weight);
        let hit = match found {
            Some(hit) => hit,
            None => self.nearest(ray, rec),
        };
        // Past what alpha leaves out, the ray goes on from there.
        let passed;
        let (ray, hit) = match self.plan.alpha {
            true => {
                passed = self.past_cutouts(ray, hit, rec);
                (&passed.0, passed.1)
            }
            false => (ray, hit),
        };
        let color = match hit {
            None => self.miss(ray, depth, rec),
            Some(hit) => self.shade(ray, &hit, depth, weight, rng, rec),
        };
        rec.end_ray(color);
        color
    }

    /// What a ray leaving the scene sees: the background colour, or the
    /// cube map or environment light where the plan looks them up (black
    /// where it does not). On a path, a background colour is a backdrop
    /// that lights nothing (seen by the camera and in mirrors only), and
    /// an environment light found by a bounce is weighed against sampling
    /// it.
    fn miss<R: Recorder>(&self, ray: &Ray, depth: Depth, rec: &mut R) -> Vec3 {
        let env = &self.scene.environment;
        let on = self.plan.environment;
        let mut mis = None;
        let color = match env {
            Environment::CubeMap(cube) if on => cube.lookup(ray.dir),
            Environment::Light(light) if on => {
                let radiance = light.eval(ray.dir);
                match depth.pdf {
                    Some(bsdf_pdf) => {
                        let m = super::recorder::Mis::new(light.pdf(ray.dir), bsdf_pdf);
                        mis = Some(m);
                        radiance * m.bsdf_weight
                    }
                    None => radiance,
                }
            }
            Environment::Color(_) if depth.pdf.is_some() => Vec3::ZERO,
            Environment::Color(c) => *c,
            Environment::CubeMap(_) | Environment::Light(_) => Vec3::ZERO,
        };
        if R::ACTIVE {
            let (face, uv) = match env {
                Environment::CubeMap(_) if on => {
                    let (f, uv) = cube_face_uv(ray.dir);
                    (Some(FACE_NAMES[f].to_string()), Some(uv))
                }
                Environment::Light(light) if on => match light.map_uv(ray.dir) {
                    Some(uv) => (Some(LATLONG.to_string()), Some(uv)),
                    None => (None, None),
                },
                _ => (None, None),
            };
            rec.miss(MissInfo {
                face,
                uv,
                color,
                mis,
            });
        }
        color
    }

    /// The colour of a hit. The stages the plan may leave out are
    /// compile-time parameters, so a scene without textures or vertex
    /// normals runs code without them.
    #[inline(always)]
    fn shade<R: Recorder>(
        &self,
        ray: &Ray,
        hit: &Hit,
        depth: Depth,
        weight: Vec3,
        rng: &mut Rng,
        rec: &mut R,
    ) -> Vec3 {
        let (h, d, w) = (hit, depth, weight);
        match (self.plan.textures, self.plan.smooth_normals) {
            (false, false) => self.shade_with::<R, false, false>(ray, h, d, w, rng, rec),
            (false, true) => self.shade_with::<R, false, true>(ray, h, d, w, rng, rec),
            (true, false) => self.shade_with::<R, true, false>(ray, h, d, w, rng, rec),
            (true, true) => self.shade_with::<R, true, true>(ray, h, d, w, rng, rec),
        }
    }

    /// [`Tracer::shade`] with the plan's stages. Kept out of line: a ray
    /// that misses (most camera rays of a mesh) then pays for none of its
    /// set-up.
    #[inline(never)]
    fn shade_with<R: Recorder, const TEX: bool, const SMOOTH: bool>(
        &self,
        ray: &Ray,
        hit: &Hit,
        depth: Depth,
        weight: Vec3,
        rng: &mut Rng,
        rec: &mut R,
    ) -> Vec3 {
        let scene = self.scene;
        let geo = &scene.geometry;
        let prim = hit.prim as usize;
        let idx = geo.indices[prim];
        let [i, j, k] = idx.map(|i| i as usize);
        let verts = [geo.positions[i], geo.positions[j], geo.positions[k]];
        let (p, err) = hit_point(verts, hit.u, hit.v);
        let b = Vec3::new(1.0 - hit.u - hit.v, hit.u, hit.v);
        let mut ng = geometric_normal(verts);
        if ng.dot(ray.dir) > 0.0 {
            ng = -ng;
        }
        let mesh = &scene.meshes[geo.tri_mesh[prim] as usize];
        let mat = &scene.materials[geo.tri_material[prim] as usize];
        let mut n = ng;
        if SMOOTH && mesh.smooth {
            let vn = idx.map(|i| geo.normals[i as usize]);
            let s = (vn[0] * b.x + vn[1] * b.y + vn[2] * b.z).normalize_or_zero();
            if s != Vec3::ZERO && s.is_finite() {
                // Keep the interpolated normal on the viewer's side of the surface.
                n = if s.dot(ng) < 0.0 { -s } else { s };
            }
        }
        let mut kd = mat.kd;
        let mut texel = None;
        let uvs = match TEX {
            true => Uvs::at(scene, prim, b),
            false => Uvs::default(),
        };
        let textures = &scene.textures;
        let tex = |id: u32| lookup(&textures[id as usize], &uvs, self.plan.bilinear);
        if let Some(c) = mat.texture.and_then(tex) {
            texel = Some(c);
            kd = c;
        }
        if mesh.colored {
            let c = idx.map(|i| geo.colors[i as usize]);
            kd *= c[0] * b.x + c[1] * b.y + c[2] * b.z;
        }
        let v = -ray.dir.normalize();
        let (mut brdf, mut emitted, mut occlusion) = (None, Vec3::ZERO, 1.0);
        let (mut pbr_info, mut pbr_mapped) = (None, None);
        if let Some(pbr) = &mat.pbr {
            let (mut metallic, mut roughness) = (pbr.metallic, pbr.roughness);
            emitted = self.emitted(pbr, &uvs);
            let mut mapped = None;
            if let Some(t) = pbr.metallic_roughness.and_then(tex) {
                (metallic, roughness) = (metallic * t.z, roughness * t.y);
            }
            if let Some(t) = pbr.roughness_texture.and_then(tex) {
                roughness *= t.x;
            }
            if let Some(t) = pbr.metallic_texture.and_then(tex) {
                metallic *= t.x;
            }
            if let Some((t, strength)) = pbr.occlusion.and_then(|(id, s)| Some((tex(id)?, s))) {
                occlusion = 1.0 + strength * (t.x - 1.0);
            }
            if let Some((id, scale)) = pbr.normal.filter(|_| self.plan.normal_maps) {
                let map = &textures[id as usize];
                // The vertex tangent frame where the mesh has one (and its
                // normals are on), else the triangle's own.
                let vertex = match SMOOTH && mesh.smooth {
                    true => geo.corner_tangents(mesh, prim),
                    false => None,
                };
                let t = tex(id);
                let by_vertex = vertex.zip(t).and_then(|(tangents, t)| {
                    let vn = idx.map(|i| geo.normals[i as usize]);
                    let vn = vn[0] * b.x + vn[1] * b.y + vn[2] * b.z;
                    let m = tangent_mapped(vn, tangents, b, t, scale)?;
                    // Seen from the back, the whole frame turns with the
                    // normal (glTF's double-sided rule).
                    let m = if n.dot(vn) < 0.0 { -m } else { m };
                    Some(if m.dot(v) > 0.0 && m.is_finite() {
                        m
                    } else {
                        n
                    })
                });
                mapped = by_vertex.or_else(|| {
                    let corners = geo.corner_uvs(mesh, prim, map.uv.set)?;
                    let corners = corners.map(|c| map.uv.apply(c));
                    Some(normal_mapped(verts, corners, n, v, t?, scale))
                });
            }
            let (mut weight, mut tint) = (pbr.specular, pbr.specular_color);
            if let Some(t) = pbr.specular_texture.and_then(tex) {
                weight *= t.x;
            }
            if let Some(t) = pbr.specular_color_texture.and_then(tex) {
                tint *= t;
            }
            let f0 = (Vec3::splat(pbr.dielectric_f0) * tint).min(Vec3::ONE) * weight;
            brdf = Some(Brdf::with_specular(kd, metallic, roughness, f0, weight));
            pbr_mapped = mapped;
            if R::ACTIVE {
                pbr_info = Some(PbrInfo {
                    metallic,
                    roughness,
                    emitted,
                    occlusion,
                    normal_mapped: mapped,
                });
            }
        }
        if R::ACTIVE {
            rec.hit(HitInfo {
                t: hit.t,
                point: p,
                triangle: hit.prim,
                mesh: mesh.name.clone(),
                material: mat.name.clone(),
                barycentric: b,
                geometric_normal: ng,
                shading_normal: n,
                vertex_normals: mesh.smooth.then(|| idx.map(|i| geo.normals[i as usize])),
                uv: uvs.0[0],
                texel,
                kd,
                ks: mat.ks,
                ns: mat.ns,
                pbr: pbr_info,
            });
        }
        // Unlit: its colour as it is, whatever the light (on a path too,
        // where it lights what it is seen from, as an emitter would).
        if mat.unlit {
            return kd;
        }
        if let Some(m) = pbr_mapped {
            n = m;
        }
        let s = Surface {
            p,
            err,
            ng,
            n,
            v,
            kd,
            mat,
            brdf,
        };
        if self.plan.path {
            let t = hit.t * ray.dir.length();
            return self.path_vertex(&s, (hit.prim, t, emitted), depth, weight, rng, rec);
        }
        // Ambient light reaches a metallic-roughness surface's diffuse
        // share, less its occlusion; what it emits adds as it is.
        let mut color = match &brdf {
            None => kd * scene.settings.ambient,
            Some(b) => b.c_diff * scene.settings.ambient * occlusion + emitted,
        };
        for (i, light) in scene.lights.iter().enumerate() {
            color += self.light(&s, i, light, rng, rec);
        }
        if let Environment::Light(env) = &scene.environment {
            if self.plan.environment {
                color += self.environment_light(&s, env, occlusion, rng, rec);
            }
        }
        let reflect = self.plan.reflections && mat.reflective();
        let through = mat.dissolve < 1.0;
        if !(reflect || through) || depth.bounces >= self.max_depth || self.cancelled() {
            return color;
        }
        // Past `MAX_PATHS`, a surface that does both takes one, at random.
        let (reflect, through, split, scale) =
            if reflect && through && !depth.may_split(2, self.max_paths) {
                let ks = s.brdf.map_or(mat.ks, |b| b.f0);
                let r = ks.max_element() * mat.dissolve;
                let chance = r / (r + 1.0 - mat.dissolve);
                match rng.next_f32() < chance {
                    true => (true, false, 1, Vec3::splat(1.0 / chance)),
                    false => (false, true, 1, Vec3::splat(1.0 / (1.0 - chance))),
                }
            } else {
                (reflect, through, 1 + (reflect && through) as u32, Vec3::ONE)
            };
        let next = depth.next(split);
        if reflect {
            let w = weight * scale;
            color += scale
                * match &s.brdf {
                    None => self.reflect(ray, &s, next, w, rng, rec),
                    Some(b) => self.reflect_lobe(ray, &s, b, next, w, rng, rec),
                };
        }
        if mat.dissolve < 1.0 {
            color *= mat.dissolve;
        }
        if through {
            let o = offset_origin(p, err, ng, ray.dir);
            let ray = Ray::new(o, ray.dir);
            let w = (1.0 - mat.dissolve) * scale;
            let kind = RayKind::Transmission;
            color += self.trace(&ray, None, next, kind, weight * w, rng, rec) * w;
        }
        color
    }

    /// The mesh and triangle a shadow ray was blocked by, as the ray tree
    /// names them.
    pub(super) fn occluder(&self, t: u32) -> (String, u32) {
        let mesh = self.scene.geometry.tri_mesh[t as usize];
        (self.scene.meshes[mesh as usize].name.clone(), t)
    }

    /// The light a metallic-roughness surface gives off at texture
    /// coordinates `uvs`, as emission has it.
    pub(super) fn emitted(&self, pbr: &crate::scene::material::Pbr, uvs: &Uvs) -> Vec3 {
        if !self.plan.emission {
            return Vec3::ZERO;
        }
        pbr.emissive_texture
            .and_then(|id| lookup(&self.scene.textures[id as usize], uvs, self.plan.bilinear))
            .unwrap_or(pbr.emissive)
    }

    /// One light's Phong contribution, averaged over its samples.
    fn light<R: Recorder>(
        &self,
        s: &Surface,
        index: usize,
        light: &Light,
        rng: &mut Rng,
        rec: &mut R,
    ) -> Vec3 {
        rec.begin_light(index, light.kind());
        let n_samples = match light {
            Light::Point { .. } | Light::Photometric { .. } | Light::Directional { .. } => 1,
            _ if !self.plan.area_sampling => 1,
            Light::Segment { .. } => self.scene.settings.light_samples.max(1),
            Light::Parallelogram { .. } => {
                let m = (self.scene.settings.light_samples as f32).sqrt().ceil() as u32;
                m.max(1) * m.max(1)
            }
        };
        // The grid of a parallelogram's strata, made only where drawn: a
        // point light (most lights) needs neither it nor the average.
        let grid = || (n_samples as f32).sqrt() as u32;
        let stratify = self.scene.settings.stratify;
        let (mut diffuse, mut specular) = (Vec3::ZERO, Vec3::ZERO);
        for k in 0..n_samples {
            let st = match light {
                Light::Point { .. } | Light::Photometric { .. } | Light::Directional { .. } => {
                    Vec2::ZERO
                }
                _ if !self.plan.area_sampling => Vec2::splat(0.5),
                Light::Segment { .. } if !stratify => Vec2::new(rng.next_f32(), 0.0),
                Light::Segment { .. } => {
                    Vec2::new((k as f32 + rng.next_f32()) / n_samples as f32, 0.0)
                }
                Light::Parallelogram { .. } if !stratify => rng.next_vec2(),
                Light::Parallelogram { .. } => jittered(k, grid(), rng.next_vec2()),
            };
            let (d, sp) = self.light_point(s, light.arriving(s.p, st), rec);
            diffuse += d;
            specular += sp;
        }
        if n_samples > 1 {
            let inv = 1.0 / n_samples as f32;
            (diffuse, specular) = (diffuse * inv, specular * inv);
        }
        rec.end_light(diffuse, specular);
        diffuse + specular
    }

    /// The diffuse light an environment light gives, from `light_samples`
    /// directions (rounded up to a square, jittered on its grid) drawn in
    /// proportion to its radiance, each shadow-tested, times the
    /// surface's occlusion. The specular lobe sees the environment through
    /// its reflection rays instead, so nothing is counted twice.
    fn environment_light<R: Recorder>(
        &self,
        s: &Surface,
        env: &EnvLight,
        occlusion: f32,
        rng: &mut Rng,
        rec: &mut R,
    ) -> Vec3 {
        rec.begin_light(self.scene.lights.len(), "environment");
        let m = ((self.scene.settings.light_samples.max(1) as f32)
            .sqrt()
            .ceil() as u32)
            .max(1);
        let n = m * m;
        let mut sum = Vec3::ZERO;
        for k in 0..n {
            let u = match self.scene.settings.stratify {
                true => jittered(k, m, rng.next_vec2()),
                false => rng.next_vec2(),
            };
            let e = env.sample(u);
            let l = e.dir;
            let facing = e.pdf > 0.0 && s.ng.dot(l) > 0.0 && s.n.dot(l) > 0.0 && l.is_finite();
            let mut shadow_ray = None;
            let mut occluder = None;
            if facing && self.plan.shadows {
                let ray = Ray::new(offset_origin(s.p, s.err, s.ng, l), l);
                occluder = self.blocked(&ray, rec);
                shadow_ray = Some(ray);
            }
            let visible = facing && occluder.is_none();
            let mut d = Vec3::ZERO;
            if visible {
                let f = match &s.brdf {
                    Some(b) => b.eval(s.n, s.v, l).diffuse,
                    None => s.kd * (s.n.dot(l) * FRAC_1_PI),
                };
                d = f * e.radiance * (occlusion / e.pdf);
                sum += d;
            }
            if R::ACTIVE {
                rec.light_sample(LightSample {
                    point: s.p + l,
                    color: e.radiance,
                    shadow_ray,
                    visible,
                    occluder: occluder.map(|t| self.occluder(t)),
                    diffuse: d,
                    specular: Vec3::ZERO,
                    mis: None,
                });
            }
        }
        let diffuse = sum / n as f32;
        rec.end_light(diffuse, Vec3::ZERO);
        diffuse
    }

    /// Diffuse and specular terms from one point of a light (or one
    /// direction), shadow-tested.
    fn light_point<R: Recorder>(&self, s: &Surface, a: Arriving, rec: &mut R) -> (Vec3, Vec3) {
        let lc = a.value;
        let (lp, to_light, dist, l) = match a.from {
            From::Point(lp) => {
                let to_light = lp - s.p;
                let dist = to_light.length();
                (lp, to_light, dist, to_light / dist)
            }
            // The recorder's point: a unit toward the light.
            From::Direction(l) => (s.p + l, l, f32::INFINITY, l),
        };
        let facing = s.ng.dot(to_light) > 0.0 && s.n.dot(l) > 0.0 && dist > 0.0 && l.is_finite();
        if !facing {
            if R::ACTIVE {
                rec.light_sample(LightSample {
                    point: lp,
                    color: lc,
                    shadow_ray: None,
                    visible: false,
                    occluder: None,
                    diffuse: Vec3::ZERO,
                    specular: Vec3::ZERO,
                    mis: None,
                });
            }
            return (Vec3::ZERO, Vec3::ZERO);
        }
        let mut shadow_ray = None;
        let mut occluder = None;
        if self.plan.shadows {
            let o = offset_origin(s.p, s.err, s.ng, to_light);
            let ray = match a.from {
                From::Point(_) => Ray::segment(o, lp - o, 1.0 - SHADOW_EPSILON),
                From::Direction(l) => Ray::new(o, l),
            };
            occluder = self.blocked(&ray, rec);
            shadow_ray = Some(ray);
        }
        let visible = occluder.is_none();
        let (mut d, mut sp) = (Vec3::ZERO, Vec3::ZERO);
        if visible {
            match &s.brdf {
                None => {
                    // A Phong surface's kd is its BRDF times π.
                    let lc = if a.physical { lc * FRAC_1_PI } else { lc };
                    d = s.kd * s.n.dot(l) * lc;
                    if self.plan.specular && s.mat.reflective() {
                        let r = (2.0 * s.n.dot(l)) * s.n - l;
                        sp = s.mat.ks * r.dot(s.v).max(0.0).powf(s.mat.ns) * lc;
                    }
                }
                Some(b) => {
                    // A Phong light lights a white Phong surface facing
                    // it to its colour: the illuminance π times that.
                    let e = if a.physical { lc } else { lc * PI };
                    let lobes = b.eval(s.n, s.v, l);
                    d = lobes.diffuse * e;
                    if self.plan.specular {
                        sp = lobes.specular * e;
                    }
                }
            }
        }
        if R::ACTIVE {
            rec.light_sample(LightSample {
                point: lp,
                color: lc,
                shadow_ray,
                visible,
                occluder: occluder.map(|t| self.occluder(t)),
                diffuse: d,
                specular: sp,
                mis: None,
            });
        }
        (d, sp)
    }

    /// A metallic-roughness surface's specular reflection: the mirror
    /// direction weighted by Fresnel for a mirror (or with glossy
    /// reflection off), else `glossy_samples` directions drawn from the
    /// lobe; `next` is the reflected rays' place in the tree.
    #[allow(clippy::too_many_arguments)]
    fn reflect_lobe<R: Recorder>(
        &self,
        ray: &Ray,
        s: &Surface,
        brdf: &Brdf,
        next: Depth,
        weight: Vec3,
        rng: &mut Rng,
        rec: &mut R,
    ) -> Vec3 {
        if !self.plan.glossy || brdf.is_mirror() {
            let mirror_lobe = Brdf {
                alpha: 0.0,
                ..*brdf
            };
            let Some(m) = mirror_lobe.sample_specular(s.n, s.v, Vec2::ZERO) else {
                return Vec3::ZERO;
            };
            let r = mirror(ray.dir, s.n, s.ng);
            let o = offset_origin(s.p, s.err, s.ng, r);
            let kind = RayKind::Reflection;
            return m.weight
                * self.trace(
                    &Ray::new(o, r),
                    None,
                    next,
                    kind,
                    weight * m.weight,
                    rng,
                    rec,
                );
        }
        let (n, next) = next.glossy(self.scene.settings.glossy_samples, self.max_paths);
        let share = 1.0 / n as f32;
        let mut sum = Vec3::ZERO;
        for _ in 0..n {
            if self.cancelled() {
                break;
            }
            let u = rng.next_vec2();
            // A direction below the surface carries no light.
            let Some(g) = brdf.sample_specular(s.n, s.v, u) else {
                continue;
            };
            if g.dir.dot(s.ng) <= 0.0 {
                continue;
            }
            let w = g.weight * share;
            let o = offset_origin(s.p, s.err, s.ng, g.dir);
            let kind = RayKind::Glossy;
            sum += w * self.trace(&Ray::new(o, g.dir), None, next, kind, weight * w, rng, rec);
        }
        sum
    }

    /// Mirror or glossy reflection, weighted by ks; `next` is the
    /// reflected rays' place in the tree.
    fn reflect<R: Recorder>(
        &self,
        ray: &Ray,
        s: &Surface,
        next: Depth,
        weight: Vec3,
        rng: &mut Rng,
        rec: &mut R,
    ) -> Vec3 {
        let r = mirror(ray.dir, s.n, s.ng);
        let ks = s.mat.ks;
        if self.plan.glossy && s.mat.glossy() {
            let (n, next) = next.glossy(self.scene.settings.glossy_samples, self.max_paths);
            let w = ks / n as f32;
            let mut sum = Vec3::ZERO;
            for _ in 0..n {
                if self.cancelled() {
                    break;
                }
                // Rejection keeps the lobe's shape above the surface (the
                // estimator of the lobe renormalised to the upper hemisphere).
                let mut dir = r;
                for _ in 0..GLOSSY_TRIES {
                    let (g, _pdf) = phong_lobe(r, s.mat.ns, rng.next_vec2());
                    if g.dot(s.ng) > 0.0 {
                        dir = g;
                        break;
                    }
                }
                let o = offset_origin(s.p, s.err, s.ng, dir);
                sum += self.trace(
                    &Ray::new(o, dir),
                    None,
                    next,
                    RayKind::Glossy,
                    weight * w,
                    rng,
                    rec,
                );
            }
            return sum * w;
        }
        let o = offset_origin(s.p, s.err, s.ng, r);
        ks * self.trace(
            &Ray::new(o, r),
            None,
            next,
            RayKind::Reflection,
            weight * ks,
            rng,
            rec,
        )
    }
}
