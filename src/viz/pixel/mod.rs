//! The views of one pixel's ray tree, drawn over the image: its rays (by
//! kind or in the colour they add), the points sampled on lights, one ray's
//! BVH walk, the normals, texel footprint and environment lookup of one
//! ray, the glossy lobes, and a zoom of the pixel's sub-pixel samples; one
//! file each. Everything drawn is read from the recorded tree (and the
//! scene it names); `rayterm render --debug ray:X,Y:VIEW` and the TUI's `o`
//! draw the same layers.

mod environment;
mod glossy;
mod lights;
mod normals;
mod rays;
mod samples;
mod texture;
mod traversal;

use anyhow::{bail, Result};
use glam::Vec3;

use super::draw::{draw_segment, Layer, Legend};
use super::View;
use crate::inspect::{tree_rays, PixelTree, RayNode, TreeRay};
use crate::raster::canvas::Canvas;
use crate::render::Tracer;
use crate::scene::Scene;
pub use glossy::LOBE_AXIS;
pub use normals::{INTERPOLATED, VERTEX_NORMAL};
pub use rays::kind_color;
pub use traversal::{OFF_PATH, ON_PATH, TRIANGLE};

/// A drawn overlay and its legend.
pub struct Overlay {
    pub layer: Layer,
    pub legend: Legend,
    /// Where the legend goes to stay clear of the pixel and the zooms.
    pub(crate) legend_bottom: bool,
    /// The views of colours rays add draw them times this, so that the
    /// brightest shows at full strength (1 when it already does, or for
    /// other views); the legend says so.
    pub exposure: f32,
}

/// Texel outlines, the sample zoom's frame and the face's name.
pub const MARK: Vec3 = Vec3::ONE;
const GRID: Vec3 = Vec3::splat(0.25);

/// How far rays that miss are drawn: twice the scene's diagonal.
fn ray_reach(scene: &Scene) -> f32 {
    2.0 * scene.bounds().extent().length()
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

/// Draws `view`, a view of a pixel's tree, of `tree` (a sample of the tracer's image). `ray` picks the
/// ray of the one-ray views (see [`tree_rays`]; by default the camera ray,
/// or for `environment` the first ray that misses); `spp` is how many
/// samples the `samples` zoom shows.
pub fn draw(
    tracer: &Tracer,
    tree: &PixelTree,
    view: View,
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
        View::Rays => d.rays(tree, false),
        View::Colour => d.rays(tree, true),
        View::Lights => d.lights(tree),
        View::Traversal => {
            let (i, r) = chosen(0);
            d.traversal(i, r)
        }
        View::Normals => {
            let (i, r) = chosen(0);
            d.normals(i, r)
        }
        View::Texture => {
            let (i, r) = chosen(0);
            d.texture(i, r, (tree.x, tree.y))
        }
        View::Environment => {
            let first_miss = rays
                .iter()
                .position(|r| r.shadow.is_none() && r.node.miss.is_some());
            let (i, r) = chosen(first_miss.unwrap_or(0));
            d.environment(i, r)
        }
        View::Glossy => d.glossy(tree),
        View::Samples => d.samples(tree, spp),
        _ => bail!("{view} is not a view of a pixel's tree"),
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
}

fn plural(n: usize, word: &str) -> String {
    match (n, word) {
        (1, w) => w.to_string(),
        (_, "box") => "boxes".to_string(),
        (_, w) => format!("{w}s"),
    }
}
