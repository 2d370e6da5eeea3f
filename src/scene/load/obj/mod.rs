//! Wavefront OBJ, read in f64 with errors that name the file and line.
//!
//! Polygons (`f`) become triangles ([`super::polygon`]: fans where they
//! are convex); `o`, `g` and a change of `usemtl` start a new mesh, and
//! each mesh's vertices are welded by their position/UV/normal indices.
//! Every vertex index is checked exactly against the vertices the file
//! holds (relative, negative ones included), and every number is finite and
//! within the range of f32, also after the mesh is placed (a vertex's `w`,
//! a curve weight, is ignored for polygons, as other readers do). What
//! other readers forgive is a warning: a face's UV or normal indices beyond
//! those defined (the face is read without them), faces of fewer than three
//! vertices (skipped), a vertex whose coordinates f32 cannot hold (the
//! faces using it skipped), a vertex colour that is not a number (none),
//! text that is not UTF-8 (read lossily) or is UTF-16 (decoded). Vertex
//! colours (`v x y z r g b`) are the diffuse colour. Points and lines (`p`,
//! `l`) and smoothing groups are ignored; other statements are ignored with
//! one warning per file.
//! Materials come from the `mtllib` files ([`super::mtl`]); a missing MTL
//! or texture is a warning.

mod piece;

use std::collections::HashMap;
use std::ops::Range;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicU64;

use anyhow::{anyhow, bail, Context, Result};
use glam::{DAffine3, DVec3, Vec2, Vec3};
use rayon::prelude::*;

use super::mtl::{self, MtlMaterial};
use super::numbers::{self, Absurd};
use super::parts::mesh_fits;
use super::polygon::Triangulator;
use super::source::{resolve, text_lossy, FileKind, ReadError, Source};
use crate::color::srgb_to_linear;
use crate::memory;
use crate::scene::rebase::Rebase;
use crate::scene::show::show3;
use crate::scene::texture::Wrap;
use crate::scene::Material;
use piece::{Out, Piece, Shared, Switch, Tally, Unusable};

pub use super::numbers::ABSURD;
pub use super::parts::{MeshData, Parts, Placed, Placement};

/// An absent UV or normal index.
const NONE: u32 = u32::MAX;

/// One polygon: its line and where its corners start in its piece's
/// [`Faces::corners`].
struct Face {
    line: u32,
    start: u32,
    len: u32,
}

/// The faces of one piece of the file, and their corners.
#[derive(Default)]
struct Faces {
    /// Position, UV and normal indices (0-based; [`NONE`] when absent).
    corners: Vec<[u32; 3]>,
    faces: Vec<Face>,
}

/// Faces that share an object name and a material.
struct Group {
    name: String,
    /// The `usemtl` name and its line.
    material: Option<(String, usize)>,
    /// Its faces in file order: runs of faces of one piece.
    runs: Vec<(usize, Range<usize>)>,
}

/// An OBJ file as read: every index checked, nothing placed yet.
pub(crate) struct ObjFile {
    path: PathBuf,
    positions: Vec<DVec3>,
    /// The line of each position, for errors found once it is placed.
    position_lines: Vec<u32>,
    normals: Vec<DVec3>,
    uvs: Vec<Vec2>,
    /// Each vertex's colour (linear RGB) where it has one; empty when none
    /// has.
    colors: Vec<Option<Vec3>>,
    /// The faces of each piece the file was read in.
    pieces: Vec<Faces>,
    groups: Vec<Group>,
    /// `mtllib` arguments as written, with their lines.
    libraries: Vec<(String, usize)>,
}

impl ObjFile {
    /// Parses OBJ text; non-fatal findings are appended to `warnings`. A
    /// mesh whose vertices or triangles would need more than `available`
    /// bytes ([`memory::mesh_bytes`]) is refused.
    ///
    /// A big file is read in pieces, in parallel ([`piece`]); the result,
    /// errors and warnings included, is the one of a reading from the top.
    pub(crate) fn parse(
        path: &Path,
        text: &str,
        warnings: &mut Vec<String>,
        available: u64,
    ) -> Result<ObjFile> {
        Self::parse_in(path, text, warnings, available, piece::PIECE)
    }

    /// [`ObjFile::parse`] in pieces of about `size` bytes.
    fn parse_in(
        path: &Path,
        text: &str,
        warnings: &mut Vec<String>,
        available: u64,
        size: usize,
    ) -> Result<ObjFile> {
        match Self::read(path, piece::cut(text, size), warnings, available)? {
            Some(f) => Ok(f),
            // The pieces together ran out of memory: in one piece, the
            // reading stops where the triangles by then do not fit.
            None => Self::read(path, vec![text], warnings, available)?
                .with_context(|| format!("{}: out of memory for triangles", path.display())),
        }
    }

