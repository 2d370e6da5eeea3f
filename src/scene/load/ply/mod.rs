//! PLY (Stanford polygon files), ASCII and binary little- or big-endian,
//! with errors that name the file, the element and its index (and the line
//! of an ASCII file, the byte of a binary one).
//!
//! Read: `vertex` `x y z`, normals `nx ny nz`, texture coordinates (`u v`,
//! `s t`, `texture_u texture_v` or `texture_s texture_t`), colours (`red
//! green blue`, sRGB as images are, 0..255 for integers, 0..1 for floats)
//! and `face` `vertex_indices` (or `vertex_index`) lists, polygons becoming
//! triangles ([`faces`]), with MeshLab's `texcoord` lists and face colours;
//! `tristrips` lists (triangle strips, -1 starting a new one); MeshLab's
//! `comment TextureFile` names the texture. Other elements and
//! properties, header lines of kinds the format does not name, and faces
//! of fewer than three vertices are skipped with one warning. The header's
//! counts are checked against the file's size before anything is
//! allocated, and every index against the vertex count.

mod bulk;
mod faces;

use std::path::Path;

use anyhow::{anyhow, bail, Result};
use glam::{DAffine3, DVec3, Vec2, Vec3};

use super::numbers::{self, ABSURD};
use super::parts::{mesh_fits, place_normals, place_positions, Placed};
use crate::color::srgb_to_linear;
use crate::memory;
use crate::scene::show::{show, show3};
use crate::words::quoted;
use faces::Faces;

/// The header must end within this many bytes.
const MAX_HEADER: usize = 1 << 20;

#[derive(Clone, Copy, Debug, PartialEq)]
enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(name: &str) -> Option<Scalar> {
        Some(match name {
            "char" | "int8" => Scalar::I8,
            "uchar" | "uint8" => Scalar::U8,
            "short" | "int16" => Scalar::I16,
            "ushort" | "uint16" => Scalar::U16,
            "int" | "int32" => Scalar::I32,
            "uint" | "uint32" => Scalar::U32,
            "float" | "float32" => Scalar::F32,
            "double" | "float64" => Scalar::F64,
            _ => return None,
        })
    }

    fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    fn is_int(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// The values an integer type holds: what an ASCII file may write for it.
    fn range(self) -> (i64, i64) {
        match self {
            Scalar::I8 => (i8::MIN.into(), i8::MAX.into()),
            Scalar::U8 => (0, u8::MAX.into()),
            Scalar::I16 => (i16::MIN.into(), i16::MAX.into()),
            Scalar::U16 => (0, u16::MAX.into()),
            Scalar::I32 => (i32::MIN.into(), i32::MAX.into()),
            Scalar::U32 => (0, u32::MAX.into()),
            Scalar::F32 | Scalar::F64 => (i64::MIN, i64::MAX),
        }
    }

    /// The value of full intensity for a colour of this type.
    fn full(self) -> f64 {
        match self {
            Scalar::U16 => 65535.0,
            t if t.is_int() => 255.0,
            _ => 1.0,
        }
    }
}

#[derive(Clone, Copy, Debug)]
enum Kind {
    Scalar(Scalar),
    /// Count type, item type.
    List(Scalar, Scalar),
}

/// What a property of the vertex or face element becomes.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Role {
    Ignored,
    Position(usize),
    Normal(usize),
    Uv(usize),
    Color(usize),
    Indices,
    /// A face's texture coordinates, two a corner (MeshLab's `texcoord`).
    FaceUvs,
    /// Triangle strips' vertex indices (`element tristrips`).
    Strips,
}

struct Property {
    name: String,
    kind: Kind,
    role: Role,
}

struct Element {
    name: String,
    count: u64,
    props: Vec<Property>,
}

#[derive(Clone, Copy, PartialEq)]
enum Format {
    Ascii,
    Binary { big: bool },
}

struct Header {
    format: Format,
    elements: Vec<Element>,
    /// Byte offset of the body, and its first line.
    body: usize,
    body_line: usize,
    texture: Option<(String, usize)>,
}

/// What a PLY file holds, in file coordinates.
pub(crate) struct PlyMesh {
    pub(crate) positions: Vec<DVec3>,
    pub(crate) normals: Option<Vec<DVec3>>,
    pub(crate) uvs: Option<Vec<Vec2>>,
    pub(crate) colors: Option<Vec<Vec3>>,
    pub(crate) indices: Vec<[u32; 3]>,
    /// `comment TextureFile` as written, with its line.
    pub(crate) texture: Option<(String, usize)>,
}

impl PlyMesh {
    /// The mesh placed by `xf` in f64.
    pub(crate) fn placed(self, path: &Path, xf: &DAffine3, material: u32) -> Result<Placed> {
        let positions = place_positions(self.positions, xf, |i, p, q, why| {
            anyhow!(
                "{}: vertex {i}: {} lands at {} once placed, which {why}",
                path.display(),
                show3(p),
                show3(q)
            )
        })?;
        Ok(Placed {
            name: path
                .file_stem()
                .map(|s| s.to_string_lossy().into_owned())
                .unwrap_or_default(),
            positions,
            normals: self.normals.map(|n| place_normals(&n, xf)),
            uvs: self.uvs,
            uvs1: None,
            tangents: None,
            colors: self.colors,
            indices: self.indices,
            material,
        })
    }
}

