//! Bicubic Bézier patches: the `.bpt` text format and a watertight tessellator.
//!
//! # The `.bpt` format
//!
//! Eric Haines' SPD "Bézier patch text": the first significant line holds the
//! number of patches; each patch is a line `3 3` (the degrees in u and v; only
//! bicubic patches are supported) followed by 16 lines `x y z`, the control
//! points row by row. `#` starts a comment that runs to the end of the line,
//! and blank lines are ignored.
//!
//! A patch is stored as `[[Vec3; 4]; 4]` indexed `[row][column]`, i.e. control
//! point `k` of the file is `patch[k / 4][k % 4]`. The parameter `u` runs along
//! a row (over the columns) and `v` down the columns (over the rows):
//!
//! ```text
//! S(u, v) = sum_i sum_j B_i(v) B_j(u) patch[i][j]
//! ```
//!
//! The surface normal is `cross(dS/du, dS/dv)`, and triangles are wound
//! counter-clockwise around it. For `data/teapot.bpt` that normal points out of
//! the teapot on every patch.
//!
//! # Watertight seams
//!
//! Patches get their own vertices (nothing is shared between patches), but a
//! point on a patch edge depends only on the four control points of that edge
//! and is evaluated bit-identically by both neighbours, even when one of them
//! runs along the edge in the opposite direction (the teapot's body/bottom
//! seam does). Three things make this hold:
//!
//! * the grid parameters are `t_i = i / N` and `s_i = (N - i) / N`, each
//!   computed by one correctly rounded division, so walking an edge backwards
//!   simply swaps `s` and `t`;
//! * points are evaluated by de Casteljau's algorithm with a *symmetric* lerp
//!   (`lerp_sym`): `lerp_sym(a, b, s, t) == lerp_sym(b, a, t, s)` bit for
//!   bit, it returns `a` exactly at `t == 0`, and it returns `a` exactly when
//!   `a == b` (so collapsed edges such as the teapot's lid and bottom poles
//!   evaluate to one exact point and their zero-area triangles can be dropped
//!   by an exact test);
//! * the tensor product reduces the rows first and then the resulting column;
//!   on an edge `v = 0`/`v = 1` the column step returns the reduced edge row
//!   exactly, and on an edge `u = 0`/`u = 1` the row step returns the edge
//!   column's control points exactly, so either way the edge point is the
//!   one-dimensional evaluation of the edge's four control points.
//!
//! On the teapot this makes the mesh, welded by exact bit pattern, a surface
//! whose only open edges are the ones in the original data (the lid rim, the
//! rim's inner lip and the two ends of the handle and of the spout): `16 N`
//! boundary edges, every other edge shared by exactly two triangles (see the
//! `teapot_seams_are_bit_identical` test). At `N = 8` the 1,024 patch-boundary
//! grid points have 513 distinct positions, the same count as exact rational
//! arithmetic gives. For comparison, the textbook sum
//! `sum B_i(v) B_j(u) P_ij` with `s = 1 - t` is not exact at the poles
//! (sliver triangles survive the zero-area test: 8 at `N = 8`, 16 at
//! `N = 16`) and at `N = 16` it opens the body/bottom seam, whose two sides
//! run in opposite directions (288 boundary edges instead of 256).

use crate::words::quoted;
use glam::{Vec2, Vec3};

/// One bicubic Bézier patch: control points indexed `[row][column]`
/// (`v` selects the row, `u` the column).
pub(crate) type Patch = [[Vec3; 4]; 4];

/// Largest tessellation level [`tessellate`] honours; larger requests are
/// clamped.
pub(crate) const MAX_SEGMENTS: u32 = 1024;

/// Largest coordinate magnitude [`parse_bpt`] accepts. Keeping coordinates
/// well inside the `f32` range keeps every evaluation step finite.
pub(crate) const MAX_COORDINATE: f32 = 1.0e15;

/// Lines one patch takes in a `.bpt` file: the degree line plus 16 points.
const LINES_PER_PATCH: usize = 17;

/// A `.bpt` parse error: the 1-based line it was found on and what is wrong.
///
/// Errors about a missing end of file point at the line just past the last
/// line of the text.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("line {line}: {message}")]
pub struct BptError {
    /// 1-based line number.
    pub(crate) line: usize,
    /// Human-readable description.
    pub(crate) message: String,
}

fn error(line: usize, message: impl Into<String>) -> BptError {
    BptError {
        line,
        message: message.into(),
    }
}