    /// Reads the pieces of a file in parallel and stitches them; `None`
    /// when they stopped for lack of memory before any line where the
    /// triangles from the top would not fit.
    fn read(
        path: &Path,
        pieces: Vec<&str>,
        warnings: &mut Vec<String>,
        available: u64,
    ) -> Result<Option<ObjFile>> {
        let census: Vec<(usize, [usize; 3])> =
            pieces.par_iter().map(|t| piece::census(t)).collect();
        let total = census
            .iter()
            .fold([0; 3], |a, (_, c)| [0, 1, 2].map(|k| a[k] + c[k]));
        // Vertices are checked before they are allocated (a file of them
        // alone takes seven times its size), triangles as they are read.
        let vertices = total.iter().sum::<usize>() as u64;
        mesh_fits(vertices, 0, available).map_err(|e| anyhow!("{}: {e}", path.display()))?;
        let mut f = ObjFile {
            path: path.to_path_buf(),
            positions: vec![DVec3::ZERO; total[0]],
            position_lines: vec![0; total[0]],
            normals: vec![DVec3::ZERO; total[2]],
            uvs: vec![Vec2::ZERO; total[1]],
            colors: Vec::new(),
            pieces: Vec::new(),
            groups: Vec::new(),
            libraries: Vec::new(),
        };
        // Each piece's place: its first line and counts before it, and its
        // part of the vertices, UVs and normals.
        let mut jobs = Vec::with_capacity(pieces.len());
        let (mut line, mut before) = (0, [0; 3]);
        let mut positions = &mut f.positions[..];
        let mut position_lines = &mut f.position_lines[..];
        let mut uvs = &mut f.uvs[..];
        let mut normals = &mut f.normals[..];
        for (text, (lines, counts)) in pieces.iter().zip(&census) {
            let out = Out {
                positions: split(&mut positions, counts[0]),
                position_lines: split(&mut position_lines, counts[0]),
                uvs: split(&mut uvs, counts[1]),
                normals: split(&mut normals, counts[2]),
            };
            jobs.push((*text, line, before, out));
            line += lines;
            before = [0, 1, 2].map(|k| before[k] + counts[k]);
        }
        let budget = Shared {
            available,
            triangles: AtomicU64::new(0),
        };
        let read: Vec<Piece> = jobs
            .into_par_iter()
            .map(|(text, line, before, out)| piece::read(path, text, line, before, out, &budget))
            .collect();
        let Some(read) = Self::settle(path, read, warnings, available)? else {
            return Ok(None);
        };
        let mut absurd = Absurd::default();
        let mut ignored = piece::Ignored::default();
        let (mut bad_colors, mut short_faces) = (Tally::default(), Tally::default());
        let mut lines = Tally::default();
        let mut unusable = Unusable::default();
        let mut colors = Vec::new();
        let mut current = Group {
            name: String::new(),
            material: None,
            runs: Vec::new(),
        };
        for (k, p) in read.into_iter().enumerate() {
            let mut from = 0;
            for (at, switch) in p.switches {
                if at > from {
                    current.runs.push((k, from..at));
                }
                from = at;
                f.switch(&mut current, switch);
            }
            if p.faces.faces.len() > from {
                current.runs.push((k, from..p.faces.faces.len()));
            }
            f.pieces.push(p.faces);
            f.libraries.extend(p.libraries);
            absurd = absurd.then(p.absurd);
            ignored.extend(p.ignored);
            bad_colors = bad_colors.then(p.bad_colors);
            short_faces = short_faces.then(p.short_faces);
            lines = lines.then(p.lines);
            unusable = unusable.then(p.unusable);
            colors.extend(p.colors);
        }
        f.finish(current);
        f.colors = vertex_colors(&colors, f.positions.len());
        drop(colors);
        let (dropped, skipped) = f.check_indices(unusable.count > 0)?;
        warnings.extend(absurd.warning(path));
        if let Some((line, why)) = unusable.first {
            let more = match unusable.count {
                1 => String::new(),
                n => format!(
                    " (and {} like it)",
                    crate::words::count(n as u64 - 1, "more vertex", "more vertices")
                ),
            };
            let it = if unusable.count == 1 { "it" } else { "them" };
            let faces = match skipped {
                0 => format!("no face uses {it}"),
                n => format!(
                    "{} using {it} skipped",
                    crate::words::count(n as u64, "face", "faces")
                ),
            };
            warnings.push(format!(
                "{}:{line}: vertex {why}{more}: {faces}",
                path.display()
            ));
        }
        let tallied = [
            (
                short_faces,
                "face with fewer than 3 vertices",
                "faces with fewer than 3 vertices",
                "skipped",
            ),
            (
                bad_colors,
                "vertex colour is not a finite number",
                "vertex colours are not finite numbers",
                "read as none (white)",
            ),
        ];
        for (t, one, many, done) in tallied {
            if let Some(line) = t.first {
                let what = crate::words::count(t.count as u64, one, many);
                warnings.push(format!("{}:{line}: {what}: {done}", path.display()));
            }
        }
        warnings.extend(dropped);
        // Said only where they are all there is: a mesh's wireframe beside
        // its faces is no fault.
        if let (Some(line), true) = (lines.first, f.pieces.iter().all(|p| p.faces.is_empty())) {
            warnings.push(format!(
                "{}:{line}: {}: not drawn (rayterm draws faces)",
                path.display(),
                crate::words::count(lines.count as u64, "line or point", "lines and points")
            ));
        }
        if let Some(list) = ignored.list() {
            warnings.push(format!(
                "{}: ignored, not supported: {list}",
                path.display()
            ));
        }
        Ok(Some(f))
    }

    /// The pieces' first error in file order, where the triangles counted
    /// from the top first do not fit in memory counting as one; the
    /// warnings up to there go into `warnings`. `None` (and no warnings)
    /// when the pieces stopped for lack of memory before such a line.
    fn settle(
        path: &Path,
        mut read: Vec<Piece>,
        warnings: &mut Vec<String>,
        available: u64,
    ) -> Result<Option<Vec<Piece>>> {
        let mut found = Vec::new();
        let settled = Self::first_error(path, &mut read, &mut found, available);
        if !matches!(settled, Ok(false)) {
            warnings.extend(found);
        }
        Ok(settled?.then_some(read))
    }

