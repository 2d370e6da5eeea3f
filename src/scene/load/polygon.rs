//! Polygons of OBJ and PLY faces as triangles: the fan from the first
//! corner wherever it covers the polygon exactly (every convex polygon,
//! so triangles and convex quads come out as they always have), else ear
//! clipping in the plane Newell's method fits to the corners.
//!
//! Ear clipping is the `earcut` crate (Mapbox's algorithm): it hashes
//! corners on a z-order curve, so large polygons take about linear time,
//! and it cures self-intersections and splits what it cannot clip instead
//! of failing, which a hand-written clipper would have to relearn.

use earcut::Earcut;
use glam::DVec3;

/// Polygons of more corners are left as fans: ear clipping may take time
/// quadratic in the corners, and one OBJ line can hold millions.
const MOST_CLIPPED: usize = 1 << 16;

/// Triangulates polygons one after another, reusing its buffers.
#[derive(Default)]
pub(crate) struct Triangulator {
    earcut: Earcut<f64>,
    flat: Vec<[f64; 2]>,
    cut: Vec<u32>,
}

/// The fan from corner `from` of `n` corners: `from, from+1, from+2`, ...
fn fan(n: usize, from: usize, out: &mut Vec<[u32; 3]>) {
    let at = |k: usize| ((from + k) % n) as u32;
    out.extend((1..n - 1).map(|k| [at(0), at(k), at(k + 1)]));
}

/// Whether the quad `points` is the fan from its first corner: its two fan
/// triangles face the same way (it is convex, or flat), as most quads are,
/// which takes no more work.
pub(crate) fn quad_is_fan([p, q, r, s]: [DVec3; 4]) -> bool {
    let (a, b, c) = (q - p, r - p, s - p);
    a.cross(b).dot(b.cross(c)) >= 0.0
}

/// Twice the polygon's area along its normal (Newell's method), corners
/// taken from the first so that far from the origin nothing cancels.
fn newell(points: &[DVec3]) -> DVec3 {
    let o = points[0];
    let mut sum = DVec3::ZERO;
    for w in points[1..].windows(2) {
        sum += (w[0] - o).cross(w[1] - o);
    }
    sum
}

/// Whether the fan from corner `from` covers the polygon exactly: each of
/// its triangles turns the way `normal` does and together they go round
/// `from` at most once (the polygon is star-shaped from that corner).
fn fan_fits(points: &[DVec3], from: usize, normal: DVec3) -> bool {
    let n = points.len();
    let o = points[from];
    let d = |k: usize| points[(from + k) % n] - o;
    // Rounding may tip a flat triangle (three corners on a line) a hair
    // either way: less than this, against the polygon's own area, is flat.
    let flat = -1e-12 * normal.length_squared();
    let first = d(1);
    let mut past_half = false;
    for k in 1..n - 1 {
        let (a, b) = (d(k), d(k + 1));
        if a.cross(b).dot(normal) < flat {
            return false;
        }
        // Turning past half a turn from the first edge and back to it is
        // going round more than once.
        let side = first.cross(b).dot(normal);
        if side < 0.0 {
            past_half = true;
        } else if past_half && side > 0.0 {
            return false;
        }
    }
    true
}

