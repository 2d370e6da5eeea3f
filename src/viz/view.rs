//! The one name of every debug view: what `--debug` parses, what the TUI's
//! `g` and `o` cycle through and what the status line calls each.

use std::fmt;

use super::heat::HeatMeasure;

/// A debug view.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum View {
    /// `bvh-level:K`: the boxes of level K over the image.
    Level(usize),
    /// `bvh-leaves`: the leaf boxes over the image.
    Leaves,
    /// `bvh-heat` (nodes visited) or `bvh-heat:tests`: each camera ray's
    /// traversal work.
    Heat(HeatMeasure),
    /// `bloom`: the pixels over bloom's threshold and their glow.
    Bloom,
    /// Samples per pixel.
    Spp,
    /// Estimated relative error per pixel.
    Error,
    /// Every ray of a pixel's tree in its kind's colour.
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

/// What a view is drawn from, which says when it is drawn.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum DrawnFrom {
    /// The BVH and the camera: a layer over the image, once per view of
    /// the scene.
    Bvh,
    /// The film: a picture in place of the image, from each pass.
    Film,
    /// One pixel's recorded ray tree: a layer over the image.
    Tree,
}

/// The views of the whole image in the order the TUI's `g` cycles them,
/// the boxes at `level`.
pub(crate) fn image_views(level: usize) -> [View; 7] {
    [
        View::Level(level),
        View::Leaves,
        View::Heat(HeatMeasure::NodesVisited),
        View::Heat(HeatMeasure::TriangleTests),
        View::Bloom,
        View::Spp,
        View::Error,
    ]
}

/// The views of a pixel's tree, in the order the TUI's `o` cycles them.
pub(crate) const PIXEL_VIEWS: [View; 9] = [
    View::Rays,
    View::Colour,
    View::Lights,
    View::Traversal,
    View::Normals,
    View::Texture,
    View::Environment,
    View::Glossy,
    View::Samples,
];

impl View {
    pub(crate) fn source(self) -> DrawnFrom {
        match self {
            View::Level(_) | View::Leaves | View::Heat(_) => DrawnFrom::Bvh,
            View::Bloom | View::Spp | View::Error => DrawnFrom::Film,
            _ => DrawnFrom::Tree,
        }
    }

    /// Whether the view shows one chosen ray of a pixel's tree.
    pub(crate) fn one_ray(self) -> bool {
        matches!(
            self,
            View::Traversal | View::Normals | View::Texture | View::Environment
        )
    }

    /// How the TUI's status line names it.
    pub(crate) fn title(self) -> String {
        match self {
            View::Level(k) => return format!("boxes of level {k}"),
            View::Leaves => "leaf boxes",
            View::Heat(HeatMeasure::NodesVisited) => "heat map of nodes visited",
            View::Heat(HeatMeasure::TriangleTests) => "heat map of triangle tests",
            View::Bloom => "bloom: the pixels over its threshold and their glow",
            View::Spp => "samples per pixel",
            View::Error => "estimated relative error per pixel",
            View::Rays => "rays by kind",
            View::Colour => "rays in the colour they add",
            View::Lights => "points sampled on lights",
            View::Traversal => "BVH traversal",
            View::Normals => "normals",
            View::Texture => "texel footprint",
            View::Environment => "environment lookup",
            View::Glossy => "glossy rays and lobe",
            View::Samples => "zoom of the pixel's samples",
        }
        .into()
    }

    /// The view after `now` in `cycle`: the first after none, none after
    /// the last. The boxes of any level count as the cycle's boxes.
    pub(crate) fn next(cycle: &[View], now: Option<View>) -> Option<View> {
        let same = |a: View, b: View| a == b || matches!((a, b), (View::Level(_), View::Level(_)));
        match now.and_then(|v| cycle.iter().position(|&c| same(c, v))) {
            None => cycle.first().copied(),
            Some(i) => cycle.get(i + 1).copied(),
        }
    }