    /// [`ObjFile::settle`]: whether the pieces read to their end.
    fn first_error(
        path: &Path,
        read: &mut [Piece],
        warnings: &mut Vec<String>,
        available: u64,
    ) -> Result<bool> {
        let mut triangles = 0u64;
        for p in read {
            for face in &p.faces.faces {
                triangles += face.len as u64 - 2;
                let needed = triangles.saturating_mul(memory::BYTES_PER_TRIANGLE);
                if needed > available {
                    let line = face.line as usize;
                    warnings.extend(
                        p.warnings
                            .drain(..)
                            .filter(|(n, _)| *n < line)
                            .map(|(_, w)| w),
                    );
                    bail!(
                        "{}:{line}: {triangles} triangles by this line would need {} of \
                         memory; {} is available",
                        path.display(),
                        memory::bytes(needed),
                        memory::bytes(available)
                    );
                }
            }
            warnings.extend(p.warnings.drain(..).map(|(_, w)| w));
            if let Some(e) = p.error.take() {
                return Err(e);
            }
            if p.full {
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// Applies a statement that changes the group.
    fn switch(&mut self, current: &mut Group, switch: Switch) {
        match switch {
            Switch::Object(name) => {
                let next = Group {
                    name,
                    material: current.material.clone(),
                    runs: Vec::new(),
                };
                self.finish(std::mem::replace(current, next));
            }
            Switch::Material(name, line) => {
                if current.material.as_ref().is_some_and(|(m, _)| *m == name) {
                    return;
                }
                let next = Group {
                    name: current.name.clone(),
                    material: Some((name, line)),
                    runs: Vec::new(),
                };
                if current.runs.is_empty() {
                    *current = next;
                } else {
                    self.finish(std::mem::replace(current, next));
                }
            }
        }
    }

    fn finish(&mut self, g: Group) {
        if !g.runs.is_empty() {
            self.groups.push(g);
        }
    }

    /// The faces of `g` in file order, each with its line and corners.
    fn faces<'a>(&'a self, g: &'a Group) -> impl Iterator<Item = (usize, &'a [[u32; 3]])> + 'a {
        g.runs.iter().flat_map(move |(k, run)| {
            let p = &self.pieces[*k];
            // Faces using a vertex that cannot be placed have no corners.
            p.faces[run.clone()]
                .iter()
                .filter(|f| f.len > 0)
                .map(move |f| {
                    let start = f.start as usize;
                    (f.line as usize, &p.corners[start..start + f.len as usize])
                })
        })
    }

    /// Every vertex of every face is one the file defines (forward
    /// references included, as other readers allow them). A face that
    /// refers to texture coordinates or normals beyond those the file
    /// defines is read without them, as tinyobjloader reads it: the
    /// warning that says so. A face using a vertex that cannot be placed
    /// (NaN; only looked for where `some_unusable`) is left with no
    /// corners: how many were.
    fn check_indices(&mut self, some_unusable: bool) -> Result<(Option<String>, usize)> {
        let counts = [self.positions.len(), self.uvs.len(), self.normals.len()];
        let names = ["vertex", "texture coordinate", "normal"];
        let beyond = |c: &[u32; 3], k: usize| c[k] != NONE && c[k] as usize >= counts[k];
        // The first such face (line, what, index) and how many there are.
        let mut first = None;
        let (mut dropped, mut skipped) = (0, 0);
        for p in &mut self.pieces {
            for f in &mut p.faces {
                let corners = &mut p.corners[f.start as usize..][..f.len as usize];
                let line = f.line;
                let mut lost = [false; 3];
                let mut unusable = false;
                for c in corners.iter() {
                    if beyond(c, 0) {
                        bail!(
                            "{}:{line}: the face refers to vertex {} but the file defines {}",
                            self.path.display(),
                            c[0] as u64 + 1,
                            counts[0]
                        );
                    }
                    unusable |= some_unusable && self.positions[c[0] as usize].is_nan();
                    lost[1] |= beyond(c, 1);
                    lost[2] |= beyond(c, 2);
                }
                if unusable {
                    f.len = 0;
                    skipped += 1;
                    continue;
                }
                if lost[1] || lost[2] {
                    for k in [1, 2].into_iter().filter(|&k| lost[k]) {
                        let c = corners.iter().find(|c| beyond(c, k)).expect("one is");
                        first.get_or_insert((line, k, c[k]));
                        corners.iter_mut().for_each(|c| c[k] = NONE);
                    }
                    dropped += 1;
                }
            }
        }
        let warning = first.map(|(line, k, index)| {
            let more = match dropped {
                1 => String::new(),
                2 => " (and 1 more face)".into(),
                n => format!(" (and {} more faces)", n - 1),
            };
            format!(
                "{}:{line}: the face refers to {} {} but the file defines {}{more}: read \
                 without its texture coordinates or normals",
                self.path.display(),
                names[k],
                index as u64 + 1,
                counts[k]
            )
        });
        Ok((warning, skipped))
    }

    /// The meshes placed by `xf` (in f64), each group with the material
    /// `material(group's usemtl, whether its vertices have colours)` gives.
    fn place(
        &self,
        xf: &DAffine3,
        mut material: impl FnMut(Option<&(String, usize)>, bool) -> u32,
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
        let mut triangulator = Triangulator::default();
        // Polygons left as fans: the first one's line, and how many.
        let (mut fans, mut fan_line) = (0, None);
        let (mut points, mut ids, mut cut) = (Vec::new(), Vec::new(), Vec::new());
        // Welding: the mesh vertex a position was first used as, by
        // position; corners that reuse a position with other UV or normal
        // indices go through a map. Reset after each mesh.
        let mut first: Vec<u32> = vec![NONE; self.positions.len()];
        for g in &self.groups {
            // Every face skipped: no mesh.
            if self.faces(g).next().is_none() {
                continue;
            }
            let mut other: HashMap<[u32; 3], u32> = HashMap::new();
            let mut corners: Vec<[u32; 3]> = Vec::new();
            let mut indices = Vec::new();
            for (line, c) in self.faces(g) {
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
                if let [p, q, r] = c {
                    indices.push([id(*p), id(*q), id(*r)]);
                    continue;
                }
                ids.clear();
                ids.extend(c.iter().map(|&corner| id(corner)));
                points.clear();
                points.extend(c.iter().map(|k| self.positions[k[0] as usize]));
                if !triangulator.triangles(&points, &mut cut) {
                    fans += 1;
                    fan_line.get_or_insert(line);
                }
                indices.extend(cut.drain(..).map(|t| t.map(|k| ids[k as usize])));
            }
            for c in &corners {
                first[c[0] as usize] = NONE;
            }
            let placed: Vec<DVec3> = corners
                .par_iter()
                .with_min_len(1 << 12)
                .map(|c| xf.transform_point3(self.positions[c[0] as usize]))
                .collect();
            let unusable = |p: &DVec3| p.to_array().into_iter().find_map(numbers::unusable);
            let bad = placed
                .par_iter()
                .with_min_len(1 << 12)
                .position_first(|p| unusable(p).is_some());
            if let Some(i) = bad {
                let (q, p) = (self.positions[corners[i][0] as usize], placed[i]);
                bail!(
                    "{}:{}: vertex {} lands at {} once placed, which {}",
                    self.path.display(),
                    self.position_lines[corners[i][0] as usize],
                    show3(q),
                    show3(p),
                    unusable(&p).unwrap_or_default()
                );
            }
            let positions = placed;
            let has = |k: usize| corners.iter().filter(|c| c[k] != NONE).count();
            let (with_uv, with_normal) = (has(1), has(2));
            if (with_uv > 0 && with_uv < corners.len())
                || (with_normal > 0 && with_normal < corners.len())
            {
                partial.extend(self.faces(g).next().map(|(line, _)| line));
            }
            let uvs = (with_uv == corners.len())
                .then(|| corners.iter().map(|c| self.uvs[c[1] as usize]).collect());
            // White where a vertex of a coloured mesh has no colour: the
            // material's own.
            let colors = (!self.colors.is_empty()
                && corners.iter().any(|c| self.colors[c[0] as usize].is_some()))
            .then(|| {
                corners
                    .iter()
                    .map(|c| self.colors[c[0] as usize].unwrap_or(Vec3::ONE))
                    .collect()
            });
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
                uvs1: None,
                tangents: None,
                material: material(g.material.as_ref(), colors.is_some()),
                colors,
                indices,
            });
        }
        if let Some(line) = fan_line {
            let what = Triangulator::warning(fans);
            warnings.push(format!("{}:{line}: {what}", self.path.display()));
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

/// The colours of `vertices` vertices from those written (`v x y z r g
/// b`), in linear RGB. Written as 0..1, as trimesh and Blender write them,
/// or as 0..255 where any value is above 1, as MeshLab reads them (which
/// decides vertex by vertex: a 0..255 file's `1 0 0` would be full red);
/// sRGB either way, as Blender reads them and PLY colours are.
fn vertex_colors(written: &[(u32, [f32; 3])], vertices: usize) -> Vec<Option<Vec3>> {
    if written.is_empty() {
        return Vec::new();
    }
    let bytes = written.iter().any(|(_, c)| c.iter().any(|&x| x > 1.0));
    let full = if bytes { 255.0 } else { 1.0 };
    let mut colors = vec![None; vertices];
    for &(i, c) in written {
        let linear = c.map(|x| srgb_to_linear((x / full).clamp(0.0, 1.0)));
        colors[i as usize] = Some(Vec3::from_array(linear));
    }
    colors
}

/// The first `n` items of `rest`, which keeps the others.
fn split<'a, T>(rest: &mut &'a mut [T], n: usize) -> &'a mut [T] {
    let (first, others) = std::mem::take(rest).split_at_mut(n);
    *rest = others;
    first
}

