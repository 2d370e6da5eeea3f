//! The ray tree as indented lines, shared by `rayterm inspect` and the TUI's
//! debug pane. Long lists of light samples fold into a summary line.

use glam::Vec3;

use super::tree::{LightNode, PixelTree, RayNode};
use crate::bvh::TraversalStats;
use crate::render::recorder::{LightSample, RayKind};

/// Lists longer than this fold unless expanded.
pub(crate) const FOLD_AT: usize = 4;

/// What a line describes, so the TUI can colour it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LineKind {
    Header,
    Ray,
    Detail,
    Light,
    Occluded,
    Visible,
    Fold,
    Result,
}

#[derive(Clone, Debug, PartialEq)]
pub struct TreeLine {
    pub(crate) depth: usize,
    pub kind: LineKind,
    pub text: String,
    /// Set on a foldable list's summary line: its id and whether it is open.
    pub(crate) fold: Option<(usize, bool)>,
    /// Set on a ray's line and a shadow ray's: its number in
    /// [`super::tree_rays`], for the overlays of one ray.
    pub ray: Option<usize>,
}

/// `x` to `digits` significant digits: fixed from 1e-3 to 1e5, scientific
/// outside (a coordinate of a scene 1e-6 across must not read 0.0000).
fn num(x: f32, digits: usize) -> String {
    let a = x.abs();
    if x == 0.0 || !x.is_finite() {
        format!("{x}")
    } else if (1e-3..1e5).contains(&a) {
        let decimals = (digits as i32 - 1 - a.log10().floor() as i32).max(0) as usize;
        format!("{x:.decimals$}")
    } else {
        format!("{x:.*e}", digits - 1)
    }
}

fn v(x: Vec3) -> String {
    format!("({}, {}, {})", num(x.x, 5), num(x.y, 5), num(x.z, 5))
}

fn uv(x: glam::Vec2) -> String {
    format!("({}, {})", num(x.x, 5), num(x.y, 5))
}

fn bvh(s: &TraversalStats) -> String {
    use crate::words::count;
    format!(
        "bvh: {} visited, {} hit, {} missed, {}, {}",
        count(s.nodes_visited, "node", "nodes"),
        count(s.boxes_hit, "box", "boxes"),
        s.boxes_missed,
        count(s.leaves, "leaf", "leaves"),
        count(s.triangle_tests, "triangle test", "triangle tests")
    )
}

struct Out<'a> {
    lines: Vec<TreeLine>,
    next_fold: usize,
    next_ray: usize,
    expanded: &'a dyn Fn(usize) -> bool,
}

impl Out<'_> {
    fn push(&mut self, depth: usize, kind: LineKind, text: String) {
        self.lines.push(TreeLine {
            depth,
            kind,
            text,
            fold: None,
            ray: None,
        });
    }

    /// Numbers the last line as the next ray.
    fn number_ray(&mut self) {
        if let Some(l) = self.lines.last_mut() {
            l.ray = Some(self.next_ray);
        }
        self.next_ray += 1;
    }
}

/// Flattens the tree; `expanded(id)` says which folds are open.
pub fn lines(tree: &PixelTree, expanded: &dyn Fn(usize) -> bool) -> Vec<TreeLine> {
    let mut out = Out {
        lines: Vec::new(),
        next_fold: 0,
        next_ray: 0,
        expanded,
    };
    out.push(
        0,
        LineKind::Header,
        format!(
            "pixel ({}, {}) sample {} seed {} of {} at {}x{}",
            tree.x, tree.y, tree.sample, tree.seed, tree.scene, tree.width, tree.height
        ),
    );
    out.push(
        0,
        LineKind::Result,
        format!("sample colour {}", v(tree.color)),
    );
    if let (Some(b), Some(a)) = (tree.pixel_before_bloom, tree.pixel_after_bloom) {
        out.push(
            0,
            LineKind::Result,
            format!("pixel colour {} before bloom, {} after", v(b), v(a)),
        );
    }
    ray(&mut out, &tree.root, 0);
    if tree.light_samples_not_listed > 0 {
        out.push(
            0,
            LineKind::Result,
            format!(
                "{} more light samples traced, not listed (a tree lists at most {})",
                tree.light_samples_not_listed,
                super::tree::LISTED_LIGHT_SAMPLES
            ),
        );
    }
    out.lines
}

