//! Input hygiene: NaN and infinite numbers in OBJ, MTL, TOML and `.bpt`
//! files are load errors that name the file and line, but in an OBJ
//! vertex, whose faces are left out with a warning that names its line
//! (as other readers leave them); absurd magnitudes (1e30) load with a
//! warning that names them. Each probe is a small file
//! set loaded through the ordinary loaders.

use std::path::Path;

use anyhow::Result;

use super::Row;
use crate::scene::load::obj::{self, Parts, Placement};
use crate::scene::load::source::Memory;
use crate::scene::load::{self, Opening};

/// What a probe must produce: an error or a warning containing the text.
#[derive(Clone, Copy, Debug)]
pub enum Expect {
    Error(&'static str),
    Warning(&'static str),
}

const TRI: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\n";

fn toml(extra: &str, mesh: &str) -> String {
    format!(
        "[[mesh]]\nfile = \"{mesh}\"\n{extra}\n[[light]]\ntype = \"point\"\nposition = [0, 2, 0]\ncolor = [1, 1, 1]\n"
    )
}

/// The probes: a name, the files, the file to load and what must happen.
pub fn probes() -> Vec<(&'static str, Memory, &'static str, Expect)> {
    let obj = |text: String| Memory::default().with("m.obj", text);
    let with_mtl = |mtl: &str| {
        Memory::default()
            .with("m.obj", format!("mtllib m.mtl\nusemtl a\n{TRI}f 1 2 3\n"))
            .with("m.mtl", mtl)
    };
    let scene = |extra: &str| {
        Memory::default()
            .with("s.toml", toml(extra, "m.obj"))
            .with("m.obj", format!("{TRI}f 1 2 3\n"))
    };
    let patch = |bad: &str| {
        let mut bpt = String::from("1\n3 3\n");
        for k in 0..16 {
            bpt.push_str(if k == 5 { bad } else { "0 0 0" });
            bpt.push('\n');
        }
        Memory::default()
            .with("s.toml", toml("", "p.bpt"))
            .with("p.bpt", bpt)
    };
    use Expect::*;
    let nan_light = Memory::default()
        .with(
            "s.toml",
            "[[mesh]]\nfile = \"m.obj\"\n[[light]]\ntype = \"point\"\n\
             position = [0, nan, 0]\ncolor = [1, 1, 1]\n",
        )
        .with("m.obj", format!("{TRI}f 1 2 3\n"));
    vec![
        (
            "OBJ NaN vertex",
            obj("v 0 0 0\nv nan 0 0\nv 0 1 0\nf 1 2 3\n".into()),
            "m.obj",
            Warning("m.obj:2: vertex 'nan' is not a finite number: 1 face using it skipped"),
        ),
        (
            "OBJ infinite normal",
            obj(format!("{TRI}vn 0 0 1\nvn 0 -inf 1\nf 1//1 2//2 3//1\n")),
            "m.obj",
            Error("m.obj:5"),
        ),
        (
            "OBJ NaN UV",
            obj(format!("{TRI}vt 0 0\nvt NaN 1\nf 1/1 2/2 3/1\n")),
            "m.obj",
            Error("m.obj:5"),
        ),
        (
            "OBJ coordinate beyond f32",
            obj(format!("{TRI}v 1e39 0 0\nf 1 2 4\n")),
            "m.obj",
            Warning("m.obj:4: vertex '1e39' is too large"),
        ),
        (
            "OBJ absurd 1e30",
            obj("v 0 0 0\nv 1e30 0 0\nv 0 1 0\nf 1 2 3\n".into()),
            "m.obj",
            Warning("m.obj:2"),
        ),
        (
            "MTL NaN Kd",
            with_mtl("newmtl a\nKd nan 0 0\n"),
            "m.obj",
            Error("m.mtl:2"),
        ),
        (
            "MTL infinite Ns",
            with_mtl("newmtl a\nKd 1 1 1\nNs inf\n"),
            "m.obj",
            Error("m.mtl:3"),
        ),
        (
            "MTL absurd Ks",
            with_mtl("newmtl a\nKs 1e30 0 0\n"),
            "m.obj",
            Warning("m.mtl:2"),
        ),
        ("TOML NaN light", nan_light, "s.toml", Error("s.toml:5:")),
        (
            "TOML number beyond f32",
            scene("translate = [1e39, 0, 0]"),
            "s.toml",
            Error("s.toml:3:"),
        ),
        (
            "TOML infinite scale",
            scene("scale = inf"),
            "s.toml",
            Error("s.toml:3:"),
        ),
        (
            "TOML absurd scale",
            scene("scale = 1e30"),
            "s.toml",
            Warning("s.toml:1:1: mesh"),
        ),
        (
            "BPT NaN control point",
            patch("0 nan 0"),
            "s.toml",
            Error("p.bpt:8"),
        ),
        (
            "BPT infinite control point",
            patch("-inf 0 0"),
            "s.toml",
            Error("p.bpt:8"),
        ),
    ]
}

/// Loads the probe's file; the error or warnings as one string each.
fn outcome(src: &Memory, entry: &str) -> (Option<String>, Vec<String>) {
    let path = Path::new(entry);
    if entry.ends_with(".toml") {
        let how = Opening {
            source: Some(src),
            ..Default::default()
        };
        match load::open(entry, &how) {
            Ok(o) => (None, o.scene.warnings),
            Err(e) => (Some(format!("{e:#}")), Vec::new()),
        }
    } else {
        let mut parts = Parts::default();
        match obj::load_into(&mut parts, src, path, &Placement::default(), None) {
            Ok(()) => (None, parts.warnings),
            Err(e) => (Some(format!("{e:#}")), Vec::new()),
        }
    }
}

/// Whether the probe behaves as expected; the failure in words otherwise.
pub fn check(src: &Memory, entry: &str, expect: Expect) -> Result<(), String> {
    let (err, warnings) = outcome(src, entry);
    match (expect, err) {
        (Expect::Error(want), Some(e)) if e.contains(want) => Ok(()),
        (Expect::Error(want), Some(e)) => Err(format!("error without '{want}': {e}")),
        (Expect::Error(_), None) => Err("loaded without an error".into()),
        (Expect::Warning(want), None) if warnings.iter().any(|w| w.contains(want)) => Ok(()),
        (Expect::Warning(want), None) => Err(format!("no warning with '{want}': {warnings:?}")),
        (Expect::Warning(_), Some(e)) => Err(format!("rejected: {e}")),
    }
}

/// The input hygiene row: probes that did not behave.
pub fn hygiene() -> Result<Vec<Row>> {
    let probes = probes();
    let failed: Vec<String> = probes
        .iter()
        .filter_map(|(name, src, entry, expect)| {
            check(src, entry, *expect)
                .err()
                .map(|e| format!("{name}: {e}"))
        })
        .collect();
    let detail = if failed.is_empty() {
        format!(
            "{} probes: NaN/inf in OBJ, MTL, TOML and .bpt rejected with file and line (an OBJ vertex's faces left out, warned), 1e30 warned",
            probes.len()
        )
    } else {
        failed.join("; ")
    };
    Ok(vec![Row::zero(
        "input: non-finite and absurd numbers",
        failed.len() as u64,
        detail,
    )])
}