/// A material library's materials, with the file they came from.
type Library = Vec<(PathBuf, MtlMaterial)>;

fn is_not_found(e: &anyhow::Error) -> bool {
    e.downcast_ref::<ReadError>()
        .is_some_and(ReadError::is_not_found)
}

/// An `mtllib` argument as one name, and as names split at whitespace,
/// where a backslash before a space escapes it (`my\ file.mtl` names `my
/// file.mtl`, as other readers take it).
fn library_names(written: &str) -> (String, Vec<String>) {
    let (mut whole, mut names) = (String::new(), vec![String::new()]);
    let mut chars = written.chars().peekable();
    while let Some(c) = chars.next() {
        let word = names.last_mut().expect("never empty");
        match c {
            '\\' if chars.peek().is_some_and(|n| n.is_whitespace()) => {
                let escaped = chars.next().expect("peeked");
                whole.push(escaped);
                word.push(escaped);
            }
            c if c.is_whitespace() => {
                whole.push(c);
                if !word.is_empty() {
                    names.push(String::new());
                }
            }
            c => {
                whole.push(c);
                word.push(c);
            }
        }
    }
    names.retain(|n| !n.is_empty());
    (whole, names)
}

/// Reads the `mtllib` files of `obj`. A missing file is a warning; an
/// unreadable or broken one an error. `mtllib a.mtl b.mtl` names two
/// files unless one file has that whole name. Text that is not UTF-8 is
/// read lossily ([`text_lossy`]).
fn read_libraries(src: &dyn Source, obj: &ObjFile, warnings: &mut Vec<String>) -> Result<Library> {
    let mut lib = Library::new();
    for (written, line) in &obj.libraries {
        let read = |w: &str| {
            let p = resolve(&obj.path, w);
            let bytes = src.read(&p, FileKind::Mtl).map_err(anyhow::Error::from);
            (p, bytes)
        };
        let (whole, split) = library_names(written);
        let mut files = vec![read(&whole)];
        if files[0].1.as_ref().is_err_and(is_not_found) && split.len() > 1 {
            files = split.iter().map(|w| read(w)).collect();
        }
        for (mtl_path, bytes) in files {
            let outside = src.outside(&obj.path, &mtl_path);
            // A file outside that cannot be read is not quoted either.
            let bytes = match &outside {
                Some(o) if bytes.as_ref().is_err_and(|e| !is_not_found(e)) => {
                    o.quiet(FileKind::Mtl, bytes, warnings, usize::MAX)
                }
                _ => bytes,
            };
            let bytes = match bytes {
                Err(e) if is_not_found(&e) => {
                    warnings.push(format!(
                        "{}:{line}: material library {} not found; using the default material",
                        obj.path.display(),
                        crate::words::path(&mtl_path)
                    ));
                    continue;
                }
                b => b.with_context(|| format!("{}:{line}: mtllib", obj.path.display()))?,
            };
            if let Some(o) = &outside {
                let from = format!("{}:{line}", obj.path.display());
                warnings.push(o.warning(&from, "material library", written));
            }
            let before = warnings.len();
            let text = text_lossy(&mtl_path, bytes, warnings);
            let materials = mtl::parse(&mtl_path, &text, warnings);
            let materials = match &outside {
                Some(o) => o.quiet(FileKind::Mtl, materials, warnings, before),
                None => materials,
            }?;
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
        let id = parts.texture(src, mtl_path, file, &from)?;
        if !m.clamp {
            return Some(id);
        }
        // `-clamp on`: a texture of its own, its texels shared.
        let mut t = parts.textures[id as usize].clone();
        t.wrap = [Wrap::Clamp; 2];
        Some(parts.add_texture(t))
    });
    // The PBR extension's materials: metallic-roughness, whose base
    // colour is Kd and its map, without Phong's specular terms.
    let pbr = m.pbr().then(|| mtl::pbr(parts, src, mtl_path, m));
    let phong = pbr.is_none();
    Material {
        name: m.name.clone(),
        kd: m.kd.unwrap_or(d.kd),
        ks: if phong {
            m.ks.unwrap_or(d.ks)
        } else {
            Vec3::ZERO
        },
        ns: if phong { m.ns.unwrap_or(d.ns) } else { 0.0 },
        dissolve: m.dissolve.unwrap_or(d.dissolve),
        texture,
        pbr,
        alpha: None,
        unlit: false,
    }
}

