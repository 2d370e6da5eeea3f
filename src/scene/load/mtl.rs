//! Wavefront MTL material libraries: the Phong subset rayterm renders.
//!
//! `Kd`, `Ks` (one number for grey or three for RGB), `Ns`, `d` and
//! `map_Kd` (with `-clamp`) are used; `Ka`, `Tf`, `Ni`, `illum` and
//! `sharpness` are checked and ignored (the ambient term is the scene's,
//! there is no refraction); a non-black `Ke`, `Tr`, the other texture
//! maps, other texture options (skipped with the values each takes) and
//! unknown statements are ignored with one warning per file. Malformed
//! statements are errors naming the file and line; negative colours and
//! out-of-range `Ns` or `d` are warnings.

use std::path::Path;

use anyhow::{anyhow, bail, Result};
use glam::Vec3;

use super::numbers::{self, Absurd};
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
        match (name.as_str(), values.first().map(String::as_str)) {
            ("-clamp", Some(v)) => args.clamp = Some(v == "on"),
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
                    ("Ke", Some(c)) if c != Vec3::ZERO => ignored.note("Ke (emission)", n),
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
