//! STL, binary and ASCII, with errors that name the file and the triangle
//! (binary) or line (ASCII).
//!
//! A file is binary when its size is the one its triangle count gives
//! (84 + 50 bytes a triangle), whatever its header says (binary files often
//! start with `solid` too); otherwise it is ASCII when it starts with
//! `solid` and reads as text, and a truncated or padded binary file when
//! not. Facet normals
//! are not read (the geometric normal is exact, and written ones are often
//! wrong); vertices are welded by exact position, so a mesh takes a sixth of
//! the memory its triangle soup would. Each `solid` of an ASCII file is a
//! mesh of its own.

use std::collections::HashMap;
use std::path::Path;

use anyhow::{anyhow, bail, Result};
use glam::{DAffine3, DVec3};

use super::numbers::{self, Absurd};
use super::parts::{mesh_fits, place_positions, Placed};
use crate::scene::show::show3;

/// Bytes of a binary triangle: normal, three vertices, attribute count.
const TRIANGLE: u64 = 50;
/// Bytes before the first binary triangle: header and count.
const HEADER: u64 = 84;

/// Welds vertices by exact position: each distinct position once, in the
/// order of first use (as the OBJ loader orders them).
#[derive(Default)]
struct Welder {
    positions: Vec<DVec3>,
    ids: HashMap<[u64; 3], u32, foldhash::fast::FixedState>,
}

impl Welder {
    fn id(&mut self, p: DVec3) -> u32 {
        // +0.0 and -0.0 are one position.
        let key = (p + DVec3::ZERO).to_array().map(f64::to_bits);
        let next = self.positions.len() as u32;
        let id = *self.ids.entry(key).or_insert(next);
        if id == next {
            self.positions.push(p);
        }
        id
    }
}

/// One mesh as read: welded positions and triangles.
struct Solid {
    name: String,
    welder: Welder,
    indices: Vec<[u32; 3]>,
}

impl Solid {
    fn new(name: String) -> Self {
        Solid {
            name,
            welder: Welder::default(),
            indices: Vec::new(),
        }
    }

    fn placed(self, xf: &DAffine3, path: &Path, material: u32) -> Result<Placed> {
        let positions = place_positions(self.welder.positions, xf, |_, p, q, why| {
            anyhow!(
                "{}: vertex {} lands at {} once placed, which {why}",
                path.display(),
                show3(p),
                show3(q)
            )
        })?;
        Ok(Placed {
            name: self.name,
            positions,
            normals: None,
            uvs: None,
            uvs1: None,
            tangents: None,
            colors: None,
            indices: self.indices,
            material,
        })
    }
}

/// Reads an STL file's bytes: its meshes placed by `xf` in f64, all with
/// `material`, refusing triangles that would need more than `available`
/// bytes.
pub(crate) fn parse(
    path: &Path,
    bytes: &[u8],
    xf: &DAffine3,
    material: u32,
    warnings: &mut Vec<String>,
    available: u64,
) -> Result<Vec<Placed>> {
    let stem = path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_default();
    let count = bytes
        .get(80..84)
        .map(|c| u32::from_le_bytes([c[0], c[1], c[2], c[3]]) as u64);
    let binary_size = count.map(|n| HEADER + n * TRIANGLE);
    let len = bytes.len() as u64;
    let solids = if binary_size == Some(len) {
        vec![binary(path, bytes, stem, available)?]
    } else if ascii_start(bytes) {
        ascii(path, bytes, &stem, warnings, available)?
    } else {
        match (count, binary_size) {
            (Some(n), Some(size)) if size < len => {
                warnings.push(format!(
                    "{}: {} bytes after the {n} triangles the header counts: ignored",
                    path.display(),
                    len - size
                ));
                vec![binary(path, &bytes[..size as usize], stem, available)?]
            }
            (Some(n), Some(size)) => bail!(
                "{}: truncated binary STL: the header counts {n} triangles ({size} bytes), \
                 the file has {len} bytes ({})",
                path.display(),
                crate::words::count(
                    len.saturating_sub(HEADER) / TRIANGLE,
                    "whole triangle",
                    "whole triangles"
                )
            ),
            _ => bail!(
                "{}: not an STL file: {len} bytes, shorter than a binary header (84 bytes), \
                 and not ASCII (which starts with 'solid')",
                path.display()
            ),
        }
    };
    solids
        .into_iter()
        .filter(|s| !s.indices.is_empty())
        .map(|s| s.placed(xf, path, material))
        .collect()
}

