//! Scale and offset: the scene scaled by 1e-8 .. 1e8 and moved up to 1e7
//! times its size from the origin, rendered through the integrator with a
//! recorder that watches every shadow ray. Acne is a shadow ray from a
//! surface facing the light that its own surface (its triangle, or one
//! coplanar with it) blocks; a lost shadow is a pixel in a light's umbra at
//! unit scale that is not here; a leak is a ray that must hit the scene and
//! does not; the image is compared with the unit-scale render.

use anyhow::Result;
use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::topology::{aimed, Crossing, Topology};
use super::Row;
use super::{format_figure, Options};
use crate::bvh::{self, Bvh, TraversalStats};
use crate::geometry::gamma;
use crate::geometry::offset::hit_point;
use crate::geometry::sampling::Rng;
use crate::render::recorder::{HitInfo, LightSample, RayKind, Recorder};
use crate::render::{Feature, Features, Plan, PlanPolicy, Tracer};
use crate::scene::{Builder, Geometry, Light, Scene};

/// A uniform scale, then a move by `offset` times the (scaled) scene's size
/// along `(1, -0.5, 0.75)` (off every axis). `recentred`: the scene as the
/// loaders hand a file that far out to the renderer, moved next to the
/// origin in f64 before its coordinates are rounded to f32; otherwise it is
/// rendered out there, where f32 positions and hit points are coarse.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Transform {
    pub(crate) scale: f32,
    pub(crate) offset: f32,
    pub(crate) recentred: bool,
}

impl Transform {
    pub const fn new(scale: f32, offset: f32) -> Self {
        Self {
            scale,
            offset,
            recentred: false,
        }
    }

    /// The same transform, with the scene moved next to the origin before
    /// rounding.
    pub(crate) const fn recentred(self) -> Self {
        Self {
            recentred: true,
            ..self
        }
    }

    /// The move, for a scene `size` across before scaling.
    pub(crate) fn offset_vec(&self, size: f64) -> DVec3 {
        DVec3::new(1.0, -0.5, 0.75) * (self.offset as f64 * self.scale as f64 * size)
    }

    pub(crate) fn is_identity(&self) -> bool {
        self.scale == 1.0 && self.offset == 0.0
    }

    pub fn label(&self) -> String {
        let e = |x: f32| format!("{x:e}").replace("e0", "");
        let moved = |o: f32| {
            let place = if self.recentred { ", recentred" } else { "" };
            format!("offset {} sizes{place}", e(o))
        };
        match (self.scale == 1.0, self.offset == 0.0) {
            (_, true) => format!("scale {}", e(self.scale)),
            (true, false) => moved(self.offset),
            (false, false) => format!("scale {} {}", e(self.scale), moved(self.offset)),
        }
    }
}

/// The transforms of the battery; the identity is the reference. Scales
/// from 1e-8 to 1e8. Up to 1e4 times its size from the origin the scene is
/// rendered out there, where f32 positions are 1e-3 of its size apart
/// (0.1 pixel at the default size; at 1e5 sizes they are a pixel apart, and
/// hit points rounded to them move shadow edges by a pixel). Farther out,
/// f32 cannot hold the scene, and the loaders move it next to the origin
/// before rounding: those cases are that scene.
pub const TRANSFORMS: [Transform; 18] = [
    Transform::new(1e-8, 0.0),
    Transform::new(1e-6, 0.0),
    Transform::new(1e-4, 0.0),
    Transform::new(1e-2, 0.0),
    Transform::new(1.0, 0.0),
    Transform::new(1e2, 0.0),
    Transform::new(1e4, 0.0),
    Transform::new(1e6, 0.0),
    Transform::new(1e8, 0.0),
    Transform::new(1.0, 1e2),
    Transform::new(1.0, 1e3),
    Transform::new(1.0, 1e4),
    Transform::new(1e-6, 1e4),
    Transform::new(1e4, 1e4),
    Transform::new(1.0, 1e5).recentred(),
    Transform::new(1.0, 1e7).recentred(),
    Transform::new(1e-8, 1e7).recentred(),
    Transform::new(1e8, 1e7).recentred(),
];