/// Reads an OBJ (and, unless `material` replaces them, its MTL files and
/// textures): materials and textures go into `parts`, the meshes come back
/// placed by `xf` in f64, for the caller to add once the scene's frame is
/// known.
pub(crate) fn load_placed(
    parts: &mut Parts,
    src: &dyn Source,
    path: &Path,
    xf: &DAffine3,
    material: Option<&Material>,
) -> Result<Vec<Placed>> {
    let text = text_lossy(path, src.read(path, FileKind::Obj)?, &mut parts.warnings);
    let obj = ObjFile::parse(path, &text, &mut parts.warnings, parts.budget.room())?;
    drop(text);
    if let Some(m) = material {
        let id = parts.add_material(m.clone());
        return obj.place(xf, |_, _| id, &mut parts.warnings);
    }
    let lib = read_libraries(src, &obj, &mut parts.warnings)?;
    let first = parts.materials.len() as u32;
    for (mtl_path, m) in &lib {
        let conv = convert_material(parts, src, mtl_path, m);
        parts.add_material(conv);
    }
    // The default material, and for meshes with vertex colours one of
    // white, so that they are the diffuse colour as they are (as in PLY).
    let mut defaults = [None, None];
    let mut unknown: Vec<(String, usize)> = Vec::new();
    let mut new_materials = Vec::new();
    let mut meshes = obj.place(
        xf,
        |used, colored| {
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
                    *defaults[colored as usize].get_or_insert_with(|| {
                        new_materials.push(Material {
                            kd: if colored {
                                Vec3::ONE
                            } else {
                                Material::default().kd
                            },
                            ..Material::default()
                        });
                        first + (lib.len() + new_materials.len()) as u32 - 1
                    })
                }
            }
        },
        &mut parts.warnings,
    )?;
    for m in new_materials {
        parts.add_material(m);
    }
    // Normal maps turn by MikkTSpace's tangents (an OBJ has none of its own).
    for m in &mut meshes {
        let normal_mapped = parts.materials[m.material as usize]
            .pbr
            .as_ref()
            .is_some_and(|p| p.normal.is_some());
        if normal_mapped {
            super::tangents::add(m);
        }
    }
    for (name, line) in unknown {
        let what = match name.is_empty() {
            true => "usemtl without a material name: no material without one".to_string(),
            false => format!("usemtl {}: no such material", crate::words::quoted(&name)),
        };
        parts.warnings.push(format!(
            "{}:{line}: {what}{}; using the default material",
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
        parts.add_placed(m, &Rebase::IDENTITY);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::load::source::Memory;

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
                format!("{QUAD}f 1 2 99999999999999999999\n"),
                "m/a.obj:6: '99999999999999999999'",
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
    fn numbers_are_checked_and_w_is_ignored() {
        for (obj, want) in [
            ("v nan 0\n", "m/a.obj:1: 'nan' is not a finite"),
            ("vn 0 0 1e39\n", "m/a.obj:1: '1e39' is too large"),
            ("vt 1.#INF 0\n", "m/a.obj:1: '1.#INF' is not a finite"),
            ("v 1 0\n", "m/a.obj:1: a vertex takes 3 coordinates"),
            ("vn 1 0\n", "m/a.obj:1: a normal takes 3 numbers"),
            ("vt\n", "m/a.obj:1: a texture coordinate takes 1 to 3"),
            ("v 1 2 3,5\n", "m/a.obj:1: '3,5' is not a number"),
        ] {
            let e = error(obj);
            assert!(e.contains(want), "{obj:?}: {e}");
        }
        // w, a curve weight, is ignored (0 too); a colour is ignored; a
        // trailing comment is a comment.
        let p = load(vec![(
            "m/a.obj",
            "v 0 0 0 2\nv 2 0 0 0\nv 0 4 0 1e-45\nv 0 0 1 0.5 0.5 0.5 # grey\nf 1 2 3\n".into(),
        )])
        .unwrap();
        assert_eq!(p.geometry.positions[1], Vec3::new(2.0, 0.0, 0.0));
        assert_eq!(p.geometry.positions[2], Vec3::new(0.0, 4.0, 0.0));
    }

    #[test]
    fn faces_using_vertices_f32_cannot_hold_are_skipped() {
        // Vertices 2 (nan), 5 (past f32, with a colour) and 6 (w): the
        // faces using them go, the others stay.
        let obj = "v 0 0 0\nv nan 0 0\nv 1 0 0\nv 0 1 0\nv 1e39 0 0 1 1 1\nv 0 0 1 -1.#IND\n\
                   f 1 2 3\nf 1 3 4\nf 3 4 5\no other\nf 4 6 1\n";
        let p = load(vec![("m/a.obj", obj.into())]).unwrap();
        assert_eq!(p.geometry.indices, [[0, 1, 2]]);
        assert_eq!(p.geometry.positions, [Vec3::ZERO, Vec3::X, Vec3::Y]);
        assert_eq!(p.meshes.len(), 1);
        assert_eq!(
            p.warnings,
            [
                "m/a.obj:2: vertex 'nan' is not a finite number (and 2 more vertices like it): 3 \
              faces using them skipped"
            ]
        );
        let p = load(vec![("m/a.obj", format!("{QUAD}v inf 0 0\n"))]).unwrap();
        assert_eq!(p.geometry.indices.len(), 2);
        assert_eq!(
            p.warnings,
            ["m/a.obj:6: vertex 'inf' is not a finite number: no face uses it"]
        );
        // In a file read in pieces, as in one read whole.
        let mut w = Vec::new();
        let text = format!("{QUAD}v 1e40 0 0\nf 1 2 -1\n{QUAD}f 1 2 3\n");
        ObjFile::parse_in(Path::new("m.obj"), &text, &mut w, u64::MAX, 8).unwrap();
        assert_eq!(
            w,
            [
                "m.obj:6: vertex '1e40' is too large: 32-bit floats are finite only up to 3.4e38: \
              1 face using it skipped"
            ]
        );
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
                .any(|w| w.starts_with("m/sub/my mat.mtl:6: texture m/tex dir/t 1.png")),
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
    fn faults_other_readers_forgive_are_warnings() {
        // UV and normal indices beyond those defined: those faces without
        // them; faces of fewer than three vertices: skipped.
        let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nvt 0 0\nf 1/5/7 2/5/7 3/5/7\n\
                   f 2/1 4/1 3/1\nf 2/1/9 4/1/9 3/1/9\nf 1 2\nf 3 # one\n";
        let p = load(vec![("m/a.obj", obj.into())]).unwrap();
        assert_eq!(p.geometry.indices.len(), 3);
        let all = p.warnings.join("\n");
        for part in [
            "m/a.obj:9: 2 faces with fewer than 3 vertices: skipped",
            "m/a.obj:6: the face refers to texture coordinate 5 but the file defines 1 (and 1 \
             more face): read without its texture coordinates or normals",
        ] {
            assert!(all.contains(part), "missing '{part}' in {all}");
        }
        // The face on line 7 keeps its UVs: the mesh has some.
        assert!(all.contains("some faces of a mesh have UVs"), "{all}");
        // Vertices beyond those defined stay an error.
        assert!(
            error("v 0 0 0\nf 1/1 2/1 3/1\n").contains("m/a.obj:2: the face refers to vertex 2")
        );
    }

    #[test]
    fn vertex_colours_are_the_diffuse_colour() {
        let tri = "f 1 2 3\n";
        // 0..1, with alpha after the colour or not.
        let p = load(vec![(
            "m/a.obj",
            format!("v 0 0 0 1 0 0\nv 1 0 0 0 1 0 0.5\nv 0 1 0 0 0 1\n{tri}"),
        )])
        .unwrap();
        assert!(p.warnings.is_empty(), "{:?}", p.warnings);
        assert_eq!(p.geometry.colors, [Vec3::X, Vec3::Y, Vec3::Z]);
        assert!(p.meshes[0].colored);
        assert_eq!(p.materials[0].kd, Vec3::ONE);
        // 0..255 where any value is above 1; sRGB.
        let p = load(vec![(
            "m/a.obj",
            format!("v 0 0 0 255 0 0\nv 1 0 0 0 128 1\nv 0 1 0 0 0 1\n{tri}"),
        )])
        .unwrap();
        let c = p.geometry.colors[1];
        assert_eq!(c.y, srgb_to_linear(128.0 / 255.0));
        assert_eq!(c.z, srgb_to_linear(1.0 / 255.0));
        // A colour that is not a number is none: white.
        let p = load(vec![(
            "m/a.obj",
            format!("v 0 0 0 nan 0 0\nv 1 0 0 0 1 0\nv 0 1 0 0 0 inf\nv 1 1 0\n{tri}f 2 4 3\n"),
        )])
        .unwrap();
        assert_eq!(
            p.geometry.colors,
            [Vec3::ONE, Vec3::Y, Vec3::ONE, Vec3::ONE]
        );
        assert_eq!(
            p.warnings,
            ["m/a.obj:1: 2 vertex colours are not finite numbers: read as none (white)"]
        );
        // Only a colour: a position or w that is no number leaves the
        // vertex out, text that is no number is an error.
        for obj in ["v nan 0 0 1 1 1\n", "v 0 0 0 nan\n"] {
            let p = load(vec![("m/a.obj", obj.into())]).unwrap();
            assert_eq!(
                p.warnings,
                ["m/a.obj:1: vertex 'nan' is not a finite number: no face uses it"]
            );
        }
        assert!(error("v 0 0 0 1 x 1\n").contains("m/a.obj:1: 'x' is not a number"));
        // A material's Kd is multiplied by them; meshes without colours
        // keep the default material.
        let obj = format!(
            "mtllib a.mtl\nv 0 0 0 1 0 0\nv 1 0 0\nv 0 1 0\nv 5 5 5\n{tri}usemtl m\n{tri}\
             g plain\nusemtl nope\nf 2 3 4\n"
        );
        let p = load(vec![
            ("m/a.obj", obj),
            ("m/a.mtl", "newmtl m\nKd 0.5 0.5 0.5\n".into()),
        ])
        .unwrap();
        let kd: Vec<Vec3> = p
            .geometry
            .tri_material
            .iter()
            .map(|&m| p.materials[m as usize].kd)
            .collect();
        assert_eq!(kd, [Vec3::ONE, Vec3::splat(0.5), Vec3::splat(0.8)]);
        let colored: Vec<bool> = p.meshes.iter().map(|m| m.colored).collect();
        assert_eq!(colored, [true, true, false]);
    }

    #[test]
    fn empty_material_names_escaped_spaces_and_latin1_are_read() {
        // A newmtl without a name is what a usemtl without one uses.
        let mtl = "newmtl x\nKd 0 1 0\nnewmtl\nKd 1 0 0\n";
        let obj = format!("mtllib my\\ lib.mtl\nusemtl\n{QUAD}");
        let p = load(vec![("m/a.obj", obj.clone()), ("m/my lib.mtl", mtl.into())]).unwrap();
        assert_eq!(p.materials[p.geometry.tri_material[0] as usize].kd, Vec3::X);
        assert_eq!(
            p.warnings,
            ["m/my lib.mtl:3: newmtl without a name: the material of a usemtl without one"]
        );
        let p = load(vec![
            ("m/a.obj", obj),
            ("m/my lib.mtl", "newmtl x\n".into()),
        ])
        .unwrap();
        assert_eq!(
            p.warnings,
            [
                "m/a.obj:2: usemtl without a material name: no material without one in \
              m/my lib.mtl; using the default material"
            ]
        );
        // Escaped spaces in one of two names.
        let obj = format!("mtllib a\\ b.mtl c.mtl\nusemtl y\n{QUAD}");
        let p = load(vec![
            ("m/a.obj", obj),
            ("m/a b.mtl", "newmtl x\n".into()),
            ("m/c.mtl", "newmtl y\nKd 0 0 1\n".into()),
        ])
        .unwrap();
        assert_eq!(p.materials[p.geometry.tri_material[0] as usize].kd, Vec3::Z);
        // Latin-1 names in both files still match.
        let src = Memory::default()
            .with(
                "m/a.obj",
                [
                    b"mtllib a.mtl\nusemtl caf\xe9\n".as_slice(),
                    QUAD.as_bytes(),
                ]
                .concat(),
            )
            .with("m/a.mtl", b"# \xa9\nnewmtl caf\xe9\nKd 1 0 0\n".to_vec());
        let mut p = Parts::default();
        load_into(
            &mut p,
            &src,
            Path::new("m/a.obj"),
            &Placement::default(),
            None,
        )
        .unwrap();
        assert_eq!(p.materials[p.geometry.tri_material[0] as usize].kd, Vec3::X);
        assert_eq!(p.materials[0].name, "caf\u{fffd}");
        let all = p.warnings.join("\n");
        for part in [
            "m/a.obj:2: not valid UTF-8 (byte 0xe9 at column 11): read as U+FFFD",
            "m/a.mtl:1: not valid UTF-8 (byte 0xa9 at column 3): read as U+FFFD",
        ] {
            assert!(all.contains(part), "missing '{part}' in {all}");
        }
    }

    #[test]
    fn concave_polygons_are_clipped_and_convex_ones_stay_fans() {
        // A U whose fan would cover its notch.
        let u = "v 0 0 0\nv 3 0 0\nv 3 3 0\nv 2 3 0\nv 2 1 0\nv 1 1 0\nv 1 3 0\nv 0 3 0\n";
        let p = load(vec![("m/a.obj", format!("{u}f 1 2 3 4 5 6 7 8\n"))]).unwrap();
        assert!(p.warnings.is_empty(), "{:?}", p.warnings);
        let g = &p.geometry;
        let twice: f32 = (0..g.indices.len())
            .map(|i| {
                let [a, b, c] = g.triangle(i);
                (b - a).cross(c - a).z
            })
            .sum();
        assert_eq!((g.indices.len(), twice), (6, 14.0));
        // A convex polygon is the fan it always was.
        let p = load(vec![("m/a.obj", format!("{u}f 1 2 3 8\n"))]).unwrap();
        assert_eq!(p.geometry.indices, [[0, 1, 2], [0, 2, 3]]);
        // Corners on a line: a fan, and a warning.
        let p = load(vec![(
            "m/a.obj",
            "v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 0 0\nv 4 0 0\nf 1 2 3 4 5\n".into(),
        )])
        .unwrap();
        assert!(
            p.warnings
                .iter()
                .any(|w| w.starts_with("m/a.obj:6: a polygon fits no plane")),
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

    /// A file read in pieces of any size reads as when read whole: the
    /// same meshes, materials, warnings and first error.
    #[test]
    fn pieces_read_as_the_whole_file() {
        let read = |text: &str, size: usize, available: u64| {
            let mut w = Vec::new();
            let f = ObjFile::parse_in(Path::new("m.obj"), text, &mut w, available, size);
            let placed = f.and_then(|f| {
                let material = |m: Option<&(String, usize)>, colored: bool| {
                    m.map_or(0, |(name, line)| name.len() as u32 * 1000 + *line as u32)
                        + colored as u32 * 100_000
                };
                let placed = f.place(&DAffine3::IDENTITY, material, &mut w)?;
                Ok(format!("{placed:?} {:?}", f.libraries))
            });
            match placed {
                Ok(p) => format!("Ok({p}) {w:?}"),
                Err(e) => format!("Err({e:#}) {w:?}"),
            }
        };
        let good = "mtllib a.mtl\n# c\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0 2\nvt 0 0\nvt 1 0\n\
                    vt 0 1\nvn 0 0 1\nusemtl r\nf 1/1/1 2/2/1 3/3/1\nvp 1\ng x\nf -4 -3 -2\n\
                    usemtl r\nf 2 4 \\\n 3\n\nusemtl\nusemtl gg\nv 2 0 0\nv 1e30 2 0\n\
                    f -1 -2 -3 1\no y\nusemtl r\nvp 2\nmtllib\nf 1 2 3\nf 3 2 -2\n";
        let whole = read(good, usize::MAX, u64::MAX);
        assert!(whole.starts_with("Ok("), "{whole}");
        for size in [1, 5, 17, 40, 100] {
            assert_eq!(read(good, size, u64::MAX), whole, "pieces of {size}");
        }
        let tri = memory::BYTES_PER_TRIANGLE;
        for (text, available) in [
            (format!("{good}f 1 2 9\n"), u64::MAX),
            (format!("{good}v 1 2\nf 1 2 3\n"), u64::MAX),
            (format!("f -1 1 2\n{good}"), u64::MAX),
            (format!("{good}{good}"), 9 * tri),
            (good.replace("vp 2", "vp 2\nf 1 2 3 4 5 6 7 8 9"), 12 * tri),
        ] {
            let whole = read(&text, usize::MAX, available);
            assert!(whole.starts_with("Err("), "{whole}");
            for size in [1, 5, 17, 40, 100] {
                assert_eq!(read(&text, size, available), whole, "pieces of {size}");
            }
        }
    }

    #[test]
    fn triangles_beyond_the_memory_available_are_refused_as_they_come() {
        let big = format!(
            "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nf{}\n",
            " 1 2 3".repeat(1000)
        );
        let budget = 1000 * memory::BYTES_PER_TRIANGLE;
        let e = ObjFile::parse(Path::new("m.obj"), &big, &mut Vec::new(), budget)
            .err()
            .map(|e| e.to_string())
            .unwrap_or_default();
        assert_eq!(
            e,
            "m.obj:5: 2999 triangles by this line would need 586 KiB of memory; 195 KiB is available"
        );
        assert!(ObjFile::parse(Path::new("m.obj"), QUAD, &mut Vec::new(), budget).is_ok());
    }

    /// Sixteen kinds are named, the rest counted; a keyword is cut to 32
    /// characters, so neither many kinds nor a long line makes the
    /// warning long.
    #[test]
    fn unsupported_statements_are_listed_within_bounds() {
        let kinds: String = (1..=20).map(|k| format!("k{k} 1\n")).collect();
        let long = format!("{}\0 1\n", "a".repeat(100_000));
        let p = load(vec![("m/a.obj", format!("{kinds}{long}{long}{QUAD}"))]).unwrap();
        let [w] = &p.warnings[..] else {
            panic!("{:?}", p.warnings)
        };
        let named: String = (1..=16).map(|k| format!("k{k} (line {k}), ")).collect();
        assert_eq!(
            *w,
            format!("m/a.obj: ignored, not supported: {named}6 statements of other kinds (line 17 and 5 more)")
        );
        let p = load(vec![("m/a.obj", format!("{long}{long}{QUAD}"))]).unwrap();
        assert_eq!(
            p.warnings,
            [format!(
                "m/a.obj: ignored, not supported: {}… (line 1 and 1 more)",
                "a".repeat(32)
            )]
        );
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