fn header(path: &Path, bytes: &[u8], warnings: &mut Vec<String>) -> Result<Header> {
    let body = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let skipped = bytes.len() - body.len();
    // Lines end where the first one does: in LF, CRLF, or a lone CR as
    // classic Mac OS wrote them (Draco's test files do; other readers take
    // them).
    let eol = match body.starts_with(b"ply\r") && !body.starts_with(b"ply\r\n") {
        true => b'\r',
        false => b'\n',
    };
    if !(body.starts_with(b"ply\n") || body.starts_with(b"ply\r")) {
        bail!(
            "{}: not a PLY file: it does not start with a 'ply' line",
            path.display()
        );
    }
    let mut format = None;
    let mut elements: Vec<Element> = Vec::new();
    let mut texture = None;
    let mut start = 0;
    let mut n = 0;
    let mut ignored_elements: Vec<String> = Vec::new();
    // Header lines of kinds the format does not name: the first's line and
    // keyword, and how many.
    let mut unknown: Option<(usize, String)> = None;
    let mut unknown_count = 0;
    loop {
        n += 1;
        let at = |msg: String| anyhow!("{}:{n}: {msg}", path.display());
        let Some(len) = body[start..].iter().position(|&b| b == eol) else {
            bail!(at("the header has no 'end_header' line".into()));
        };
        if start + len > MAX_HEADER {
            bail!(at(format!(
                "no 'end_header' within the first {}",
                memory::bytes(MAX_HEADER as u64)
            )));
        }
        let raw = &body[start..start + len];
        start += len + 1;
        let line = std::str::from_utf8(raw.strip_suffix(b"\r").unwrap_or(raw))
            .map_err(|_| at("the header is not text (invalid UTF-8)".into()))?;
        // Names and values reach messages: each cut as messages quote them
        // (none rayterm knows is near that long), and made printable once
        // split, so that a tab separates words as a space does.
        let cut: Vec<String> = line
            .split_whitespace()
            .map(|w| quoted(&crate::words::printable(w)))
            .collect();
        let line = crate::words::printable(line);
        let words: Vec<&str> = cut.iter().map(String::as_str).collect();
        match words.as_slice() {
            ["ply"] if n == 1 => {}
            ["format", f, version] => {
                if *version != "1.0" {
                    warnings.push(format!(
                        "{}:{n}: PLY version {version}: read as 1.0",
                        path.display()
                    ));
                }
                format = Some(match *f {
                    "ascii" => Format::Ascii,
                    "binary_little_endian" => Format::Binary { big: false },
                    "binary_big_endian" => Format::Binary { big: true },
                    other => bail!(at(format!(
                        "unknown format '{}' (ascii, binary_little_endian or \
                         binary_big_endian)",
                        quoted(other)
                    ))),
                });
            }
            ["comment", "TextureFile", ..] => {
                let name =
                    line.trim_start()["comment".len()..].trim_start()["TextureFile".len()..].trim();
                if !name.is_empty() {
                    texture = Some((name.to_string(), n));
                }
            }
            ["comment", ..] | ["obj_info", ..] | [] => {}
            ["element", name, count] => {
                let count: u64 = count.parse().map_err(|_| {
                    at(format!(
                        "element {}: '{}' is not a count",
                        quoted(name),
                        quoted(count)
                    ))
                })?;
                if elements.iter().any(|e| e.name == *name) {
                    bail!(at(format!("element {name} is declared twice")));
                }
                elements.push(Element {
                    name: name.to_string(),
                    count,
                    props: Vec::new(),
                });
            }
            ["property", rest @ ..] => {
                let Some(e) = elements.last_mut() else {
                    bail!(at("a property before any element".into()));
                };
                let ty = |t: &str| {
                    Scalar::parse(t)
                        .ok_or_else(|| at(format!("unknown property type '{}'", quoted(t))))
                };
                let (kind, name) = match rest {
                    ["list", count, item, name] => {
                        let count = ty(count)?;
                        if !count.is_int() {
                            bail!(at(format!(
                                "list {name}: the count must be an integer type"
                            )));
                        }
                        (Kind::List(count, ty(item)?), *name)
                    }
                    [t, name] => (Kind::Scalar(ty(t)?), *name),
                    _ => bail!(at(
                        "a property is 'property TYPE NAME' or 'property list COUNT ITEM NAME'"
                            .into()
                    )),
                };
                if e.props.iter().any(|p| p.name == name) {
                    bail!(at(format!(
                        "element {}: property {name} is declared twice",
                        e.name
                    )));
                }
                let Some(role) = role(&e.name, name, kind) else {
                    bail!(at(format!(
                        "element {}: property {name} must be {}",
                        e.name,
                        if matches!(kind, Kind::List(..)) {
                            "a single value, not a list"
                        } else {
                            "a list"
                        }
                    )));
                };
                if role == Role::Indices || role == Role::Strips {
                    if let Kind::List(_, item) = kind {
                        if !item.is_int() {
                            bail!(at(format!("{name}: indices must be of an integer type")));
                        }
                    }
                }
                e.props.push(Property {
                    name: name.to_string(),
                    kind,
                    role,
                });
            }
            ["end_header"] => break,
            [keyword, ..] if !["ply", "format", "element", "property"].contains(keyword) => {
                unknown.get_or_insert((n, keyword.to_string()));
                unknown_count += 1;
            }
            _ => bail!(at(format!(
                "not a header line: '{}'",
                line.chars().take(40).collect::<String>()
            ))),
        }
    }
    // Other readers (trimesh, MeshLab's) skip lines they do not know, as
    // later versions of a format may add them.
    if let Some((line, keyword)) = unknown {
        warnings.push(format!(
            "{}:{line}: {} of a kind the PLY format does not name ('{keyword}'{}): skipped",
            path.display(),
            crate::words::count(unknown_count as u64, "header line", "header lines"),
            if unknown_count > 1 { " ..." } else { "" }
        ));
    }
    let Some(format) = format else {
        bail!("{}: the header has no 'format' line", path.display());
    };
    // Strips name the file's vertices, which faces that give their corners
    // UVs or colours of their own renumber: such strips are not read.
    let renumbered = elements
        .iter()
        .any(|e| e.name == "face" && faces::given(e).any());
    for e in &mut elements {
        if e.name == "tristrips" && renumbered {
            e.props.iter_mut().for_each(|p| p.role = Role::Ignored);
            ignored_elements.push(format!(
                "{} ({}, as the faces give corners texture coordinates or colours of their own)",
                e.name, e.count
            ));
        } else if !["vertex", "face", "tristrips"].contains(&e.name.as_str()) {
            ignored_elements.push(format!("{} ({})", e.name, e.count));
        }
    }
    let mut ignored_props: Vec<String> = elements
        .iter()
        .filter(|e| {
            ["vertex", "face"].contains(&e.name.as_str()) || (e.name == "tristrips" && !renumbered)
        })
        .flat_map(|e| {
            e.props
                .iter()
                .filter(|p| p.role == Role::Ignored)
                .map(move |p| format!("{} {}", e.name, p.name))
        })
        .collect();
    ignored_props.splice(
        0..0,
        ignored_elements.iter().map(|e| format!("element {e}")),
    );
    if !ignored_props.is_empty() {
        warnings.push(format!(
            "{}: ignored, not used: {}",
            path.display(),
            ignored_props.join(", ")
        ));
    }
    Ok(Header {
        format,
        elements,
        body: skipped + start,
        body_line: n + 1,
        texture,
    })
}

/// What a property holds; `None` for a name rayterm reads declared with
/// the wrong shape (a list position, a scalar index), which would otherwise
/// be read as nothing.
fn role(element: &str, name: &str, kind: Kind) -> Option<Role> {
    let role = match element {
        "vertex" => match name {
            "x" => Role::Position(0),
            "y" => Role::Position(1),
            "z" => Role::Position(2),
            "nx" => Role::Normal(0),
            "ny" => Role::Normal(1),
            "nz" => Role::Normal(2),
            "u" | "s" | "texture_u" | "texture_s" => Role::Uv(0),
            "v" | "t" | "texture_v" | "texture_t" => Role::Uv(1),
            "red" | "diffuse_red" => Role::Color(0),
            "green" | "diffuse_green" => Role::Color(1),
            "blue" | "diffuse_blue" => Role::Color(2),
            _ => Role::Ignored,
        },
        "face" => match name {
            "vertex_indices" | "vertex_index" => Role::Indices,
            "texcoord" => Role::FaceUvs,
            "red" => Role::Color(0),
            "green" => Role::Color(1),
            "blue" => Role::Color(2),
            _ => Role::Ignored,
        },
        "tristrips" => match name {
            "vertex_indices" | "vertex_index" => Role::Strips,
            _ => Role::Ignored,
        },
        _ => Role::Ignored,
    };
    let list = matches!(kind, Kind::List(..));
    match role {
        Role::Ignored => Some(role),
        Role::Indices | Role::FaceUvs | Role::Strips => list.then_some(role),
        _ => (!list).then_some(role),
    }
}

