//! Wavefront MTL material libraries: the Phong subset rayterm renders, and
//! the PBR extension's physically based materials.
//!
//! `Kd`, `Ks` (one number for grey or three for RGB), `Ns`, `d` and
//! `map_Kd` (with `-clamp`) are used; `Ka`, `Tf`, `Ni`, `illum` and
//! `sharpness` are checked and ignored (the ambient term is the scene's,
//! there is no refraction). A material with `Pr` or `Pm` (or their maps)
//! is physically based: `Pr`, `Pm`, `Ke`, `map_Pr`, `map_Pm`, `map_Ke`
//! and `norm` or `map_Bump` (with `-bm`) are read for it. On a Phong
//! material a non-black `Ke` and those maps, and anywhere `Tr`, the other
//! texture maps, other texture options (skipped with the values each
//! takes) and unknown statements are ignored with one warning per file.
//! Malformed statements are errors naming the file and line; negative
//! colours and out-of-range `Ns`, `d`, `Pr` or `Pm` are warnings.

use std::path::Path;

use anyhow::{anyhow, bail, Result};
use glam::Vec3;

use super::numbers::{self, Absurd};
use super::parts::Parts;
use super::source::{resolve, Source};
use crate::scene::texture::{Encoding, Texture};
use crate::scene::Pbr;
use crate::words::quoted;

/// One `newmtl` block as written.
#[derive(Clone, Debug, Default, PartialEq)]
pub(crate) struct MtlMaterial {
    pub(crate) name: String,
    pub(crate) kd: Option<Vec3>,
    pub(crate) ks: Option<Vec3>,
    pub(crate) ns: Option<f32>,
    pub(crate) dissolve: Option<f32>,
    /// The `map_Kd` file as written (options removed, escaped spaces
    /// unescaped) and its line.
    pub(crate) map_kd: Option<(String, usize)>,
    /// `map_Kd -clamp on`: the texture clamped rather than repeated.
    pub(crate) clamp: bool,
    /// The PBR extension: roughness and metalness, and their maps.
    pub(crate) pr: Option<f32>,
    pub(crate) pm: Option<f32>,
    pub(crate) map_pr: Option<(String, usize)>,
    pub(crate) map_pm: Option<(String, usize)>,
    /// Emission (`Ke`) and its line, and its map.
    pub(crate) ke: Option<(Vec3, usize)>,
    pub(crate) map_ke: Option<(String, usize)>,
    /// The normal map (`norm`, or `map_Bump` and `bump` where the image is
    /// one).
    pub(crate) normal: Option<Normal>,
}

/// A normal map as an MTL statement names it.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct Normal {
    pub(crate) file: String,
    pub(crate) line: usize,
    /// `-bm`: how far the normals tilt (1 as written).
    pub(crate) scale: f32,
    /// The statement: `norm` holds only normal maps, `map_Bump` and
    /// `bump` height maps too.
    pub(crate) statement: &'static str,
}

impl MtlMaterial {
    /// Whether it is a physically based material: one with the PBR
    /// extension's roughness or metalness.
    pub(crate) fn pbr(&self) -> bool {
        self.pr.is_some() || self.pm.is_some() || self.map_pr.is_some() || self.map_pm.is_some()
    }
}

/// What a texture option takes after its name.
#[derive(Clone, Copy)]
enum Takes {
    /// Up to this many numbers (`-o 0.5` or `-o 0.5 0.5 0`).
    Numbers(usize),
    /// `on` or `off`.
    Switch,
    /// One word (`-type sphere`, `-imfchan r`).
    Word,
}

/// The texture options of the MTL format, and `-colorspace`
/// (tinyobjloader's).
const TEXTURE_OPTIONS: &[(&str, Takes)] = &[
    ("-blendu", Takes::Switch),
    ("-blendv", Takes::Switch),
    ("-bm", Takes::Numbers(1)),
    ("-boost", Takes::Numbers(1)),
    ("-cc", Takes::Switch),
    ("-clamp", Takes::Switch),
    ("-colorspace", Takes::Word),
    ("-imfchan", Takes::Word),
    ("-mm", Takes::Numbers(2)),
    ("-o", Takes::Numbers(3)),
    ("-s", Takes::Numbers(3)),
    ("-t", Takes::Numbers(3)),
    ("-texres", Takes::Numbers(1)),
    ("-type", Takes::Word),
];