/// Parses `.bpt` text into bicubic patches.
///
/// Never panics; rejects (with the offending line) a missing or malformed
/// patch count, a zero count, a count larger than the file can hold, degrees
/// other than `3 3`, lines with the wrong number of values, unparsable,
/// non-finite or absurdly large ([`MAX_COORDINATE`]) coordinates, truncated
/// files and trailing data after the last patch. Memory use is bounded by the
/// size of the text, whatever count the file declares.
pub fn parse_bpt(text: &str) -> Result<Vec<Patch>, BptError> {
    // Significant lines only: comments stripped, blank lines skipped.
    let lines: Vec<(usize, &str)> = text
        .lines()
        .enumerate()
        .filter_map(|(index, raw)| {
            let content = match raw.find('#') {
                Some(hash) => &raw[..hash],
                None => raw,
            }
            .trim();
            (!content.is_empty()).then_some((index + 1, content))
        })
        .collect();
    let end_line = text.lines().count() + 1;

    let Some(&(count_line, count_text)) = lines.first() else {
        return Err(error(
            end_line,
            "unexpected end of file: expected the number of patches",
        ));
    };
    let mut tokens = count_text.split_whitespace();
    let (Some(count_token), None) = (tokens.next(), tokens.next()) else {
        return Err(error(
            count_line,
            format!(
                "expected the number of patches alone on a line, found '{}'",
                quoted(count_text)
            ),
        ));
    };
    let count: usize = count_token.parse().map_err(|_| {
        error(
            count_line,
            format!("invalid number of patches '{}'", quoted(count_token)),
        )
    })?;
    if count == 0 {
        return Err(error(count_line, "the file declares 0 patches"));
    }
    let available = lines.len() - 1;
    if count
        .checked_mul(LINES_PER_PATCH)
        .is_none_or(|needed| needed > available)
    {
        return Err(error(
            count_line,
            format!(
                "the file declares {count} patches ({LINES_PER_PATCH} lines each) but only \
                 {available} data lines follow: truncated file or wrong patch count"
            ),
        ));
    }

    let mut patches = Vec::with_capacity(count);
    let mut rest = lines[1..].iter().copied();
    for patch_index in 1..=count {
        let Some((line, degree_text)) = rest.next() else {
            return Err(error(
                end_line,
                format!("unexpected end of file: expected patch {patch_index} of {count}"),
            ));
        };
        parse_degrees(line, degree_text, patch_index)?;

        let mut patch = [[Vec3::ZERO; 4]; 4];
        for point_index in 0..16 {
            let Some((line, point_text)) = rest.next() else {
                return Err(error(
                    end_line,
                    format!(
                        "unexpected end of file: expected control point {} of patch {patch_index}",
                        point_index + 1
                    ),
                ));
            };
            patch[point_index / 4][point_index % 4] =
                parse_point(line, point_text, point_index + 1, patch_index)?;
        }
        patches.push(patch);
    }
    if let Some((line, _)) = rest.next() {
        return Err(error(
            line,
            format!("unexpected data after the last of {count} patches"),
        ));
    }
    Ok(patches)
}

fn parse_degrees(line: usize, text: &str, patch_index: usize) -> Result<(), BptError> {
    let tokens: Vec<&str> = text.split_whitespace().collect();
    let degrees = match tokens.as_slice() {
        [u, v] => u.parse::<u32>().ok().zip(v.parse::<u32>().ok()),
        _ => None,
    };
    match degrees {
        Some((3, 3)) => Ok(()),
        Some((u, v)) => Err(error(
            line,
            format!(
                "patch {patch_index} has degrees {u} {v}: only bicubic patches ('3 3') are supported"
            ),
        )),
        None => Err(error(
            line,
            format!(
                "expected the degrees of patch {patch_index} ('3 3'), found '{}'",
                quoted(text)
            ),
        )),
    }
}