    /// A view of the BVH by its `--debug` name.
    pub(crate) fn parse_bvh(s: &str) -> Result<View, String> {
        const VIEWS: &str = "bvh-level:K, bvh-leaves, bvh-heat or bvh-heat:tests";
        let (name, arg) = match s.split_once(':') {
            Some((n, a)) => (n, Some(a)),
            None => (s, None),
        };
        match (name, arg) {
            ("bvh-level", Some(k)) => k.trim().parse().map(View::Level).map_err(|_| {
                format!("'{s}': the level must be a whole number from 0, as in bvh-level:3")
            }),
            ("bvh-level", None) => Err("bvh-level needs a level, as in bvh-level:3".into()),
            ("bvh-leaves", None) => Ok(View::Leaves),
            ("bvh-heat", None | Some("nodes")) => Ok(View::Heat(HeatMeasure::NodesVisited)),
            ("bvh-heat", Some("tests")) => Ok(View::Heat(HeatMeasure::TriangleTests)),
            ("bvh-heat", Some(m)) => Err(format!(
                "'{s}': unknown measure '{m}' (bvh-heat counts nodes; bvh-heat:tests counts triangle tests)"
            )),
            _ => Err(format!("unknown debug view '{s}': expected {VIEWS}")),
        }
    }

    /// A view of a pixel's tree by its name (`color` and `env` too).
    pub(crate) fn parse_pixel(s: &str) -> Result<View, String> {
        match s {
            "color" => return Ok(View::Colour),
            "env" => return Ok(View::Environment),
            _ => {}
        }
        PIXEL_VIEWS
            .iter()
            .copied()
            .find(|v| v.to_string() == s)
            .ok_or_else(|| {
                let names: Vec<String> = PIXEL_VIEWS.iter().map(|v| v.to_string()).collect();
                format!("unknown overlay '{s}': expected {}", names.join(", "))
            })
    }
}

/// The `--debug` name: `bvh-level:3`, `bloom`, `traversal` (a pixel view's
/// name after `ray:X,Y:`).
impl fmt::Display for View {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            View::Level(k) => return write!(f, "bvh-level:{k}"),
            View::Leaves => "bvh-leaves",
            View::Heat(HeatMeasure::NodesVisited) => "bvh-heat",
            View::Heat(HeatMeasure::TriangleTests) => "bvh-heat:tests",
            View::Bloom => "bloom",
            View::Spp => "spp",
            View::Error => "error",
            View::Rays => "rays",
            View::Colour => "colour",
            View::Lights => "lights",
            View::Traversal => "traversal",
            View::Normals => "normals",
            View::Texture => "texture",
            View::Environment => "environment",
            View::Glossy => "glossy",
            View::Samples => "samples",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_view_and_rejects_bad_ones() {
        for s in ["bvh-level:3", "bvh-leaves", "bvh-heat", "bvh-heat:tests"] {
            let v = View::parse_bvh(s).unwrap();
            assert_eq!(v.to_string(), s);
        }
        assert_eq!(
            View::parse_bvh("bvh-heat:nodes"),
            Ok(View::Heat(HeatMeasure::NodesVisited))
        );
        for bad in [
            "bvh-level:x",
            "bvh-level:-1",
            "bvh-level",
            "bvh",
            "bvh-heat:t",
        ] {
            let e = View::parse_bvh(bad).unwrap_err();
            assert!(e.contains("bvh-"), "{bad}: {e}");
        }
        assert!(View::parse_bvh("bvh-level:x")
            .unwrap_err()
            .contains("whole number"));
        for v in PIXEL_VIEWS {
            assert_eq!(View::parse_pixel(&v.to_string()), Ok(v));
        }
    }

    #[test]
    fn cycles_end_in_none_and_start_again() {
        let g = image_views(2);
        assert_eq!(View::next(&g, None), Some(View::Level(2)));
        // A level changed since counts as the cycle's boxes.
        assert_eq!(View::next(&g, Some(View::Level(5))), Some(View::Leaves));
        assert_eq!(View::next(&g, Some(View::Error)), None);
        assert_eq!(
            View::next(&PIXEL_VIEWS, Some(View::Rays)),
            Some(View::Colour)
        );
    }
}