/// A texture statement's arguments.
#[derive(Debug, PartialEq)]
struct TextureArgs {
    /// The options rayterm does not use, as written.
    ignored: Vec<String>,
    /// `-clamp on` (or `off`), the last one written.
    clamp: Option<bool>,
    /// `-bm`, the last one written.
    bm: Option<f32>,
    /// The file name, which may hold spaces, a backslash before one
    /// escaping it (`my\ texture.png`).
    file: String,
}

/// Splits texture statement arguments into options, each with the values
/// it takes, and the file name. An option's values end early at a word
/// that is not one (`-o 0.5 t.png`).
fn texture_args(rest: &str) -> TextureArgs {
    let mut args = TextureArgs {
        ignored: Vec::new(),
        clamp: None,
        bm: None,
        file: String::new(),
    };
    // The first word of `rest`, taken off it.
    fn word(rest: &mut &str) -> String {
        let end = rest.find(char::is_whitespace).unwrap_or(rest.len());
        let w = rest[..end].to_string();
        *rest = rest[end..].trim_start();
        w
    }
    let mut rest = rest.trim_start();
    while rest.starts_with('-') {
        let name = word(&mut rest);
        let takes = TEXTURE_OPTIONS.iter().find(|(n, _)| *n == name);
        let next = rest.split_whitespace().next().unwrap_or("");
        let mut values = Vec::new();
        match takes.map(|(_, t)| *t) {
            Some(Takes::Numbers(most)) => {
                while values.len() < most
                    && rest
                        .split_whitespace()
                        .next()
                        .is_some_and(|w| w.parse::<f64>().is_ok())
                {
                    values.push(word(&mut rest));
                }
            }
            Some(Takes::Switch) if ["on", "off"].contains(&next) => values.push(word(&mut rest)),
            Some(Takes::Word) if !next.is_empty() => values.push(word(&mut rest)),
            _ => {}
        }
        // `-bm` scales a normal map, and is ignored (and said) elsewhere.
        if let ("-bm", Some(v)) = (name.as_str(), values.first()) {
            args.bm = v.parse().ok().filter(|b: &f32| b.is_finite());
        }
        let wanted = matches!(takes, Some((_, Takes::Numbers(_)))) && values.is_empty();
        match (name.as_str(), values.first().map(String::as_str)) {
            ("-clamp", Some(v)) => args.clamp = Some(v == "on"),
            ("-bm", Some(v)) if args.bm.is_none() => {
                args.ignored.push(format!("-bm {v} (not a finite number)"))
            }
            _ if wanted => args.ignored.push(format!(
                "{name} (no number after it: {} is read as part of the file's name)",
                quoted(next)
            )),
            _ => args.ignored.push(
                [name]
                    .into_iter()
                    .chain(values)
                    .collect::<Vec<_>>()
                    .join(" "),
            ),
        }
    }
    let mut chars = rest.trim_end().chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '\\' if chars.peek().is_some_and(|n| n.is_whitespace()) => {}
            c => args.file.push(c),
        }
    }
    args
}

/// Statements ignored in one file, for one warning: name, first line,
/// count; past [`Ignored::KINDS`] kinds, counted together (a file of a
/// million made-up keywords says so in a line).
#[derive(Default)]
struct Ignored(Vec<(String, usize, usize)>, usize);

impl Ignored {
    const KINDS: usize = 16;

    fn note(&mut self, what: &str, line: usize) {
        let what = quoted(what);
        let kinds = self.0.len();
        match self.0.iter_mut().find(|(w, _, _)| *w == what) {
            Some(e) => e.2 += 1,
            None if kinds < Self::KINDS => self.0.push((what, line, 1)),
            None => self.1 += 1,
        }
    }

    fn warning(self, path: &Path) -> Option<String> {
        if self.0.is_empty() {
            return None;
        }
        let list: Vec<String> = self
            .0
            .iter()
            .map(|(w, line, n)| match n {
                1 => format!("{w} (line {line})"),
                n => format!("{w} (line {line} and {} more)", n - 1),
            })
            .chain((self.1 > 0).then(|| {
                crate::words::count(self.1 as u64, "statement", "statements") + " of other kinds"
            }))
            .collect();
        Some(format!(
            "{}: ignored, not supported: {}",
            path.display(),
            list.join(", ")
        ))
    }
}

