//! The `texture` view: one hit's texel footprint on the surface, and a
//! zoom of the texture around it.

use glam::{Vec2, Vec3};

use super::{Drawing, MARK};
use crate::inspect::TreeRay;

/// The hit point in the texture view.
const HIT: Vec3 = Vec3::new(1.0, 0.0, 1.0);
/// Texels across the texture view's zoom.
const TEXELS_ACROSS: u32 = 8;

impl Drawing<'_, '_> {
    pub(super) fn texture(&mut self, i: usize, r: &TreeRay, pixel: (u32, u32)) {
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
        // The coordinates the texture reads: its UV set, moved by its
        // transform.
        let mesh = &scene.meshes[geo.tri_mesh[prim] as usize];
        let Some(t) = geo.corner_uvs(mesh, prim, tex.uv.set) else {
            let set = tex.uv.set;
            self.say(None, format!("mesh '{}' has no TEXCOORD_{set}", h.mesh));
            return;
        };
        let t = t.map(|c| tex.uv.apply(c));
        let uv = match (tex.uv.set, tex.uv.transform) {
            (0, None) => uv,
            _ => {
                let b = h.barycentric;
                t[0] * b.x + t[1] * b.y + t[2] * b.z
            }
        };
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
}
