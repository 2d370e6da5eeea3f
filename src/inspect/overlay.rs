//! The selected pixel's overlays: one sample's ray tree drawn over the
//! image as its rays (by kind or in the colour they add), the points
//! sampled on lights, one ray's BVH walk, the normals, texel footprint and
//! environment lookup of one ray, the glossy lobes, and a zoom of the
//! pixel's sub-pixel samples. Everything drawn is read from the recorded
//! tree (and the scene it names); `rayterm render --debug ray:X,Y:VIEW`
//! and the TUI's `o` draw the same layers.

use std::fmt;
use std::str::FromStr;

use anyhow::{bail, Result};
use glam::{Vec2, Vec3};

use super::tree::{inspect_pixel, PixelTree, RayNode};
use crate::geometry::sampling::PIXEL_GRID;
use crate::geometry::Ray;
use crate::raster::canvas::{text_width, Canvas, GLYPH};
use crate::render::integrator::mirror;
use crate::render::overlay::{clip_to_rect, draw_box, draw_segment, Layer, Legend};
use crate::render::recorder::{LightSample, RayKind};
use crate::render::Tracer;
use crate::scene::Scene;

/// What the selected pixel's overlay shows.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PixelView {
    /// Every ray in its kind's colour.
    Rays,
    /// Every ray in the colour it adds to the pixel.
    Colour,
    /// The points sampled on lights, in the light's colour there.
    Lights,
    /// The BVH nodes one ray visited.
    Traversal,
    /// One hit's vertex normals and interpolated normal.
    Normals,
    /// One hit's texel footprint.
    Texture,
    /// One missing ray in the environment's colour.
    Environment,
    /// The glossy rays and their lobe's axis.
    Glossy,
    /// A zoom of the pixel: where its samples fall and their colours.
    Samples,
}

/// Every view, in the order the TUI's `o` cycles them.
pub const VIEWS: [PixelView; 9] = [
    PixelView::Rays,
    PixelView::Colour,
    PixelView::Lights,
    PixelView::Traversal,
    PixelView::Normals,
    PixelView::Texture,
    PixelView::Environment,
    PixelView::Glossy,
    PixelView::Samples,
];

impl PixelView {
    pub fn name(self) -> &'static str {
        match self {
            PixelView::Rays => "rays",
            PixelView::Colour => "colour",
            PixelView::Lights => "lights",
            PixelView::Traversal => "traversal",
            PixelView::Normals => "normals",
            PixelView::Texture => "texture",
            PixelView::Environment => "environment",
            PixelView::Glossy => "glossy",
            PixelView::Samples => "samples",
        }
    }

    /// Whether the view shows one chosen ray of the tree.
    pub fn one_ray(self) -> bool {
        matches!(
            self,
            PixelView::Traversal | PixelView::Normals | PixelView::Texture | PixelView::Environment
        )
    }
}

impl fmt::Display for PixelView {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for PixelView {
    type Err = String;

    fn from_str(s: &str) -> Result<Self, String> {
        match s {
            "color" => return Ok(PixelView::Colour),
            "env" => return Ok(PixelView::Environment),
            _ => {}
        }
        VIEWS
            .iter()
            .copied()
            .find(|v| v.name() == s)
            .ok_or_else(|| {
                let names: Vec<&str> = VIEWS.iter().map(|v| v.name()).collect();
                format!("unknown overlay '{s}': expected {}", names.join(", "))
            })
    }
}

/// A drawn overlay and its legend.
pub struct Overlay {
    pub layer: Layer,
    pub legend: Legend,
    /// Where the legend goes to stay clear of the pixel and the zooms.
    pub legend_bottom: bool,
    /// The views of colours rays add draw them times this, so that the
    /// brightest shows at full strength (1 when it already does, or for
    /// other views); the legend says so.
    pub exposure: f32,
}

/// Shadow ray colours, as the original renderer drew them.
pub const BLOCKED: Vec3 = Vec3::new(1.0, 0.0, 0.0);
pub const CLEAR: Vec3 = Vec3::ONE;
/// Traversal: boxes on the path to the hit triangle, and the others.
pub const ON_PATH: Vec3 = Vec3::new(0.0, 1.0, 0.0);
pub const OFF_PATH: Vec3 = Vec3::new(1.0, 0.0, 0.0);
/// The hit triangle's outline.
pub const TRIANGLE: Vec3 = Vec3::new(1.0, 1.0, 0.0);
/// Normals: the vertex normals and the interpolated one.
pub const VERTEX_NORMAL: Vec3 = Vec3::new(1.0, 0.0, 0.0);
pub const INTERPOLATED: Vec3 = Vec3::new(0.0, 1.0, 0.0);
/// Texel outlines, the sample zoom's frame and the face's name.
pub const MARK: Vec3 = Vec3::ONE;
/// The glossy lobe's axis.
pub const LOBE_AXIS: Vec3 = Vec3::new(1.0, 0.0, 1.0);
const GRID: Vec3 = Vec3::splat(0.25);

/// The colour of a ray of `kind` in the `rays` view.
pub fn kind_color(k: RayKind) -> Vec3 {
    match k {
        RayKind::Camera => Vec3::new(1.0, 1.0, 0.0),
        RayKind::Reflection => Vec3::new(0.0, 1.0, 1.0),
        RayKind::Glossy => Vec3::new(0.3, 0.5, 1.0),
        RayKind::Transmission => Vec3::new(0.0, 1.0, 0.0),
        RayKind::Diffuse => Vec3::new(1.0, 0.5, 0.0),
    }
}

fn kind_color_name(k: RayKind) -> &'static str {
    match k {
        RayKind::Camera => "yellow",
        RayKind::Reflection => "cyan",
        RayKind::Glossy => "blue",
        RayKind::Transmission => "green",
        RayKind::Diffuse => "orange",
    }
}