impl Triangulator {
    /// Appends the triangles of the polygon with corners at `points` (at
    /// least three) to `out`, as corner numbers, each turning as the
    /// polygon does. `false` where the polygon fits no plane (its corners
    /// on a line, or a figure of eight whose halves cancel) or is too large
    /// to clip, and is a fan all the same ([`Triangulator::warning`]); a
    /// quad whose fan triangles face the same way is the fan, flat or not.
    pub(crate) fn triangles(&mut self, points: &[DVec3], out: &mut Vec<[u32; 3]>) -> bool {
        let n = points.len();
        if n == 3 {
            out.push([0, 1, 2]);
            return true;
        }
        if let &[p, q, r, s] = points {
            if quad_is_fan([p, q, r, s]) {
                fan(n, 0, out);
                return true;
            }
        }
        let normal = newell(points);
        // The polygon's area against its size: nothing when it fits no plane.
        let size = points
            .iter()
            .map(|p| (*p - points[0]).length_squared())
            .fold(0.0, f64::max);
        let planar = normal.length_squared() > (1e-12 * size).powi(2);
        if planar && fan_fits(points, 0, normal) {
            fan(n, 0, out);
            return true;
        }
        // A quad that is not convex is a fan from its reflex corner.
        if planar && n == 4 && fan_fits(points, 1, normal) {
            fan(n, 1, out);
            return true;
        }
        if !planar || n == 4 || n > MOST_CLIPPED {
            fan(n, 0, out);
            return false;
        }
        // In the plane: `normal` is its z, so the polygon turns
        // anticlockwise there.
        let z = normal.normalize();
        let x = z.any_orthonormal_vector();
        let y = z.cross(x);
        self.flat.clear();
        self.flat.extend(points.iter().map(|p| {
            let d = *p - points[0];
            [d.dot(x), d.dot(y)]
        }));
        self.earcut
            .earcut(self.flat.iter().copied(), &[], &mut self.cut);
        if self.cut.is_empty() {
            fan(n, 0, out);
            return false;
        }
        let flat = &self.flat;
        out.extend(self.cut.chunks_exact(3).map(|t| {
            let [a, b, c] = [t[0], t[1], t[2]];
            let [p, q, r] = [a, b, c].map(|i| flat[i as usize]);
            let turn = (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0]);
            match turn < 0.0 {
                true => [a, c, b],
                false => [a, b, c],
            }
        }));
        true
    }

    /// What a warning says of `count` polygons [`Triangulator::triangles`]
    /// left as fans.
    pub(crate) fn warning(count: usize) -> String {
        match count {
            1 => "a polygon fits no plane (its corners on a line or its edges crossing) \
                  or has more than 65536 corners: triangulated as a fan"
                .into(),
            n => format!(
                "{n} polygons fit no plane (their corners on a line or their edges \
                 crossing) or have more than 65536 corners: triangulated as fans"
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The triangles, and whether the polygon fitted a plane.
    fn cut(points: &[[f64; 3]]) -> (Vec<[u32; 3]>, bool) {
        let mut t = Triangulator::default();
        let p: Vec<DVec3> = points.iter().map(|&p| DVec3::from_array(p)).collect();
        let mut out = Vec::new();
        let fits = t.triangles(&p, &mut out);
        (out, fits)
    }

    /// Twice the area the triangles cover, and whether each turns along
    /// +z.
    fn area(points: &[[f64; 3]], tris: &[[u32; 3]]) -> (f64, bool) {
        let p = |i: u32| DVec3::from_array(points[i as usize]);
        let turns: Vec<f64> = tris
            .iter()
            .map(|t| (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0])).z)
            .collect();
        (turns.iter().sum(), turns.iter().all(|&z| z >= 0.0))
    }

    #[test]
    fn convex_polygons_are_fans_from_the_first_corner() {
        let square = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ];
        assert_eq!(cut(&square), (vec![[0, 1, 2], [0, 2, 3]], true));
        let hexagon: Vec<[f64; 3]> = (0..6)
            .map(|k| {
                let a = k as f64 * std::f64::consts::TAU / 6.0;
                [a.cos(), 1.0 + a.sin(), 0.3 * a.cos()]
            })
            .collect();
        let (t, fits) = cut(&hexagon);
        assert_eq!(t, [[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]]);
        assert!(fits);
        // Corners on a side of a convex polygon keep the fan too.
        let on_side = [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [2.0, 0.0, 0.0],
            [2.0, 1.0, 0.0],
        ];
        assert_eq!(cut(&on_side).0, [[0, 1, 2], [0, 2, 3]]);
    }

    #[test]
    fn concave_polygons_cover_exactly_their_area() {
        // A quad whose corner 1 is reflex: the fan from 1.
        let dart = [
            [0.0, 0.0, 0.0],
            [1.0, 0.4, 0.0],
            [2.0, 0.0, 0.0],
            [1.0, 2.0, 0.0],
        ];
        assert_eq!(cut(&dart), (vec![[1, 2, 3], [1, 3, 0]], true));
        // A U (an outline with a notch), far from the origin and tilted:
        // the fan would cover the notch.
        let u = [
            [0.0, 0.0],
            [3.0, 0.0],
            [3.0, 3.0],
            [2.0, 3.0],
            [2.0, 1.0],
            [1.0, 1.0],
            [1.0, 3.0],
            [0.0, 3.0],
        ];
        let flat: Vec<[f64; 3]> = u.iter().map(|&[x, y]| [x, y, 0.0]).collect();
        let (t, fits) = cut(&flat);
        assert_eq!((t.len(), fits), (6, true));
        let (twice, turning) = area(&flat, &t);
        assert!(turning && (twice - 2.0 * 7.0).abs() < 1e-9, "{twice} {t:?}");
        let far: Vec<[f64; 3]> = u
            .iter()
            .map(|&[x, y]| [1e6 + x, 2e6 + 0.6 * y, 3e6 + 0.8 * y])
            .collect();
        assert_eq!(cut(&far).0, t);
        // Wound the other way round, the triangles are too.
        let back: Vec<[f64; 3]> = flat.iter().rev().copied().collect();
        let (t, _) = cut(&back);
        let (twice, _) = area(&back, &t);
        assert!((twice + 2.0 * 7.0).abs() < 1e-9, "{twice}");
    }

    #[test]
    fn a_polygon_that_goes_round_twice_is_no_fan() {
        // A star polygon (a pentagram): every fan triangle turns one way
        // at first, then the fan crosses itself.
        let star: Vec<[f64; 3]> = (0..5)
            .map(|k| {
                let a = (k * 2) as f64 * std::f64::consts::TAU / 5.0;
                [a.cos(), a.sin(), 0.0]
            })
            .collect();
        let (t, _) = cut(&star);
        assert_ne!(t, [[0, 1, 2], [0, 2, 3], [0, 3, 4]]);
    }

    #[test]
    fn degenerate_polygons_are_fans() {
        for points in [
            // On a line.
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 0.0, 0.0],
                [2.0, 0.0, 0.0],
                [3.0, 0.0, 0.0],
                [4.0, 0.0, 0.0],
            ],
            // A figure of eight whose halves cancel.
            vec![
                [0.0, 0.0, 0.0],
                [1.0, 1.0, 0.0],
                [1.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
            ],
            // One point.
            vec![[1.0; 3]; 6],
        ] {
            let (t, fits) = cut(&points);
            assert_eq!((t.len(), fits), (points.len() - 2, false), "{points:?}");
            assert_eq!(t[0], [0, 1, 2]);
        }
    }

    /// A comb of many teeth is clipped quickly, into one triangle fewer
    /// than corners less one.
    #[test]
    fn large_concave_polygons_are_clipped_quickly() {
        let teeth = 20_000;
        let mut comb = vec![[0.0, -1.0, 0.0]];
        for k in 0..teeth {
            let x = k as f64;
            comb.extend([[x, 0.0, 0.0], [x + 0.5, 5.0, 0.0]]);
        }
        comb.push([teeth as f64, -1.0, 0.0]);
        comb.reverse();
        let start = std::time::Instant::now();
        let (t, fits) = cut(&comb);
        assert!(fits);
        assert!(t.len() <= comb.len() - 2 && t.len() > comb.len() / 2);
        assert!(
            start.elapsed().as_secs_f64() < 10.0,
            "{:?}",
            start.elapsed()
        );
        assert!(area(&comb, &t).1);
    }
}
