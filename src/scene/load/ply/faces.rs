//! The faces of a PLY file as triangles, read value by value: polygons
//! clipped in their plane ([`Triangulator`]) as they are read (or, where
//! the faces come before the vertices, once every vertex is read), and,
//! where the face element gives corners texture coordinates (MeshLab's
//! `texcoord` lists) or faces a colour, each corner a vertex of its own
//! (shared by the corners of one vertex that agree).

use std::collections::HashMap;

use glam::{DVec3, Vec2, Vec3};

use super::{Element, PlyMesh, Role};
use crate::scene::load::polygon::{quad_is_fan, Triangulator};

/// What the face element gives each face beyond its vertices.
#[derive(Clone, Copy, Default)]
pub(crate) struct Given {
    pub(crate) uvs: bool,
    pub(crate) colors: bool,
}

impl Given {
    /// Whether corners get vertices of their own.
    pub(crate) fn any(self) -> bool {
        self.uvs || self.colors
    }
}

/// What the face element `face` gives: `texcoord` lists, and colours
/// where it has all three.
pub(crate) fn given(face: &Element) -> Given {
    let has = |f: fn(Role) -> bool| face.props.iter().filter(|p| f(p.role)).count();
    Given {
        uvs: has(|r| r == Role::FaceUvs) > 0,
        colors: has(|r| matches!(r, Role::Color(_))) == 3,
    }
}

/// The faces read so far.
pub(crate) struct Faces {
    given: Given,
    /// Where the faces give corners anything ([`Given`]): the vertex of a
    /// corner by its vertex in the file, UV and colour (as bits), and each
    /// such vertex's vertex in the file, UV and colour.
    ids: HashMap<(u32, [u32; 2], [u32; 3]), u32>,
    from: Vec<u32>,
    uvs: Vec<Vec2>,
    colors: Vec<Vec3>,
    /// Polygons of more than three corners read before the vertices: where
    /// their fans start among the triangles, their corners and the face's
    /// number.
    polygons: Vec<(usize, u32, u64)>,
    triangulator: Triangulator,
    points: Vec<DVec3>,
    cut: Vec<[u32; 3]>,
    /// Polygons left as fans: the first face's number and how many.
    fans: (Option<u64>, usize),
    /// Faces whose `texcoord` list is not two numbers a corner: the first
    /// face's number and how many.
    odd_uvs: (Option<u64>, u64),
}

impl Faces {
    pub(crate) fn new(given: Given) -> Faces {
        Faces {
            given,
            ids: HashMap::new(),
            from: Vec::new(),
            uvs: Vec::new(),
            colors: Vec::new(),
            polygons: Vec::new(),
            triangulator: Triangulator::default(),
            points: Vec::new(),
            cut: Vec::new(),
            fans: (None, 0),
            odd_uvs: (None, 0),
        }
    }

    /// Cuts the polygon of `corners`, with their vertices at `positions`,
    /// into `self.cut`.
    fn cut(&mut self, face: u64, corners: &[u32], positions: &[DVec3]) {
        self.points.clear();
        self.points
            .extend(corners.iter().map(|&i| positions[i as usize]));
        if !self.triangulator.triangles(&self.points, &mut self.cut) {
            self.fans.0.get_or_insert(face);
            self.fans.1 += 1;
        }
    }

    /// The vertices the mesh has so far, where corners have their own.
    pub(crate) fn split(&self) -> usize {
        self.from.len()
    }