/// The numbers after a statement, each checked, up to a comment (`Ka 0 0
/// 0 # ambient`, as tinyobjloader and tobj read it).
fn numbers(rest: &str, line: usize, absurd: &mut Absurd) -> Result<Vec<f64>, String> {
    rest.split_whitespace()
        .take_while(|w| !w.starts_with('#'))
        .map(|w| {
            let x = numbers::parse(w)?;
            absurd.check(line, x, || w.to_string());
            Ok(x)
        })
        .collect()
}

/// Parses an MTL file; warnings are appended to `warnings`.
pub(crate) fn parse(
    path: &Path,
    text: &str,
    warnings: &mut Vec<String>,
) -> Result<Vec<MtlMaterial>> {
    let mut materials: Vec<MtlMaterial> = Vec::new();
    let mut ignored = Ignored::default();
    let mut absurd = Absurd::default();
    let mut orphans = None;
    for (i, raw) in text.lines().enumerate() {
        let n = i + 1;
        let at = |msg: String| anyhow!("{}:{n}: {msg}", path.display());
        let line = raw.trim();
        if line.is_empty() || line.starts_with('#') {
            continue;
        }
        let (key, rest) = line
            .split_once(char::is_whitespace)
            .map_or((line, ""), |(k, r)| (k, r.trim()));
        if key == "newmtl" {
            if let Some(m) = materials.last() {
                phong_leftovers(m, &mut ignored);
            }
            if rest.is_empty() {
                warnings.push(format!(
                    "{}:{n}: newmtl without a name: the material of a usemtl without one",
                    path.display()
                ));
            }
            materials.push(MtlMaterial {
                name: rest.to_string(),
                ..MtlMaterial::default()
            });
            continue;
        }
        let Some(m) = materials.last_mut() else {
            orphans.get_or_insert(n);
            continue;
        };
        let mut colour = |absurd: &mut Absurd| -> Result<Option<Vec3>> {
            if rest.starts_with("spectral") || rest.starts_with("xyz") {
                return Ok(None);
            }
            let v = numbers(rest, n, absurd).map_err(at)?;
            let c = match v[..] {
                [g] => Vec3::splat(g as f32),
                [r, g, b] => Vec3::new(r as f32, g as f32, b as f32),
                _ => bail!(at(format!(
                    "{key} takes 1 or 3 numbers (r [g b]), found {}",
                    v.len()
                ))),
            };
            if c.min_element() < 0.0 {
                warnings.push(format!(
                    "{}:{n}: negative colour {key} {}: no surface reflects less than nothing",
                    path.display(),
                    quoted(rest)
                ));
            }
            Ok(Some(c))
        };
        let single = |absurd: &mut Absurd| -> Result<f32> {
            match numbers(rest, n, absurd).map_err(at)?[..] {
                [x] => Ok(x as f32),
                ref v => bail!(at(format!("{key} takes one number, found {}", v.len()))),
            }
        };
        match key {
            "Kd" | "Ks" | "Ka" | "Tf" | "Ke" => {
                let c = colour(&mut absurd)?;
                match (key, c) {
                    (_, None) => ignored.note(&format!("{key} {}", rest_word(rest)), n),
                    ("Kd", c) => m.kd = c,
                    ("Ks", c) => m.ks = c,
                    ("Ke", Some(c)) => m.ke = Some((c, n)),
                    _ => {}
                }
            }
            "Ns" => {
                let ns = single(&mut absurd)?;
                if ns < 0.0 {
                    warnings.push(format!(
                        "{}:{n}: negative Ns {}: using 0",
                        path.display(),
                        quoted(rest)
                    ));
                }
                m.ns = Some(ns.max(0.0));
            }
            "d" => {
                let value = match rest.strip_prefix("-halo") {
                    Some(v) => {
                        ignored.note("d -halo", n);
                        v.trim()
                    }
                    None => rest,
                };
                let d = match numbers(value, n, &mut absurd).map_err(at)?[..] {
                    [x] => x as f32,
                    ref v => bail!(at(format!("d takes one number, found {}", v.len()))),
                };
                if !(0.0..=1.0).contains(&d) {
                    warnings.push(format!(
                        "{}:{n}: d {} is outside 0..1: clamped",
                        path.display(),
                        quoted(value)
                    ));
                }
                m.dissolve = Some(d.clamp(0.0, 1.0));
            }
            "Ni" | "sharpness" => {
                single(&mut absurd)?;
            }
            "Pr" | "Pm" => {
                let x = single(&mut absurd)?;
                if !(0.0..=1.0).contains(&x) {
                    warnings.push(format!(
                        "{}:{n}: {key} {} is outside 0..1: clamped",
                        path.display(),
                        quoted(rest)
                    ));
                }
                let x = Some(x.clamp(0.0, 1.0));
                match key {
                    "Pr" => m.pr = x,
                    _ => m.pm = x,
                }
            }
            "map_Pr" | "map_Pm" | "map_Ke" | "norm" | "map_Bump" | "bump" => {
                let args = texture_args(rest);
                let file = args.file.trim_matches('"').trim();
                if file.is_empty() {
                    warnings.push(format!(
                        "{}:{n}: {key} names no file: ignored",
                        path.display()
                    ));
                    continue;
                }
                let normal = matches!(key, "norm" | "map_Bump" | "bump");
                // `-bm` is the normal map's scale, not an option ignored.
                let scale = args.bm.map(|b| format!("-bm {b}"));
                let options: Vec<&String> = args
                    .ignored
                    .iter()
                    .filter(|o| {
                        !(normal
                            && args.bm.is_some()
                            && o.strip_prefix("-bm ")
                                .and_then(|v| v.parse::<f32>().ok())
                                .map(|b| format!("-bm {b}"))
                                == scale)
                    })
                    .collect();
                if !options.is_empty() {
                    let list: Vec<&str> = options.iter().map(|o| o.as_str()).collect();
                    warnings.push(format!(
                        "{}:{n}: {key} options ignored: {} (the texture is applied as is)",
                        path.display(),
                        quoted(&list.join(", "))
                    ));
                }
                let at = Some((args.file.clone(), n));
                match key {
                    "map_Pr" => m.map_pr = at,
                    "map_Pm" => m.map_pm = at,
                    "map_Ke" => m.map_ke = at,
                    _ => {
                        m.normal = Some(Normal {
                            file: args.file,
                            line: n,
                            scale: args.bm.unwrap_or(1.0),
                            statement: match key {
                                "norm" => "norm",
                                "bump" => "bump",
                                _ => "map_Bump",
                            },
                        })
                    }
                }
            }
            "Tr" => {
                single(&mut absurd)?;
                ignored.note("Tr (opacity is read from d)", n);
            }
            "illum" => {}
            "map_Kd" => {
                let TextureArgs {
                    ignored: options,
                    clamp,
                    file,
                    ..
                } = texture_args(rest);
                // As a missing texture: the material keeps its Kd.
                if file.trim_matches('"').trim().is_empty() {
                    warnings.push(format!(
                        "{}:{n}: map_Kd names no file: ignored (Kd is used)",
                        path.display()
                    ));
                    continue;
                }
                if !options.is_empty() {
                    warnings.push(format!(
                        "{}:{n}: map_Kd options ignored: {} (the texture is applied as is)",
                        path.display(),
                        quoted(&options.join(", "))
                    ));
                }
                m.map_kd = Some((file, n));
                m.clamp = clamp == Some(true);
            }
            other => ignored.note(other, n),
        }
    }
    if let Some(m) = materials.last() {
        phong_leftovers(m, &mut ignored);
    }
    if let Some(n) = orphans {
        warnings.push(format!(
            "{}:{n}: statements before the first newmtl belong to no material: ignored",
            path.display()
        ));
    }
    warnings.extend(absurd.warning(path));
    warnings.extend(ignored.warning(path));
    Ok(materials)
}