/// Values of the body, read element by element.
trait Values {
    /// Starts the next element (an ASCII line).
    fn begin(&mut self) -> Result<(), String>;
    /// Ends an element: how many values an ASCII line holds past the
    /// declared ones (ignored, as other readers ignore them).
    fn end(&mut self) -> usize;
    fn float(&mut self, t: Scalar) -> Result<f64, String>;
    fn int(&mut self, t: Scalar) -> Result<i64, String>;
    /// Where the reader is, for messages: `file:line` or `file (byte N)`.
    fn place(&self, path: &Path) -> String;
    /// What follows the last element, if anything.
    fn rest(&mut self) -> Option<String>;
    /// The bytes left to read and whether they are big-endian, where
    /// elements of fixed-size records can be read in bulk (binary files).
    fn bulk(&self) -> Option<(&[u8], bool)> {
        None
    }
    /// Steps over `n` bytes read in bulk.
    fn skip(&mut self, _n: usize) {}
}

struct Binary<'a> {
    bytes: &'a [u8],
    pos: usize,
    big: bool,
}

impl Values for Binary<'_> {
    fn begin(&mut self) -> Result<(), String> {
        Ok(())
    }
    fn end(&mut self) -> usize {
        0
    }
    #[inline]
    fn float(&mut self, t: Scalar) -> Result<f64, String> {
        let b = self
            .bytes
            .get(self.pos..self.pos + t.size())
            .ok_or("the file ends here (truncated)")?;
        self.pos += t.size();
        Ok(bulk::scalar(b, t, self.big))
    }
    #[inline]
    fn int(&mut self, t: Scalar) -> Result<i64, String> {
        // Integer types only (checked with the header): exact in f64.
        self.float(t).map(|x| x as i64)
    }
    fn place(&self, path: &Path) -> String {
        format!("{} (byte {})", path.display(), self.pos)
    }
    fn rest(&mut self) -> Option<String> {
        let left = self.bytes.len() - self.pos.min(self.bytes.len());
        (left > 0).then(|| format!("{left} bytes"))
    }
    fn bulk(&self) -> Option<(&[u8], bool)> {
        Some((self.bytes.get(self.pos..)?, self.big))
    }
    fn skip(&mut self, n: usize) {
        self.pos += n;
    }
}

struct Ascii<'a> {
    lines: std::iter::Enumerate<std::str::Lines<'a>>,
    first_line: usize,
    line: usize,
    words: std::str::SplitWhitespace<'a>,
}

impl Ascii<'_> {
    fn word(&mut self) -> Result<&str, String> {
        self.words
            .next()
            .ok_or_else(|| "the line ends before the element does".to_string())
    }
}

impl Values for Ascii<'_> {
    fn begin(&mut self) -> Result<(), String> {
        loop {
            let Some((i, l)) = self.lines.next() else {
                return Err("the file ends here (truncated)".into());
            };
            self.line = self.first_line + i;
            if !l.trim().is_empty() {
                self.words = l.split_whitespace();
                return Ok(());
            }
        }
    }
    fn end(&mut self) -> usize {
        self.words.clone().count()
    }
    fn float(&mut self, t: Scalar) -> Result<f64, String> {
        if t.is_int() {
            return self.int(t).map(|x| x as f64);
        }
        let w = self.word()?;
        numbers::parse(w)
    }
    fn int(&mut self, t: Scalar) -> Result<i64, String> {
        let w = self.word()?;
        let x: i64 = w
            .parse()
            .map_err(|_| format!("'{}' is not an integer", quoted(w)))?;
        let (lo, hi) = t.range();
        match (lo..=hi).contains(&x) {
            true => Ok(x),
            false => Err(format!("{x} is out of range for its type ({lo} to {hi})")),
        }
    }
    fn place(&self, path: &Path) -> String {
        format!("{}:{}", path.display(), self.line)
    }
    fn rest(&mut self) -> Option<String> {
        let (i, _) = self.lines.find(|(_, l)| !l.trim().is_empty())?;
        Some(format!("line {}", self.first_line + i))
    }
}

/// Least bytes an element can take in the body (ASCII: a digit and a
/// separator a value; a list may be empty).
fn least_bytes(e: &Element, format: Format) -> u64 {
    e.props
        .iter()
        .map(|p| match (format, p.kind) {
            (Format::Ascii, _) => 2,
            (_, Kind::Scalar(t)) | (_, Kind::List(t, _)) => t.size() as u64,
        })
        .sum()
}

/// Parses a PLY file's bytes, refusing one that would need more than
/// `available` bytes ([`memory::mesh_bytes`]) before reading its body.
pub(crate) fn parse(
    path: &Path,
    bytes: &[u8],
    warnings: &mut Vec<String>,
    available: u64,
) -> Result<PlyMesh> {
    let h = header(path, bytes, warnings)?;
    let body = &bytes[h.body..];
    let vertices = h.elements.iter().find(|e| e.name == "vertex");
    let Some(vertices) = vertices else {
        bail!("{}: no 'element vertex' in the header", path.display());
    };
    for axis in ["x", "y", "z"] {
        if !vertices.props.iter().any(|p| p.name == axis) {
            bail!("{}: element vertex has no property {axis}", path.display());
        }
    }
    if vertices.count >= u32::MAX as u64 {
        bail!(
            "{}: {} vertices: more than 32-bit indices address",
            path.display(),
            vertices.count
        );
    }
    let least = h.elements.iter().fold(0u64, |s, e| {
        s.saturating_add(e.count.saturating_mul(least_bytes(e, h.format)))
    });
    if least > body.len() as u64 {
        let counts: Vec<String> = h
            .elements
            .iter()
            .map(|e| format!("element {} {}", e.name, e.count))
            .collect();
        bail!(
            "{}: truncated: the header declares {}: at least {least} bytes after the header, \
             and {} follow it",
            path.display(),
            counts.join(", "),
            body.len()
        );
    }
    let faces = h
        .elements
        .iter()
        .find(|e| e.name == "face")
        .map_or(0, |e| e.count);
    mesh_fits(vertices.count, faces, available).map_err(|e| anyhow!("{}: {e}", path.display()))?;
    match h.format {
        Format::Binary { big } => {
            let mut r = Binary {
                bytes,
                pos: h.body,
                big,
            };
            body_from(path, &h, &mut r, warnings, available)
        }
        Format::Ascii => {
            let text = super::source::text(path, bytes.to_vec())?;
            let mut lines = text.lines().enumerate();
            // The header, already read.
            lines.nth(h.body_line - 2);
            let mut r = Ascii {
                lines,
                first_line: 1,
                line: h.body_line,
                words: "".split_whitespace(),
            };
            body_from(path, &h, &mut r, warnings, available)
        }
    }
}