fn ray(out: &mut Out, n: &RayNode, d: usize) {
    let kind = match n.kind {
        RayKind::Camera => "camera ray",
        RayKind::Reflection => "reflection ray",
        RayKind::Glossy => "glossy ray",
        RayKind::Transmission => "transmitted ray",
        RayKind::Diffuse => "diffuse ray",
    };
    out.push(
        d,
        LineKind::Ray,
        format!(
            "{kind} o={} d={} weight {}",
            v(n.origin),
            v(n.dir),
            v(n.weight)
        ),
    );
    out.number_ray();
    out.push(d + 1, LineKind::Detail, bvh(&n.bvh));
    if let Some(h) = &n.hit {
        out.push(
            d + 1,
            LineKind::Detail,
            format!(
                "hit t={} at {} mesh {} material {} triangle {}",
                num(h.t, 7),
                v(h.point),
                h.mesh,
                h.material,
                h.triangle
            ),
        );
        out.push(
            d + 2,
            LineKind::Detail,
            format!("barycentric {}", v(h.barycentric)),
        );
        out.push(
            d + 2,
            LineKind::Detail,
            format!(
                "normal: geometric {} shading {}",
                v(h.geometric_normal),
                v(h.shading_normal)
            ),
        );
        if let Some(vn) = h.vertex_normals {
            out.push(
                d + 2,
                LineKind::Detail,
                format!("vertex normals {} {} {}", v(vn[0]), v(vn[1]), v(vn[2])),
            );
        }
        if let Some(c) = h.uv {
            let texel = h
                .texel
                .map_or(String::new(), |t| format!(" texel {}", v(t)));
            out.push(d + 2, LineKind::Detail, format!("uv {}{texel}", uv(c)));
        }
        match &h.pbr {
            None => out.push(
                d + 2,
                LineKind::Detail,
                format!("kd {} ks {} Ns {}", v(h.kd), v(h.ks), h.ns),
            ),
            Some(p) => {
                out.push(
                    d + 2,
                    LineKind::Detail,
                    format!(
                        "metallic-roughness: base colour {} metallic {:.3} roughness {:.3}",
                        v(h.kd),
                        p.metallic,
                        p.roughness
                    ),
                );
                if let Some(m) = p.normal_mapped {
                    out.push(
                        d + 2,
                        LineKind::Detail,
                        format!("normal map: normal {}", v(m)),
                    );
                }
                if p.emitted != glam::Vec3::ZERO {
                    out.push(d + 2, LineKind::Detail, format!("emits {}", v(p.emitted)));
                }
                if p.occlusion < 1.0 {
                    out.push(
                        d + 2,
                        LineKind::Detail,
                        format!("occlusion {:.3} (of ambient light)", p.occlusion),
                    );
                }
            }
        }
    }
    if let Some(m) = &n.miss {
        let text = match (&m.face, m.uv) {
            (Some(f), Some(c)) => format!(
                "miss: environment face {f} uv {} colour {}",
                uv(c),
                v(m.color)
            ),
            _ => format!("miss: background {}", v(m.color)),
        };
        out.push(
            d + 1,
            LineKind::Detail,
            text + &mis_text(m.mis.as_ref(), false),
        );
    }
    if let Some(e) = &n.emission {
        out.push(
            d + 1,
            LineKind::Detail,
            format!("emits {}{}", v(e.radiance), mis_text(e.mis.as_ref(), false)),
        );
    }
    for l in &n.lights {
        light(out, l, d + 1);
    }
    if let Some(b) = &n.bounce {
        let pdf = b.pdf.map_or("none (one direction)".into(), |p| num(p, 5));
        let ends = if n.children.is_empty() {
            ", ended by Russian roulette"
        } else {
            ""
        };
        out.push(
            d + 1,
            LineKind::Detail,
            format!(
                "bounce: {} lobe{}, pdf {pdf}, factor {}, survival {}{ends}",
                b.lobe.name(),
                if b.regularized { " (regularized)" } else { "" },
                v(b.factor),
                num(b.survival, 4)
            ),
        );
    }
    for c in &n.children {
        ray(out, c, d + 1);
    }
    out.push(
        d + 1,
        LineKind::Result,
        format!(
            "radiance {} contributes {} to the pixel",
            v(n.color),
            v(n.contribution)
        ),
    );
}

/// How a light arrival was weighed between light and BSDF sampling:
/// `light` for the light sample's side, else the BSDF's.
fn mis_text(m: Option<&crate::render::recorder::Mis>, light: bool) -> String {
    m.map_or(String::new(), |m| {
        format!(
            "; MIS weight {} (light {} / bsdf {}; pdfs light {} bsdf {})",
            num(if light { m.light_weight } else { m.bsdf_weight }, 4),
            num(m.light_weight, 4),
            num(m.bsdf_weight, 4),
            num(m.light_pdf, 5),
            num(m.bsdf_pdf, 5)
        )
    })
}