fn parse_point(
    line: usize,
    text: &str,
    point_index: usize,
    patch_index: usize,
) -> Result<Vec3, BptError> {
    let tokens: Vec<&str> = text.split_whitespace().collect();
    if tokens.len() != 3 {
        return Err(error(
            line,
            format!(
                "expected 3 coordinates 'x y z' for control point {point_index} of patch \
                 {patch_index}, found {} values",
                tokens.len()
            ),
        ));
    }
    let mut point = [0.0f32; 3];
    for (value, token) in point.iter_mut().zip(&tokens) {
        let parsed: f32 = token
            .parse()
            .map_err(|_| error(line, format!("invalid coordinate '{}'", quoted(token))))?;
        // Beyond f32 but finite as written: out of range, not "non-finite".
        let written_finite = token.parse::<f64>().is_ok_and(f64::is_finite);
        if !parsed.is_finite() && !written_finite {
            return Err(error(
                line,
                format!("non-finite coordinate '{}'", quoted(token)),
            ));
        }
        if !parsed.is_finite() || parsed.abs() > MAX_COORDINATE {
            return Err(error(
                line,
                format!(
                    "coordinate '{}' is out of range (|x| <= {MAX_COORDINATE:e})",
                    quoted(token)
                ),
            ));
        }
        // `+ 0.0` turns -0 into +0, so equal-looking points are equal bit for bit.
        *value = parsed + 0.0;
    }
    Ok(Vec3::from_array(point))
}

/// A tessellated patch set: one vertex per grid point of every patch
/// (vertices are not shared between patches), counter-clockwise triangles.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PatchMesh {
    /// Vertex positions.
    pub positions: Vec<Vec3>,
    /// Unit surface normals, `normalize(cross(dS/du, dS/dv))`.
    pub normals: Vec<Vec3>,
    /// The patch parameters `(u, v)` of each vertex, in `[0, 1]`.
    pub(crate) uvs: Vec<Vec2>,
    /// Triangles, counter-clockwise around the surface normal.
    pub indices: Vec<[u32; 3]>,
}

/// Tessellates `patches` into an `(N + 1) x (N + 1)` vertex grid each
/// (`N = segments`, clamped to `1..=MAX_SEGMENTS`), two triangles per grid cell
/// split along the `(u0, v0)-(u1, v1)` diagonal.
///
/// Triangles with exactly zero area (the collapsed rows at a pole, where two
/// of their vertices are bit-identical) and triangles with non-finite
/// positions are left out, so for the teapot the count is
/// `32 * 2 * N^2 - 8 * N`. Vertices of dropped triangles stay in the vertex
/// arrays unreferenced. Patches beyond what `u32` indices can address are
/// ignored (more than 4,000 patches at the maximum level).
pub fn tessellate(patches: &[Patch], segments: u32) -> PatchMesh {
    let n = segments.clamp(1, MAX_SEGMENTS);
    let row = n as usize + 1;
    let per_patch = row * row;
    let max_patches = (u32::MAX as usize) / per_patch;
    let patches = &patches[..patches.len().min(max_patches)];

    // (s, t) = ((N - i) / N, i / N): reversing an edge swaps s and t exactly.
    let params: Vec<(f32, f32)> = (0..=n)
        .map(|i| ((n - i) as f32 / n as f32, i as f32 / n as f32))
        .collect();

    let mut mesh = PatchMesh {
        positions: Vec::with_capacity(patches.len() * per_patch),
        normals: Vec::with_capacity(patches.len() * per_patch),
        uvs: Vec::with_capacity(patches.len() * per_patch),
        indices: Vec::with_capacity(patches.len() * 2 * (row - 1) * (row - 1)),
    };
    for patch in patches {
        let base = mesh.positions.len() as u32;
        for &(sv, tv) in &params {
            for &(su, tu) in &params {
                let eval = evaluate(patch, (su, tu), (sv, tv));
                mesh.positions.push(eval.position);
                mesh.normals.push(eval.normal(patch, tu, tv));
                mesh.uvs.push(Vec2::new(tu, tv));
            }
        }
        let row = row as u32;
        for i in 0..n {
            for j in 0..n {
                let a = base + i * row + j; // (u0, v0)
                let b = a + 1; // (u1, v0)
                let c = a + row + 1; // (u1, v1)
                let d = a + row; // (u0, v1)
                for triangle in [[a, b, c], [a, c, d]] {
                    if has_area(&mesh.positions, triangle) {
                        mesh.indices.push(triangle);
                    }
                }
            }
        }
    }
    mesh
}

/// `true` unless two corners coincide, the cross product of the edges is
/// exactly zero, or a position is not finite.
fn has_area(positions: &[Vec3], [a, b, c]: [u32; 3]) -> bool {
    let (pa, pb, pc) = (
        positions[a as usize],
        positions[b as usize],
        positions[c as usize],
    );
    if pa == pb || pb == pc || pa == pc {
        return false;
    }
    let cross = (pb - pa).cross(pc - pa);
    cross.is_finite() && cross != Vec3::ZERO
}