/// Largest fraction of pixels allowed to differ from the reference (see
/// [`image_difference`]); tiny images are allowed [`IMAGE_LIMIT_PIXELS`].
pub(crate) const IMAGE_LIMIT: f64 = 0.01;
pub(crate) const IMAGE_LIMIT_PIXELS: f64 = 4.0;
/// A pixel differs when a channel (clamped to [0, 1]) moves by more than this.
pub(crate) const PIXEL_TOLERANCE: f32 = 0.02;

/// Watches the integrator: the triangle hit by each open ray (with the
/// barycentrics of the hit), whether the camera ray hit, whether its hit is
/// in the umbra of a light (every shadow ray toward it blocked), and every
/// shadow ray from a surface facing its light.
struct Probe<'g> {
    geom: &'g Geometry,
    stack: Vec<Option<(u32, f32, f32)>>,
    primary: bool,
    shadowed: bool,
    /// Shadow rays from the camera hit toward the current light, and how
    /// many were blocked.
    traced: u32,
    blocked: u32,
    lit: u64,
    acne: u64,
}

impl Recorder for Probe<'_> {
    const ACTIVE: bool = true;

    fn begin_ray(&mut self, _kind: RayKind, _ray: &crate::geometry::Ray, _weight: Vec3) {
        self.stack.push(None);
    }

    fn hit(&mut self, info: HitInfo) {
        if self.stack.len() == 1 {
            self.primary = true;
        }
        if let Some(top) = self.stack.last_mut() {
            *top = Some((info.triangle, info.barycentric.y, info.barycentric.z));
        }
    }

    fn begin_light(&mut self, _index: usize, _kind: &'static str) {
        (self.traced, self.blocked) = (0, 0);
    }

    fn light_sample(&mut self, s: LightSample) {
        if s.shadow_ray.is_none() {
            return;
        }
        self.lit += 1;
        if self.stack.len() == 1 {
            self.traced += 1;
            self.blocked += s.occluder.is_some() as u32;
        }
        if let (Some((_, occ)), Some(Some((tri, u, v)))) = (s.occluder, self.stack.last()) {
            if own_surface(self.geom, *tri, occ, *u, *v) {
                self.acne += 1;
            }
        }
    }

    fn end_light(&mut self, _diffuse: Vec3, _specular: Vec3) {
        if self.stack.len() == 1 && self.traced > 0 && self.blocked == self.traced {
            self.shadowed = true;
        }
    }

    fn end_ray(&mut self, _color: Vec3) {
        self.stack.pop();
    }
}

/// Whether triangle `occ` is the surface that the hit at barycentrics
/// `(u, v)` of triangle `hit` lies on: the same triangle, or a parallel one
/// whose plane the hit point reaches within its rounding error bound (the
/// bound the integrator offsets spawned rays by).
pub fn own_surface(g: &Geometry, hit: u32, occ: u32, u: f32, v: f32) -> bool {
    if hit == occ {
        return true;
    }
    let (p, err) = hit_point(g.triangle(hit as usize), u, v);
    let plane = |i: u32| {
        let [a, b, c] = g.triangle(i as usize).map(|v| v.as_dvec3());
        ((b - a).cross(c - a).normalize_or_zero(), a)
    };
    let (nh, _) = plane(hit);
    let (no, a) = plane(occ);
    nh.dot(no).abs() >= 1.0 - 1e-6 && no.dot(p.as_dvec3() - a).abs() <= no.abs().dot(err.as_dvec3())
}

/// What one render through the probe saw.
#[derive(Default)]
pub struct Probed {
    pub image: Vec<Vec3>,
    /// Whether each pixel's camera ray hit the scene.
    pub primary: Vec<bool>,
    /// Whether each pixel's camera hit is in the umbra of a light: every
    /// shadow ray from it toward that light blocked (a point light's shadow;
    /// an area light's penumbra is left out, since one of its rays grazing
    /// an occluder's edge flips with any rounding).
    pub shadowed: Vec<bool>,
    /// Shadow rays from surfaces facing their light, and those that hit their own surface.
    pub lit: u64,
    pub acne: u64,
}