/// One light sample, its verdict first so that a narrow pane shows it.
fn sample_line(s: &LightSample) -> (LineKind, String) {
    let at = format!(
        "point {} colour {}{}",
        v(s.point),
        v(s.color),
        mis_text(s.mis.as_ref(), true)
    );
    match (&s.shadow_ray, &s.occluder) {
        // With shadows off no ray is traced, and a facing light counts.
        (None, _) if s.visible => (
            LineKind::Detail,
            format!(
                "not shadow-tested (shadows off), diffuse {} specular {}: {at}",
                v(s.diffuse),
                v(s.specular)
            ),
        ),
        (None, _) => (LineKind::Detail, format!("behind the surface: {at}")),
        (Some(r), Some((mesh, tri))) => (
            LineKind::Occluded,
            format!(
                "occluded by {mesh} triangle {tri}: {at}; shadow ray o={} d={}",
                v(r.origin),
                v(r.dir)
            ),
        ),
        (Some(r), None) => (
            LineKind::Visible,
            format!(
                "clear, diffuse {} specular {}: {at}; shadow ray o={} d={}",
                v(s.diffuse),
                v(s.specular),
                v(r.origin),
                v(r.dir)
            ),
        ),
    }
}

/// How a light's samples ended: `12 clear, 4 occluded`, leaving out the
/// kinds that did not occur.
fn verdicts(samples: &[LightSample]) -> String {
    let untested = |s: &&LightSample| s.shadow_ray.is_none();
    let behind = samples
        .iter()
        .filter(untested)
        .filter(|s| !s.visible)
        .count();
    let unshadowed = samples
        .iter()
        .filter(untested)
        .filter(|s| s.visible)
        .count();
    let occluded = samples.iter().filter(|s| s.occluder.is_some()).count();
    let clear = samples.len() - behind - unshadowed - occluded;
    let parts: Vec<String> = [
        (clear, "clear"),
        (occluded, "occluded"),
        (behind, "behind the surface"),
        (unshadowed, "not shadow-tested"),
    ]
    .iter()
    .filter(|(n, _)| *n > 0)
    .map(|(n, what)| format!("{n} {what}"))
    .collect();
    parts.join(", ")
}

fn light(out: &mut Out, l: &LightNode, d: usize) {
    let visible = l.samples.iter().filter(|s| s.visible).count();
    out.push(
        d,
        LineKind::Light,
        format!(
            "light {} ({}): {} of {} samples visible; diffuse {} specular {}",
            l.index,
            l.kind,
            visible,
            l.samples.len(),
            v(l.diffuse),
            v(l.specular)
        ),
    );
    if l.bvh != TraversalStats::default() {
        out.push(d + 1, LineKind::Detail, format!("shadow {}", bvh(&l.bvh)));
    }
    if l.samples.len() > FOLD_AT {
        let id = out.next_fold;
        out.next_fold += 1;
        let open = (out.expanded)(id);
        let mean_colour = l.samples.iter().map(|s| s.color).sum::<Vec3>() / l.samples.len() as f32;
        out.lines.push(TreeLine {
            depth: d + 1,
            kind: LineKind::Fold,
            text: format!(
                "{} {} samples: {}; mean colour {}",
                if open { "[-]" } else { "[+]" },
                l.samples.len(),
                verdicts(&l.samples),
                v(mean_colour)
            ),
            fold: Some((id, open)),
            ray: None,
        });
        if !open {
            // The folded shadow rays keep their numbers.
            out.next_ray += l.samples.iter().filter(|s| s.shadow_ray.is_some()).count();
            return;
        }
    }
    for s in &l.samples {
        let (kind, text) = sample_line(s);
        out.push(d + 1, kind, text);
        if s.shadow_ray.is_some() {
            out.number_ray();
        }
    }
}

/// Plain text, two spaces per level.
pub fn to_text(tree: &PixelTree, expand_all: bool) -> String {
    lines(tree, &|_| expand_all)
        .iter()
        .map(|l| format!("{}{}\n", "  ".repeat(l.depth), l.text))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::num;

    #[test]
    fn numbers_keep_their_significant_digits_at_any_scale() {
        assert_eq!(num(0.0, 5), "0");
        assert_eq!(num(1.0, 5), "1.0000");
        assert_eq!(num(-0.25, 5), "-0.25000");
        assert_eq!(num(3.4, 5), "3.4000");
        assert_eq!(num(1234.5678, 5), "1234.6");
        assert_eq!(num(0.0012345, 5), "0.0012345");
        assert_eq!(num(1.2345e-6, 5), "1.2345e-6");
        assert_eq!(num(-3.4e-6, 5), "-3.4000e-6");
        assert_eq!(num(2.0e7, 5), "2.0000e7");
        assert_eq!(num(3.4e-6, 7), "3.400000e-6");
        assert_eq!(num(f32::NAN, 5), "NaN");
        assert_eq!(num(f32::INFINITY, 5), "inf");
    }
}