/// Symmetric linear interpolation between `a` (at `t = 0`) and `b` (at
/// `t = 1`), with `s = 1 - t` supplied separately.
///
/// `lerp_sym(a, b, s, t)` and `lerp_sym(b, a, t, s)` are bit-identical (both
/// take the branch anchored at the nearer end; the midpoint is the
/// commutative `(a + b) / 2`), the ends are exact (`t == 0` gives `a`), and
/// `a == b` gives exactly `a`.
#[inline]
fn lerp_sym(a: Vec3, b: Vec3, s: f32, t: f32) -> Vec3 {
    if t < s {
        a + (b - a) * t
    } else if s < t {
        b + (a - b) * s
    } else {
        (a + b) * 0.5
    }
}

/// A cubic Bézier curve at parameter `t` (`s = 1 - t`): the point (de
/// Casteljau with [`lerp_sym`]) and the derivative with respect to `t`.
#[inline]
fn cubic(p: &[Vec3; 4], s: f32, t: f32) -> (Vec3, Vec3) {
    let p01 = lerp_sym(p[0], p[1], s, t);
    let p12 = lerp_sym(p[1], p[2], s, t);
    let p23 = lerp_sym(p[2], p[3], s, t);
    let p012 = lerp_sym(p01, p12, s, t);
    let p123 = lerp_sym(p12, p23, s, t);
    (lerp_sym(p012, p123, s, t), (p123 - p012) * 3.0)
}

/// The surface and its first derivatives (plus the mixed one) at a point.
struct Evaluation {
    position: Vec3,
    du: Vec3,
    dv: Vec3,
    duv: Vec3,
}

/// Evaluates the patch at `u = (s_u, t_u)`, `v = (s_v, t_v)`: rows first (in
/// u), then the resulting column (in v).
fn evaluate(patch: &Patch, (su, tu): (f32, f32), (sv, tv): (f32, f32)) -> Evaluation {
    let mut rows = [Vec3::ZERO; 4];
    let mut rows_du = [Vec3::ZERO; 4];
    for (i, control_row) in patch.iter().enumerate() {
        (rows[i], rows_du[i]) = cubic(control_row, su, tu);
    }
    let (position, dv) = cubic(&rows, sv, tv);
    let (du, duv) = cubic(&rows_du, sv, tv);
    Evaluation {
        position,
        du,
        dv,
        duv,
    }
}

/// `v / |v|`, or `None` for a zero, tiny or non-finite vector.
fn unit(v: Vec3) -> Option<Vec3> {
    let length = v.length();
    (length.is_finite() && length > 0.0).then(|| v / length)
}

/// `normalize(cross(a, b))` from the directions alone (so the scale of the
/// patch does not matter), or `None` when `a` or `b` vanishes or they are
/// parallel to within about 1e-6 radians.
fn normal_from(a: Vec3, b: Vec3) -> Option<Vec3> {
    let n = unit(a)?.cross(unit(b)?);
    let length = n.length();
    (length > 1.0e-6).then(|| n / length)
}