fn kind_name(k: RayKind) -> &'static str {
    match k {
        RayKind::Camera => "camera",
        RayKind::Reflection => "reflection",
        RayKind::Glossy => "glossy",
        RayKind::Transmission => "transmitted",
        RayKind::Diffuse => "diffuse",
    }
}

/// How far rays that miss are drawn: twice the scene's diagonal.
pub fn ray_reach(scene: &Scene) -> f32 {
    2.0 * scene.bounds().extent().length()
}

/// One ray of a tree: a traced ray, or a shadow ray of one of its hits.
pub struct TreeRay<'a> {
    pub node: &'a RayNode,
    /// Set for a shadow ray: the light and the sample.
    pub shadow: Option<(usize, &'a LightSample)>,
}

impl TreeRay<'_> {
    /// The ray as traced.
    pub fn ray(&self) -> Ray {
        match self.shadow.and_then(|(_, s)| s.shadow_ray) {
            Some(r) => r,
            None => Ray::new(self.node.origin, self.node.dir),
        }
    }

    pub fn label(&self) -> String {
        match self.shadow {
            Some((light, s)) => format!(
                "shadow ray to light {light}, {}",
                if s.occluder.is_some() {
                    "blocked"
                } else {
                    "clear"
                }
            ),
            None => format!(
                "{} ray, {}",
                kind_name(self.node.kind),
                if self.node.hit.is_some() {
                    "hits"
                } else {
                    "misses"
                }
            ),
        }
    }
}

/// The tree's rays numbered as the text shows them: each ray, then its
/// shadow rays, then the rays it spawned.
pub fn tree_rays(tree: &PixelTree) -> Vec<TreeRay<'_>> {
    fn walk<'a>(n: &'a RayNode, out: &mut Vec<TreeRay<'a>>) {
        out.push(TreeRay {
            node: n,
            shadow: None,
        });
        for l in &n.lights {
            for s in l.samples.iter().filter(|s| s.shadow_ray.is_some()) {
                out.push(TreeRay {
                    node: n,
                    shadow: Some((l.index, s)),
                });
            }
        }
        for c in &n.children {
            walk(c, out);
        }
    }
    let mut out = Vec::new();
    walk(&tree.root, &mut out);
    out
}

/// Every traced ray of the tree, parents first.
fn nodes(tree: &PixelTree) -> Vec<&RayNode> {
    let mut out = vec![];
    let mut stack = vec![&tree.root];
    while let Some(n) = stack.pop() {
        out.push(n);
        stack.extend(n.children.iter().rev());
    }
    out
}

/// Where a traced ray ends in the drawing: its hit, or `reach` along it.
fn end_of(n: &RayNode, reach: f32) -> Vec3 {
    n.hit
        .as_ref()
        .map_or(n.origin + n.dir.normalize_or_zero() * reach, |h| h.point)
}

