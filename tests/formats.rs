//! Mesh formats beside OBJ: one mesh written as OBJ, ASCII and binary PLY
//! (both byte orders) and STL (ASCII and binary) loads to the same
//! geometry and renders the same image, bit for bit; PLY vertex colours
//! shade; every format opens bare, from the command line and as a
//! `[[mesh]]`; malformed files say which file and where.

mod common;
mod files;

use files::{rayterm, within_deadline, Dir};
use glam::Vec3;
use rayterm::render::{Feature, Features};
use rayterm::scene::{self, Builder, Scene};

/// Positions, vertex normals and triangles of a mesh.
type Mesh = (Vec<[f32; 3]>, Vec<[f32; 3]>, Vec<[u32; 3]>);

/// A lumpy sphere with distinct f32 vertices in the order faces first use
/// them, its vertex normals, and its triangles.
fn lumpy_sphere() -> Mesh {
    let (rings, segments) = (9u32, 14u32);
    let mut p: Vec<[f32; 3]> = vec![[0.0, 1.0, 0.0]];
    for r in 1..rings {
        let th = std::f32::consts::PI * r as f32 / rings as f32;
        for s in 0..segments {
            let ph = std::f32::consts::TAU * s as f32 / segments as f32;
            let k = 1.0 + 0.15 * (3.0 * ph).sin() * th.sin();
            p.push([
                k * th.sin() * ph.cos(),
                k * th.cos(),
                k * th.sin() * ph.sin(),
            ]);
        }
    }
    p.push([0.0, -1.0, 0.0]);
    let last = p.len() as u32 - 1;
    let at = |r: u32, s: u32| 1 + (r - 1) * segments + s % segments;
    let mut t = Vec::new();
    for s in 0..segments {
        t.push([0, at(1, s + 1), at(1, s)]);
    }
    for r in 1..rings - 1 {
        for s in 0..segments {
            t.push([at(r, s), at(r, s + 1), at(r + 1, s + 1)]);
            t.push([at(r, s), at(r + 1, s + 1), at(r + 1, s)]);
        }
    }
    for s in 0..segments {
        t.push([at(rings - 1, s), at(rings - 1, s + 1), last]);
    }
    // Renumber in order of first use, as every loader orders vertices.
    let mut new = vec![u32::MAX; p.len()];
    let mut order = Vec::new();
    for &i in t.iter().flatten() {
        if new[i as usize] == u32::MAX {
            new[i as usize] = order.len() as u32;
            order.push(i);
        }
    }
    let t = t.iter().map(|tri| tri.map(|i| new[i as usize])).collect();
    let p: Vec<[f32; 3]> = order.iter().map(|&i| p[i as usize]).collect();
    let n = p
        .iter()
        .map(|v| Vec3::from_array(*v).normalize().to_array())
        .collect();
    (p, n, t)
}

/// An f32 as text that reads back exactly (through f64, as loaders read).
fn num(x: f32) -> String {
    format!("{}", x as f64)
}

fn obj(p: &[[f32; 3]], n: Option<&[[f32; 3]]>, t: &[[u32; 3]]) -> String {
    let mut s = String::new();
    for v in p {
        s += &format!("v {} {} {}\n", num(v[0]), num(v[1]), num(v[2]));
    }
    for v in n.unwrap_or(&[]) {
        s += &format!("vn {} {} {}\n", num(v[0]), num(v[1]), num(v[2]));
    }
    for f in t {
        let [a, b, c] = f.map(|i| match n {
            Some(_) => format!("{0}//{0}", i + 1),
            None => format!("{}", i + 1),
        });
        s += &format!("f {a} {b} {c}\n");
    }
    s
}

/// A PLY file: `format` is `ascii`, `binary_little_endian` or
/// `binary_big_endian`; polygons as `uchar`-counted `int` lists.
fn ply(format: &str, p: &[[f32; 3]], n: Option<&[[f32; 3]]>, t: &[[u32; 3]]) -> Vec<u8> {
    let normals = if n.is_some() {
        "property float nx\nproperty float ny\nproperty float nz\n"
    } else {
        ""
    };
    let mut b = format!(
        "ply\nformat {format} 1.0\ncomment written by the test\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n{normals}element face {}\n\
         property list uchar int vertex_indices\nend_header\n",
        p.len(),
        t.len()
    )
    .into_bytes();
    let big = format == "binary_big_endian";
    let f = |b: &mut Vec<u8>, x: f32| {
        b.extend(if big {
            x.to_be_bytes()
        } else {
            x.to_le_bytes()
        })
    };
    for (i, v) in p.iter().enumerate() {
        let mut all = v.to_vec();
        if let Some(n) = n {
            all.extend(n[i]);
        }
        if format == "ascii" {
            let words: Vec<String> = all.iter().map(|&x| num(x)).collect();
            b.extend(format!("{}\n", words.join(" ")).bytes());
        } else {
            for x in all {
                f(&mut b, x);
            }
        }
    }
    for tri in t {
        if format == "ascii" {
            b.extend(format!("3 {} {} {}\n", tri[0], tri[1], tri[2]).bytes());
        } else {
            b.push(3);
            for &i in tri {
                b.extend(if big {
                    (i as i32).to_be_bytes()
                } else {
                    (i as i32).to_le_bytes()
                });
            }
        }
    }
    b
}

