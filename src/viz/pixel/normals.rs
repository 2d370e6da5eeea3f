//! The `normals` view: one hit's vertex normals and the normal
//! interpolated between them.

use glam::Vec3;

use super::{Drawing, GRID};
use crate::inspect::TreeRay;

/// The vertex normals and the interpolated one.
pub const VERTEX_NORMAL: Vec3 = Vec3::new(1.0, 0.0, 0.0);
pub const INTERPOLATED: Vec3 = Vec3::new(0.0, 1.0, 0.0);

impl Drawing<'_, '_> {
    pub(super) fn normals(&mut self, i: usize, r: &TreeRay) {
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
}