/// Draws `view` of `tree` (a sample of the tracer's image). `ray` picks the
/// ray of the one-ray views (see [`tree_rays`]; by default the camera ray,
/// or for `environment` the first ray that misses); `spp` is how many
/// samples the `samples` zoom shows.
pub fn draw(
    tracer: &Tracer,
    tree: &PixelTree,
    view: PixelView,
    ray: Option<usize>,
    spp: u32,
) -> Result<Overlay> {
    let mut d = Drawing {
        tracer,
        layer: Canvas::new(tracer.width, tracer.height, None),
        legend: Vec::new(),
        reach: ray_reach(tracer.scene),
        exposure: 1.0,
    };
    let rays = tree_rays(tree);
    if let Some(i) = ray {
        if i >= rays.len() {
            bail!(
                "ray {i} is not in the tree of pixel ({}, {}): it has rays 0 to {}",
                tree.x,
                tree.y,
                rays.len() - 1
            );
        }
    }
    let chosen = |default: usize| {
        let i = ray.unwrap_or(default);
        (i, &rays[i])
    };
    match view {
        PixelView::Rays => d.rays(tree, false),
        PixelView::Colour => d.rays(tree, true),
        PixelView::Lights => d.lights(tree),
        PixelView::Traversal => {
            let (i, r) = chosen(0);
            d.traversal(i, r)
        }
        PixelView::Normals => {
            let (i, r) = chosen(0);
            d.normals(i, r)
        }
        PixelView::Texture => {
            let (i, r) = chosen(0);
            d.texture(i, r, (tree.x, tree.y))
        }
        PixelView::Environment => {
            let first_miss = rays
                .iter()
                .position(|r| r.shadow.is_none() && r.node.miss.is_some());
            let (i, r) = chosen(first_miss.unwrap_or(0));
            d.environment(i, r)
        }
        PixelView::Glossy => d.glossy(tree),
        PixelView::Samples => d.samples(tree, spp),
    }
    Ok(Overlay {
        layer: d.layer,
        legend: d.legend,
        legend_bottom: 2 * tree.y < tracer.height,
        exposure: d.exposure,
    })
}

struct Drawing<'t, 'a> {
    tracer: &'t Tracer<'a>,
    layer: Layer,
    legend: Legend,
    reach: f32,
    /// The factor ray colours are drawn with (see [`Overlay::exposure`]).
    exposure: f32,
}