fn stl_binary(p: &[[f32; 3]], t: &[[u32; 3]]) -> Vec<u8> {
    let mut b = b"solid written by the test, binary all the same".to_vec();
    b.resize(80, 0);
    b.extend((t.len() as u32).to_le_bytes());
    for tri in t {
        b.extend([0u8; 12]);
        for &i in tri {
            for x in p[i as usize] {
                b.extend(x.to_le_bytes());
            }
        }
        b.extend([0u8; 2]);
    }
    b
}

fn stl_ascii(p: &[[f32; 3]], t: &[[u32; 3]]) -> String {
    let mut s = String::from("solid lumpy\n");
    for tri in t {
        s += "  facet normal 0 0 0\n    outer loop\n";
        for &i in tri {
            let v = p[i as usize];
            s += &format!("      vertex {} {} {}\n", num(v[0]), num(v[1]), num(v[2]));
        }
        s += "    endloop\n  endfacet\n";
    }
    s + "endsolid lumpy\n"
}

fn load(spec: &str) -> Result<Scene, String> {
    let s = spec.to_string();
    within_deadline(spec, move || scene::load(&s).map_err(|e| format!("{e:#}")))
}

/// Deterministic: one pass is exact.
fn exact() -> Features {
    Features::all().without(&[Feature::Supersampling, Feature::Bloom])
}

fn image(s: &Scene) -> Vec<Vec3> {
    common::render(s, 48, 40, 1, exact(), Builder::Sah, 1).image
}

#[test]
fn one_mesh_in_every_format_renders_the_same_image() {
    let d = Dir::new("formats-same");
    let (p, n, t) = lumpy_sphere();
    let flat = [
        d.write("m.obj", obj(&p, None, &t)),
        d.write("m.ply", ply("ascii", &p, None, &t)),
        d.write("le.ply", ply("binary_little_endian", &p, None, &t)),
        d.write("be.PLY", ply("binary_big_endian", &p, None, &t)),
        d.write("b.stl", stl_binary(&p, &t)),
        d.write("a.stl", stl_ascii(&p, &t)),
    ];
    let smooth = [
        d.write("n.obj", obj(&p, Some(&n), &t)),
        d.write("n.ply", ply("ascii", &p, Some(&n), &t)),
        d.write("nle.ply", ply("binary_little_endian", &p, Some(&n), &t)),
        d.write("nbe.ply", ply("binary_big_endian", &p, Some(&n), &t)),
    ];
    for files in [&flat[..], &smooth[..]] {
        let reference = load(&files[0]).unwrap();
        assert!(reference.warnings.is_empty(), "{:?}", reference.warnings);
        assert_eq!(reference.geometry.positions.len(), p.len());
        let want = image(&reference);
        assert!(want.iter().any(|c| c.max_element() > 0.1), "a black image");
        for f in &files[1..] {
            let s = load(f).unwrap();
            assert!(s.warnings.is_empty(), "{f}: {:?}", s.warnings);
            let (g, r) = (&s.geometry, &reference.geometry);
            assert_eq!(g.positions, r.positions, "{f}");
            assert_eq!(g.indices, r.indices, "{f}");
            assert_eq!(g.normals, r.normals, "{f}");
            assert_eq!(s.camera, reference.camera, "{f}");
            assert_eq!(s.lights, reference.lights, "{f}");
            assert!(image(&s) == want, "{f}: another image");
        }
    }
    // Smooth normals make a difference the comparison above would see.
    assert!(image(&load(&flat[1]).unwrap()) != image(&load(&smooth[1]).unwrap()));
}

#[test]
fn ply_vertex_colours_are_the_diffuse_colour() {
    let d = Dir::new("formats-colours");
    let quad = |rgb: &str| {
        format!(
            "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
             property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n\
             element face 1\nproperty list uchar int vertex_indices\nend_header\n\
             -1 -1 0 {rgb}\n1 -1 0 {rgb}\n1 1 0 {rgb}\n-1 1 0 {rgb}\n4 0 1 2 3\n"
        )
    };
    let red = load(&d.write("red.ply", quad("255 0 0"))).unwrap();
    let white = load(&d.write("white.ply", quad("255 255 255"))).unwrap();
    assert!(red.meshes[0].colored);
    let (r, w) = (image(&red), image(&white));
    // The middle pixel: red keeps white's red channel and loses the others.
    let mid = 20 * 48 + 24;
    assert!(w[mid].min_element() > 0.05, "{:?}", w[mid]);
    assert_eq!(r[mid].x, w[mid].x);
    assert_eq!((r[mid].y, r[mid].z), (0.0, 0.0));
}