/// Renders one sample per pixel at the pixel centres through the probe.
pub fn probe_render(scene: &Scene, bvh: &Bvh, w: u32, h: u32, seed: u64) -> Probed {
    let features = Features::all().without(&[Feature::Supersampling, Feature::Bloom]);
    let plan = Plan::new(scene, features, PlanPolicy::Prune);
    let tracer = Tracer::new(scene, bvh, &plan, scene.camera.frame(w, h), seed);
    let rows: Vec<Probed> = (0..h)
        .into_par_iter()
        .map(|y| {
            let mut rec = Probe {
                geom: &scene.geometry,
                stack: Vec::new(),
                primary: false,
                shadowed: false,
                traced: 0,
                blocked: 0,
                lit: 0,
                acne: 0,
            };
            let mut row = Probed::default();
            for x in 0..w {
                rec.primary = false;
                rec.shadowed = false;
                row.image.push(tracer.sample(x, y, 0, &mut rec));
                row.primary.push(rec.primary);
                row.shadowed.push(rec.shadowed);
            }
            row.lit = rec.lit;
            row.acne = rec.acne;
            row
        })
        .collect();
    let mut out = Probed::default();
    for row in rows {
        out.image.extend(row.image);
        out.primary.extend(row.primary);
        out.shadowed.extend(row.shadowed);
        out.lit += row.lit;
        out.acne += row.acne;
    }
    out
}

/// Fraction of pixels of either `w x h` image that differ by more than
/// [`PIXEL_TOLERANCE`] from every pixel of the other's 3x3 neighbourhood: an
/// edge or shadow boundary moved by a rounding across one pixel is not a
/// difference, a change of shading or speckle is.
pub fn image_difference(a: &[Vec3], b: &[Vec3], w: u32, h: u32) -> f64 {
    let clamp = |c: Vec3| {
        if c.is_finite() {
            c.clamp(Vec3::ZERO, Vec3::ONE)
        } else {
            Vec3::NAN
        }
    };
    let (w, h) = (w as i64, h as i64);
    let unmatched = |x: &[Vec3], y: &[Vec3], i: i64| {
        let c = clamp(x[i as usize]);
        let (px, py) = (i % w, i / w);
        !(-1..=1).any(|dy| {
            (-1..=1).any(|dx| {
                let (qx, qy) = (px + dx, py + dy);
                (0..w).contains(&qx)
                    && (0..h).contains(&qy)
                    && (c - clamp(y[(qy * w + qx) as usize])).abs().max_element() <= PIXEL_TOLERANCE
            })
        })
    };
    let off = (0..w * h)
        .filter(|&i| unmatched(a, b, i) || unmatched(b, a, i))
        .count();
    off as f64 / (w * h).max(1) as f64
}

/// Rays that must hit: from the eye at crossing vertices, crossing edges and
/// interior points of the scene's triangles, at most `rays` of each.
/// Returns (aimed, missed).
pub fn aimed_leaks(scene: &Scene, bvh: &Bvh, rays: u32, seed: u64) -> (u64, u64) {
    let tris = (0..scene.geometry.triangle_count())
        .map(|i| scene.geometry.triangle(i))
        .collect();
    let topo = Topology::new(tris);
    let eye = scene.camera.eye;
    let mut rng = Rng::for_sample(0, 1, seed);
    // At most `rays` of each kind, so big meshes stay quick.
    let mut targets = Vec::new();
    for (kind, per_edge) in [
        (Crossing::Vertex, 0),
        (Crossing::Edge, 4),
        (Crossing::Surface, 0),
    ] {
        let mut t = topo.targets(eye, kind, per_edge, rays, &mut rng);
        while t.len() > rays as usize {
            let i = rng.next_u32() as usize % t.len();
            t.swap_remove(i);
        }
        targets.extend(t);
    }
    let missed = targets
        .par_iter()
        .filter(|t| {
            aimed(eye, **t).is_some_and(|r| {
                bvh.intersect::<false>(&r, &mut TraversalStats::default())
                    .is_none()
            })
        })
        .count();
    (targets.len() as u64, missed as u64)
}