/// An ASCII STL starts with `solid` (after blanks), followed by a blank,
/// and reads as text near its start: UTF-8 without control characters but
/// blanks. A binary file that starts with `solid` has its numbers there,
/// whose bytes hardly ever are text (NUL bytes or not).
fn ascii_start(bytes: &[u8]) -> bool {
    let body = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    let head = &body[..body.len().min(4096)];
    // A character cut at the end of the head is still text.
    let utf8 = std::str::from_utf8(head).map_or_else(|e| e.error_len().is_none(), |_| true);
    let control = |b: &u8| (*b < 0x20 && !b.is_ascii_whitespace()) || *b == 0x7f;
    let start = body.iter().position(|b| !b.is_ascii_whitespace());
    start.is_some_and(|i| {
        body[i..]
            .get(..5)
            .is_some_and(|w| w.eq_ignore_ascii_case(b"solid"))
            && body.get(i + 5).is_none_or(|b| b.is_ascii_whitespace())
            && utf8
            && !head.iter().any(control)
    })
}

fn binary(path: &Path, bytes: &[u8], name: String, available: u64) -> Result<Solid> {
    let body = &bytes[HEADER as usize..];
    let n = body.len() / TRIANGLE as usize;
    mesh_fits(0, n as u64, available).map_err(|e| anyhow!("{}: {e}", path.display()))?;
    let mut solid = Solid::new(name);
    solid.indices.reserve_exact(n);
    for (t, tri) in body.chunks_exact(TRIANGLE as usize).enumerate() {
        let f = |k: usize| {
            let b = &tri[12 + 4 * k..16 + 4 * k];
            f32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f64
        };
        let mut ids = [0u32; 3];
        for (v, id) in ids.iter_mut().enumerate() {
            let p = DVec3::new(f(3 * v), f(3 * v + 1), f(3 * v + 2));
            if let Some(why) = p.to_array().into_iter().find_map(numbers::unusable) {
                bail!(
                    "{}: triangle {} (of {n}), vertex {}: {} {why}",
                    path.display(),
                    t + 1,
                    v + 1,
                    show3(p)
                );
            }
            *id = solid.welder.id(p);
        }
        solid.indices.push(ids);
    }
    Ok(solid)
}