impl Evaluation {
    /// The unit normal at `(u, v)`, robust where a derivative vanishes.
    fn normal(&self, patch: &Patch, u: f32, v: f32) -> Vec3 {
        if let Some(n) = normal_from(self.du, self.dv) {
            return n;
        }
        // A collapsed edge (pole): the vanishing derivative grows linearly
        // with the distance from the edge, so the normal's limit is the cross
        // product with the mixed derivative, signed by which edge it is.
        let limit = if self.du.length_squared() <= self.dv.length_squared() {
            let sign = if v < 0.5 { 1.0 } else { -1.0 };
            normal_from(self.duv, self.dv).map(|n| n * sign)
        } else {
            let sign = if u < 0.5 { 1.0 } else { -1.0 };
            normal_from(self.du, self.duv).map(|n| n * sign)
        };
        // The normal a little inside the patch: a cross-check on the limit's
        // sign, and the answer where there is no limit (a corner where both
        // derivatives vanish, or a cusp).
        let inside = [1.0e-3f32, 1.0e-2, 1.0e-1].into_iter().find_map(|step| {
            let nudge = |x: f32| if x < 0.5 { x + step } else { x - step };
            let (nu, nv) = (nudge(u), nudge(v));
            let eval = evaluate(patch, (1.0 - nu, nu), (1.0 - nv, nv));
            normal_from(eval.du, eval.dv)
        });
        match (limit, inside) {
            (Some(limit), Some(inside)) if limit.dot(inside) < 0.0 => inside,
            (Some(n), _) | (None, Some(n)) => n,
            // A patch with no usable derivative anywhere near: its control net.
            (None, None) => {
                let across = (patch[0][3] - patch[0][0]) + (patch[3][3] - patch[3][0]);
                let down = (patch[3][0] - patch[0][0]) + (patch[3][3] - patch[0][3]);
                normal_from(across, down).unwrap_or(Vec3::Y)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::collections::HashMap;

    const TEAPOT: &str = include_str!("../../../data/teapot.bpt");

    fn teapot() -> Vec<Patch> {
        parse_bpt(TEAPOT).expect("data/teapot.bpt parses")
    }

    fn triangle_area2(mesh: &PatchMesh, [a, b, c]: [u32; 3]) -> Vec3 {
        let p = |i: u32| mesh.positions[i as usize];
        (p(b) - p(a)).cross(p(c) - p(a))
    }

    /// A flat patch in the y = 2 plane: corners (-1, 2, 1) .. (2, 2, -1),
    /// u along +X, v along -Z, so the normal is +Y. `wobble` moves the inner
    /// control points within the plane (the surface stays the same region
    /// only when it is zero).
    fn flat_patch(wobble: f32) -> Patch {
        let mut patch = [[Vec3::ZERO; 4]; 4];
        for (i, row) in patch.iter_mut().enumerate() {
            for (j, point) in row.iter_mut().enumerate() {
                let inner = (1..3).contains(&i) && (1..3).contains(&j);
                let dx = if inner {
                    wobble * (i as f32 - 1.5)
                } else {
                    0.0
                };
                *point = Vec3::new(-1.0 + j as f32 + dx, 2.0, 1.0 - 2.0 * i as f32 / 3.0);
            }
        }
        patch
    }

    #[test]
    fn flat_patch_area_normals_and_uvs() {
        let mesh = tessellate(&[flat_patch(0.0)], 5);
        assert_eq!(mesh.positions.len(), 36);
        assert_eq!(mesh.indices.len(), 50);
        let area: f32 = mesh
            .indices
            .iter()
            .map(|&t| triangle_area2(&mesh, t).length() * 0.5)
            .sum();
        assert!((area - 6.0).abs() < 1e-4, "area {area}");
        for &t in &mesh.indices {
            let n = triangle_area2(&mesh, t).normalize();
            assert!(n.abs_diff_eq(Vec3::Y, 1e-5), "geometric normal {n}");
        }
        for n in &mesh.normals {
            assert!(n.abs_diff_eq(Vec3::Y, 1e-6), "vertex normal {n}");
        }
        for (p, uv) in mesh.positions.iter().zip(&mesh.uvs) {
            let expected = Vec3::new(-1.0 + 3.0 * uv.x, 2.0, 1.0 - 2.0 * uv.y);
            assert!(p.abs_diff_eq(expected, 1e-5), "{p} at uv {uv}");
        }
        assert_eq!(mesh.uvs[0], Vec2::ZERO);
        assert_eq!(mesh.uvs[35], Vec2::ONE);
        // Corners are the corner control points, exactly.
        assert_eq!(mesh.positions[0], Vec3::new(-1.0, 2.0, 1.0));
        assert_eq!(mesh.positions[35], Vec3::new(2.0, 2.0, -1.0));

        // Moving control points within the plane keeps every normal +Y.
        let mesh = tessellate(&[flat_patch(0.4)], 7);
        assert!(mesh.normals.iter().all(|n| n.abs_diff_eq(Vec3::Y, 1e-5)));
    }

    #[test]
    fn segments_are_clamped() {
        let one = tessellate(&[flat_patch(0.0)], 0);
        assert_eq!((one.positions.len(), one.indices.len()), (4, 2));
        let max = tessellate(&[flat_patch(0.0)], u32::MAX);
        assert_eq!(max.indices.len(), 2 * 1024 * 1024);
        assert!(tessellate(&[], 8).indices.is_empty());
    }

    #[test]
    fn teapot_parses_with_expected_bounds() {
        let patches = teapot();
        assert_eq!(patches.len(), 32);
        let mesh = tessellate(&patches, 16);
        let (mut lo, mut hi) = (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN));
        for &p in &mesh.positions {
            lo = lo.min(p);
            hi = hi.max(p);
        }
        // Y up, sitting on y = 0, knob at 1.575, spout +X, handle -X.
        assert_eq!(lo.y, 0.0);
        assert_eq!(hi.y, 1.575);
        assert!((lo.x + 1.5).abs() < 1e-3, "{lo}");
        assert!(hi.x > 1.7 && hi.x < 1.7625, "{hi}");
        assert!((lo.z + 1.0).abs() < 1e-3 && (hi.z - 1.0).abs() < 1e-3);
    }

    #[test]
    fn teapot_triangle_counts() {
        let patches = teapot();
        // 32 patches x 2 N^2 triangles, minus one triangle per cell along
        // the 8 collapsed pole edges (4 lid-knob patches, 4 bottom patches).
        // At N = 1 the two spout-tip patches also vanish: their four corners
        // lie on one line, so both triangles have exactly zero area.
        for (n, triangles) in [(1, 52), (2, 240), (4, 992), (8, 4032), (16, 16256)] {
            let mesh = tessellate(&patches, n);
            assert_eq!(mesh.indices.len(), triangles, "N = {n}");
            if n > 1 {
                assert_eq!(mesh.indices.len() as u32, 64 * n * n - 8 * n);
            }
            let vertices = 32 * (n as usize + 1).pow(2);
            assert_eq!(mesh.positions.len(), vertices);
            assert_eq!(mesh.normals.len(), vertices);
            assert_eq!(mesh.uvs.len(), vertices);
            for &t in &mesh.indices {
                let a = triangle_area2(&mesh, t);
                assert!(a.is_finite() && a != Vec3::ZERO);
            }
        }
    }

    #[test]
    fn teapot_winding_is_outward() {
        let patches = teapot();
        let mesh = tessellate(&patches, 8);
        // Winding agrees with the analytic normals everywhere...
        for &t in &mesh.indices {
            let geometric = triangle_area2(&mesh, t).normalize();
            let interpolated: Vec3 = t.iter().map(|&i| mesh.normals[i as usize]).sum();
            assert!(
                geometric.dot(interpolated.normalize()) > 0.5,
                "triangle {t:?}: {geometric} vs {interpolated}"
            );
        }
        for n in &mesh.normals {
            assert!(n.is_finite() && (n.length() - 1.0).abs() < 1e-5);
        }
        // ...and the analytic normals point out of the teapot: check each
        // patch at its centre against what "out" means for its part.
        for (index, patch) in patches.iter().enumerate() {
            let at = |u: f32, v: f32| evaluate(patch, (1.0 - u, u), (1.0 - v, v));
            let centre = at(0.5, 0.5);
            let n = centre.normal(patch, 0.5, 0.5);
            let p = centre.position;
            let radial = Vec3::new(p.x, 0.0, p.z);
            let outward = match index {
                0..=3 => n.y,             // rim: the top of the lip
                4..=11 => n.dot(radial),  // body
                20..=23 => n.dot(radial), // lid knob, its underside
                24..=27 => n.y,           // lid
                28..=31 => -n.y,          // bottom
                _ => {
                    // Handle and spout are tubes cut in half by the z = 0
                    // plane; the tube's centre is between the two u edges.
                    let axis = (at(0.0, 0.5).position + at(1.0, 0.5).position) * 0.5;
                    assert!(at(0.0, 0.5).position.z.abs() < 1e-6);
                    n.dot(p - axis)
                }
            };
            assert!(outward > 0.0, "patch {index} faces inward: n = {n} at {p}");
        }
        // The poles: lid knob top points up, bottom centre down.
        let top = mesh
            .positions
            .iter()
            .position(|p| p.y == 1.575)
            .expect("knob top");
        assert!(mesh.normals[top].abs_diff_eq(Vec3::Y, 1e-5));
        let bottom = mesh
            .positions
            .iter()
            .position(|&p| p == Vec3::ZERO)
            .expect("bottom centre");
        assert!(mesh.normals[bottom].abs_diff_eq(Vec3::NEG_Y, 1e-5));
    }

    /// Welding by exact bit pattern leaves only the open edges that the
    /// Newell data really has; every seam between patches closes exactly.
    #[test]
    fn teapot_seams_are_bit_identical() {
        let patches = teapot();
        for n in [3u32, 4, 8, 16] {
            let mesh = tessellate(&patches, n);
            let key = |i: u32| mesh.positions[i as usize].to_array().map(f32::to_bits);
            let mut welded: HashMap<[u32; 3], u32> = HashMap::new();
            let ids: Vec<u32> = (0..mesh.positions.len() as u32)
                .map(|i| {
                    let next = welded.len() as u32;
                    *welded.entry(key(i)).or_insert(next)
                })
                .collect();
            let mut edges: HashMap<(u32, u32), i32> = HashMap::new();
            for t in &mesh.indices {
                for k in 0..3 {
                    let (a, b) = (ids[t[k] as usize], ids[t[(k + 1) % 3] as usize]);
                    // +1 for a -> b, -1 for b -> a: a closed, consistently
                    // wound seam sums to zero.
                    *edges.entry((a.min(b), a.max(b))).or_default() += if a < b { 1 } else { -1 };
                }
            }
            let open: Vec<_> = edges.values().filter(|&&v| v != 0).collect();
            assert!(open.iter().all(|v| v.abs() == 1), "edge used > 2 times");
            // Lid rim 4N, rim lip 4N, handle ends 2 x 2N, spout ends 2 x 2N.
            assert_eq!(open.len(), 16 * n as usize, "N = {n}");

            // Patch-boundary vertices: 32 patches x 4N of them (corners
            // counted once per patch); the seams and poles share them.
            let nn = n as usize + 1;
            let mut boundary = std::collections::HashSet::new();
            let mut total = 0;
            for patch in 0..32 {
                for i in 0..nn {
                    for j in 0..nn {
                        if i == 0 || j == 0 || i == nn - 1 || j == nn - 1 {
                            boundary.insert(key((patch * nn * nn + i * nn + j) as u32));
                            total += 1;
                        }
                    }
                }
            }
            assert_eq!(total, 32 * 4 * n as usize);
            // Welding with a tolerance finds no coincidence that the exact
            // bit patterns missed.
            let near: std::collections::HashSet<[i64; 3]> = boundary
                .iter()
                .map(|bits| bits.map(|b| (f32::from_bits(b) * 1.0e5).round() as i64))
                .collect();
            assert_eq!(near.len(), boundary.len(), "N = {n}");
            if n == 8 {
                // 1024 boundary grid points, 513 distinct positions.
                assert_eq!(boundary.len(), 513, "distinct boundary positions");
            }
        }
    }

    #[test]
    fn lerp_sym_is_symmetric_and_exact() {
        let (a, b) = (Vec3::new(0.1, -7.3, 1e-3), Vec3::new(3.7, 0.2, -2.9));
        for n in 1..40u32 {
            for i in 0..=n {
                let (s, t) = ((n - i) as f32 / n as f32, i as f32 / n as f32);
                assert_eq!(lerp_sym(a, b, s, t), lerp_sym(b, a, t, s));
                assert_eq!(lerp_sym(a, a, s, t), a);
            }
        }
        assert_eq!(lerp_sym(a, b, 1.0, 0.0), a);
        assert_eq!(lerp_sym(a, b, 0.0, 1.0), b);
    }

    fn patch_text(point: &str) -> String {
        let mut text = String::from("3 3\n");
        for _ in 0..16 {
            text.push_str(point);
            text.push('\n');
        }
        text
    }

    #[test]
    fn parses_comments_blank_lines_and_crlf() {
        let text = format!(
            "# header\n\n  2   # two patches\r\n{}\n# between\n\n{}",
            patch_text("1 2 3"),
            patch_text("-1.5e0 +0.25 -0").replace('\n', "\r\n")
        );
        let patches = parse_bpt(&text).unwrap();
        assert_eq!(patches.len(), 2);
        assert_eq!(patches[0][3][3], Vec3::new(1.0, 2.0, 3.0));
        assert_eq!(patches[1][0][0], Vec3::new(-1.5, 0.25, 0.0));
        assert_eq!(patches[1][0][0].z.to_bits(), 0, "-0 is stored as +0");
    }

    fn error_of(text: &str) -> BptError {
        parse_bpt(text).expect_err("must not parse")
    }

    #[test]
    fn errors_carry_line_numbers() {
        // Lines: 1 comment, 2 count, 3 blank, 4 degrees, 5..=20 points.
        let good = format!("# c\n1\n\n{}", patch_text("0 0 0"));
        assert!(parse_bpt(&good).is_ok());
        let lines: Vec<&str> = good.lines().collect();
        let with_line = |n: usize, replacement: &str| {
            let mut l = lines.clone();
            l[n - 1] = replacement;
            l.join("\n")
        };

        let e = error_of(&with_line(4, "3 2"));
        assert_eq!(e.line, 4);
        assert!(e.message.contains("only bicubic"), "{e}");
        assert_eq!(error_of(&with_line(4, "3")).line, 4);
        assert_eq!(error_of(&with_line(4, "three 3")).line, 4);

        let e = error_of(&with_line(9, "1 2"));
        assert_eq!((e.line, e.to_string().starts_with("line 9: ")), (9, true));
        assert_eq!(error_of(&with_line(12, "1 2 3 4")).line, 12);
        assert_eq!(error_of(&with_line(20, "1 x 3")).line, 20);
        for bad in [
            "nan 0 0",
            "0 inf 0",
            "0 0 -infinity",
            "1e39 0 0",
            "0 0 2e15",
        ] {
            let e = error_of(&with_line(7, bad));
            assert_eq!(e.line, 7, "{bad}: {e}");
        }
        assert!(parse_bpt(&with_line(7, "1e15 -1e15 0 # fine")).is_ok());

        assert_eq!(error_of(&with_line(2, "x")).line, 2);
        assert_eq!(error_of(&with_line(2, "-1")).line, 2);
        assert_eq!(error_of(&with_line(2, "1 1")).line, 2);
        assert_eq!(error_of(&with_line(2, "0")).line, 2);
        // More patches declared than lines present.
        let e = error_of(&with_line(2, "2"));
        assert_eq!(e.line, 2);
        assert!(e.message.contains("declares 2 patches"), "{e}");
        let e = error_of(&with_line(2, "18446744073709551615"));
        assert_eq!(e.line, 2);
        assert_eq!(error_of(&with_line(2, "99999999999999999999999")).line, 2);

        // Truncated: the count check catches it at the count line.
        let truncated = lines[..lines.len() - 1].join("\n");
        assert_eq!(error_of(&truncated).line, 2);
        // Trailing data after the last patch.
        let e = error_of(&format!("{good}\n\n7 7 7\n"));
        assert_eq!(e.line, 23);
        assert!(e.message.contains("after the last"), "{e}");

        assert_eq!(error_of("").line, 1);
        assert_eq!(error_of("# only a comment\n\n").line, 3);
    }

    #[test]
    fn garbage_is_an_error_not_a_panic() {
        for text in [
            "3 3",
            "1\n3 3",
            "1\n3 3\n1 2 3",
            "\u{0}\u{1}\u{ff}",
            "32\n",
            "🫖",
            "1 # \n # \n 3 3 # x",
            "4294967296\n3 3\n",
            &"1\n".repeat(1000),
            &TEAPOT[..TEAPOT.len() / 2],
            &TEAPOT.replace("3 3", "3 3 3"),
        ] {
            assert!(parse_bpt(text).is_err(), "{text:?}");
        }
        // Deterministic fuzzing: mutate the teapot text and random bytes.
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let alphabet = b"0123456789 \n\n#.-+eE3nafix\t\r";
        for _ in 0..300 {
            let mut bytes = TEAPOT.as_bytes().to_vec();
            for _ in 0..(next() % 8 + 1) {
                let at = (next() % bytes.len() as u64) as usize;
                bytes[at] = alphabet[(next() % alphabet.len() as u64) as usize];
            }
            let _ = parse_bpt(&String::from_utf8_lossy(&bytes));
            let len = (next() % 200) as usize;
            let noise: Vec<u8> = (0..len)
                .map(|_| alphabet[(next() % alphabet.len() as u64) as usize])
                .collect();
            let _ = parse_bpt(&String::from_utf8_lossy(&noise));
        }
    }

    #[test]
    fn degenerate_and_absurd_patches_do_not_panic() {
        let point = [[Vec3::ONE; 4]; 4];
        let mesh = tessellate(&[point], 4);
        assert!(mesh.indices.is_empty());
        assert!(mesh.normals.iter().all(|n| n.is_finite()));
        let mut line = [[Vec3::ZERO; 4]; 4];
        for (i, row) in line.iter_mut().enumerate() {
            for (j, p) in row.iter_mut().enumerate() {
                *p = Vec3::new((i + j) as f32, 0.0, 0.0);
            }
        }
        let mesh = tessellate(&[line], 4);
        assert!(mesh.normals.iter().all(|n| n.is_finite()));
        let mut nan = flat_patch(0.0);
        nan[1][2] = Vec3::NAN;
        let mesh = tessellate(&[nan, flat_patch(0.0)], 2);
        assert!(mesh.normals.iter().all(|n| n.is_finite()));
        assert!(mesh.indices.len() >= 8);
    }
}