/// What a Phong material (one without the PBR extension's roughness or
/// metalness) has no use for: a non-black `Ke` and the extension's maps,
/// listed with the ignored statements once its block has ended.
fn phong_leftovers(m: &MtlMaterial, ignored: &mut Ignored) {
    if m.pbr() {
        return;
    }
    if let Some((_, line)) = m.ke.filter(|(c, _)| *c != Vec3::ZERO) {
        ignored.note("Ke (emission)", line);
    }
    if let Some(n) = &m.normal {
        ignored.note(n.statement, n.line);
    }
    if let Some((_, line)) = &m.map_ke {
        ignored.note("map_Ke", *line);
    }
}

/// The physically based material of an MTL material with the PBR
/// extension (`m.pbr()`), its textures read into `parts`: `Pr` and `Pm`
/// or their maps (a map replaces its number, as Blender's importer reads
/// them; a roughness given by neither comes from `Ns`, `1 - √Ns / 30`, the
/// inverse of Blender's exporter, else is 1), `Ke` tinting `map_Ke`, and
/// the normal map.
pub(crate) fn pbr(parts: &mut Parts, src: &dyn Source, mtl_path: &Path, m: &MtlMaterial) -> Pbr {
    let texture = |parts: &mut Parts, file: &str, line: usize, encoding| {
        let from = format!("{}:{line}", mtl_path.display());
        let path = resolve(mtl_path, file);
        parts.texture_at(
            src,
            &path,
            src.outside(mtl_path, &path),
            file,
            &from,
            encoding,
        )
    };
    let map = |parts: &mut Parts, m: &Option<(String, usize)>, encoding| {
        m.as_ref()
            .and_then(|(file, line)| texture(parts, file, *line, encoding))
    };
    let roughness_texture = map(parts, &m.map_pr, Encoding::Linear);
    let metallic_texture = map(parts, &m.map_pm, Encoding::Linear);
    let roughness = match (roughness_texture, m.pr, m.ns) {
        (Some(_), _, _) => 1.0,
        (None, Some(r), _) => r,
        (None, None, Some(ns)) => (1.0 - ns.sqrt() / 30.0).clamp(0.0, 1.0),
        (None, None, None) => 1.0,
    };
    let metallic = match (metallic_texture, m.pm) {
        (Some(_), _) => 1.0,
        (None, pm) => pm.unwrap_or(0.0),
    };
    let ke = m.ke.map_or(Vec3::ZERO, |(c, _)| c.max(Vec3::ZERO));
    let mut emissive = ke;
    let emissive_texture = map(parts, &m.map_ke, Encoding::Srgb).map(|id| {
        // The map is the emitted colour, tinted by a Ke beside it.
        let tint = if ke == Vec3::ZERO { Vec3::ONE } else { ke };
        emissive = tint;
        match tint == Vec3::ONE {
            true => id,
            false => {
                let mut t = parts.textures[id as usize].clone();
                t.tint = tint;
                parts.add_texture(t)
            }
        }
    });
    let normal = m.normal.as_ref().and_then(|n| {
        let id = texture(parts, &n.file, n.line, Encoding::Linear)?;
        let what = match map_kind(&parts.textures[id as usize]) {
            MapKind::Normal => return Some((id, n.scale)),
            MapKind::Height => "a height map (its texels are grey)",
            MapKind::Other => "not a normal map (its texels are not the bluish of one)",
        };
        parts.warnings.push(format!(
            "{}:{}: {} {} is {what}: no normal map for this material",
            mtl_path.display(),
            n.line,
            n.statement,
            quoted(&n.file)
        ));
        None
    });
    Pbr {
        metallic,
        roughness,
        roughness_texture,
        metallic_texture,
        normal,
        emissive,
        emissive_texture,
        ..Pbr::default()
    }
}