/// Pixels set in `reference` whose eight neighbours are set too (so the
/// pixel is not on a silhouette or a shadow's edge), and how many of them
/// are not set in `probed`: camera rays that hit and then leaked, or shadows
/// that vanished.
pub fn interior_lost(reference: &[bool], probed: &[bool], w: u32, h: u32) -> (u64, u64) {
    interior_lost_within(reference, probed, w, h, 1)
}

/// [`interior_lost`] for pixels whose neighbours within `r` pixels (on
/// each axis) are set too: an edge may move by `r` pixels.
pub fn interior_lost_within(
    reference: &[bool],
    probed: &[bool],
    w: u32,
    h: u32,
    r: u32,
) -> (u64, u64) {
    let (w, h, r) = (w as i64, h as i64, r as i64);
    let at = |x: i64, y: i64| x >= 0 && y >= 0 && x < w && y < h && reference[(y * w + x) as usize];
    let (mut n, mut leaks) = (0, 0);
    for y in 0..h {
        for x in 0..w {
            if (-r..=r).all(|dy| (-r..=r).all(|dx| at(x + dx, y + dy))) {
                n += 1;
                leaks += !probed[(y * w + x) as usize] as u64;
            }
        }
    }
    (n, leaks)
}

/// The scene with every point mapped by `f` and every vector scaled by `s`.
fn map_scene(scene: &Scene, f: impl Fn(Vec3) -> Vec3, s: f32) -> Scene {
    let mut out = scene.clone();
    for p in &mut out.geometry.positions {
        *p = f(*p);
    }
    out.camera.eye = f(out.camera.eye);
    out.camera.target = f(out.camera.target);
    out.camera.projection = out.camera.projection.scaled(s);
    for l in &mut out.lights {
        match l {
            Light::Point { position, .. } => *position = f(*position),
            Light::Photometric {
                position,
                intensity,
                range,
                ..
            } => {
                *position = f(*position);
                *intensity *= s * s;
                if let Some(r) = range {
                    *r *= s;
                }
            }
            Light::Directional { .. } => {}
            Light::Segment { a, b, .. } => {
                *a = f(*a);
                *b = f(*b);
            }
            Light::Parallelogram {
                corner,
                edge1,
                edge2,
                ..
            } => {
                *corner = f(*corner);
                *edge1 *= s;
                *edge2 *= s;
            }
        }
    }
    out
}

/// How many pixels a shadow's edge may move in a `w x h` render of
/// `scene` (placed by [`place`]): one, or, where f32 is coarser, the bound
/// the integrator keeps a shadow ray's origin within of its exact hit point
/// (the hit point's rounding bound, γ₇ times the largest coordinate, plus
/// the offset by that bound) across the pixels the scene's size spans. For
/// the Cornell box 1e4 sizes from the origin that is 0.8 pixel at 96x96
/// and 9 at 1024x1024: shadow rays start 5 f32 steps (0.0049) above the
/// floor there, and the far edge of the short box's shadow moves by 2
/// pixels.
pub fn shadow_edge_allowance(scene: &Scene, w: u32, h: u32) -> u32 {
    let b = scene.bounds();
    let far = b.min.abs().max(b.max.abs()).max_element() as f64;
    let bound = 2.0 * gamma(7) as f64 * far;
    let pixel = size(scene) / w.max(h) as f64;
    let r = (bound / pixel).ceil();
    if r.is_finite() {
        r.clamp(1.0, w.max(h) as f64) as u32
    } else {
        1
    }
}

