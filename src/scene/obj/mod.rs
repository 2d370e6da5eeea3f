//! Wavefront OBJ, read in f64 with errors that name the file and line.
//!
//! Polygons (`f`) become triangle fans; `o`, `g` and a change of `usemtl`
//! start a new mesh, and each mesh's vertices are welded by their
//! position/UV/normal indices. Every index is checked exactly against the
//! vertices, UVs and normals the file holds (relative, negative ones
//! included), and every number is finite and within the range of f32, also
//! after a `w` component divides it and after the mesh is placed. Points
//! and lines (`p`, `l`) and smoothing groups are ignored; other statements
//! are ignored with one warning per file. Materials come from the `mtllib`
//! files ([`super::mtl`]); a missing MTL or texture is a warning.

use std::borrow::Cow;
use std::collections::HashMap;
use std::path::{Path, PathBuf};

use anyhow::{anyhow, bail, Context, Result};
use glam::{DAffine3, DVec3, Vec2};

use super::frame::Frame;
use super::mtl::{self, MtlMaterial};
use super::numbers::{self, show, show3, Absurd};
use super::source::{resolve, Kind, ReadError, Source};
use super::Material;
use crate::memory;

pub use super::numbers::ABSURD;
pub use super::parts::{MeshData, Parts, Placed, Placement};

/// An absent UV or normal index.
const NONE: u32 = u32::MAX;

/// One polygon: its line and its corners in [`ObjFile::corners`].
struct Face {
    line: usize,
    start: usize,
    len: usize,
}

/// Faces that share an object name and a material.
struct Group {
    name: String,
    /// The `usemtl` name and its line.
    material: Option<(String, usize)>,
    faces: Vec<Face>,
}

/// An OBJ file as read: every index checked, nothing placed yet.
pub struct ObjFile {
    path: PathBuf,
    positions: Vec<DVec3>,
    /// The line of each position, for errors found once it is placed.
    position_lines: Vec<u32>,
    normals: Vec<DVec3>,
    uvs: Vec<Vec2>,
    /// Position, UV and normal indices (0-based; [`NONE`] when absent).
    corners: Vec<[u32; 3]>,
    groups: Vec<Group>,
    /// `mtllib` arguments as written, with their lines.
    libraries: Vec<(String, usize)>,
}

/// One index of a face corner, resolved against the `count` defined so far.
fn index(word: &str, count: usize, what: &str) -> Result<u32, String> {
    let k: i64 = word
        .parse()
        .map_err(|_| format!("'{word}' is not a valid {what} index"))?;
    let i = match k {
        0 => return Err(format!("{what} index 0 (indices start at 1)")),
        k if k > 0 => k - 1,
        k => count as i64 + k,
    };
    if i < 0 {
        return Err(format!(
            "relative {what} index {k} reaches before the first {what} \
             (only {count} defined so far)"
        ));
    }
    u32::try_from(i)
        .ok()
        .filter(|&i| i != NONE)
        .ok_or_else(|| format!("{what} index {k} is out of range ({count} defined so far)"))
}

/// The numbers of a `v`, `vt` or `vn` statement (up to a trailing
/// comment), without allocating: the first seven, and how many there were.
struct Numbers {
    values: [f64; 7],
    total: usize,
}

impl std::ops::Deref for Numbers {
    type Target = [f64];
    fn deref(&self) -> &[f64] {
        &self.values[..self.total.min(7)]
    }
}

fn numbers(rest: &str, line: usize, absurd: &mut Absurd) -> Result<Numbers, String> {
    let mut n = Numbers {
        values: [0.0; 7],
        total: 0,
    };
    for w in rest.split_whitespace().take_while(|w| !w.starts_with('#')) {
        let x = numbers::parse(w)?;
        absurd.check(line, x, || w.to_string());
        if let Some(slot) = n.values.get_mut(n.total) {
            *slot = x;
        }
        n.total += 1;
    }
    Ok(n)
}

/// Statements ignored by design, silently.
const SILENT: &[&str] = &["s", "l", "p"];