/// ASCII STL: `solid`, then `facet normal`, `outer loop`, three (or more,
/// as a fan) `vertex` lines, `endloop`, `endfacet`, and `endsolid`.
fn ascii(
    path: &Path,
    bytes: &[u8],
    stem: &str,
    warnings: &mut Vec<String>,
    available: u64,
) -> Result<Vec<Solid>> {
    let text = super::source::text(path, bytes.to_vec())?;
    let mut solids: Vec<Solid> = Vec::new();
    let mut current: Option<Solid> = None;
    let mut facet: Option<(usize, Vec<DVec3>)> = None;
    let mut in_loop = false;
    let mut absurd = Absurd::default();
    let mut triangles = 0u64;
    let mut last = 0;
    for (i, line) in text.lines().enumerate() {
        let n = i + 1;
        last = n;
        let at = |msg: String| anyhow!("{}:{n}: {msg}", path.display());
        let mut words = line.split_whitespace();
        let Some(key) = words.next() else { continue };
        // Keywords in any case, as exporters write them (SOLID, FACET ...);
        // lower case, as most are, is taken as it is.
        let lower;
        let key = match key.bytes().any(|b| b.is_ascii_uppercase()) {
            true => {
                lower = key.to_ascii_lowercase();
                lower.as_str()
            }
            false => key,
        };
        let rest: Vec<&str> = words.collect();
        let expect = |what: &str| {
            at(format!(
                "expected {what}, found '{}'",
                line.trim().chars().take(40).collect::<String>()
            ))
        };
        match (key, current.is_some(), &facet, in_loop) {
            ("solid", false, _, _) => {
                let name = rest.join(" ");
                current = Some(Solid::new(if name.is_empty() {
                    stem.to_string()
                } else {
                    name
                }));
            }
            ("endsolid", true, None, _) => {
                solids.extend(current.take());
            }
            ("facet", true, None, _) => {
                if !rest
                    .first()
                    .is_some_and(|w| w.eq_ignore_ascii_case("normal"))
                    || rest.len() != 4
                {
                    bail!(expect("'facet normal nx ny nz'"));
                }
                for w in &rest[1..] {
                    numbers::parse(w).map_err(at)?;
                }
                facet = Some((n, Vec::new()));
            }
            ("outer", true, Some((_, v)), false) if v.is_empty() => {
                if !(rest.len() == 1 && rest[0].eq_ignore_ascii_case("loop")) {
                    bail!(expect("'outer loop'"));
                }
                in_loop = true;
            }
            ("vertex", true, Some(_), true) => {
                if rest.len() != 3 {
                    bail!(at(format!(
                        "a vertex takes 3 coordinates (x y z), found {}",
                        rest.len()
                    )));
                }
                let mut p = [0.0; 3];
                for (x, w) in p.iter_mut().zip(&rest) {
                    *x = numbers::parse(w).map_err(at)?;
                    absurd.check(n, *x, || w.to_string());
                }
                if let Some((_, v)) = &mut facet {
                    v.push(DVec3::from_array(p));
                }
            }
            ("endloop", true, Some(_), true) => in_loop = false,
            ("endfacet", true, Some(_), false) => {
                let (Some(solid), Some((start, v))) = (current.as_mut(), facet.take()) else {
                    continue;
                };
                if v.len() < 3 {
                    bail!(at(format!(
                        "the facet from line {start} has {} vertices; a facet needs 3",
                        v.len()
                    )));
                }
                triangles += v.len() as u64 - 2;
                mesh_fits(0, triangles, available).map_err(at)?;
                let ids: Vec<u32> = v.iter().map(|&p| solid.welder.id(p)).collect();
                for k in 2..ids.len() {
                    solid.indices.push([ids[0], ids[k - 1], ids[k]]);
                }
            }
            (_, false, _, _) => bail!(expect("'solid'")),
            (_, true, None, _) => bail!(expect("'facet normal' or 'endsolid'")),
            (_, true, Some((_, v)), false) if v.is_empty() => bail!(expect("'outer loop'")),
            (_, true, Some(_), true) => bail!(expect("'vertex' or 'endloop'")),
            _ => bail!(expect("'endfacet'")),
        }
    }
    if let Some(s) = current {
        if facet.is_some() {
            bail!(
                "{}:{last}: the file ends inside a facet (truncated?)",
                path.display()
            );
        }
        warnings.push(format!(
            "{}:{last}: no 'endsolid' at the end (truncated?)",
            path.display()
        ));
        solids.push(s);
    }
    warnings.extend(absurd.warning(path));
    Ok(solids)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn binary_stl(tris: &[[[f32; 3]; 3]], header: &[u8]) -> Vec<u8> {
        let mut b = header.to_vec();
        b.resize(80, b' ');
        b.extend((tris.len() as u32).to_le_bytes());
        for t in tris {
            b.extend([0u8; 12]);
            for v in t {
                for x in v {
                    b.extend(x.to_le_bytes());
                }
            }
            b.extend([0u8; 2]);
        }
        b
    }

    const TWO: [[[f32; 3]; 3]; 2] = [
        [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]],
        [[1.0, 0.0, 0.0], [1.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
    ];

    fn read(bytes: &[u8]) -> Result<(Vec<Placed>, Vec<String>)> {
        let mut w = Vec::new();
        let m = parse(
            Path::new("p.stl"),
            bytes,
            &DAffine3::IDENTITY,
            0,
            &mut w,
            u64::MAX,
        )?;
        Ok((m, w))
    }

    #[test]
    fn binary_welds_and_starting_with_solid_is_still_binary() {
        let (m, w) = read(&binary_stl(&TWO, b"solid but binary")).unwrap();
        assert!(w.is_empty(), "{w:?}");
        assert_eq!(m[0].positions.len(), 4);
        assert_eq!(m[0].indices, [[0, 1, 2], [1, 3, 2]]);
        assert_eq!(m[0].name, "p");
    }

    /// A binary file that starts with `solid` and holds no NUL byte (a
    /// count and numbers without one), cut short, is a truncated binary
    /// file, not ASCII that makes no sense.
    #[test]
    fn binary_without_nul_bytes_is_told_by_its_bytes() {
        let tri = [[1.1f32, 2.2, 3.3], [4.4, 5.7, 6.6], [7.7, 8.8, 9.9]];
        let mut b = binary_stl(&[tri, tri], b"solid but binary");
        b[80..84].copy_from_slice(&0x0101_0101u32.to_le_bytes());
        for t in 0..2 {
            let at = 84 + 50 * t;
            b[at..at + 12].copy_from_slice(&[0x3f; 12]);
            b[at + 48..at + 50].copy_from_slice(&[1, 1]);
        }
        assert!(!b.contains(&0));
        let e = format!("{:#}", read(&b).unwrap_err());
        assert!(
            e.starts_with("p.stl: truncated binary STL: the header counts 16843009 triangles"),
            "{e}"
        );
    }

    #[test]
    fn ascii_reads_solids_and_fans() {
        let text = "solid part one\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   \
                    vertex 1 0 0\n   vertex 1 1 0\n   vertex 0 1 0\n  endloop\n endfacet\n\
                    endsolid part one\nsolid\nfacet normal 0 0 0\nouter loop\nvertex 0 0 1\n\
                    vertex 1 0 1\nvertex 0 1 1\nendloop\nendfacet\nendsolid\n";
        let (m, w) = read(text.as_bytes()).unwrap();
        assert!(w.is_empty(), "{w:?}");
        assert_eq!(m.len(), 2);
        assert_eq!(m[0].name, "part one");
        assert_eq!(m[0].indices, [[0, 1, 2], [0, 2, 3]]);
        assert_eq!(m[1].name, "p");
        assert_eq!(m[1].positions[1], DVec3::new(1.0, 0.0, 1.0));
    }

    /// Keywords in upper or mixed case, as some exporters write them.
    #[test]
    fn ascii_keywords_in_any_case() {
        let text = "SOLID Part\nFACET NORMAL 0 0 1\nOuter Loop\nVERTEX 0 0 0\nVERTEX 1 0 0\n\
                    VERTEX 0 1 0\nENDLOOP\nENDFACET\nENDSOLID Part\n";
        let (m, w) = read(text.as_bytes()).unwrap();
        assert!(w.is_empty(), "{w:?}");
        assert_eq!((m.len(), m[0].name.as_str()), (1, "Part"));
        assert_eq!(m[0].indices, [[0, 1, 2]]);
    }

    #[test]
    fn malformed_files_name_the_place() {
        let e = |b: &[u8]| format!("{:#}", read(b).unwrap_err());
        let mut cut = binary_stl(&TWO, b"x");
        cut.truncate(cut.len() - 7);
        assert_eq!(
            e(&cut),
            "p.stl: truncated binary STL: the header counts 2 triangles (184 bytes), \
             the file has 177 bytes (1 whole triangle)"
        );
        assert!(e(b"abc").contains("not an STL file"));
        let mut nan = binary_stl(&TWO, b"x");
        nan[84 + 12 + 12 + 4..84 + 12 + 12 + 8].copy_from_slice(&f32::NAN.to_le_bytes());
        assert!(
            e(&nan).starts_with("p.stl: triangle 1 (of 2), vertex 2: (1, NaN, 0)"),
            "{}",
            e(&nan)
        );
        for (text, want) in [
            (
                "solid\nfacet normal 0 0 1\nvertex 0 0 0\n",
                "p.stl:3: expected 'outer loop'",
            ),
            (
                "solid\nfacet normal 0 0 1\nouter loop\nvertex 0 0\n",
                "p.stl:4: a vertex takes 3 coordinates",
            ),
            (
                "solid\nfacet normal 0 0 1\nouter loop\nvertex 0 0 x\n",
                "p.stl:4: 'x' is not a number",
            ),
            (
                "solid\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nendloop\nendfacet\n",
                "p.stl:6: the facet from line 2 has 1 vertices",
            ),
            (
                "solid\nfacet normal 0 0 1\nouter loop\n",
                "p.stl:3: the file ends inside a facet",
            ),
            (
                "solid\nvertex 1 2 3\n",
                "p.stl:2: expected 'facet normal' or 'endsolid'",
            ),
        ] {
            assert!(
                e(text.as_bytes()).starts_with(want),
                "{text:?}: {}",
                e(text.as_bytes())
            );
        }
    }

    #[test]
    fn padding_warns_and_memory_is_checked_first() {
        let mut padded = binary_stl(&TWO, b"x");
        padded.extend([0u8; 3]);
        let (m, w) = read(&padded).unwrap();
        assert_eq!(m[0].indices.len(), 2);
        assert!(w[0].contains("3 bytes after the 2 triangles"), "{w:?}");
        let e = parse(
            Path::new("p.stl"),
            &binary_stl(&TWO, b"x"),
            &DAffine3::IDENTITY,
            0,
            &mut Vec::new(),
            crate::memory::BYTES_PER_TRIANGLE,
        )
        .err()
        .map(|e| e.to_string());
        assert!(e.is_some_and(|e| e.contains("2 triangles would need")));
    }
}