fn body_from<R: Values>(
    path: &Path,
    h: &Header,
    r: &mut R,
    warnings: &mut Vec<String>,
    available: u64,
) -> Result<PlyMesh> {
    let vertex_count = h
        .elements
        .iter()
        .find(|e| e.name == "vertex")
        .map_or(0, |e| e.count as usize);
    let face_count = h
        .elements
        .iter()
        .find(|e| e.name == "face")
        .map_or(0, |e| e.count as usize);
    let mut m = PlyMesh {
        positions: Vec::with_capacity(vertex_count),
        normals: None,
        uvs: None,
        colors: None,
        // One triangle a face at least: within the memory checked above.
        indices: Vec::with_capacity(face_count),
        texture: h.texture.clone(),
    };
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    let mut colors = Vec::new();
    // The first absurd coordinate (vertex, value) and how many more.
    let mut absurd: (Option<(u64, f64)>, u64) = (None, 0);
    // The first line with values past the declared ones (where, how
    // many), and how many such lines.
    let mut longer: (Option<(String, usize)>, u64) = (None, 0);
    let mut triangles = 0u64;
    // The first face of fewer than three vertices (where, which, how
    // many), and how many such faces.
    let mut short: (Option<(String, u64, i64)>, u64) = (None, 0);
    let mut corners: Vec<u32> = Vec::new();
    let mut face_uvs: Vec<f32> = Vec::new();
    let face = h.elements.iter().find(|e| e.name == "face");
    let mut faces = Faces::new(face.map(faces::given).unwrap_or_default());
    for e in &h.elements {
        let has = |f: fn(Role) -> bool| e.props.iter().filter(|p| f(p.role)).count();
        let (n_normal, n_uv, n_color) = (
            has(|r| matches!(r, Role::Normal(_))),
            has(|r| matches!(r, Role::Uv(_))),
            has(|r| matches!(r, Role::Color(_))),
        );
        let color_full = e
            .props
            .iter()
            .find_map(|p| match (p.role, p.kind) {
                (Role::Color(_), Kind::Scalar(t)) => Some(t.full()),
                _ => None,
            })
            .unwrap_or(1.0);
        if e.name == "vertex" {
            if n_normal == 3 {
                normals.reserve_exact(vertex_count);
            }
            if n_uv == 2 {
                uvs.reserve_exact(vertex_count);
            }
            if n_color == 3 {
                colors.reserve_exact(vertex_count);
            }
        }
        // An element without properties holds nothing, in either format:
        // its count, however large, is no reason to loop.
        if e.props.is_empty() {
            continue;
        }
        let in_bulk = r.bulk().and_then(|(body, big)| match e.name.as_str() {
            "vertex" => bulk::vertices(e, body, big, color_full),
            "face" => bulk::triangles(e, body, big, vertex_count),
            _ => None,
        });
        if let Some((read, len)) = in_bulk {
            r.skip(len);
            match read {
                bulk::Read::Vertices(v) => {
                    m.positions = v.positions;
                    (normals, uvs, colors) = (v.normals, v.uvs, v.colors);
                }
                bulk::Read::Triangles(t) if m.indices.is_empty() => m.indices = t,
                bulk::Read::Triangles(t) => m.indices.extend(t),
            }
            continue;
        }
        for i in 0..e.count {
            let fail = |r: &R, prop: Option<&str>, msg: String| {
                let place = r.place(path);
                let prop = prop.map(|p| format!(", {p}")).unwrap_or_default();
                anyhow!(
                    "{place}: element {} {i} (of {}){prop}: {msg}",
                    e.name,
                    e.count
                )
            };
            r.begin().map_err(|m| fail(r, None, m))?;
            let mut skipped = false;
            let mut p = [0.0; 3];
            let mut nrm = [0.0; 3];
            let mut uv = [0.0; 2];
            let mut rgb = [0.0; 3];
            for prop in &e.props {
                let name = Some(prop.name.as_str());
                match (prop.kind, prop.role) {
                    (Kind::Scalar(t), role) => {
                        let x = r.float(t).map_err(|m| fail(r, name, m))?;
                        if role == Role::Ignored {
                            continue;
                        }
                        if let Some(why) = numbers::unusable(x) {
                            return Err(fail(r, name, format!("{} {why}", show(x))));
                        }
                        match role {
                            Role::Position(k) => {
                                if x.abs() > ABSURD {
                                    match absurd.0 {
                                        None => absurd.0 = Some((i, x)),
                                        Some(_) => absurd.1 += 1,
                                    }
                                }
                                p[k] = x;
                            }
                            Role::Normal(k) => nrm[k] = x,
                            Role::Uv(k) => uv[k] = x,
                            Role::Color(k) => rgb[k] = x,
                            _ => {}
                        }
                    }
                    (Kind::List(ct, item), role) => {
                        let n = r.int(ct).map_err(|m| fail(r, name, m))?;
                        if n < 0 {
                            return Err(fail(r, name, format!("negative count {n}")));
                        }
                        if role == Role::FaceUvs {
                            face_uvs.clear();
                            for _ in 0..n {
                                let x = r.float(item).map_err(|m| fail(r, name, m))?;
                                if let Some(why) = numbers::unusable(x) {
                                    let shown = show(x);
                                    return Err(fail(r, name, format!("{shown} {why}")));
                                }
                                face_uvs.push(x as f32);
                            }
                            continue;
                        }
                        if role == Role::Strips {
                            // The most triangles it can make, checked first.
                            let most = triangles + (n as u64).saturating_sub(2);
                            let vertices = vertex_count.max(faces.split()) as u64;
                            mesh_fits(vertices, most, available).map_err(|m| fail(r, name, m))?;
                            let read = strips(r, item, n as u64, vertex_count)
                                .map_err(|m| fail(r, name, m))?;
                            triangles += read.len() as u64;
                            m.indices.extend(read);
                            continue;
                        }
                        // Skipped, as other readers skip them; their
                        // indices read past.
                        if role != Role::Indices || n < 3 {
                            if role == Role::Indices {
                                short.1 += 1;
                                if short.0.is_none() {
                                    short.0 = Some((r.place(path), i, n));
                                }
                                skipped = true;
                            }
                            for _ in 0..n {
                                r.float(item).map_err(|m| fail(r, name, m))?;
                            }
                            continue;
                        }
                        triangles += n as u64 - 2;
                        let vertices = vertex_count.max(faces.split()) as u64;
                        mesh_fits(vertices, triangles, available).map_err(|m| fail(r, name, m))?;
                        corners.clear();
                        for _ in 0..n {
                            let k = r.int(item).map_err(|m| fail(r, name, m))?;
                            if k < 0 || k as u64 >= vertex_count as u64 {
                                return Err(fail(
                                    r,
                                    name,
                                    format!(
                                        "vertex index {k} is out of range ({vertex_count} \
                                         vertices)"
                                    ),
                                ));
                            }
                            corners.push(k as u32);
                        }
                    }
                }
            }
            let extra = r.end();
            if extra > 0 {
                longer.0.get_or_insert_with(|| (r.place(path), extra));
                longer.1 += 1;
            }
            if e.name == "face" && !skipped {
                let color = rgb.map(|c| srgb_to_linear((c / color_full).clamp(0.0, 1.0) as f32));
                // The vertices are read where they come first, as they do
                // in most files.
                let positions = (m.positions.len() == vertex_count).then_some(&m.positions[..]);
                let color = Vec3::from_array(color);
                faces.add(i, &mut corners, &face_uvs, color, positions, &mut m.indices);
            }
            corners.clear();
            face_uvs.clear();
            if e.name == "vertex" {
                m.positions.push(DVec3::from_array(p));
                if n_normal == 3 {
                    normals.push(DVec3::from_array(nrm));
                }
                if n_uv == 2 {
                    uvs.push(Vec2::new(uv[0] as f32, uv[1] as f32));
                }
                if n_color == 3 {
                    colors.push(Vec3::from_array(
                        rgb.map(|c| srgb_to_linear((c / color_full).clamp(0.0, 1.0) as f32)),
                    ));
                }
            }
        }
    }
    if let (Some((place, n)), lines) = longer {
        warnings.push(format!(
            "{place}: {} past those the header declares: ignored{}",
            crate::words::count(n as u64, "value", "values"),
            match lines {
                1 => String::new(),
                l => format!(" (on {l} lines)"),
            }
        ));
    }
    if let (Some((place, i, n)), count) = short {
        let more = match count {
            1 => String::new(),
            c => format!(" (and {c} more of fewer than 3)", c = c - 1),
        };
        warnings.push(format!(
            "{place}: element face {i}: a face of {}{more}: skipped",
            crate::words::count(n as u64, "vertex", "vertices")
        ));
    }
    if let Some(rest) = r.rest() {
        warnings.push(format!(
            "{}: data after the last element ({rest}): ignored",
            path.display()
        ));
    }
    for (n, what) in [
        (n_of(h, "vertex", "normal"), "normal"),
        (n_of(h, "vertex", "uv"), "texture coordinate"),
    ] {
        if n > 0 && n < if what == "normal" { 3 } else { 2 } {
            warnings.push(format!(
                "{}: element vertex has only some {what} properties: ignored",
                path.display()
            ));
        }
    }
    for element in ["vertex", "face"] {
        if (1..3).contains(&n_of(h, element, "color")) {
            warnings.push(format!(
                "{}: element {element} has only some of red, green and blue: ignored",
                path.display()
            ));
        }
    }
    if let (Some((i, x)), more) = absurd {
        let more = if more > 0 {
            format!(" (and {more} more)")
        } else {
            String::new()
        };
        warnings.push(format!(
            "{}: vertex {i}: absurd value {}{more}: beyond {ABSURD:e} shading and shadows \
             lose all precision",
            path.display(),
            show(x)
        ));
    }
    m.normals = (!normals.is_empty()).then_some(normals);
    m.uvs = (!uvs.is_empty()).then_some(uvs);
    m.colors = (!colors.is_empty()).then_some(colors);
    faces.finish(&path.display().to_string(), &mut m, warnings);
    Ok(m)
}