/// Lines of `text` with `\` continuations joined, numbered from 1 by
/// their first line.
fn logical_lines(text: &str) -> impl Iterator<Item = (usize, Cow<'_, str>)> + '_ {
    let mut lines = text.lines().enumerate();
    std::iter::from_fn(move || {
        let (i, first) = lines.next()?;
        if !first.trim_end().ends_with('\\') {
            return Some((i + 1, Cow::Borrowed(first)));
        }
        let mut line = first.to_string();
        while line.trim_end().ends_with('\\') {
            let cut = line.trim_end().len() - 1;
            line.truncate(cut);
            match lines.next() {
                Some((_, next)) => {
                    line.push(' ');
                    line.push_str(next);
                }
                None => break,
            }
        }
        Some((i + 1, Cow::Owned(line)))
    })
}

impl ObjFile {
    /// Parses OBJ text; non-fatal findings are appended to `warnings`.
    pub fn parse(path: &Path, text: &str, warnings: &mut Vec<String>) -> Result<ObjFile> {
        Self::parse_within(path, text, warnings, memory::available())
    }

    /// [`ObjFile::parse`], refusing a mesh whose triangles would need more
    /// than `available` bytes ([`memory::BYTES_PER_TRIANGLE`] each).
    fn parse_within(
        path: &Path,
        text: &str,
        warnings: &mut Vec<String>,
        available: u64,
    ) -> Result<ObjFile> {
        let mut f = ObjFile {
            path: path.to_path_buf(),
            positions: Vec::new(),
            position_lines: Vec::new(),
            normals: Vec::new(),
            uvs: Vec::new(),
            corners: Vec::new(),
            groups: Vec::new(),
            libraries: Vec::new(),
        };
        let mut current = Group {
            name: String::new(),
            material: None,
            faces: Vec::new(),
        };
        let mut absurd = Absurd::default();
        let mut ignored: Vec<(String, usize, usize)> = Vec::new();
        // A polygon of a million corners is a few megabytes of text and a
        // million triangles: the count is checked as it grows.
        let mut triangles = 0u64;
        for (n, line) in logical_lines(text) {
            let at = |msg: String| anyhow!("{}:{n}: {msg}", path.display());
            let line = line.trim();
            if line.is_empty() || line.starts_with('#') {
                continue;
            }
            let (key, rest) = line
                .split_once(char::is_whitespace)
                .map_or((line, ""), |(k, r)| (k, r.trim()));
            match key {
                "v" => {
                    let v = numbers(rest, n, &mut absurd).map_err(at)?;
                    let p = match *v {
                        [x, y, z] | [x, y, z, _, _, _] => DVec3::new(x, y, z),
                        [x, y, z, w] => {
                            if w == 0.0 {
                                bail!(at("vertex with w = 0".into()));
                            }
                            let p = DVec3::new(x, y, z) / w;
                            if let Some(why) = p.to_array().into_iter().find_map(numbers::unusable)
                            {
                                bail!(at(format!(
                                    "w = {} divides the vertex to {}, which {why}",
                                    show(w),
                                    show3(p)
                                )));
                            }
                            absurd.check(n, p.abs().max_element(), || {
                                format!("{} (x, y, z divided by w)", show(p.abs().max_element()))
                            });
                            p
                        }
                        _ => bail!(at(format!(
                            "a vertex takes 3 coordinates (x y z), optionally with w or an \
                             RGB colour; found {} numbers",
                            v.total
                        ))),
                    };
                    f.positions.push(p);
                    f.position_lines.push(n as u32);
                }
                "vt" => {
                    let v = numbers(rest, n, &mut absurd).map_err(at)?;
                    let uv = match *v {
                        [u] => Vec2::new(u as f32, 0.0),
                        [u, v] | [u, v, _] => Vec2::new(u as f32, v as f32),
                        _ => bail!(at(format!(
                            "a texture coordinate takes 1 to 3 numbers (u [v [w]]), found {}",
                            v.total
                        ))),
                    };
                    f.uvs.push(uv);
                }
                "vn" => {
                    let v = numbers(rest, n, &mut absurd).map_err(at)?;
                    match *v {
                        [x, y, z] => f.normals.push(DVec3::new(x, y, z)),
                        _ => bail!(at(format!(
                            "a normal takes 3 numbers (x y z), found {}",
                            v.total
                        ))),
                    }
                }
                "f" => {
                    let start = f.corners.len();
                    for word in rest.split_whitespace().take_while(|w| !w.starts_with('#')) {
                        let corner = f.corner(word).map_err(at)?;
                        f.corners.push(corner);
                    }
                    let len = f.corners.len() - start;
                    if len < 3 {
                        bail!(at(format!("a face needs at least 3 vertices, found {len}")));
                    }
                    triangles += len as u64 - 2;
                    if triangles * memory::BYTES_PER_TRIANGLE > available {
                        bail!(at(format!(
                            "{triangles} triangles by this line would need {} of memory; \
                             {} is available",
                            memory::bytes(triangles * memory::BYTES_PER_TRIANGLE),
                            memory::bytes(available)
                        )));
                    }
                    current.faces.push(Face {
                        line: n,
                        start,
                        len,
                    });
                }
                "o" | "g" => {
                    let next = Group {
                        name: rest.to_string(),
                        material: current.material.clone(),
                        faces: Vec::new(),
                    };
                    f.finish(std::mem::replace(&mut current, next));
                }
                "usemtl" => {
                    if rest.is_empty() {
                        warnings.push(format!(
                            "{}:{n}: usemtl without a material name: ignored",
                            path.display()
                        ));
                        continue;
                    }
                    if current.material.as_ref().is_some_and(|(m, _)| m == rest) {
                        continue;
                    }
                    let next = Group {
                        name: current.name.clone(),
                        material: Some((rest.to_string(), n)),
                        faces: Vec::new(),
                    };
                    if current.faces.is_empty() {
                        current = next;
                    } else {
                        f.finish(std::mem::replace(&mut current, next));
                    }
                }
                "mtllib" => {
                    if rest.is_empty() {
                        warnings.push(format!(
                            "{}:{n}: mtllib without a file name: ignored",
                            path.display()
                        ));
                    } else {
                        f.libraries.push((rest.to_string(), n));
                    }
                }
                k if SILENT.contains(&k) => {}
                other => match ignored.iter_mut().find(|(w, _, _)| w == other) {
                    Some(e) => e.2 += 1,
                    None => ignored.push((other.to_string(), n, 1)),
                },
            }
        }
        f.finish(current);
        f.check_indices()?;
        warnings.extend(absurd.warning(path));
        if !ignored.is_empty() {
            let list: Vec<String> = ignored
                .iter()
                .map(|(w, line, count)| match count {
                    1 => format!("{w} (line {line})"),
                    c => format!("{w} (line {line} and {} more)", c - 1),
                })
                .collect();
            warnings.push(format!(
                "{}: ignored, not supported: {}",
                path.display(),
                list.join(", ")
            ));
        }
        Ok(f)
    }

    /// One face corner, `v`, `v/vt`, `v//vn` or `v/vt/vn`.
    fn corner(&self, word: &str) -> Result<[u32; 3], String> {
        let mut parts = word.split('/');
        let v = parts.next().unwrap_or("");
        let vt = parts.next().unwrap_or("");
        let vn = parts.next().unwrap_or("");
        if parts.next().is_some() || v.is_empty() {
            return Err(format!(
                "'{word}' is not a face vertex (v, v/vt, v//vn or v/vt/vn)"
            ));
        }
        let optional = |w: &str, count, what| match w {
            "" => Ok(NONE),
            w => index(w, count, what),
        };
        Ok([
            index(v, self.positions.len(), "vertex")?,
            optional(vt, self.uvs.len(), "texture coordinate")?,
            optional(vn, self.normals.len(), "normal")?,
        ])
    }

    fn finish(&mut self, g: Group) {
        if !g.faces.is_empty() {
            self.groups.push(g);
        }
    }

    /// Every index of every face refers to something the file defines
    /// (forward references included, as other readers allow them).
    fn check_indices(&self) -> Result<()> {
        let counts = [self.positions.len(), self.uvs.len(), self.normals.len()];
        let names = ["vertex", "texture coordinate", "normal"];
        for face in self.groups.iter().flat_map(|g| &g.faces) {
            for c in &self.corners[face.start..face.start + face.len] {
                for k in 0..3 {
                    if c[k] != NONE && c[k] as usize >= counts[k] {
                        bail!(
                            "{}:{}: the face refers to {} {} but the file defines {}",
                            self.path.display(),
                            face.line,
                            names[k],
                            c[k] as u64 + 1,
                            counts[k]
                        );
                    }
                }
            }
        }
        Ok(())
    }

    /// The meshes placed by `xf` (in f64), each group with the material
    /// `material(group's usemtl)` gives.
    fn place(
        &self,
        xf: &DAffine3,
        mut material: impl FnMut(Option<&(String, usize)>) -> u32,
        warnings: &mut Vec<String>,
    ) -> Result<Vec<Placed>> {
        let nxf = xf.matrix3.inverse().transpose();
        let stem = self
            .path
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .unwrap_or_default();
        let mut partial = Vec::new();
        let mut meshes = Vec::with_capacity(self.groups.len());
        // Welding: the mesh vertex a position was first used as, by
        // position; corners that reuse a position with other UV or normal
        // indices go through a map. Reset after each mesh.
        let mut first: Vec<u32> = vec![NONE; self.positions.len()];
        for g in &self.groups {
            let mut other: HashMap<[u32; 3], u32> = HashMap::new();
            let mut corners: Vec<[u32; 3]> = Vec::new();
            let mut indices = Vec::new();
            for face in &g.faces {
                let c = &self.corners[face.start..face.start + face.len];
                let mut id = |corner: [u32; 3]| {
                    let slot = &mut first[corner[0] as usize];
                    if *slot == NONE {
                        *slot = corners.len() as u32;
                        corners.push(corner);
                        return *slot;
                    }
                    if corners[*slot as usize] == corner {
                        return *slot;
                    }
                    *other.entry(corner).or_insert_with(|| {
                        corners.push(corner);
                        corners.len() as u32 - 1
                    })
                };
                let first = id(c[0]);
                let mut prev = id(c[1]);
                for &corner in &c[2..] {
                    let next = id(corner);
                    indices.push([first, prev, next]);
                    prev = next;
                }
            }
            for c in &corners {
                first[c[0] as usize] = NONE;
            }
            let mut positions = Vec::with_capacity(corners.len());
            for c in &corners {
                let p = xf.transform_point3(self.positions[c[0] as usize]);
                if let Some(why) = p.to_array().into_iter().find_map(numbers::unusable) {
                    let q = self.positions[c[0] as usize];
                    bail!(
                        "{}:{}: vertex {} lands at {} once placed, which {why}",
                        self.path.display(),
                        self.position_lines[c[0] as usize],
                        show3(q),
                        show3(p)
                    );
                }
                positions.push(p);
            }
            let has = |k: usize| corners.iter().filter(|c| c[k] != NONE).count();
            let (with_uv, with_normal) = (has(1), has(2));
            if (with_uv > 0 && with_uv < corners.len())
                || (with_normal > 0 && with_normal < corners.len())
            {
                partial.push(g.faces[0].line);
            }
            let uvs = (with_uv == corners.len())
                .then(|| corners.iter().map(|c| self.uvs[c[1] as usize]).collect());
            let normals = (with_normal == corners.len()).then(|| {
                corners
                    .iter()
                    .map(|c| {
                        (nxf * self.normals[c[2] as usize])
                            .normalize_or_zero()
                            .as_vec3()
                    })
                    .collect()
            });
            meshes.push(Placed {
                name: if g.name.is_empty() {
                    stem.clone()
                } else {
                    g.name.clone()
                },
                positions,
                normals,
                uvs,
                colors: None,
                indices,
                material: material(g.material.as_ref()),
            });
        }
        if let Some(line) = partial.first() {
            warnings.push(format!(
                "{}:{line}: some faces of a mesh have UVs or normals and others not: \
                 {} such mesh{} shaded flat and untextured where they lack them",
                self.path.display(),
                partial.len(),
                if partial.len() == 1 { "" } else { "es" }
            ));
        }
        Ok(meshes)
    }
}

/// A material library's materials, with the file they came from.
type Library = Vec<(PathBuf, MtlMaterial)>;

fn is_not_found(e: &anyhow::Error) -> bool {
    e.downcast_ref::<ReadError>()
        .is_some_and(ReadError::is_not_found)
}

/// Reads the `mtllib` files of `obj`. A missing file is a warning; an
/// unreadable or broken one an error. `mtllib a.mtl b.mtl` names two
/// files unless one file has that whole name.
fn read_libraries(src: &dyn Source, obj: &ObjFile, warnings: &mut Vec<String>) -> Result<Library> {
    let mut lib = Library::new();
    for (written, line) in &obj.libraries {
        let read = |w: &str| {
            let p = resolve(&obj.path, w);
            let text = src.read_text(&p, Kind::Mtl);
            (p, text)
        };
        let mut files = vec![read(written)];
        if files[0].1.as_ref().is_err_and(is_not_found) && written.contains(char::is_whitespace) {
            files = written.split_whitespace().map(read).collect();
        }
        for (mtl_path, text) in files {
            let text = match text {
                Err(e) if is_not_found(&e) => {
                    warnings.push(format!(
                        "{}:{line}: material library {} not found; using the default material",
                        obj.path.display(),
                        mtl_path.display()
                    ));
                    continue;
                }
                t => t.with_context(|| format!("{}:{line}: mtllib", obj.path.display()))?,
            };
            let materials = mtl::parse(&mtl_path, &text, warnings)?;
            lib.extend(materials.into_iter().map(|m| (mtl_path.clone(), m)));
        }
    }
    Ok(lib)
}

fn convert_material(
    parts: &mut Parts,
    src: &dyn Source,
    mtl_path: &Path,
    m: &MtlMaterial,
) -> Material {
    let d = Material::default();
    let texture = m.map_kd.as_ref().and_then(|(file, line)| {
        let from = format!("{}:{line}", mtl_path.display());
        parts.texture(src, &resolve(mtl_path, file), &from)
    });
    Material {
        name: m.name.clone(),
        kd: m.kd.unwrap_or(d.kd),
        ks: m.ks.unwrap_or(d.ks),
        ns: m.ns.unwrap_or(d.ns),
        dissolve: m.dissolve.unwrap_or(d.dissolve),
        texture,
    }
}

/// Reads an OBJ (and, unless `material` replaces them, its MTL files and
/// textures): materials and textures go into `parts`, the meshes come back
/// placed by `xf` in f64, for the caller to add once the scene's frame is
/// known.
pub fn load_placed(
    parts: &mut Parts,
    src: &dyn Source,
    path: &Path,
    xf: &DAffine3,
    material: Option<&Material>,
) -> Result<Vec<Placed>> {
    let text = src.read_text(path, Kind::Obj)?;
    let obj = ObjFile::parse(path, &text, &mut parts.warnings)?;
    drop(text);
    if let Some(m) = material {
        let id = parts.add_material(m.clone());
        return obj.place(xf, |_| id, &mut parts.warnings);
    }
    let lib = read_libraries(src, &obj, &mut parts.warnings)?;
    let first = parts.materials.len() as u32;
    for (mtl_path, m) in &lib {
        let conv = convert_material(parts, src, mtl_path, m);
        parts.add_material(conv);
    }
    let mut default = None;
    let mut unknown: Vec<(String, usize)> = Vec::new();
    let mut new_materials = Vec::new();
    let meshes = obj.place(
        xf,
        |used| {
            // The last definition of a name wins, as in other readers.
            let found = used.and_then(|(name, _)| lib.iter().rposition(|(_, m)| &m.name == name));
            match (found, used) {
                (Some(i), _) => first + i as u32,
                (None, used) => {
                    if let Some((name, line)) = used {
                        if !unknown.iter().any(|(n, _)| n == name) {
                            unknown.push((name.clone(), *line));
                        }
                    }
                    *default.get_or_insert_with(|| {
                        new_materials.push(Material::default());
                        first + lib.len() as u32
                    })
                }
            }
        },
        &mut parts.warnings,
    )?;
    for m in new_materials {
        parts.add_material(m);
    }
    for (name, line) in unknown {
        parts.warnings.push(format!(
            "{}:{line}: usemtl {name}: no such material{}; using the default material",
            path.display(),
            if lib.is_empty() {
                String::new()
            } else {
                format!(" in {}", libraries_named(&lib))
            }
        ));
    }
    Ok(meshes)
}

fn libraries_named(lib: &Library) -> String {
    let mut names: Vec<String> = Vec::new();
    for (p, _) in lib {
        let s = p.display().to_string();
        if !names.contains(&s) {
            names.push(s);
        }
    }
    names.join(", ")
}

/// Loads an OBJ (and its MTL files) into `parts`, placed by `place` and
/// rounded to f32 where it lands. `material` overrides every material of
/// the file when given.
pub fn load_into(
    parts: &mut Parts,
    src: &dyn Source,
    path: &Path,
    place: &Placement,
    material: Option<&Material>,
) -> Result<()> {
    let xf = place.transform.as_daffine3();
    for m in load_placed(parts, src, path, &xf, material)? {
        parts.add_placed(m, &Frame::IDENTITY);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::source::Memory;
    use glam::Vec3;

    fn load(files: Vec<(&'static str, String)>) -> Result<Parts> {
        let src = files
            .into_iter()
            .fold(Memory::default(), |m, (p, t)| m.with(p, t));
        let mut p = Parts::default();
        load_into(
            &mut p,
            &src,
            Path::new("m/a.obj"),
            &Placement::default(),
            None,
        )?;
        Ok(p)
    }

    fn error(obj: &str) -> String {
        format!("{:#}", load(vec![("m/a.obj", obj.into())]).unwrap_err())
    }

    const QUAD: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";

    #[test]
    fn quad_is_two_triangles_with_default_material() {
        let p = load(vec![("m/a.obj", QUAD.into())]).unwrap();
        assert_eq!(p.geometry.indices, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(p.materials, vec![Material::default()]);
        assert_eq!(p.meshes[0].name, "a");
        assert!(p.warnings.is_empty(), "{:?}", p.warnings);
    }

    #[test]
    fn objects_materials_and_welding_split_as_written() {
        let obj = "mtllib a.mtl\no first\nusemtl r\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\n\
                   vn 0 0 1\nf 1//1 2//1 3//1\nf 2//1 4//1 3//1\nusemtl g\nf 1 2 4\ng second\nf -4 -3 -2\n";
        let mtl = "newmtl r\nKd 1 0 0\nnewmtl g\nKd 0 1 0\n";
        let p = load(vec![("m/a.obj", obj.into()), ("m/a.mtl", mtl.into())]).unwrap();
        let names: Vec<&str> = p.meshes.iter().map(|m| m.name.as_str()).collect();
        assert_eq!(names, ["first", "first", "second"]);
        assert!(p.meshes[0].smooth && !p.meshes[1].smooth);
        // Four corners welded to four vertices in the first mesh.
        assert_eq!(p.geometry.indices[..2], [[0, 1, 2], [1, 3, 2]]);
        assert_eq!(p.geometry.tri_material, [0, 0, 1, 1]);
        assert_eq!(p.geometry.positions.len(), 4 + 3 + 3);
    }

    #[test]
    fn bad_indices_name_the_line() {
        for (obj, want) in [
            (
                format!("{QUAD}\n# c\nf 1 2 9\n"),
                "m/a.obj:8: the face refers to vertex 9",
            ),
            (format!("{QUAD}f 1 2 0\n"), "m/a.obj:6: vertex index 0"),
            (
                format!("{QUAD}f 1 2 -5\n"),
                "m/a.obj:6: relative vertex index -5",
            ),
            (
                "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\n\
                 f 1//6148914691236517207 2//1 3//1\n"
                    .into(),
                "m/a.obj:7: normal index 6148914691236517207 is out of range",
            ),
            (
                format!("{QUAD}vt 0 0\nf 1/2 2/1 3/1\n"),
                "m/a.obj:7: the face refers to texture coordinate 2",
            ),
            (
                format!("{QUAD}f 1 2 99999999999999999999\n"),
                "m/a.obj:6: '99999999999999999999'",
            ),
            (
                format!("{QUAD}f 1 2\n"),
                "m/a.obj:6: a face needs at least 3",
            ),
            (
                format!("{QUAD}f 1/1/1/1 2 3\n"),
                "m/a.obj:6: '1/1/1/1' is not a face vertex",
            ),
        ] {
            let e = error(&obj);
            assert!(e.contains(want), "{obj:?}: {e}");
        }
        // Relative indices and forward references that land in range load.
        let p = load(vec![(
            "m/a.obj",
            "f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf -3 -2 -1\n".into(),
        )])
        .unwrap();
        assert_eq!(p.geometry.indices.len(), 2);
    }

    #[test]
    fn numbers_are_checked_before_and_after_w() {
        for (obj, want) in [
            (
                "v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n",
                "m/a.obj:2: 'nan' is not a finite",
            ),
            ("v 0 0 0\nv 1e39 0 0\n", "m/a.obj:2: '1e39' is too large"),
            (
                "v 0 0 0\nv 1 0 0 1e-45\n",
                "m/a.obj:2: w = 1e-45 divides the vertex to (1e45, 0, 0)",
            ),
            ("v 1 0 0 0\n", "m/a.obj:1: vertex with w = 0"),
            ("v 1 0\n", "m/a.obj:1: a vertex takes 3 coordinates"),
            ("vn 1 0\n", "m/a.obj:1: a normal takes 3 numbers"),
            ("vt\n", "m/a.obj:1: a texture coordinate takes 1 to 3"),
            ("v 1 2 3,5\n", "m/a.obj:1: '3,5' is not a number"),
        ] {
            let e = error(obj);
            assert!(e.contains(want), "{obj:?}: {e}");
        }
        // w divides; a colour is ignored; a trailing comment is a comment.
        let p = load(vec![(
            "m/a.obj",
            "v 0 0 0 2\nv 2 0 0 2\nv 0 4 0 2\nv 0 0 1 0.5 0.5 0.5 # grey\nf 1 2 3\n".into(),
        )])
        .unwrap();
        assert_eq!(p.geometry.positions[1], Vec3::X);
        assert_eq!(p.geometry.positions[2], Vec3::new(0.0, 2.0, 0.0));
    }

    #[test]
    fn bom_crlf_cr_and_continuations_read_alike() {
        let plain = load(vec![("m/a.obj", QUAD.into())]).unwrap();
        for text in [
            format!("\u{feff}{QUAD}"),
            QUAD.replace('\n', "\r\n"),
            QUAD.replace('\n', "\r"),
            QUAD.replace("f 1 2 3 4", "f 1 2 \\\n 3 4"),
        ] {
            let p = load(vec![("m/a.obj", text.clone())]).unwrap();
            assert_eq!(p.geometry.positions, plain.geometry.positions, "{text:?}");
            assert_eq!(p.geometry.indices, plain.geometry.indices, "{text:?}");
        }
        let e = format!(
            "{:#}",
            load(vec![("m/a.obj", "v 0 0 0\r\nv \u{0}\u{ff}".into())]).unwrap_err()
        );
        assert!(e.contains("m/a.obj:2"), "{e}");
    }

    #[test]
    fn missing_mtl_and_texture_warn() {
        let obj = format!("mtllib nope.mtl\nusemtl x\n{QUAD}");
        let p = load(vec![("m/a.obj", obj)]).unwrap();
        let all = p.warnings.join("\n");
        assert!(
            all.contains("m/a.obj:1: material library m/nope.mtl not found"),
            "{all}"
        );
        assert!(
            all.contains("m/a.obj:2: usemtl x: no such material"),
            "{all}"
        );
        let obj = format!("mtllib sub\\my mat.mtl\nusemtl x\n{QUAD}");
        let mtl = "newmtl x\nKd 1 0 0\nKs 0.5 0.5 0.5\nNs 50\nd 0.5\nmap_Kd ..\\tex dir\\t 1.png\n";
        let p = load(vec![("m/a.obj", obj), ("m/sub/my mat.mtl", mtl.into())]).unwrap();
        assert_eq!(p.materials[0].kd, Vec3::X);
        assert_eq!(p.materials[0].ns, 50.0);
        assert_eq!(p.materials[0].dissolve, 0.5);
        assert!(
            p.warnings
                .iter()
                .any(|w| w.starts_with("m/sub/my mat.mtl:6: texture m/sub/../tex dir/t 1.png")),
            "{:?}",
            p.warnings
        );
        // Two libraries on one line; the second defines the material used.
        let obj = format!("mtllib a.mtl b.mtl\nusemtl y\n{QUAD}");
        let p = load(vec![
            ("m/a.obj", obj),
            ("m/a.mtl", "newmtl x\nKd 1 0 0\n".into()),
            ("m/b.mtl", "newmtl y\nKd 0 1 0\n".into()),
        ])
        .unwrap();
        assert_eq!(p.materials[p.geometry.tri_material[0] as usize].kd, Vec3::Y);
        assert!(p.warnings.is_empty(), "{:?}", p.warnings);
    }

    #[test]
    fn non_finite_mtl_numbers_are_errors_and_absurd_ones_warn() {
        let obj = format!("mtllib a.mtl\nusemtl x\n{QUAD}");
        for (mtl, line) in [
            ("newmtl x\nKd nan 0 0\n", 2),
            ("newmtl x\nKd 1 1 1\nNs inf\n", 3),
            ("newmtl x\n\nd -infinity\n", 3),
            ("newmtl x\nKs 0 0 1e39\n", 2),
            ("newmtl x\nKd 0.5 0.5\n", 2),
            ("newmtl x\nKd\n", 2),
        ] {
            let e = load(vec![("m/a.obj", obj.clone()), ("m/a.mtl", mtl.into())]).unwrap_err();
            assert!(format!("{e}").contains(&format!("m/a.mtl:{line}")), "{e}");
        }
        // A texture named like a number is not a number.
        let mtl = "newmtl x\nmap_Kd nan\nKs 1e30 0 0\n";
        let p = load(vec![("m/a.obj", obj), ("m/a.mtl", mtl.into())]).unwrap();
        assert!(
            p.warnings.iter().any(|w| w.contains("m/a.mtl:3: absurd")),
            "{:?}",
            p.warnings
        );
    }

    #[test]
    fn degenerate_triangles_are_skipped_and_counted() {
        let p = load(vec![(
            "m/a.obj",
            "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 0 1 0\nf 1 2 3\nf 1 2 4\n".into(),
        )])
        .unwrap();
        assert_eq!(p.geometry.indices.len(), 1);
        assert!(p.warnings.iter().any(|w| w.contains("1 degenerate")));
    }

    #[test]
    fn triangles_beyond_the_memory_available_are_refused_as_they_come() {
        let big = format!(
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf{}\n",
            " 1 2 3".repeat(1000)
        );
        let budget = 1000 * memory::BYTES_PER_TRIANGLE;
        let e = ObjFile::parse_within(Path::new("m.obj"), &big, &mut Vec::new(), budget)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert_eq!(
            e,
            "m.obj:5: 2999 triangles by this line would need 586 KiB of memory; 195 KiB is available"
        );
        assert!(ObjFile::parse_within(Path::new("m.obj"), QUAD, &mut Vec::new(), budget).is_ok());
    }

    #[test]
    fn unsupported_statements_warn_once() {
        let p = load(vec![(
            "m/a.obj",
            format!("vp 0.5\nvp 0.2\ncurv 0 1 1 2\ns 1\nl 1 2\n{QUAD}"),
        )])
        .unwrap();
        assert_eq!(
            p.warnings,
            ["m/a.obj: ignored, not supported: vp (line 1 and 1 more), curv (line 3)"]
        );
    }
}