impl Drawing<'_, '_> {
    /// Sets the exposure so the brightest of `colours` shows at full
    /// strength, and says so in the legend.
    fn expose<'c>(&mut self, colours: impl Iterator<Item = &'c Vec3>) {
        let most = colours
            .map(|c| c.max_element())
            .filter(|m| m.is_finite())
            .fold(0.0f32, f32::max);
        if most > 0.0 && most < 1.0 {
            self.exposure = 1.0 / most;
            self.say(
                None,
                format!(
                    "colours x{:.3} so the brightest shows at full strength",
                    self.exposure
                ),
            );
        }
    }

    fn seg(&mut self, a: Vec3, b: Vec3, c: Vec3) {
        draw_segment(&mut self.layer, &self.tracer.frame, a, b, Some(c));
    }

    fn say(&mut self, swatch: Option<Vec3>, text: impl Into<String>) {
        self.legend.push((swatch, text.into()));
    }

    /// Half the side of the squares that mark points.
    fn dot_radius(&self) -> i32 {
        (self.layer.width.min(self.layer.height) / 300).max(1) as i32
    }

    /// A square of colour `c` with a black rim at world point `p`.
    fn dot(&mut self, p: Vec3, c: Vec3) {
        if let Some((x, y)) = self.tracer.frame.project(p) {
            let (x, y) = (x.floor() as i32, y.floor() as i32);
            let r = self.dot_radius();
            self.layer
                .rect(x - r - 1, y - r - 1, x + r + 1, y + r + 1, Some(Vec3::ZERO));
            self.layer.rect(x - r, y - r, x + r, y + r, Some(c));
        }
    }

    fn triangle(&mut self, prim: u32) -> [Vec3; 3] {
        let geo = &self.tracer.scene.geometry;
        geo.indices[prim as usize].map(|i| geo.positions[i as usize])
    }

    fn outline(&mut self, v: [Vec3; 3], c: Vec3) {
        for k in 0..3 {
            self.seg(v[k], v[(k + 1) % 3], c);
        }
    }

    fn shadow_rays(&mut self, n: &RayNode) -> (usize, usize) {
        let (mut clear, mut blocked) = (0, 0);
        for s in n.lights.iter().flat_map(|l| &l.samples) {
            if let Some(r) = &s.shadow_ray {
                let c = if s.occluder.is_some() {
                    blocked += 1;
                    BLOCKED
                } else {
                    clear += 1;
                    CLEAR
                };
                self.seg(r.origin, s.point, c);
            }
        }
        (clear, blocked)
    }

    fn shadow_legend(&mut self, (clear, blocked): (usize, usize)) {
        if clear > 0 {
            self.say(
                Some(CLEAR),
                format!(
                    "white: {}",
                    crate::words::count(clear as u64, "shadow ray clear", "shadow rays clear")
                ),
            );
        }
        if blocked > 0 {
            self.say(
                Some(BLOCKED),
                format!(
                    "red: {}",
                    crate::words::count(
                        blocked as u64,
                        "shadow ray blocked",
                        "shadow rays blocked"
                    )
                ),
            );
        }
    }

    fn rays(&mut self, tree: &PixelTree, by_colour: bool) {
        let mut shadows = (0, 0);
        let mut kinds: Vec<(RayKind, usize)> = Vec::new();
        if by_colour {
            self.expose(nodes(tree).iter().map(|n| &n.contribution));
        }
        for n in nodes(tree) {
            let c = if by_colour {
                n.contribution * self.exposure
            } else {
                kind_color(n.kind)
            };
            let end = end_of(n, self.reach);
            self.seg(n.origin, end, c);
            let (a, b) = self.shadow_rays(n);
            shadows = (shadows.0 + a, shadows.1 + b);
            match kinds.iter_mut().find(|k| k.0 == n.kind) {
                Some(k) => k.1 += 1,
                None => kinds.push((n.kind, 1)),
            }
        }
        // The camera ray runs along the line of sight: a square where it
        // ends shows it.
        let root = &tree.root;
        let c = if by_colour {
            root.contribution * self.exposure
        } else {
            kind_color(root.kind)
        };
        self.dot(end_of(root, self.reach), c);
        if by_colour {
            let total: usize = kinds.iter().map(|k| k.1).sum();
            self.say(
                None,
                format!(
                    "{total} rays, each in the colour it adds to the pixel (weight x radiance)"
                ),
            );
        } else {
            for (k, count) in kinds {
                self.say(
                    Some(kind_color(k)),
                    format!(
                        "{}: {count} {} {}",
                        kind_color_name(k),
                        kind_name(k),
                        plural(count, "ray")
                    ),
                );
            }
        }
        self.shadow_legend(shadows);
    }

    fn lights(&mut self, tree: &PixelTree) {
        let mut points = 0;
        let mut shadows = (0, 0);
        let mut lights: Vec<(usize, String)> = Vec::new();
        for n in nodes(tree) {
            let (a, b) = self.shadow_rays(n);
            shadows = (shadows.0 + a, shadows.1 + b);
            for l in &n.lights {
                if !lights.iter().any(|(i, _)| *i == l.index) {
                    lights.push((l.index, l.kind.clone()));
                }
                for s in &l.samples {
                    self.dot(s.point, s.color);
                    points += 1;
                }
            }
        }
        if points == 0 {
            self.say(
                None,
                "no light was sampled: no ray of this sample hit a surface",
            );
            return;
        }
        let kinds: Vec<String> = lights
            .iter()
            .map(|(i, k)| format!("light {i} ({k})"))
            .collect();
        self.say(
            None,
            format!(
                "squares: {points} {} on {}, each in the light's colour there",
                plural(points, "point"),
                kinds.join(", ")
            ),
        );
        self.shadow_legend(shadows);
    }

    fn traversal(&mut self, i: usize, r: &TreeRay) {
        let bvh = self.tracer.bvh;
        self.say(None, format!("ray {i}: {}", r.label()));
        if !self.tracer.plan.bvh {
            self.say(
                None,
                "the BVH is off in this plan: rays test every triangle",
            );
            return;
        }
        let ray = r.ray();
        let log = bvh.walk_log(&ray, r.shadow.is_some());
        let path = log.found.map_or(Vec::new(), |t| bvh.path_to(t));
        let (on, off): (Vec<u32>, Vec<u32>) = log.visited.iter().partition(|n| path.contains(n));
        for &n in &off {
            draw_box(
                &mut self.layer,
                &self.tracer.frame,
                &bvh.nodes[n as usize].bounds(),
                Some(OFF_PATH),
            );
        }
        for &n in &on {
            draw_box(
                &mut self.layer,
                &self.tracer.frame,
                &bvh.nodes[n as usize].bounds(),
                Some(ON_PATH),
            );
        }
        let end = match r.shadow {
            Some((_, s)) => s.point,
            None => end_of(r.node, self.reach),
        };
        match log.found {
            Some(t) => {
                self.seg(ray.origin, end, MARK);
                let v = self.triangle(t);
                self.outline(v, TRIANGLE);
                self.say(
                    Some(ON_PATH),
                    format!(
                        "green: {} {} on the path to triangle {t}",
                        on.len(),
                        plural(on.len(), "box")
                    ),
                );
                self.say(
                    Some(OFF_PATH),
                    format!(
                        "red: {} {} entered off that path",
                        off.len(),
                        plural(off.len(), "box")
                    ),
                );
                self.say(
                    Some(TRIANGLE),
                    format!("yellow: triangle {t}, the hit; white: the ray"),
                );
            }
            None => {
                self.seg(ray.origin, end, OFF_PATH);
                let what = if r.shadow.is_some() {
                    "nothing blocks the shadow ray"
                } else {
                    "the ray hits nothing"
                };
                self.say(
                    Some(OFF_PATH),
                    format!(
                        "{what} (red); {} {} entered",
                        off.len(),
                        plural(off.len(), "box")
                    ),
                );
            }
        }
        let st = log.stats;
        self.say(
            None,
            format!(
                "{} visited, {}, {}",
                crate::words::count(st.nodes_visited, "wide node", "wide nodes"),
                crate::words::count(st.leaves, "leaf", "leaves"),
                crate::words::count(st.triangle_tests, "triangle test", "triangle tests"),
            ),
        );
    }

    /// The chosen ray's hit, or a legend line saying why there is none.
    fn hit_of<'n>(&mut self, i: usize, r: &TreeRay<'n>) -> Option<&'n RayNode> {
        self.say(None, format!("ray {i}: {}", r.label()));
        if r.shadow.is_some() {
            self.say(None, "a shadow ray shades nothing: choose a ray that hits");
            return None;
        }
        if r.node.hit.is_none() {
            self.say(None, "the ray hits nothing: choose a ray that hits");
            return None;
        }
        Some(r.node)
    }

    fn normals(&mut self, i: usize, r: &TreeRay) {
        let Some(n) = self.hit_of(i, r) else { return };
        let h = n.hit.as_ref().expect("checked by hit_of");
        let Some(vn) = h.vertex_normals else {
            self.say(
                None,
                format!(
                    "mesh '{}' is flat-shaded: no vertex normals to interpolate",
                    h.mesh
                ),
            );
            return;
        };
        let v = self.triangle(h.triangle);
        // Scaled to the triangle (half its mean edge), and long enough to
        // be seen: at least a twentieth of the distance from the eye.
        let edge = (0..3).map(|k| v[k].distance(v[(k + 1) % 3])).sum::<f32>() / 6.0;
        let seen = h.t * n.dir.length() / 20.0;
        let len = edge.max(seen);
        self.outline(v, GRID * 2.0);
        for k in 0..3 {
            self.seg(v[k], v[k] + vn[k].normalize_or_zero() * len, VERTEX_NORMAL);
        }
        self.seg(h.point, h.point + h.shading_normal * len, INTERPOLATED);
        self.say(
            None,
            format!(
                "triangle {} of '{}' (grey); normals drawn {:.3} long ({})",
                h.triangle,
                h.mesh,
                len,
                if len > edge {
                    "enlarged to be seen"
                } else {
                    "half the triangle's mean edge"
                }
            ),
        );
        self.say(Some(VERTEX_NORMAL), "red: the three vertex normals");
        self.say(
            Some(INTERPOLATED),
            format!(
                "green: the interpolated normal at the hit (barycentric {:.3}, {:.3}, {:.3})",
                h.barycentric.x, h.barycentric.y, h.barycentric.z
            ),
        );
        if !self.tracer.plan.smooth_normals {
            self.say(
                None,
                "smooth normals are off in this plan: shading uses the flat normal",
            );
        }
    }

    fn texture(&mut self, i: usize, r: &TreeRay, pixel: (u32, u32)) {
        let Some(n) = self.hit_of(i, r) else { return };
        let h = n.hit.as_ref().expect("checked by hit_of");
        let scene = self.tracer.scene;
        let Some(uv) = h.uv else {
            self.say(
                None,
                format!(
                    "no texture coordinates at this hit (mesh '{}' has none, or textures are off)",
                    h.mesh
                ),
            );
            return;
        };
        let geo = &scene.geometry;
        let prim = h.triangle as usize;
        let Some(tex) = scene.materials[geo.tri_material[prim] as usize].texture else {
            self.say(None, format!("material '{}' has no texture", h.material));
            return;
        };
        let tex = &scene.textures[tex as usize];
        let idx = geo.indices[prim];
        let t = idx.map(|i| geo.uvs[i as usize]);
        let p = idx.map(|i| geo.positions[i as usize]);
        // The triangle's affine map from uv to the world.
        let (e1, e2) = (t[1] - t[0], t[2] - t[0]);
        let det = e1.perp_dot(e2);
        if det.abs() < f32::EPSILON * e1.length() * e2.length() || !det.is_finite() {
            self.say(None, "the triangle's uv mapping is degenerate");
            return;
        }
        let world = |q: Vec2| {
            let d = q - t[0];
            let (a, b) = (d.perp_dot(e2) / det, e1.perp_dot(d) / det);
            p[0] + (p[1] - p[0]) * a + (p[2] - p[0]) * b
        };
        let (w, hgt) = (tex.width as f32, tex.height as f32);
        let cell = Vec2::new(1.0 / w, 1.0 / hgt);
        // Texel boundaries fall on multiples of 1/size in uv whatever the
        // wrapping; bilinear blends the 2x2 texels whose centres surround uv.
        let (first, n_side) = if self.tracer.plan.bilinear {
            (((uv * Vec2::new(w, hgt)) - 0.5).floor(), 2)
        } else {
            ((uv * Vec2::new(w, hgt)).floor(), 1)
        };
        for j in 0..n_side {
            for k in 0..n_side {
                let lo = (first + Vec2::new(k as f32, j as f32)) * cell;
                let corners = [
                    lo,
                    lo + Vec2::new(cell.x, 0.0),
                    lo + cell,
                    lo + Vec2::new(0.0, cell.y),
                ];
                for c in 0..4 {
                    self.seg(world(corners[c]), world(corners[(c + 1) % 4]), MARK);
                }
            }
        }
        self.dot(h.point, HIT);
        // Texels are often smaller than a pixel: a zoom of the texture
        // around uv shows them, the footprint outlined.
        if let Some((x0, y0, side)) = self.zoom_box(pixel) {
            let across = TEXELS_ACROSS as f32;
            let texel = side as f32 / across;
            // The zoom's top-left texel, so the footprint sits in the middle.
            let origin = (first + n_side as f32 / 2.0 - across / 2.0).floor();
            let to_zoom = |q: Vec2| {
                let t = (q * Vec2::new(w, hgt) - origin) * texel;
                // v grows upward in uv, downward in the picture.
                (x0 as f32 + t.x, y0 as f32 + side as f32 - t.y)
            };
            for j in 0..TEXELS_ACROSS {
                for k in 0..TEXELS_ACROSS {
                    let lo = (origin + Vec2::new(k as f32, j as f32)) * cell;
                    let (ax, ay) = to_zoom(lo);
                    let (bx, by) = to_zoom(lo + cell);
                    let c = tex.nearest(lo + cell * 0.5);
                    self.layer.rect(
                        ax.round() as i32,
                        by.round() as i32,
                        bx.round() as i32 - 1,
                        ay.round() as i32 - 1,
                        Some(c),
                    );
                }
            }
            let (ax, ay) = to_zoom(first * cell);
            let (bx, by) = to_zoom((first + n_side as f32) * cell);
            let (ax, ay, bx, by) = (
                ax.round() as i32,
                ay.round() as i32,
                bx.round() as i32,
                by.round() as i32,
            );
            for o in 0..2 {
                self.layer
                    .rect(ax - o, by - o, bx - 1 + o, by - o, Some(MARK));
                self.layer
                    .rect(ax - o, ay - 1 + o, bx - 1 + o, ay - 1 + o, Some(MARK));
                self.layer
                    .rect(ax - o, by - o, ax - o, ay - 1 + o, Some(MARK));
                self.layer
                    .rect(bx - 1 + o, by - o, bx - 1 + o, ay - 1 + o, Some(MARK));
            }
            if n_side == 2 {
                let (mx, my) = to_zoom((first + 1.0) * cell);
                let (mx, my) = (mx.round() as i32, my.round() as i32);
                self.layer.rect(mx, by, mx, ay - 1, Some(MARK));
                self.layer.rect(ax, my, bx - 1, my, Some(MARK));
            }
            let (ux, uy) = to_zoom(uv);
            let r = (side / 60).max(2);
            let (ux, uy) = (ux.floor() as i32, uy.floor() as i32);
            self.layer.rect(
                ux - r - 1,
                uy - r - 1,
                ux + r + 1,
                uy + r + 1,
                Some(Vec3::ZERO),
            );
            self.layer.rect(ux - r, uy - r, ux + r, uy + r, Some(HIT));
        }
        self.say(
            None,
            format!(
                "uv ({:.4}, {:.4}) on texture '{}' ({}x{}), {}",
                uv.x,
                uv.y,
                tex.name,
                tex.width,
                tex.height,
                if n_side == 2 { "bilinear" } else { "nearest" }
            ),
        );
        self.say(
            Some(MARK),
            if n_side == 2 {
                "white: the four texels bilinear filtering blends, on the surface and in the zoom"
            } else {
                "white: the texel nearest lookup reads, on the surface and in the zoom"
            },
        );
        self.say(Some(HIT), "magenta: the hit point and its uv");
    }

    /// The corner box of a zoom: across from `pixel`, on its half of the
    /// height (the legend takes the other): left, top and side.
    fn zoom_box(&self, pixel: (u32, u32)) -> Option<(i32, i32, i32)> {
        let (w, h) = (self.layer.width as i32, self.layer.height as i32);
        let side = w.min(h) * 2 / 5;
        if side < 24 {
            return None;
        }
        let (px, py) = (pixel.0 as i32, pixel.1 as i32);
        let margin = (w.min(h) / 40).max(2);
        let x0 = if px < w / 2 {
            w - side - margin
        } else {
            margin
        };
        let y0 = if py < h / 2 {
            margin
        } else {
            h - side - margin
        };
        Some((x0, y0, side))
    }

    fn environment(&mut self, i: usize, r: &TreeRay) {
        self.say(None, format!("ray {i}: {}", r.label()));
        let miss = match (&r.shadow, &r.node.miss) {
            (None, Some(m)) => m,
            _ => {
                self.say(
                    None,
                    "no ray of this sample leaves the scene here: choose one that misses",
                );
                return;
            }
        };
        let n = r.node;
        let end = end_of(n, self.reach);
        match &miss.face {
            Some(face) => {
                let uv = miss.uv.unwrap_or_default();
                self.say(
                    Some(miss.color),
                    format!(
                        "the ray in the colour found on face {face} at uv ({:.3}, {:.3})",
                        uv.x, uv.y
                    ),
                );
                // The face's name beside where the ray leaves the picture.
                let frame = &self.tracer.frame;
                let (w, h) = (self.layer.width as f64, self.layer.height as f64);
                let shown = frame
                    .project_clip(n.origin, end, 1e-6)
                    .and_then(|(p, q)| clip_to_rect(p, q, w, h));
                if let Some((_, q)) = shown {
                    let scale = (self.layer.height as i32 / 320).max(1);
                    let (tw, th) = (text_width(face, scale), GLYPH * scale);
                    let gap = 4 * self.dot_radius() + 4;
                    let x = (q.0 as i32 - tw / 2).clamp(0, (self.layer.width as i32 - tw).max(0));
                    let above = q.1 as i32 - th - gap;
                    let y = if above >= 0 { above } else { q.1 as i32 + gap };
                    self.layer
                        .rect(x - 2, y - 2, x + tw + 1, y + th + 1, Some(Vec3::ZERO));
                    self.layer.text(x, y, face, Some(MARK), scale);
                }
            }
            None => self.say(
                Some(miss.color),
                "the ray in the background colour (no environment map)",
            ),
        }
        self.seg(n.origin, end, miss.color);
        self.dot(end, miss.color);
    }

    fn glossy(&mut self, tree: &PixelTree) {
        let mut rays = 0;
        let all = nodes(tree);
        self.expose(
            all.iter()
                .filter(|n| n.kind == RayKind::Glossy)
                .map(|n| &n.contribution),
        );
        for n in all {
            let lobe: Vec<&RayNode> = n
                .children
                .iter()
                .filter(|c| c.kind == RayKind::Glossy)
                .collect();
            let Some(h) = n.hit.as_ref().filter(|_| !lobe.is_empty()) else {
                continue;
            };
            for c in &lobe {
                let end = end_of(c, self.reach);
                self.seg(c.origin, end, c.contribution * self.exposure);
            }
            rays += lobe.len();
            let axis = mirror(n.dir, h.shading_normal, h.geometric_normal);
            let len = lobe
                .iter()
                .map(|c| end_of(c, self.reach).distance(c.origin))
                .fold(f32::INFINITY, f32::min)
                .min(self.reach);
            self.seg(h.point, h.point + axis * len, LOBE_AXIS);
            self.say(
                Some(LOBE_AXIS),
                match &h.pbr {
                    None => format!(
                        "magenta: the lobe axis (mirror direction) at {} (Phong exponent {})",
                        h.mesh, h.ns
                    ),
                    Some(p) => format!(
                        "magenta: the lobe axis (mirror direction) at {} (GGX, roughness {:.3})",
                        h.mesh, p.roughness
                    ),
                },
            );
        }
        if rays == 0 {
            self.say(
                None,
                "no glossy rays in this sample (no glossy surface hit, or glossy reflection is off)",
            );
        } else {
            self.say(
                None,
                format!(
                    "{rays} glossy {}, each in the colour it adds to the pixel",
                    plural(rays, "ray")
                ),
            );
        }
    }

    /// A zoom of the pixel in a corner away from it: the strata, and each
    /// sample where its camera ray passes, in the sample's colour.
    fn samples(&mut self, tree: &PixelTree, spp: u32) {
        let Some((x0, y0, side)) = self.zoom_box((tree.x, tree.y)) else {
            self.say(None, "the image is too small for the zoom");
            return;
        };
        let (px, py) = (tree.x as i32, tree.y as i32);
        // Lines from the pixel to the zoom's corners, then the zoom.
        let c = (px as f64 + 0.5, py as f64 + 0.5);
        for (cx, cy) in [
            (x0, y0),
            (x0 + side, y0),
            (x0, y0 + side),
            (x0 + side, y0 + side),
        ] {
            self.layer
                .line(c, (cx as f64, cy as f64), Some(GRID * 2.0), 1, Some((4, 4)));
        }
        self.layer
            .rect(x0 - 2, y0 - 2, x0 + side + 1, y0 + side + 1, Some(MARK));
        self.layer
            .rect(x0, y0, x0 + side - 1, y0 + side - 1, Some(Vec3::ZERO));
        self.layer.rect(px - 2, py - 2, px + 2, py - 2, Some(MARK));
        self.layer.rect(px - 2, py + 2, px + 2, py + 2, Some(MARK));
        self.layer.rect(px - 2, py - 2, px - 2, py + 2, Some(MARK));
        self.layer.rect(px + 2, py - 2, px + 2, py + 2, Some(MARK));
        let stratified = tree.stratum.is_some();
        if stratified {
            for k in 1..PIXEL_GRID as i32 {
                let o = side * k / PIXEL_GRID as i32;
                self.layer
                    .rect(x0 + o, y0, x0 + o, y0 + side - 1, Some(GRID));
                self.layer
                    .rect(x0, y0 + o, x0 + side - 1, y0 + o, Some(GRID));
            }
        }
        let shown = spp.clamp(1, MAX_ZOOM_SAMPLES);
        let r = (side / 60).max(1);
        let mut sum = Vec3::ZERO;
        for k in 0..shown {
            let t = if k == tree.sample {
                tree.clone()
            } else {
                inspect_pixel(self.tracer, tree.x, tree.y, k)
            };
            let (sx, sy) = (
                x0 + (t.offset.x * side as f32).floor() as i32,
                y0 + (t.offset.y * side as f32).floor() as i32,
            );
            self.layer.rect(
                sx - r - 1,
                sy - r - 1,
                sx + r + 1,
                sy + r + 1,
                Some(GRID * 2.0),
            );
            self.layer
                .rect(sx - r, sy - r, sx + r, sy + r, Some(t.color));
            sum += t.color;
        }
        let mean = sum / shown as f32;
        self.say(
            None,
            format!(
                "pixel ({}, {}): {shown} {} where each camera ray passes, in the sample's colour",
                tree.x,
                tree.y,
                plural(shown as usize, "sample")
            ),
        );
        if spp > shown {
            self.say(None, format!("the first {shown} of {spp} samples shown"));
        }
        self.say(
            Some(GRID),
            if stratified {
                "grey lines: the 4x4 strata; each run of 16 samples visits each once"
            } else if self.tracer.plan.supersampling {
                "uniform random positions (stratification off)"
            } else {
                "supersampling is off: every sample at the pixel's centre"
            },
        );
        self.say(
            Some(mean),
            format!(
                "their mean ({:.3}, {:.3}, {:.3}); white frame: the pixel and its zoom",
                mean.x, mean.y, mean.z
            ),
        );
    }
}

/// The hit point in the texture view.
const HIT: Vec3 = Vec3::new(1.0, 0.0, 1.0);
/// Texels across the texture view's zoom.
const TEXELS_ACROSS: u32 = 8;

/// The most samples the zoom draws.
pub const MAX_ZOOM_SAMPLES: u32 = 1024;

fn plural(n: usize, word: &str) -> String {
    match (n, word) {
        (1, w) => w.to_string(),
        (_, "box") => "boxes".to_string(),
        (_, w) => format!("{w}s"),
    }
}