/// The triangles of a `tristrips` list of `n` indices of type `item`
/// into `vertex_count` vertices: each index after a strip's first two
/// makes one with the two before it, every other one turned the other way
/// (so that all face one way), and -1 starts a new strip. Triangles with a
/// repeated corner, which join strips, are left out.
fn strips<R: Values>(
    r: &mut R,
    item: Scalar,
    n: u64,
    vertex_count: usize,
) -> Result<Vec<[u32; 3]>, String> {
    let mut out = Vec::new();
    // The strip's last two corners, and its triangles so far.
    let (mut last, mut made) = ([None; 2], 0u64);
    for _ in 0..n {
        let k = r.int(item)?;
        if k == -1 {
            (last, made) = ([None; 2], 0);
            continue;
        }
        if k < 0 || k as u64 >= vertex_count as u64 {
            return Err(format!(
                "vertex index {k} is out of range ({vertex_count} vertices; -1 starts a strip)"
            ));
        }
        let c = k as u32;
        if let [Some(a), Some(b)] = last {
            if a != b && b != c && a != c {
                out.push(if made % 2 == 0 { [a, b, c] } else { [b, a, c] });
            }
            made += 1;
        }
        last = [last[1], Some(c)];
    }
    Ok(out)
}

/// How many properties of `element` have the role named `what`.
fn n_of(h: &Header, element: &str, what: &str) -> usize {
    h.elements
        .iter()
        .filter(|e| e.name == element)
        .flat_map(|e| &e.props)
        .filter(|p| {
            matches!(
                (what, p.role),
                ("normal", Role::Normal(_)) | ("uv", Role::Uv(_)) | ("color", Role::Color(_))
            )
        })
        .count()
}

#[cfg(test)]
mod tests {
    use super::*;

    const HEAD: &str = "ply\nformat ascii 1.0\ncomment made by hand\nelement vertex 4\n\
                        property float x\nproperty float y\nproperty float z\n\
                        element face 1\nproperty list uchar int vertex_indices\nend_header\n";
    const QUAD: &str = "0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 3\n";

    fn read(bytes: &[u8]) -> Result<(PlyMesh, Vec<String>)> {
        let mut w = Vec::new();
        let m = parse(Path::new("p.ply"), bytes, &mut w, u64::MAX)?;
        Ok((m, w))
    }

    fn err(text: &str) -> String {
        format!("{:#}", read(text.as_bytes()).err().expect("should fail"))
    }