    /// Adds face `face` of `corners` (vertex numbers), with `uvs` (two
    /// numbers a corner) and `color` where the element gives them, to
    /// `triangles`; `positions` are the vertices' where they are read, else
    /// a polygon is a fan until [`Faces::finish`] cuts it.
    pub(crate) fn add(
        &mut self,
        face: u64,
        corners: &mut [u32],
        uvs: &[f32],
        color: Vec3,
        positions: Option<&[DVec3]>,
        triangles: &mut Vec<[u32; 3]>,
    ) {
        // Cut where the vertices are read, but for the quads that are
        // their fan, most of them, which take no detour.
        let cut = match (&*corners, positions) {
            ([a, b, c, d], Some(p)) if quad_is_fan([a, b, c, d].map(|&i| p[i as usize])) => false,
            (corners, Some(p)) if corners.len() > 3 => {
                self.cut(face, corners, p);
                true
            }
            _ => false,
        };
        let Given {
            uvs: given_uvs,
            colors: given_colors,
        } = self.given;
        let whole = uvs.len() == 2 * corners.len();
        if given_uvs && !whole {
            self.odd_uvs.0.get_or_insert(face);
            self.odd_uvs.1 += 1;
        }
        if self.given.any() {
            for (k, c) in corners.iter_mut().enumerate() {
                let uv = match uvs.get(2 * k..2 * k + 2) {
                    Some(&[u, v]) if whole => Vec2::new(u, v),
                    _ => Vec2::ZERO,
                };
                let key = (
                    *c,
                    uv.to_array().map(f32::to_bits),
                    color.to_array().map(f32::to_bits),
                );
                *c = *self.ids.entry(key).or_insert_with(|| {
                    self.from.push(*c);
                    if given_uvs {
                        self.uvs.push(uv);
                    }
                    if given_colors {
                        self.colors.push(color);
                    }
                    self.from.len() as u32 - 1
                });
            }
        }
        if cut {
            triangles.extend(self.cut.drain(..).map(|t| t.map(|k| corners[k as usize])));
            return;
        }
        if corners.len() > 3 && positions.is_none() {
            self.polygons
                .push((triangles.len(), corners.len() as u32, face));
        }
        triangles.extend((2..corners.len()).map(|k| [corners[0], corners[k - 1], corners[k]]));
    }

    /// The mesh `m`, whose vertices are all read, with its corners' own
    /// vertices and its polygons clipped; warnings naming `file`.
    pub(crate) fn finish(mut self, file: &str, m: &mut PlyMesh, warnings: &mut Vec<String>) {
        if let (Some(face), n) = self.odd_uvs {
            let more = match n {
                1 => String::new(),
                n => format!(" (and {} more)", n - 1),
            };
            warnings.push(format!(
                "{file}: element face {face}{more}: the texcoord list does not hold two numbers \
                 a corner: its corners are at UV 0 0"
            ));
        }
        if self.given.any() {
            let from = &self.from;
            m.positions = pick(from, std::mem::take(&mut m.positions));
            m.normals = m.normals.take().map(|v| pick(from, v));
            m.uvs = match self.given.uvs {
                true => Some(std::mem::take(&mut self.uvs)),
                false => m.uvs.take().map(|v| pick(from, v)),
            };
            m.colors = match self.given.colors {
                true => Some(std::mem::take(&mut self.colors)),
                false => m.colors.take().map(|v| pick(from, v)),
            };
        }
        if !self.polygons.is_empty() {
            let old = std::mem::take(&mut m.indices);
            m.indices.reserve_exact(old.len());
            let mut corners = Vec::new();
            let mut done = 0;
            for (start, n, face) in std::mem::take(&mut self.polygons) {
                m.indices.extend_from_slice(&old[done..start]);
                done = start + n as usize - 2;
                let fan = &old[start..done];
                corners.clear();
                corners.extend([fan[0][0], fan[0][1]]);
                corners.extend(fan.iter().map(|t| t[2]));
                self.cut(face, &corners, &m.positions);
                m.indices
                    .extend(self.cut.drain(..).map(|t| t.map(|k| corners[k as usize])));
            }
            m.indices.extend_from_slice(&old[done..]);
        }
        if let (Some(face), n) = self.fans {
            warnings.push(format!(
                "{file}: element face {face}: {}",
                Triangulator::warning(n)
            ));
        }
    }
}

/// The items of `v` that `from` names, in its order.
fn pick<T: Copy>(from: &[u32], v: Vec<T>) -> Vec<T> {
    from.iter().map(|&i| v[i as usize]).collect()
}