#[test]
fn every_format_opens_from_the_command_line_and_in_scene_files() {
    let d = Dir::new("formats-cli");
    let (p, _, t) = lumpy_sphere();
    d.write("m.ply", ply("binary_little_endian", &p, None, &t));
    d.write("m.stl", stl_binary(&p, &t));
    d.write("m.obj", obj(&p, None, &t));
    for file in ["m.ply", "m.stl"] {
        let r = rayterm(
            &d.0,
            &[
                "render", file, "--size", "16x12", "--spp", "1", "-o", "out.png",
            ],
        );
        assert!(
            r.ok() && !r.stderr.contains("warning"),
            "{file}: {}",
            r.stderr
        );
        let r = rayterm(
            &d.0,
            &["inspect", file, "--pixel", "8,6", "--size", "16x12"],
        );
        assert!(
            r.ok() && r.stdout.contains("mesh m "),
            "{file}: {}{}",
            r.stdout,
            r.stderr
        );
        let r = rayterm(
            &d.0,
            &["bench", "rays", file, "--size", "8x8", "--reps", "1"],
        );
        assert!(
            r.ok() && r.stdout.contains("primary_rays"),
            "{file}: {}",
            r.stderr
        );
    }
    // As meshes of a scene file, placed like an OBJ.
    let scene = |mesh: &str| {
        format!(
            "[[mesh]]\nfile = \"{mesh}\"\ntranslate = [1, 0, 0]\n[[mesh]]\nfile = \"m.obj\"\n\
             translate = [-1.5, 0, 0]\n[[light]]\ntype = \"point\"\nposition = [0, 3, 3]\n\
             color = [1, 1, 1]\n"
        )
    };
    let reference = load(&d.write("obj.toml", scene("m.obj"))).unwrap();
    for mesh in ["m.ply", "m.stl"] {
        let s = load(&d.write("s.toml", scene(mesh))).unwrap();
        assert!(s.warnings.is_empty(), "{mesh}: {:?}", s.warnings);
        assert_eq!(s.geometry.positions, reference.geometry.positions, "{mesh}");
        assert!(image(&s) == image(&reference), "{mesh}");
    }
}

#[test]
fn malformed_files_say_which_file_and_where() {
    let d = Dir::new("formats-bad");
    let (p, _, t) = lumpy_sphere();
    let mut cut = stl_binary(&p, &t);
    cut.truncate(cut.len() - 10);
    let stl = d.write("cut.stl", &cut);
    let mut bad_index = ply("binary_little_endian", &p, None, &t);
    let n = bad_index.len();
    bad_index[n - 4..].copy_from_slice(&(p.len() as i32).to_le_bytes());
    let ply_index = d.write("index.ply", &bad_index);
    let mut short = ply("binary_big_endian", &p, None, &t);
    short.truncate(short.len() / 2);
    let ply_short = d.write("short.ply", &short);
    let ascii = String::from_utf8(ply("ascii", &p, None, &t)).unwrap();
    let ply_count = d.write(
        "count.ply",
        ascii.replacen(
            &format!("element face {}", t.len()),
            "element face 999999",
            1,
        ),
    );
    let ply_extra = d.write("extra.ply", ascii.replacen("\n3 ", "\n3 0 ", 1));
    let stl_text = d.write(
        "text.stl",
        stl_ascii(&p, &t).replacen("endloop", "vertex 1 2", 1),
    );
    let faces = t.len();
    for (file, want) in [
        (
            stl.clone(),
            format!("{stl}: truncated binary STL: the header counts {faces} triangles"),
        ),
        (
            ply_index.clone(),
            format!(
                "{ply_index} (byte {n}): element face {} (of {faces}), vertex_indices: vertex \
                 index {} is out of range ({} vertices)",
                faces - 1,
                p.len(),
                p.len()
            ),
        ),
        (
            ply_short.clone(),
            "vertex_indices: the file ends here (truncated)".into(),
        ),
        (
            ply_count.clone(),
            format!("{ply_count}: truncated: the header declares"),
        ),
        (
            ply_extra.clone(),
            format!("{ply_extra}:{}: element face 0", 11 + p.len()),
        ),
        (
            stl_text.clone(),
            format!("{stl_text}:7: a vertex takes 3 coordinates"),
        ),
    ] {
        let e = load(&file).err().unwrap_or_else(|| panic!("{file} loaded"));
        assert!(
            e.contains(&want) && e.contains(&file),
            "{e}\nwanted: {want}"
        );
    }
    // Through the binary: the message and a failure, nothing else.
    let r = rayterm(&d.0, &["render", "cut.stl", "-o", "x.png"]);
    assert!(
        !r.ok() && r.stderr.contains("cut.stl: truncated binary STL"),
        "{}",
        r.stderr
    );
    assert!(!d.path("x.png").exists());
}
