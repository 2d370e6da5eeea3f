//! The tree's rays numbered as the text shows them: each ray, then its
//! shadow rays, then the rays it spawned. `render --debug` lists them so,
//! and the debug views of one ray pick one by its number.

use super::tree::{PixelTree, RayNode};
use crate::geometry::Ray;
use crate::render::recorder::{LightSample, RayKind};

/// How a ray of `kind` is named.
pub(crate) fn kind_name(k: RayKind) -> &'static str {
    match k {
        RayKind::Camera => "camera",
        RayKind::Reflection => "reflection",
        RayKind::Glossy => "glossy",
        RayKind::Transmission => "transmitted",
        RayKind::Diffuse => "diffuse",
    }
}

/// One ray of a tree: a traced ray, or a shadow ray of one of its hits.
pub struct TreeRay<'a> {
    pub(crate) node: &'a RayNode,
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

    pub(crate) fn label(&self) -> String {
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