    fn binary(big: bool) -> Vec<u8> {
        let mut b = format!(
            "ply\nformat binary_{}_endian 1.0\nelement vertex 4\nproperty float x\n\
             property float y\nproperty float z\nproperty uchar red\nproperty uchar green\n\
             property uchar blue\nelement face 1\nproperty list uchar uint vertex_indices\n\
             end_header\n",
            if big { "big" } else { "little" }
        )
        .into_bytes();
        let f = |x: f32| {
            if big {
                x.to_be_bytes()
            } else {
                x.to_le_bytes()
            }
        };
        for p in [
            [0.0, 0.0, 0.0],
            [1.0, 0.0, 0.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ] {
            for x in p {
                b.extend(f(x));
            }
            b.extend([255, 0, 128]);
        }
        b.push(4);
        for i in 0u32..4 {
            b.extend(if big {
                i.to_be_bytes()
            } else {
                i.to_le_bytes()
            });
        }
        b
    }

    #[test]
    fn ascii_and_binary_read_alike() {
        let (a, w) = read(format!("{HEAD}{QUAD}").as_bytes()).unwrap();
        assert!(w.is_empty(), "{w:?}");
        assert_eq!(a.indices, [[0, 1, 2], [0, 2, 3]]);
        for big in [false, true] {
            let (b, w) = read(&binary(big)).unwrap();
            assert!(w.is_empty(), "{w:?}");
            assert_eq!(b.positions, a.positions);
            assert_eq!(b.indices, a.indices);
            let c = b.colors.unwrap()[0];
            assert_eq!(c, Vec3::new(1.0, 0.0, srgb_to_linear(128.0 / 255.0)));
        }
    }

    #[test]
    fn malformed_files_name_element_and_place() {
        let cases = [
            (format!("{HEAD}0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2 9\n"), "p.ply:15: element face 0 (of 1), vertex_indices: vertex index 9 is out of range (4 vertices)"),
            (format!("{HEAD}0 0 0\n1 0 0\n1 1 0\n0 1 0\n4 0 1 2\n"), "p.ply:15: element face 0 (of 1), vertex_indices: the line ends"),
            (format!("{HEAD}0 0 nan\n1 0 0\n1 1 0\n0 1 0\n3 0 1 2\n"), "p.ply:11: element vertex 0 (of 4), z: 'nan' is not a finite"),
            (format!("{HEAD}0 0 0\n1 0 0\n1 1 0\n0 1 0\n3 0 1 -1\n"), "p.ply:15: element face 0 (of 1), vertex_indices: vertex index -1 is out of range"),
            (format!("{HEAD}0 0 0\n1 0 0\n1 1 0\n0 1 0\n259 0 1 2\n"), "p.ply:15: element face 0 (of 1), vertex_indices: 259 is out of range for its type (0 to 255)"),
            (HEAD.replace("vertex 4", "vertex 4000"), "p.ply: truncated: the header declares element vertex 4000, element face 1:"),
            (HEAD.replace("float x", "float33 x"), "p.ply:5: unknown property type 'float33'"),
            (HEAD.replace("format ascii 1.0\n", ""), "p.ply: the header has no 'format' line"),
            (HEAD.replace("end_header\n", ""), "p.ply:10: the header has no 'end_header' line"),
            (HEAD.replace("property float z\n", ""), "p.ply: element vertex has no property z"),
            (HEAD.replace("uchar int vertex", "uchar float vertex"), "p.ply:9: vertex_indices: indices must be of an integer type"),
            ("plyx\n".into(), "p.ply: not a PLY file"),
        ];
        for (text, want) in cases {
            let e = err(&text);
            assert!(e.starts_with(want), "{text:?}:\n{e}\nwanted {want}");
        }
        let mut cut = binary(false);
        cut.truncate(cut.len() - 2);
        let e = format!("{:#}", read(&cut).err().unwrap());
        assert!(
            e.ends_with("element face 0 (of 1), vertex_indices: the file ends here (truncated)"),
            "{e}"
        );
        cut.truncate(cut.len() - 20);
        let e = format!("{:#}", read(&cut).err().unwrap());
        assert!(
            e.starts_with(
                "p.ply: truncated: the header declares element vertex 4, element face 1:"
            ),
            "{e}"
        );
        let mut bad = binary(true);
        let n = bad.len();
        bad[n - 1] = 7;
        let e = format!("{:#}", read(&bad).err().unwrap());
        assert!(
            e.starts_with(&format!(
                "p.ply (byte {n}): element face 0 (of 1), vertex_indices: vertex index 7"
            )),
            "{e}"
        );
    }

    #[test]
    fn other_elements_and_properties_are_skipped_with_a_warning() {
        let text = "ply\nformat ascii 1.0\nelement material 1\nproperty list uchar float k\n\
                    element vertex 3\nproperty float x\nproperty float y\nproperty float z\n\
                    property float confidence\nproperty float nx\nelement face 1\n\
                    property list uchar int vertex_index\nproperty uchar flags\nend_header\n\
                    2 0.5 0.5\n0 0 0 1 0\n1 0 0 1 0\n0 1 0 1 0\n3 0 1 2 9\n\n";
        let (m, w) = read(text.as_bytes()).unwrap();
        assert_eq!(m.indices, [[0, 1, 2]]);
        assert!(m.normals.is_none());
        assert_eq!(
            w,
            [
                "p.ply: ignored, not used: element material (1), vertex confidence, face flags",
                "p.ply: element vertex has only some normal properties: ignored"
            ]
        );
    }

    #[test]
    fn a_property_rayterm_reads_in_the_wrong_shape_is_an_error() {
        let list_x = "ply\nformat ascii 1.0\nelement vertex 3\nproperty list uchar float x\n\
                      property float y\nproperty float z\nelement face 1\n\
                      property list uchar int vertex_indices\nend_header\n";
        let e = format!("{:#}", read(list_x.as_bytes()).err().unwrap());
        assert_eq!(
            e,
            "p.ply:4: element vertex: property x must be a single value, not a list"
        );
        let scalar_faces = "ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\n\
                            property float y\nproperty float z\nelement face 1\n\
                            property int vertex_indices\nend_header\n";
        let e = format!("{:#}", read(scalar_faces.as_bytes()).err().unwrap());
        assert_eq!(
            e,
            "p.ply:8: element face: property vertex_indices must be a list"
        );
    }

    /// The binary reader without its bulk reading: every value one at a
    /// time.
    struct ByValue<'a>(Binary<'a>);