/// The largest extent of `scene`'s geometry (1 for an empty or flat-out
/// degenerate scene, so offsets stay defined).
fn size(scene: &Scene) -> f64 {
    let e = scene.bounds().extent().max_element() as f64;
    if e > 0.0 && e.is_finite() {
        e
    } else {
        1.0
    }
}

/// `scene` under `t`, and the shift subtracted from it: every point scaled
/// and moved in f64 and rounded once to f32, as the loaders place a file's
/// coordinates; for a recentred transform the shift is the one
/// [`Scene::recentre`] picks for the scene out there, subtracted before
/// rounding, as the loaders do for a scene far from the origin.
pub fn place(scene: &Scene, t: Transform) -> (Scene, DVec3) {
    let (s, off) = (t.scale as f64, t.offset_vec(size(scene)));
    let put = |shift: DVec3| {
        map_scene(
            scene,
            |p| (p.as_dvec3() * s + off - shift).as_vec3(),
            t.scale,
        )
    };
    let out = put(DVec3::ZERO);
    if !t.recentred {
        return (out, DVec3::ZERO);
    }
    match out.clone().recentre() {
        Some(shift) => (put(shift.as_dvec3()), shift.as_dvec3()),
        None => (out, DVec3::ZERO),
    }
}

/// The scale and offset rows for `scene`: acne, lost shadows, leaks and
/// image difference for every transform.
pub fn scale_offset(scene: &Scene, o: &Options) -> Result<Vec<Row>> {
    let base_bvh = bvh::build(&scene.geometry, Builder::Sah);
    let reference = probe_render(scene, &base_bvh, o.width, o.height, o.seed);
    // The transforms in parallel (two cores halve a big mesh's time).
    let per: Vec<Vec<Row>> = TRANSFORMS
        .par_iter()
        .map(|t| transform_rows(scene, *t, &reference, o))
        .collect();
    Ok(per.concat())
}

/// Renders `scene` through the probe.
fn probe_scene(scene: &Scene, o: &Options) -> (Probed, Bvh) {
    let bvh = bvh::build(&scene.geometry, Builder::Sah);
    (probe_render(scene, &bvh, o.width, o.height, o.seed), bvh)
}