/// What an image a normal-map statement names holds.
enum MapKind {
    /// A tangent-space normal map: bluish (its texels point out of the
    /// surface, `z` near 1, and lean in x and y).
    Normal,
    /// A height map (bump map): grey.
    Height,
    Other,
}

fn map_kind(t: &Texture) -> MapKind {
    // A sample of at most 64k texels says as much as all of them.
    let step = (t.texels.len() / 65536).max(1);
    let (mut coloured, mut z, mut n) = (0usize, 0.0f64, 0usize);
    let mut bluish = 0usize;
    for c in t.texels.iter().step_by(step) {
        coloured += (c.max_element() - c.min_element() > 0.02) as usize;
        // x and y about their middle, z above it.
        bluish += ((c.x - 0.5).abs() < 0.4 && (c.y - 0.5).abs() < 0.4 && c.z > 0.5) as usize;
        z += c.z as f64;
        n += 1;
    }
    if coloured * 10 <= n {
        MapKind::Height
    } else if z / n as f64 > 0.6 && bluish * 10 >= n * 9 {
        MapKind::Normal
    } else {
        MapKind::Other
    }
}

/// The first word of `rest` (`spectral`, `xyz`), for the ignored list.
fn rest_word(rest: &str) -> &str {
    rest.split_whitespace().next().unwrap_or("")
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse_ok(text: &str) -> (Vec<MtlMaterial>, Vec<String>) {
        let mut w = Vec::new();
        let m = parse(Path::new("m.mtl"), text, &mut w).unwrap();
        (m, w)
    }

    fn parse_err(text: &str) -> String {
        format!(
            "{:#}",
            parse(Path::new("m.mtl"), text, &mut Vec::new()).unwrap_err()
        )
    }

    #[test]
    fn phong_subset() {
        let (m, w) = parse_ok(
            "# c\nnewmtl a b\n  Kd 1 0 0\nKs 0.5\nNs 50\nd 0.5\nillum 2\nKa 1 1 1\nKe 0 0 0\n\
             map_Kd ..\\tex dir\\t 1.png\nnewmtl c\n",
        );
        assert!(w.is_empty(), "{w:?}");
        assert_eq!(m.len(), 2);
        assert_eq!(m[0].name, "a b");
        assert_eq!(m[0].kd, Some(Vec3::X));
        assert_eq!(m[0].ks, Some(Vec3::splat(0.5)));
        assert_eq!((m[0].ns, m[0].dissolve), (Some(50.0), Some(0.5)));
        assert_eq!(m[0].map_kd, Some(("..\\tex dir\\t 1.png".into(), 10)));
        assert_eq!(
            m[1],
            MtlMaterial {
                name: "c".into(),
                ..MtlMaterial::default()
            }
        );
    }

    #[test]
    fn short_colours_are_errors_with_the_line_and_empty_textures_warn() {
        for (text, line) in [
            ("newmtl a\nKd 0.5 0.5\n", 2),
            ("newmtl a\n\nKs\n", 3),
            ("newmtl a\nKa 1 2 3 4\n", 2),
            ("newmtl a\nKd 1 zz 1\n", 2),
            ("newmtl a\nKd nan 0 0\n", 2),
            ("newmtl a\nNs\n", 2),
            ("newmtl a\nd 1 2\n", 2),
        ] {
            let e = parse_err(text);
            assert!(e.starts_with(&format!("m.mtl:{line}: ")), "{text:?}: {e}");
        }
        // A texture naming no file is left out, as a missing one is.
        for (text, line) in [
            ("newmtl a\nmap_Kd -s 1 1 1\n", 2),
            ("newmtl a\n\nmap_Kd \"\"\n", 3),
        ] {
            let (m, w) = parse_ok(text);
            assert_eq!(m[0].map_kd, None);
            assert_eq!(
                w,
                [format!(
                    "m.mtl:{line}: map_Kd names no file: ignored (Kd is used)"
                )]
            );
        }
        // A comment may end a line of numbers.
        let (m, w) = parse_ok("newmtl a\nKd 0.5 0.25 1 #there's a comment\nNs 10 # shiny\n");
        assert_eq!(
            (m[0].kd, m[0].ns),
            (Some(Vec3::new(0.5, 0.25, 1.0)), Some(10.0))
        );
        assert!(w.is_empty(), "{w:?}");
        // One number is grey, as the MTL specification says.
        assert_eq!(
            parse_ok("newmtl a\nKd 0.5\n").0[0].kd,
            Some(Vec3::splat(0.5))
        );
    }

    #[test]
    fn texture_options_take_their_values_and_escaped_spaces_are_spaces() {
        let args = |ignored: &[&str], clamp, file: &str| TextureArgs {
            ignored: ignored.iter().map(|s| s.to_string()).collect(),
            clamp,
            bm: ignored
                .iter()
                .find_map(|o| o.strip_prefix("-bm ")?.parse().ok()),
            file: file.into(),
        };
        for (written, want) in [
            ("my\\ texture.png", args(&[], None, "my texture.png")),
            ("a\\  b.png ", args(&[], None, "a  b.png")),
            (
                "-s 1 1 1 -o 0 0 0 -bm 0.5 tex.png",
                args(&["-s 1 1 1", "-o 0 0 0", "-bm 0.5"], None, "tex.png"),
            ),
            (
                "-blendu off -blendv on -cc off -colorspace sRGB -type sphere -imfchan r \
                 -mm 0 1 -texres 512 -boost 2 -t 1 2 my\\ t.png",
                args(
                    &[
                        "-blendu off",
                        "-blendv on",
                        "-cc off",
                        "-colorspace sRGB",
                        "-type sphere",
                        "-imfchan r",
                        "-mm 0 1",
                        "-texres 512",
                        "-boost 2",
                        "-t 1 2",
                    ],
                    None,
                    "my t.png",
                ),
            ),
            ("-clamp on t.png", args(&[], Some(true), "t.png")),
            (
                "-clamp on -clamp off t.png",
                args(&[], Some(false), "t.png"),
            ),
            // Values end where a word is not one.
            ("-s 2 t.png", args(&["-s 2"], None, "t.png")),
            ("-clamp t.png", args(&["-clamp"], None, "t.png")),
            ("-foo t.png", args(&["-foo"], None, "t.png")),
            ("-o 1 -clamp on", args(&["-o 1"], Some(true), "")),
            ("", args(&[], None, "")),
        ] {
            assert_eq!(texture_args(written), want, "{written}");
        }
        let (m, w) =
            parse_ok("newmtl a\nmap_Kd -clamp on -bm 2 my\\ t.png\nnewmtl b\nmap_Kd b.png\n");
        assert_eq!(m[0].map_kd, Some(("my t.png".into(), 2)));
        assert!(m[0].clamp && !m[1].clamp);
        assert_eq!(
            w,
            ["m.mtl:2: map_Kd options ignored: -bm 2 (the texture is applied as is)"]
        );
    }

    #[test]
    fn the_pbr_extension_is_read_where_a_material_has_it() {
        let (m, w) = parse_ok(
            "newmtl a\nPr 1.5\nPm 0.5\nKe 1 0 0\nnorm -bm 0.25 -s 2 n.png\nmap_Pr r.png\n\
             newmtl b\nKe 0 1 0\nnorm n.png\n",
        );
        assert!(m[0].pbr() && !m[1].pbr());
        assert_eq!((m[0].pr, m[0].pm), (Some(1.0), Some(0.5)));
        assert_eq!(m[0].ke, Some((Vec3::X, 4)));
        let n = m[0].normal.as_ref().unwrap();
        assert_eq!(
            (n.file.as_str(), n.scale, n.statement),
            ("n.png", 0.25, "norm")
        );
        assert_eq!(m[0].map_pr, Some(("r.png".into(), 6)));
        let all = w.join("\n");
        for part in [
            "m.mtl:2: Pr 1.5 is outside 0..1: clamped",
            "m.mtl:5: norm options ignored: -s 2 (the texture is applied as is)",
            "Ke (emission) (line 8), norm (line 9)",
        ] {
            assert!(all.contains(part), "missing '{part}' in {all}");
        }
        // The physically based material's Ke is read, not ignored.
        assert!(!all.contains("line 4"), "{all}");
    }

    #[test]
    fn doubtful_values_and_unsupported_options_warn() {
        let (m, w) = parse_ok(
            "newmtl a\nKd -0.5 0 0\nNs -3\nd 1.5\nmap_Kd -s 2 2 1 -o 0.5 t.png\nKe 1 1 1\n\
             map_Bump b.png\nTr 0.2\nfoo 1\nfoo 2\nKd spectral x.rfl\n",
        );
        assert_eq!(m[0].ns, Some(0.0));
        assert_eq!(m[0].dissolve, Some(1.0));
        assert_eq!(m[0].map_kd, Some(("t.png".into(), 5)));
        let all = w.join("\n");
        for part in [
            "m.mtl:2: negative colour Kd -0.5 0 0",
            "m.mtl:3: negative Ns",
            "m.mtl:4: d 1.5 is outside 0..1",
            "m.mtl:5: map_Kd options ignored: -s 2 2 1, -o 0.5",
            "Ke (emission) (line 6)",
            "map_Bump (line 7)",
            "Tr (opacity is read from d) (line 8)",
            "foo (line 9 and 1 more)",
            "Kd spectral (line 11)",
        ] {
            assert!(all.contains(part), "missing '{part}' in {all}");
        }
        // A material without a name is read as one named "".
        let (m, w) = parse_ok("newmtl a\nnewmtl\t\nKd 1 0 0\n");
        assert_eq!((m[1].name.as_str(), m[1].kd), ("", Some(Vec3::X)));
        assert_eq!(
            w,
            ["m.mtl:2: newmtl without a name: the material of a usemtl without one"]
        );
        let (_, w) = parse_ok("Kd 1 1 1\nnewmtl a\n");
        assert!(
            w[0].starts_with("m.mtl:1: statements before the first newmtl"),
            "{w:?}"
        );
    }
}
