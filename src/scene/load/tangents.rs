//! Per-vertex tangents for normal maps, where a file gives none:
//! MikkTSpace's (through `bevy_mikktspace`, a port that matches the
//! reference implementation's output), the frame normal maps are baked
//! in by Blender, Substance and xNormal, and the one glTF asks for.

use std::collections::HashMap;

use glam::{Vec2, Vec3, Vec4};

use super::parts::Placed;

/// A mesh's triangles as MikkTSpace reads them, and the tangent it gives
/// each corner.
struct Mesh<'a> {
    positions: &'a [Vec3],
    normals: &'a [Vec3],
    uvs: &'a [Vec2],
    indices: &'a [[u32; 3]],
    corners: Vec<Vec4>,
}

impl Mesh<'_> {
    fn vertex(&self, face: usize, vert: usize) -> usize {
        self.indices[face][vert] as usize
    }
}

impl bevy_mikktspace::Geometry for Mesh<'_> {
    fn num_faces(&self) -> usize {
        self.indices.len()
    }

    fn num_vertices_of_face(&self, _face: usize) -> usize {
        3
    }

    fn position(&self, face: usize, vert: usize) -> [f32; 3] {
        self.positions[self.vertex(face, vert)].to_array()
    }

    fn normal(&self, face: usize, vert: usize) -> [f32; 3] {
        self.normals[self.vertex(face, vert)].to_array()
    }

    fn tex_coord(&self, face: usize, vert: usize) -> [f32; 2] {
        self.uvs[self.vertex(face, vert)].to_array()
    }

    fn set_tangent(
        &mut self,
        tangent: Option<bevy_mikktspace::TangentSpace>,
        face: usize,
        vert: usize,
    ) {
        // A corner MikkTSpace finds no frame for (a degenerate triangle
        // alone) keeps zero, which shading reads as "none".
        if let Some(t) = tangent {
            self.corners[3 * face + vert] = Vec4::from_array(t.tangent_encoded());
        }
    }
}

/// MikkTSpace tangents (xyz, and w the bitangent's sign: the bitangent is
/// `w · normal × tangent`) for each vertex of a mesh with per-vertex
/// normals and texture coordinates (v up, so that the bitangent follows
/// the image's up, as glTF and Blender have it). A vertex whose corners
/// get different tangents (on a mirror seam of the texture) is split:
/// `indices` are rewritten to the copies, and the second value lists, for
/// each copy in order, the vertex it copies (past the mesh's vertices).
pub(crate) fn generate(
    positions: &[Vec3],
    normals: &[Vec3],
    uvs: &[Vec2],
    indices: &mut [[u32; 3]],
) -> (Vec<Vec4>, Vec<u32>) {
    let mut mesh = Mesh {
        positions,
        normals,
        uvs,
        indices,
        corners: vec![Vec4::ZERO; 3 * indices.len()],
    };
    // The crate's error type has no values: it cannot fail.
    let _ = bevy_mikktspace::generate_tangents(&mut mesh);
    let corners = mesh.corners;
    let n = positions.len();
    let mut tangents: Vec<Option<Vec4>> = vec![None; n];
    let mut copies = Vec::new();
    let mut split: HashMap<(u32, [u32; 4]), u32> = HashMap::new();
    for (tri, corner) in indices.iter_mut().zip(corners.chunks_exact(3)) {
        for (v, &t) in tri.iter_mut().zip(corner) {
            match tangents[*v as usize] {
                None => tangents[*v as usize] = Some(t),
                Some(had) if had.to_array().map(f32::to_bits) == t.to_array().map(f32::to_bits) => {
                }
                Some(_) => {
                    let key = (*v, t.to_array().map(f32::to_bits));
                    *v = *split.entry(key).or_insert_with(|| {
                        copies.push(*v);
                        tangents.push(Some(t));
                        (n + copies.len() - 1) as u32
                    });
                }
            }
        }
    }
    let tangents = tangents
        .into_iter()
        .map(Option::unwrap_or_default)
        .collect();
    (tangents, copies)
}

/// Gives a placed mesh with normals and texture coordinates MikkTSpace's
/// tangents, splitting vertices where [`generate`] does; others are left
/// as they are (shaded with each triangle's own frame).
pub(crate) fn add(m: &mut Placed) {
    let (Some(normals), Some(uvs)) = (&mut m.normals, &mut m.uvs) else {
        return;
    };
    let positions: Vec<Vec3> = m.positions.iter().map(|p| p.as_vec3()).collect();
    let (t, copies) = generate(&positions, normals, uvs, &mut m.indices);
    extend(&mut m.positions, &copies);
    extend(normals, &copies);
    extend(uvs, &copies);
    if let Some(v) = &mut m.uvs1 {
        extend(v, &copies);
    }
    if let Some(v) = &mut m.colors {
        extend(v, &copies);
    }
    m.tangents = Some(t);
}

/// `v` with the vertices `copies` names appended, in order: a vertex
/// attribute kept in step with [`generate`]'s split vertices.
pub(crate) fn extend<T: Copy>(v: &mut Vec<T>, copies: &[u32]) {
    v.reserve(copies.len());
    for &c in copies {
        v.push(v[c as usize]);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A square of two triangles in the xy plane facing +z, u along x
    /// and v along y: the tangent is +x and the bitangent +y.
    #[test]
    fn a_plain_square_gets_the_texture_axes() {
        let p = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y];
        let uv = p.map(|p| p.truncate());
        let n = [Vec3::Z; 4];
        let mut idx = [[0, 1, 2], [0, 2, 3]];
        let (t, copies) = generate(&p, &n, &uv, &mut idx);
        assert!(copies.is_empty());
        for t in t {
            assert!(
                (t - Vec4::new(1.0, 0.0, 0.0, 1.0)).abs().max_element() < 1e-6,
                "{t}"
            );
        }
    }

    /// Mirrored texture coordinates (the right half's u runs back) give
    /// the mirrored half w = -1; the vertices on the seam, shared by both
    /// halves, are split so that each half keeps its own frame.
    #[test]
    fn a_mirror_seam_splits_its_vertices() {
        // Two squares side by side, sharing the edge x = 1.
        let p = [0.0, 1.0, 2.0].map(|x| [Vec3::new(x, 0.0, 0.0), Vec3::new(x, 1.0, 0.0)]);
        let p: Vec<Vec3> = p.concat();
        // u: 0 at x = 0, 1 at x = 1, back to 0 at x = 2.
        let uv: Vec<Vec2> = p
            .iter()
            .map(|p| Vec2::new(1.0 - (p.x - 1.0).abs(), p.y))
            .collect();
        let n = vec![Vec3::Z; p.len()];
        let mut idx = vec![[0, 2, 3], [0, 3, 1], [2, 4, 5], [2, 5, 3]];
        let (t, copies) = generate(&p, &n, &uv, &mut idx);
        assert_eq!(copies, [2, 3]);
        assert_eq!(t.len(), 8);
        let mut uv = uv;
        extend(&mut uv, &copies);
        assert_eq!(uv[6..], [uv[2], uv[3]]);
        let w = |tri: &[u32; 3]| tri.map(|v| t[v as usize].w);
        assert_eq!(w(&idx[0]), [1.0; 3]);
        assert_eq!(w(&idx[2]), [-1.0; 3]);
        // Both halves' tangents follow u: +x on the left, -x on the right.
        assert!(t[idx[0][0] as usize].x > 0.99 && t[idx[2][1] as usize].x < -0.99);
    }
}