/// Acne, lost shadows, leaks and image difference of `scene` under `t`,
/// against `reference`, the probed render of `scene` itself.
pub fn transform_rows(scene: &Scene, t: Transform, reference: &Probed, o: &Options) -> Vec<Row> {
    let (w, h) = (o.width, o.height);
    let mut rows = Vec::new();
    let (moved, shift) = place(scene, t);
    let (probed, bvh) = probe_scene(&moved, o);
    // The reference: this scene's own (rounded) geometry mapped back to
    // unit scale in f64, so the figures measure the renderer and not the
    // rounding of the input (the original scene's figures are given too).
    let unit = if t.is_identity() {
        None
    } else {
        let (s, off) = (t.scale as f64, t.offset_vec(size(scene)));
        let undone = map_scene(
            &moved,
            |p| ((p.as_dvec3() + shift - off) / s).as_vec3(),
            1.0 / t.scale,
        );
        Some(probe_scene(&undone, o).0)
    };
    let unit_ref = unit.as_ref().unwrap_or(reference);
    // A recentred case against the same scene rounded to f32 out there
    // first (and then recentred, exactly): what a loader reading in f32
    // would give.
    let coarse = t.recentred.then(|| {
        let mut c = place(scene, Transform::new(t.scale, t.offset)).0;
        c.recentre();
        probe_scene(&c, o).0
    });
    let label = t.label();
    rows.push(Row::at_most(
        format!("{label}: acne"),
        probed.acne as f64 / probed.lit.max(1) as f64,
        0.0,
        format!(
            "{} of {} shadow rays from lit surfaces hit their own surface",
            probed.acne, probed.lit
        ),
    ));
    // Shadow edges may move by what f32 out there allows, at least a pixel.
    let r = shadow_edge_allowance(&moved, w, h);
    let lost = |reference: &Probed, probed: &Probed| {
        interior_lost_within(&reference.shadowed, &probed.shadowed, w, h, r)
    };
    let (sn, sl) = lost(unit_ref, &probed);
    let around = if r == 1 {
        "as are their 8 neighbours".to_string()
    } else {
        format!("as are all within {r} pixels, the error bound of shadow-ray origins here")
    };
    let mut detail = format!(
        "{sl} of {sn} pixels in a light's umbra ({around}) in the unit-scale render of \
         the same geometry lit here"
    );
    if unit.is_some() {
        let (on, ol) = lost(reference, &probed);
        detail += &format!("; {ol} of {on} of the original scene's");
    }
    if let Some(c) = &coarse {
        let (_, cl) = lost(reference, c);
        detail += &format!(", {cl} if rounded to f32 out there");
    }
    rows.push(Row::at_most(
        format!("{label}: shadows"),
        sl as f64 / sn.max(1) as f64,
        0.0,
        detail,
    ));
    let (pn, pl) = interior_lost(&reference.primary, &probed.primary, w, h);
    let (an, al) = aimed_leaks(&moved, &bvh, o.rays / 10, o.seed);
    rows.push(Row::at_most(
        format!("{label}: leaks"),
        (pl + al) as f64 / (pn + an).max(1) as f64,
        0.0,
        format!(
            "{pl} of {pn} camera rays into the scene and {al} of {an} rays aimed at \
             edges, vertices and faces missed"
        ),
    ));
    if let Some(unit) = &unit {
        // As `scene::load::open` would hand it to the renderer: recentred
        // when far from the origin.
        let mut shown = moved.clone();
        let recentred = shown.recentre().is_some();
        let image = if recentred {
            probe_scene(&shown, o).0.image
        } else {
            probed.image.clone()
        };
        let mut detail = format!(
            "pixels off by > {PIXEL_TOLERANCE} from all 3x3 neighbours in the unit-scale \
             render of the same geometry; {} against the original scene",
            format_figure(image_difference(&image, &reference.image, w, h))
        );
        if recentred {
            detail += &format!(
                "; recentred at load, {} without",
                format_figure(image_difference(&probed.image, &unit.image, w, h))
            );
        }
        if let Some(c) = &coarse {
            detail += &format!(
                ", {} if rounded to f32 out there",
                format_figure(image_difference(&c.image, &reference.image, w, h))
            );
        }
        rows.push(Row::at_most(
            format!("{label}: image"),
            image_difference(&image, &unit.image, w, h),
            IMAGE_LIMIT.max(IMAGE_LIMIT_PIXELS / (w * h) as f64),
            detail,
        ));
    }
    rows
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn labels_are_short() {
        assert_eq!(Transform::new(1e-4, 0.0).label(), "scale 1e-4");
        assert_eq!(Transform::new(1.0, 1e5).label(), "offset 1e5 sizes");
        assert_eq!(
            Transform::new(1e4, 1e7).recentred().label(),
            "scale 1e4 offset 1e7 sizes, recentred"
        );
    }

    #[test]
    fn far_cases_are_placed_in_f64_and_moved_back() {
        let scene = crate::scene::load::open("cornell", &Default::default())
            .unwrap()
            .scene;
        let t = Transform::new(1.0, 1e7).recentred();
        let (near, shift) = place(&scene, t);
        // Cornell is 2 across: its centre lands near (2e7, -1e7, 1.5e7),
        // where f32 positions are 2 apart; moved back before rounding,
        // every coordinate is within an f32 ulp of the original.
        let off = t.offset_vec(2.0);
        assert!((shift - off).abs().max_element() < 4.0, "{shift}");
        for (a, b) in near
            .geometry
            .positions
            .iter()
            .zip(&scene.geometry.positions)
        {
            let back = a.as_dvec3() + shift - off;
            assert!((back - b.as_dvec3()).abs().max_element() < 1e-6, "{a} {b}");
        }
        let (out, none) = place(&scene, Transform::new(1.0, 1e5));
        assert_eq!(none, DVec3::ZERO);
        assert!(out.bounds().min.x > 1e5);
    }
}