    impl Values for ByValue<'_> {
        fn begin(&mut self) -> Result<(), String> {
            self.0.begin()
        }
        fn end(&mut self) -> usize {
            self.0.end()
        }
        fn float(&mut self, t: Scalar) -> Result<f64, String> {
            self.0.float(t)
        }
        fn int(&mut self, t: Scalar) -> Result<i64, String> {
            self.0.int(t)
        }
        fn place(&self, path: &Path) -> String {
            self.0.place(path)
        }
        fn rest(&mut self) -> Option<String> {
            self.0.rest()
        }
    }

    /// A binary file of every kind of vertex attribute, in many types:
    /// `z[i]` is vertex i's z, `faces` its faces.
    fn every_attribute(big: bool, z: [f64; 4], faces: &[&[i32]]) -> Vec<u8> {
        let mut b = format!(
            "ply\nformat binary_{}_endian 1.0\nelement vertex 4\nproperty double x\n\
             property float y\nproperty double z\nproperty int confidence\n\
             property float nx\nproperty float ny\nproperty float nz\nproperty float u\n\
             property float v\nproperty ushort red\nproperty ushort green\n\
             property ushort blue\nelement face {}\n\
             property list uchar int vertex_indices\nend_header\n",
            if big { "big" } else { "little" },
            faces.len()
        )
        .into_bytes();
        macro_rules! put {
            ($x:expr) => {
                b.extend(if big {
                    $x.to_be_bytes()
                } else {
                    $x.to_le_bytes()
                })
            };
        }
        for (i, z) in z.into_iter().enumerate() {
            let f = i as f32;
            put!(f as f64 * 0.5);
            put!(1.0 - f);
            put!(z);
            put!(-7i32);
            put!(0.6f32);
            put!(0.0f32);
            put!(-0.8f32);
            put!(f / 3.0);
            put!(1.0 - f / 7.0);
            put!(1000u16 * i as u16);
            put!(65535u16);
            put!(3u16);
        }
        for face in faces {
            b.push(face.len() as u8);
            for &i in *face {
                put!(i);
            }
        }
        b
    }

    /// The mesh (or error) and warnings of a binary file read in bulk where
    /// it can be, and read value by value, as text to compare.
    fn both_ways(bytes: &[u8]) -> [String; 2] {
        let path = Path::new("p.ply");
        let mut w = Vec::new();
        let h = header(path, bytes, &mut w).unwrap();
        let Format::Binary { big } = h.format else {
            panic!("not binary");
        };
        let r = Binary {
            bytes,
            pos: h.body,
            big,
        };
        let show = |m: Result<PlyMesh>, w: Vec<String>| match m {
            Ok(m) => format!(
                "{:?} {:?} {:?} {:?} {:?} {w:?}",
                m.positions, m.normals, m.uvs, m.colors, m.indices
            ),
            Err(e) => format!("{e:#}"),
        };
        let (mut w1, mut w2) = (w.clone(), w);
        let bulk = body_from(path, &h, &mut Binary { ..r }, &mut w1, u64::MAX);
        let by_value = body_from(path, &h, &mut ByValue(r), &mut w2, u64::MAX);
        [show(bulk, w1), show(by_value, w2)]
    }

    #[test]
    fn bulk_reading_reads_what_value_by_value_reading_reads() {
        let z = [0.25, -1.5, 3.0, 0.0];
        let tris: &[&[i32]] = &[&[0, 1, 2], &[0, 2, 3], &[3, 1, 0]];
        for big in [false, true] {
            let file = every_attribute(big, z, tris);
            let h = header(Path::new("p.ply"), &file, &mut Vec::new()).unwrap();
            let body = &file[h.body..];
            // The bulk reading takes this file whole...
            let v = bulk::vertices(&h.elements[0], body, big, 65535.0);
            let (_, len) = v.expect("the vertices are read in bulk");
            assert!(bulk::triangles(&h.elements[1], &body[len..], big, 4).is_some());
            let [a, b] = both_ways(&file);
            assert_eq!(a, b);
            assert!(a.contains("[[0, 1, 2], [0, 2, 3], [3, 1, 0]]"), "{a}");
            // ...and leaves to the value-by-value reading what it does not
            // take as it stands, which reads it the same.
            let cases: [(_, &[&[i32]]); 7] = [
                (z, &[&[0, 1, 2], &[0, 1, 2, 3]]),
                (z, &[&[0, 1, 2], &[0, 9, 2]]),
                (z, &[&[0, 1, 2], &[0, -1, 2]]),
                (z, &[&[0, 1]]),
                ([0.0, f64::NAN, 0.0, 0.0], tris),
                ([0.0, 1e30, 0.0, -1e31], tris),
                ([0.0, 1e39, 0.0, 0.0], tris),
            ];
            for (z, faces) in cases {
                let [a, b] = both_ways(&every_attribute(big, z, faces));
                assert_eq!(a, b, "{z:?} {faces:?}");
            }
            let mut cut = every_attribute(big, z, tris);
            cut.truncate(cut.len() - 2);
            let [a, b] = both_ways(&cut);
            assert_eq!(a, b);
            assert!(a.contains("the file ends here (truncated)"), "{a}");
        }
    }

    /// A quad's header with `face` properties after its vertex indices.
    fn quad(face_props: &str) -> String {
        format!(
            "ply\nformat ascii 1.0\ncomment TextureFile t.png\nelement vertex 4\n\
             property float x\nproperty float y\nproperty float z\nelement face 2\n\
             property list uchar int vertex_indices\n{face_props}end_header\n\
             0 0 0\n1 0 0\n1 1 0\n0 1 0\n"
        )
    }

    #[test]
    fn face_texcoords_give_corners_their_own_vertices() {
        let text = quad("property list uchar float texcoord\nproperty int texnumber\n")
            + "3 0 1 2 6 0 0 1 0 1 1 0\n3 0 2 3 6 0 0.5 1 1 0 1 0\n";
        let (m, w) = read(text.as_bytes()).unwrap();
        assert_eq!(w, ["p.ply: ignored, not used: face texnumber"]);
        assert_eq!(m.texture, Some(("t.png".into(), 3)));
        // Vertex 0 is at two UVs: two vertices; vertex 2 at one.
        assert_eq!(m.indices, [[0, 1, 2], [3, 2, 4]]);
        let uv = |u, v| Vec2::new(u, v);
        assert_eq!(
            m.uvs.unwrap(),
            [
                uv(0.0, 0.0),
                uv(1.0, 0.0),
                uv(1.0, 1.0),
                uv(0.0, 0.5),
                uv(0.0, 1.0)
            ]
        );
        assert_eq!(m.positions[3], DVec3::ZERO);
        assert_eq!(m.positions[4], DVec3::Y);
        // A list of another length leaves its face at UV 0 0.
        let text = quad("property list uchar float texcoord\n")
            + "3 0 1 2 4 0 0 1 0\n3 0 2 3 6 0 0 1 1 0 1\n";
        let (m, w) = read(text.as_bytes()).unwrap();
        assert_eq!(m.uvs.unwrap()[..3], [Vec2::ZERO; 3]);
        assert_eq!(
            w,
            [
                "p.ply: element face 0: the texcoord list does not hold two numbers a corner: \
              its corners are at UV 0 0"
            ]
        );
    }

    #[test]
    fn face_colours_are_the_faces_diffuse_colour() {
        let props = "property uchar red\nproperty uchar green\nproperty uchar blue\n\
                     property uchar alpha\n";
        let text = quad(props) + "3 0 1 2 255 0 0 255\n3 0 2 3 0 255 0 9\n";
        let (m, w) = read(text.as_bytes()).unwrap();
        assert_eq!(w, ["p.ply: ignored, not used: face alpha"]);
        assert_eq!(m.indices, [[0, 1, 2], [3, 4, 5]]);
        let c = m.colors.unwrap();
        assert_eq!(c, [Vec3::X, Vec3::X, Vec3::X, Vec3::Y, Vec3::Y, Vec3::Y]);
        let text = quad("property uchar red\n") + "3 0 1 2 255\n3 0 2 3 0\n";
        let (m, w) = read(text.as_bytes()).unwrap();
        assert!(m.colors.is_none());
        assert_eq!(
            w,
            ["p.ply: element face has only some of red, green and blue: ignored"]
        );
    }

    #[test]
    fn concave_polygons_are_clipped_wherever_the_faces_come() {
        let u = "0 0 0\n3 0 0\n3 3 0\n2 3 0\n2 1 0\n1 1 0\n1 3 0\n0 3 0\n";
        let vertices = "element vertex 8\nproperty float x\nproperty float y\nproperty float z\n";
        let faces = "element face 2\nproperty list uchar int vertex_indices\n";
        let polygons = "8 0 1 2 3 4 5 6 7\n4 0 1 2 7\n";
        let head = "ply\nformat ascii 1.0\n";
        let first = format!("{head}{vertices}{faces}end_header\n{u}{polygons}");
        let (m, w) = read(first.as_bytes()).unwrap();
        assert!(w.is_empty(), "{w:?}");
        // The U in six triangles, each turning as it does, covering its
        // area; the square after it the fan it was.
        assert_eq!(m.indices.len(), 8);
        assert_eq!(m.indices[6..], [[0, 1, 2], [0, 2, 7]]);
        let twice: f64 = m.indices[..6]
            .iter()
            .map(|t| {
                let [a, b, c] = t.map(|i| m.positions[i as usize]);
                let z = (b - a).cross(c - a).z;
                assert!(z >= 0.0, "{t:?}");
                z
            })
            .sum();
        assert_eq!(twice, 14.0);
        let last = format!("{head}{faces}{vertices}end_header\n{polygons}{u}");
        let (late, _) = read(last.as_bytes()).unwrap();
        assert_eq!(late.indices, m.indices);
        // Corners on a line: a fan, and a warning.
        let collinear = "0 0 0\n1 0 0\n2 0 0\n3 0 0\n4 0 0\n5 0 0\n6 0 0\n7 0 0\n";
        let line = format!("{head}{vertices}{faces}end_header\n{collinear}{polygons}");
        let (_, w) = read(line.as_bytes()).unwrap();
        let warning = "p.ply: element face 0: a polygon fits no plane (its corners on a line or \
                       its edges crossing) or has more than 65536 corners: triangulated as a fan";
        assert_eq!(w, [warning]);
        // The same where the faces come first.
        let last = format!("{head}{faces}{vertices}end_header\n{polygons}{collinear}");
        assert_eq!(read(last.as_bytes()).unwrap().1, [warning]);
    }

    #[test]
    fn header_lines_of_unknown_kinds_are_skipped() {
        let text = format!("{HEAD}{QUAD}").replace(
            "comment made by hand\n",
            "obj_info by hand\nfoo bar\n\nvendor x\n",
        );
        let (m, w) = read(text.as_bytes()).unwrap();
        assert_eq!(m.indices.len(), 2);
        assert_eq!(
            w,
            [
                "p.ply:4: 2 header lines of a kind the PLY format does not name ('foo' ...): \
              skipped"
            ]
        );
        // Lines of kinds the format names are read as they must be.
        for (from, to, want) in [
            (
                "element face 1",
                "element face",
                "p.ply:8: not a header line",
            ),
            (
                "format ascii 1.0",
                "format ascii",
                "p.ply:2: not a header line",
            ),
        ] {
            let e = err(&format!("{HEAD}{QUAD}").replace(from, to));
            assert!(e.starts_with(want), "{e}");
        }
    }

    #[test]
    fn lone_cr_lines_tabs_and_values_past_the_declared_ones_are_read() {
        let (want, _) = read(format!("{HEAD}{QUAD}").as_bytes()).unwrap();
        // Lines ending in a lone CR (Draco's test files), in an ASCII body
        // and before a binary one.
        let (m, w) = read(format!("{HEAD}{QUAD}").replace('\n', "\r").as_bytes()).unwrap();
        assert_eq!(
            (m.positions, m.indices, w.len()),
            (want.positions.clone(), want.indices.clone(), 0)
        );
        let mut bin = binary(false);
        let end = bin.windows(11).position(|w| w == b"end_header\n").unwrap() + 11;
        for b in &mut bin[..end] {
            if *b == b'\n' {
                *b = b'\r';
            }
        }
        assert_eq!(
            read(&bin).unwrap().0.indices,
            read(&binary(false)).unwrap().0.indices
        );
        // Tabs and leading blanks between a header line's words.
        let tabs = format!("{HEAD}{QUAD}").replace("element vertex 4", " element\tvertex\t4");
        assert_eq!(read(tabs.as_bytes()).unwrap().0.positions, want.positions);
        // Values past the declared ones, as MeshLab's writers have left
        // them: ignored, said once with where the first was.
        let long = format!("{HEAD}0 0 0 7\n1 0 0 7 7\n1 1 0\n0 1 0\n4 0 1 2 3 9\n");
        let (m, w) = read(long.as_bytes()).unwrap();
        assert_eq!(m.indices, want.indices);
        assert_eq!(
            w,
            ["p.ply:11: 1 value past those the header declares: ignored (on 3 lines)"]
        );
    }

    #[test]
    fn face_counts_are_checked_against_memory() {
        let text = format!("{HEAD}{QUAD}");
        let e = parse(Path::new("p.ply"), text.as_bytes(), &mut Vec::new(), 1)
            .err()
            .map(|e| e.to_string());
        assert!(e.is_some_and(|e| e.contains("1 triangles and 4 vertices would need")));
    }

    #[test]
    fn faces_of_fewer_than_three_vertices_are_skipped() {
        let text = format!(
            "{}0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 1\n3 0 1 2\n0\n1 9\n",
            HEAD.replace("face 1", "face 4")
        );
        let (m, w) = read(text.as_bytes()).unwrap();
        assert_eq!(m.indices, [[0, 1, 2]]);
        assert_eq!(
            w,
            ["p.ply:15: element face 0: a face of 2 vertices (and 2 more of fewer than 3): skipped"]
        );
        // Binary: the bulk reading leaves them to the value-by-value one.
        for big in [false, true] {
            let mut b = binary(big);
            let at = b.windows(14).position(|w| w == b"element face 1").unwrap();
            b[at + 13] = b'2';
            b.push(1);
            b.extend(if big {
                3u32.to_be_bytes()
            } else {
                3u32.to_le_bytes()
            });
            let (m, w) = read(&b).unwrap();
            assert_eq!(m.indices, [[0, 1, 2], [0, 2, 3]]);
            assert_eq!(w.len(), 1, "{w:?}");
            assert!(
                w[0].ends_with("element face 1: a face of 1 vertex: skipped"),
                "{w:?}"
            );
        }
    }

    const STRIPS: &str = "ply\nformat ascii 1.0\nelement vertex 5\nproperty float x\n\
                          property float y\nproperty float z\nelement tristrips 1\n\
                          property list int int vertex_indices\nend_header\n\
                          0 0 0\n1 0 0\n0 1 0\n1 1 0\n2 1 0\n";

    #[test]
    fn triangle_strips_are_triangles_facing_one_way() {
        // Two strips; the second ends in a triangle with a repeated corner,
        // as strips are joined.
        let (m, w) = read(format!("{STRIPS}9 0 1 2 3 -1 3 1 4 4\n").as_bytes()).unwrap();
        assert!(w.is_empty(), "{w:?}");
        assert_eq!(m.indices, [[0, 1, 2], [2, 1, 3], [3, 1, 4]]);
        for t in &m.indices {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            assert!((b - a).cross(c - a).z > 0.0, "{t:?}");
        }
        // Binary, either byte order, read as ASCII is.
        for big in [false, true] {
            let head = STRIPS.split_once("end_header\n").unwrap().0.replace(
                "ascii",
                if big {
                    "binary_big_endian"
                } else {
                    "binary_little_endian"
                },
            );
            let mut b = format!("{head}end_header\n").into_bytes();
            let f = |x: f32| {
                if big {
                    x.to_be_bytes()
                } else {
                    x.to_le_bytes()
                }
            };
            let i = |x: i32| {
                if big {
                    x.to_be_bytes()
                } else {
                    x.to_le_bytes()
                }
            };
            for x in [
                0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 2.0, 1.0, 0.0,
            ] {
                b.extend(f(x));
            }
            for k in [9, 0, 1, 2, 3, -1, 3, 1, 4, 4] {
                b.extend(i(k));
            }
            let (n, w) = read(&b).unwrap();
            assert!(w.is_empty(), "{w:?}");
            assert_eq!(n.indices, m.indices);
        }
        // Nothing but restarts: no triangles; an index out of range, or
        // more than the line holds, an error naming the place.
        let (m, _) = read(format!("{STRIPS}3 -1 -1 -1\n").as_bytes()).unwrap();
        assert!(m.indices.is_empty());
        for (body, want) in [
            ("4 0 1 -2 3\n", "p.ply:15: element tristrips 0 (of 1), vertex_indices: vertex index -2 is out of range (5 vertices; -1 starts a strip)"),
            ("4 0 1 5\n", "vertex index 5 is out of range"),
            ("2147483647 0 1 2\n", "p.ply:15: element tristrips 0 (of 1), vertex_indices: the line ends"),
        ] {
            let e = err(&format!("{STRIPS}{body}"));
            assert!(e.contains(want), "{body}: {e}");
        }
        // The most triangles a strip can make are checked against memory
        // before they are read.
        let e = parse(
            Path::new("p.ply"),
            format!("{STRIPS}2147483647 0\n").as_bytes(),
            &mut Vec::new(),
            1 << 20,
        )
        .err()
        .map(|e| format!("{e:#}"))
        .unwrap_or_default();
        assert!(e.contains("2147483645 triangles would need"), "{e}");
        // Faces giving corners UVs of their own renumber the vertices that
        // strips name: such strips are not read.
        let text = STRIPS.replace(
            "end_header",
            "element face 1\nproperty list uchar int vertex_indices\nproperty list uchar float texcoord\nend_header",
        ) + "3 0 1 2\n3 0 1 2 6 0 0 1 0 0 1\n";
        let (m, w) = read(text.as_bytes()).unwrap();
        assert_eq!(m.indices.len(), 1);
        assert_eq!(
            w,
            ["p.ply: ignored, not used: element tristrips (1, as the faces give corners texture \
              coordinates or colours of their own)"]
        );
    }
}
