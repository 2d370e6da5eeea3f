//! Mesh formats beside OBJ: one mesh written as OBJ, ASCII and binary PLY
//! (both byte orders) and STL (ASCII and binary) loads to the same
//! geometry and renders the same image, bit for bit; PLY vertex colours
//! shade; every format opens bare, from the command line and as a
//! `[[mesh]]`; malformed files say which file and where.

use crate::common;

use crate::files::{rayterm, within_deadline, Dir};
use glam::Vec3;
use rayterm::render::{Feature, Features};
use rayterm::scene::{self, Builder, Projection, Scene};

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
    within_deadline(spec, move || {
        scene::load::open(&s, &Default::default())
            .map(|o| o.scene)
            .map_err(|e| format!("{e:#}"))
    })
}

/// As [`load`], with the file's up axis given.
fn load_up(spec: &str, up: &str) -> Result<Scene, String> {
    let how = scene::load::Opening {
        up: Some(up.parse().unwrap()),
        ..Default::default()
    };
    scene::load::open(spec, &how)
        .map(|o| o.scene)
        .map_err(|e| format!("{e:#}"))
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
        assert_eq!(reference.geometry.positions().len(), p.len());
        let want = image(&reference);
        assert!(want.iter().any(|c| c.max_element() > 0.1), "a black image");
        for f in &files[1..] {
            // STL files are Z-up unless told.
            let s = load_up(f, "y").unwrap();
            assert!(s.warnings.is_empty(), "{f}: {:?}", s.warnings);
            let (g, r) = (&s.geometry, &reference.geometry);
            assert_eq!(g.positions(), r.positions(), "{f}");
            assert_eq!(g.indices(), r.indices(), "{f}");
            assert_eq!(g.normals(), r.normals(), "{f}");
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
            "[[mesh]]\nfile = \"{mesh}\"\nup = \"y\"\ntranslate = [1, 0, 0]\n[[mesh]]\nfile = \"m.obj\"\n\
             translate = [-1.5, 0, 0]\n[[light]]\ntype = \"point\"\nposition = [0, 3, 3]\n\
             color = [1, 1, 1]\n"
        )
    };
    let reference = load(&d.write("obj.toml", scene("m.obj"))).unwrap();
    for mesh in ["m.ply", "m.stl"] {
        let s = load(&d.write("s.toml", scene(mesh))).unwrap();
        assert!(s.warnings.is_empty(), "{mesh}: {:?}", s.warnings);
        assert_eq!(
            s.geometry.positions(),
            reference.geometry.positions(),
            "{mesh}"
        );
        assert!(image(&s) == image(&reference), "{mesh}");
    }
}

/// The extent of a scene's geometry along y over that along z.
fn tall(s: &Scene) -> f32 {
    let (lo, hi) = s.geometry.positions().iter().fold(
        (Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)),
        |(lo, hi), &p| (lo.min(p), hi.max(p)),
    );
    (hi.y - lo.y) / (hi.z - lo.z)
}

#[test]
fn stl_files_are_z_up_and_any_mesh_takes_its_up_axis() {
    let d = Dir::new("formats-up");
    // A spike along +z, four times as long as it is wide.
    let p = [
        [-0.5, -0.5, 0.0],
        [0.5, -0.5, 0.0],
        [0.0, 0.5, 0.0],
        [0.0, 0.0, 4.0],
    ];
    let t = [[0, 2, 1], [0, 1, 3], [1, 2, 3], [2, 0, 3]];
    let stl = d.write("spike.stl", stl_binary(&p, &t));
    let objf = d.write("spike.obj", obj(&p, None, &t));
    // Bare: the STL stands up, the OBJ lies as written until told.
    let (s, o) = (load(&stl).unwrap(), load(&objf).unwrap());
    assert!(
        tall(&s) > 3.0 && tall(&o) < 0.3,
        "{} {}",
        tall(&s),
        tall(&o)
    );
    let oz = load_up(&objf, "z").unwrap();
    assert_eq!(oz.geometry.positions(), s.geometry.positions());
    assert_eq!(oz.camera, s.camera);
    assert_eq!(
        load_up(&stl, "y").unwrap().geometry.positions(),
        o.geometry.positions()
    );
    // -z turns it upside down: the tip below the base.
    let down = load_up(&stl, "-z").unwrap();
    let lowest = down
        .geometry
        .positions()
        .iter()
        .map(|p| p.y)
        .fold(f32::MAX, f32::min);
    assert!(
        down.geometry
            .positions()
            .iter()
            .filter(|p| p.y == lowest)
            .count()
            == 1
    );
    // The same in scene files, before the entry's own placement.
    let scene = |mesh: &str, up: &str| {
        format!(
            "[[mesh]]\nfile = \"{mesh}\"\n{up}translate = [0, 1, 0]\n[[light]]\n\
             type = \"point\"\nposition = [0, 9, 9]\ncolor = [1, 1, 1]\n"
        )
    };
    let a = load(&d.write("a.toml", scene("spike.stl", ""))).unwrap();
    let b = load(&d.write("b.toml", scene("spike.obj", "up = \"Z\"\n"))).unwrap();
    assert!(tall(&a) > 3.0);
    assert_eq!(a.geometry.positions(), b.geometry.positions());
    let e = load(&d.write("c.toml", scene("spike.obj", "up = \"sideways\"\n"))).unwrap_err();
    assert!(
        e.contains("c.toml:3") && e.contains("x, y, z, -x, -y or -z"),
        "{e}"
    );
    // On the command line: any mesh file, nothing else.
    let r = rayterm(
        &d.0,
        &[
            "render",
            "spike.obj",
            "--up",
            "-x",
            "--size",
            "8x8",
            "--spp",
            "1",
            "-o",
            "o.png",
        ],
    );
    assert!(r.ok(), "{}", r.stderr);
    for (args, says) in [
        (
            &["render", "spike.obj", "--up", "w", "-o", "w.png"][..],
            "x, y, z, -x, -y or -z",
        ),
        (
            &["render", "cornell", "--up", "z", "-o", "w.png"][..],
            "applies to mesh files",
        ),
        (
            &["render", "a.toml", "--up", "z", "-o", "w.png"][..],
            "its own `up`",
        ),
    ] {
        let r = rayterm(&d.0, args);
        assert!(!r.ok() && r.stderr.contains(says), "{args:?}: {}", r.stderr);
        assert!(!d.0.join("w.png").exists());
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
    // A value past the declared ones is ignored, as other readers ignore it.
    let w = load(&ply_extra).unwrap().warnings;
    assert!(
        w.iter().any(|w| w.contains(&format!(
            "{ply_extra}:{}: 1 value past those the header declares: ignored",
            11 + p.len()
        ))),
        "{w:?}"
    );
    // Through the binary: the message and a failure, nothing else.
    let r = rayterm(&d.0, &["render", "cut.stl", "-o", "x.png"]);
    assert!(
        !r.ok() && r.stderr.contains("cut.stl: truncated binary STL"),
        "{}",
        r.stderr
    );
    assert!(!d.path("x.png").exists());
}

/// A 4x4 PNG: the columns of u < 0.5 red, the others blue.
fn half_red_png() -> Vec<u8> {
    let img = image::RgbImage::from_fn(4, 4, |x, _| {
        if x < 2 {
            image::Rgb([255, 0, 0])
        } else {
            image::Rgb([0, 0, 255])
        }
    });
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    png
}

/// The binary buffer of the test's glTF: a unit quad in the XY plane
/// (positions, glTF UVs, u16 indices) and the PNG; the JSON that
/// describes it, its buffer given by `buffer`.
fn gltf_parts(buffer: serde_json::Value) -> (serde_json::Value, Vec<u8>) {
    let mut bin = Vec::new();
    for p in [
        [-0.5f32, -0.5, 0.0],
        [0.5, -0.5, 0.0],
        [0.5, 0.5, 0.0],
        [-0.5, 0.5, 0.0],
    ] {
        p.iter().for_each(|x| bin.extend(x.to_le_bytes()));
    }
    for uv in [[0.0f32, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]] {
        uv.iter().for_each(|x| bin.extend(x.to_le_bytes()));
    }
    for i in [0u16, 1, 2, 0, 2, 3] {
        bin.extend(i.to_le_bytes());
    }
    let png = half_red_png();
    bin.extend(&png);
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let mut buffer = buffer;
    buffer["byteLength"] = bin.len().into();
    let json = serde_json::json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_clearcoat"],
        "scene": 0,
        "scenes": [{"nodes": [0, 4, 6, 7]}],
        "nodes": [
            {"name": "Root", "scale": [2.0, 2.0, 2.0], "children": [1, 3]},
            // 90 degrees about z: u runs along world +y.
            {"name": "Arm", "translation": [-0.6, 0.0, 0.0],
             "rotation": [0.0, 0.0, std::f64::consts::FRAC_1_SQRT_2, std::f64::consts::FRAC_1_SQRT_2],
             "children": [2]},
            {"name": "Tile", "mesh": 0},
            {"name": "Mirror", "translation": [0.6, 0.0, 0.0], "mesh": 1},
            {"name": "Rig", "translation": [0.0, 0.0, 3.0], "children": [5]},
            {"name": "Eye", "translation": [0.0, 0.0, 3.0], "camera": 0},
            {"name": "Lamp", "translation": [0.0, 0.0, 6.0],
             "extensions": {"KHR_lights_punctual": {"light": 0}}},
            // A second camera, turned to look along -x.
            {"name": "Side", "translation": [4.0, 0.0, 0.0],
             "rotation": [0.0, std::f64::consts::FRAC_1_SQRT_2, 0.0, std::f64::consts::FRAC_1_SQRT_2],
             "camera": 1}
        ],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "color": [1.0, 1.0, 1.0], "intensity": 5.0}
        ]}},
        "cameras": [{"type": "perspective",
                     "perspective": {"yfov": 0.8, "znear": 0.1, "aspectRatio": 1.333}},
                    {"name": "SideCam", "type": "perspective",
                     "perspective": {"yfov": 0.5, "znear": 0.1}}],
        "meshes": [
            {"name": "TileMesh", "primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1},
                                                 "indices": 2, "material": 0}]},
            {"name": "MirrorMesh", "primitives": [{"attributes": {"POSITION": 0},
                                                   "indices": 2, "material": 1}]}
        ],
        "materials": [
            {"name": "Checker", "pbrMetallicRoughness": {
                "baseColorFactor": [0.5, 1.0, 1.0, 1.0], "metallicFactor": 0.0,
                "baseColorTexture": {"index": 0}},
             "normalTexture": {"index": 0}},
            {"name": "Chrome", "pbrMetallicRoughness": {
                "baseColorFactor": [0.2, 0.8, 0.2, 1.0], "metallicFactor": 1.0,
                "roughnessFactor": 0.0},
             "emissiveFactor": [1.0, 0.0, 0.0]}
        ],
        "textures": [{"source": 0, "sampler": 0}],
        "samplers": [{"wrapS": 33071, "wrapT": 33648}],
        "images": [{"bufferView": 3, "mimeType": "image/png"}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [-0.5, -0.5, 0.0], "max": [0.5, 0.5, 0.0]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 2, "componentType": 5123, "count": 6, "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 32},
            {"buffer": 0, "byteOffset": 80, "byteLength": 12},
            {"buffer": 0, "byteOffset": 92, "byteLength": png.len()}
        ],
        "buffers": [buffer]
    });
    (json, bin)
}

fn glb(json: &serde_json::Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(json).unwrap();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let total = 12 + 8 + j.len() + 8 + bin.len();
    let mut b = b"glTF".to_vec();
    b.extend(2u32.to_le_bytes());
    b.extend((total as u32).to_le_bytes());
    b.extend((j.len() as u32).to_le_bytes());
    b.extend(b"JSON");
    b.extend(&j);
    b.extend((bin.len() as u32).to_le_bytes());
    b.extend(b"BIN\0");
    b.extend(bin);
    b
}

/// The colour of the pixel whose centre sees `world`, and the cosine at
/// which the light (at the eye) meets the plane z = 0 there.
fn pixel_at(s: &Scene, img: &[Vec3], w: u32, h: u32, world: Vec3) -> (Vec3, f32) {
    let f = s.camera.frame(w, h);
    let (x, y) = f.project(world).unwrap();
    let (px, py) = (x.floor(), y.floor());
    let ray = f.ray(px + 0.5, py + 0.5);
    let t = -ray.origin.z / ray.dir.z;
    let hit = ray.origin + ray.dir * t;
    let cos = (s.camera.eye - hit).normalize().z;
    (img[py as usize * w as usize + px as usize], cos)
}

#[test]
fn a_gltf_scene_renders_with_its_hierarchy_materials_camera_and_light() {
    let d = Dir::new("formats-gltf");
    let (json, bin) = gltf_parts(serde_json::json!({}));
    let file = d.write("scene.glb", glb(&json, &bin));
    let s = load(&file).unwrap();
    // The node chain: Root scale 2, Arm turned 90 degrees and moved.
    let tile = s
        .meshes
        .iter()
        .position(|m| m.name == "TileMesh (node Tile)")
        .unwrap();
    let first = s
        .geometry
        .tri_mesh()
        .iter()
        .position(|&m| m as usize == tile)
        .unwrap();
    let corners: Vec<Vec3> = s.geometry.indices()[first]
        .iter()
        .map(|&i| s.geometry.positions()[i as usize])
        .collect();
    let near = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
    // (-0.5, -0.5) turned to (0.5, -0.5), moved to (-0.1, -0.5), doubled.
    assert!(near(corners[0], Vec3::new(-0.2, -1.0, 0.0)), "{corners:?}");
    assert!(near(corners[1], Vec3::new(-0.2, 1.0, 0.0)), "{corners:?}");
    assert!(near(corners[2], Vec3::new(-2.2, 1.0, 0.0)), "{corners:?}");
    // Camera (Rig then Eye) and light from the file, in candela.
    assert!(near(s.camera.eye, Vec3::new(0.0, 0.0, 6.0)));
    assert!(matches!(s.camera.projection,
        Projection::Perspective { vfov } if (vfov - 0.8f32.to_degrees()).abs() < 1e-4));
    assert_eq!(
        s.lights,
        [rayterm::scene::Light::Photometric {
            position: Vec3::new(0.0, 0.0, 6.0),
            intensity: Vec3::splat(5.0),
            range: None,
            cone: None,
        }]
    );
    // The metallic material, as the file has it.
    let chrome = s.materials.iter().find(|m| m.name == "Chrome").unwrap();
    let pbr = chrome.pbr.as_ref().unwrap();
    assert_eq!(chrome.kd, Vec3::new(0.2, 0.8, 0.2));
    assert_eq!((pbr.metallic, pbr.roughness), (1.0, 0.0));
    assert_eq!(pbr.emissive, Vec3::X);
    // What was not read, once.
    let w = s.warnings.join("\n");
    assert!(w.contains("KHR_materials_clearcoat"), "{w}");
    assert_eq!(s.warnings.len(), 1, "{w}");
    // Hand-checked pixels of the glTF BRDF (normal maps off: the file's
    // is its colour texture): base = texel * factor 0.5 (a dielectric,
    // roughness 1), the light at the eye, so v = l = h: Fresnel is 0.04,
    // the diffuse share 0.96 base/π, the specular 0.04 D V with D = 1/π
    // and V = 1/(4 cos); 5 cd at 6/cos give E = 5 cos²/36 lux. No
    // ambient light: the file has its own.
    let (w_, h_) = (64, 48);
    let features = exact().without(&[Feature::NormalMaps]);
    let img = common::render(&s, w_, h_, 1, features, Builder::Sah, 1).image;
    let pi = std::f32::consts::PI;
    let lit = |base: Vec3, cos: f32| {
        let e = 5.0 * cos * cos / 36.0;
        (0.96 * base / pi * cos + Vec3::splat(0.01 / pi)) * e
    };
    let (red, cos) = pixel_at(&s, &img, w_, h_, Vec3::new(-1.2, -0.5, 0.0));
    let want = lit(Vec3::new(0.5, 0.0, 0.0), cos);
    assert!(
        (red - want).abs().max_element() < 1e-5,
        "{red} against {want}"
    );
    let (blue, cos) = pixel_at(&s, &img, w_, h_, Vec3::new(-1.2, 0.5, 0.0));
    let want = lit(Vec3::new(0.0, 0.0, 1.0), cos);
    assert!(
        (blue - want).abs().max_element() < 1e-5,
        "{blue} against {want}"
    );
    // The mirror shows the black sky and glows red; the background is
    // black.
    let (chrome_px, _) = pixel_at(&s, &img, w_, h_, Vec3::new(1.7, 0.5, 0.0));
    assert!(
        (chrome_px - Vec3::X).abs().max_element() < 1e-3,
        "{chrome_px}"
    );
    assert_eq!(img[0], Vec3::ZERO);
    // The inspector names the glTF mesh, node and material.
    let f = s.camera.frame(w_, h_);
    let (x, y) = f.project(Vec3::new(-1.2, -0.5, 0.0)).unwrap();
    let pixel = format!("{},{}", x as u32, y as u32);
    let r = rayterm(
        &d.0,
        &["inspect", "scene.glb", "--pixel", &pixel, "--size", "64x48"],
    );
    assert!(
        r.ok()
            && r.stdout
                .contains("mesh TileMesh (node Tile) material Checker"),
        "{}{}",
        r.stdout,
        r.stderr
    );
    // The same file as .gltf with its buffer beside it loads the same.
    let (json, bin) = gltf_parts(serde_json::json!({"uri": "scene%20data.bin"}));
    d.write("scene data.bin", &bin);
    let t = load(&d.write("scene.gltf", serde_json::to_vec(&json).unwrap())).unwrap();
    assert_eq!(t.geometry.positions(), s.geometry.positions());
    assert!(common::render(&t, w_, h_, 1, features, Builder::Sah, 1).image == img);
    // As a mesh of a scene file: the meshes, with a note on the rest.
    let toml = d.write(
        "s.toml",
        "[[mesh]]\nfile = \"scene.glb\"\n[[light]]\ntype = \"point\"\nposition = [0, 0, 6]\n\
         color = [1, 1, 1]\n",
    );
    let in_scene = load(&toml).unwrap();
    assert_eq!(in_scene.geometry.positions(), s.geometry.positions());
    assert!(in_scene
        .warnings
        .iter()
        .any(|w| w.contains("its camera and lights are used")));
}

#[test]
fn a_gltf_camera_is_chosen_by_name_or_number() {
    let d = Dir::new("formats-gltf-camera");
    let (json, bin) = gltf_parts(serde_json::json!({}));
    let file = d.write("scene.glb", glb(&json, &bin));
    let through = |camera: &str| scene::load::Opening {
        camera: Some(camera.into()),
        ..Default::default()
    };
    let with = |camera: &str| scene::load::open(&file, &through(camera)).map(|o| o.scene.camera);
    let near = |a: Vec3, b: Vec3| (a - b).length() < 1e-5;
    for name in ["Side", "SideCam", "2"] {
        let c = with(name).unwrap();
        assert!(near(c.eye, Vec3::new(4.0, 0.0, 0.0)), "{name}: {c:?}");
        assert!((c.target - c.eye).normalize().x < -0.999, "{name}: {c:?}");
        assert!(matches!(c.projection,
            Projection::Perspective { vfov } if (vfov - 0.5f32.to_degrees()).abs() < 1e-4));
    }
    for name in ["Eye", "1"] {
        assert!(near(with(name).unwrap().eye, Vec3::new(0.0, 0.0, 6.0)));
    }
    for name in ["Nope", "0", "3"] {
        let e = format!("{:#}", with(name).unwrap_err());
        assert!(
            e.contains(&format!("--camera {name}"))
                && e.contains("scene.glb")
                && e.contains("Eye (1), Side / SideCam (2)"),
            "{e}"
        );
    }
    // Files without named cameras, and scene files, say so.
    let obj = d.write("m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let toml = d.write("s.toml", "[[mesh]]\nfile = \"m.obj\"\n");
    for spec in ["cornell", obj.as_str(), toml.as_str()] {
        let e = format!(
            "{:#}",
            scene::load::open(spec, &through("Side")).unwrap_err()
        );
        assert!(e.contains("--camera Side"), "{e}");
    }
    // From the command line, the chosen camera is the one rendered.
    let r = rayterm(
        &d.0,
        &[
            "render",
            "scene.glb",
            "--camera",
            "Side",
            "--size",
            "8x8",
            "-o",
            "side.png",
        ],
    );
    assert!(r.ok(), "{}", r.stderr);
    let r = rayterm(
        &d.0,
        &["render", "scene.glb", "--camera", "Top", "-o", "top.png"],
    );
    assert!(
        !r.ok() && r.stderr.contains("its cameras are"),
        "{}",
        r.stderr
    );
    assert!(!d.0.join("top.png").exists());
}

#[test]
fn malformed_gltf_files_say_what_is_wrong() {
    let d = Dir::new("formats-gltf-bad");
    let (json, bin) = gltf_parts(serde_json::json!({}));
    let mut bad_accessor = json.clone();
    bad_accessor["meshes"][0]["primitives"][0]["indices"] = 99.into();
    let mut bad_index = bin.clone();
    bad_index[80..82].copy_from_slice(&7u16.to_le_bytes());
    let mut cut = glb(&json, &bin);
    cut.truncate(cut.len() - 100);
    let (ext, ext_bin) = gltf_parts(serde_json::json!({"uri": "gone.bin"}));
    let mut short_bin = ext_bin.clone();
    short_bin.truncate(50);
    let mut cycle = json.clone();
    cycle["nodes"][2]["children"] = serde_json::json!([0]);
    // The crate's reader trusts accessors: wrong types, short strides and
    // views beyond the buffer must be caught before it reads them.
    let edit = |f: &dyn Fn(&mut serde_json::Value)| {
        let mut j = json.clone();
        f(&mut j);
        glb(&j, &bin)
    };
    let float_indices = edit(&|j| j["accessors"][2]["componentType"] = 5126.into());
    let vec2_positions = edit(&|j| j["accessors"][0]["type"] = "VEC2".into());
    let short_stride = edit(&|j| j["bufferViews"][0]["byteStride"] = 4.into());
    let beyond = edit(&|j| j["accessors"][0]["count"] = 4_000_000_000u64.into());
    let unaligned = edit(&|j| j["accessors"][0]["byteOffset"] = 1.into());
    // A node shared by two parents, doubling at every level, would be
    // placed 2^30 times.
    let shared = edit(&|j| {
        let nodes: Vec<_> = (0..31)
            .map(|i| serde_json::json!({"mesh": 0, "children": [i + 1, i + 1]}))
            .chain([serde_json::json!({"mesh": 0})])
            .collect();
        j["nodes"] = nodes.into();
        j["scenes"] = serde_json::json!([{"nodes": [0]}]);
    });
    let wide_fov = edit(&|j| j["cameras"][1]["perspective"]["yfov"] = 3.2.into());
    let bright = edit(&|j| {
        j["materials"][1]["pbrMetallicRoughness"]["baseColorFactor"] =
            serde_json::json!([2.0, 0.0, 0.0, 1.0])
    });
    let rough =
        edit(&|j| j["materials"][1]["pbrMetallicRoughness"]["roughnessFactor"] = (-1.0).into());
    let v1 = edit(&|j| j["asset"]["version"] = "1.0".into());
    let inf_light =
        edit(&|j| j["extensions"]["KHR_lights_punctual"]["lights"][0]["intensity"] = 1e39.into());
    let huge_scale = edit(&|j| j["nodes"][0]["scale"] = serde_json::json!([1e300, 1e300, 1e300]));
    // The crate's accessors unwrap what a camera's type names and an
    // image's source: checked first, an error where used.
    let ortho = serde_json::json!({"xmag": 1.0, "ymag": 1.0, "zfar": 10.0, "znear": 0.1});
    let typeless = edit(&|j| {
        j["cameras"][0] = serde_json::json!({"type": "perspective", "orthographic": ortho})
    });
    let flat = edit(&|j| j["cameras"][1]["type"] = "orthographic".into());
    let mimeless = edit(&|j| j["images"][0] = serde_json::json!({"bufferView": 3}));
    let sourceless = edit(&|j| j["images"][0] = serde_json::json!({"name": "Nowhere"}));
    let uri = |u: &str| {
        let (mut j, _) = gltf_parts(serde_json::json!({"uri": "x.bin"}));
        j["buffers"][0]["uri"] = u.into();
        serde_json::to_vec(&j).unwrap()
    };
    for (name, bytes, want) in [
        ("typeless.glb", typeless, "typeless.glb: node Eye: camera 0: its type is perspective and it has no perspective object"),
        ("flat.glb", flat, "flat.glb: node Side: camera SideCam: its type is orthographic and it has no orthographic object"),
        ("mimeless.glb", mimeless, "mimeless.glb: image 0 (of material Checker): it has a bufferView and no mimeType"),
        ("sourceless.glb", sourceless, "sourceless.glb: image Nowhere (of material Checker): it has neither a uri nor a bufferView"),
        ("wide.glb", wide_fov, "camera SideCam: yfov 3.2 radians is not between 1 and 179 degrees"),
        ("v1.glb", v1, "v1.glb: glTF version 1.0: only glTF 2.x is read"),
        ("inf.glb", inf_light, "inf.glb: light 0: intensity inf, color [1, 1, 1]: beyond 32-bit floats"),
        ("scale.glb", huge_scale, "scale.glb: node Root: scale [inf, inf, inf] is beyond 32-bit floats"),
        ("bright.glb", bright, "material Chrome: baseColorFactor 2 is outside 0 to 1"),
        ("rough.glb", rough, "material Chrome: roughnessFactor -1 is outside 0 to 1"),
        ("http.gltf", uri("http://example.com/x.bin"), "http.gltf: buffer 0: http: URIs are not read"),
        ("empty-uri.gltf", uri(""), "empty-uri.gltf: buffer 0: its uri is empty"),
        ("float-indices.glb", float_indices, "indices (accessor 2) is Scalar F32; glTF allows Scalar of U8, U16, U32"),
        ("vec2.glb", vec2_positions, "POSITION (accessor 0) is Vec2 F32"),
        ("stride.glb", short_stride, "byteStride 4 is smaller than one element (12 bytes)"),
        ("beyond.glb", beyond, "its 4000000000 elements end at byte 48000000000 of a 48-byte buffer view"),
        // Read all the same where not aligned, but never past its view.
        ("unaligned.glb", unaligned, "its 4 elements end at byte 49 of a 48-byte buffer view"),
        ("shared.glb", shared, "node 1 is the child of 2 nodes; glTF node hierarchies are trees"),
        ("accessor.glb", glb(&bad_accessor, &bin), "accessor.glb: not a valid glTF file"),
        (
            "index.glb",
            glb(&json, &bad_index),
            "index.glb: mesh TileMesh primitive 0 (node Tile): index 0 is 7, out of range (4 vertices)",
        ),
        ("cut.glb", cut, "cut.glb: not a valid glTF file"),
        ("missing.gltf", serde_json::to_vec(&ext).unwrap(), "missing.gltf: buffer 0"),
        ("cycle.glb", glb(&cycle, &bin), "a cycle in the node hierarchy"),
        ("junk.glb", b"glTF\x02\x00\x00\x00junk".to_vec(), "junk.glb: not a valid glTF file"),
        // glTF 1.0, as its writers left it: objects where 2.0 has arrays.
        (
            "old.gltf",
            br#"{"asset":{"version":"1.0"},"meshes":{"m":{"primitives":[]}},"scene":"s","scenes":{"s":{"nodes":[]}}}"#.to_vec(),
            "old.gltf: glTF 1.0 is not supported (rayterm reads glTF 2.0",
        ),
        (
            "old.glb",
            b"glTF\x01\x00\x00\x00\x20\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00\x00".to_vec(),
            "old.glb: glTF 1.0 is not supported",
        ),
        // As collada2gltf wrote it: the version a number, or none at all.
        (
            "number.gltf",
            br#"{"asset":{"version":1},"meshes":{"m":{"primitives":[]}}}"#.to_vec(),
            "number.gltf: glTF 1.0 is not supported",
        ),
        (
            "none.gltf",
            br#"{"asset":{},"nodes":{"n":{}},"accessors":{}}"#.to_vec(),
            "none.gltf: glTF 1.0 is not supported",
        ),
    ] {
        let e = load(&d.write(name, bytes)).err().unwrap_or_else(|| panic!("{name} loaded"));
        assert!(e.contains(want), "{name}: {e}\nwanted: {want}");
    }
    // An empty version is read as 2.0, as other readers read it.
    let mut unversioned = json.clone();
    unversioned["asset"]["version"] = "".into();
    let s = load(&d.write("unversioned.glb", glb(&unversioned, &bin))).unwrap();
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("unversioned.glb: its asset.version is empty: read as glTF 2.0")),
        "{:?}",
        s.warnings
    );
    let e = load(&d.path("missing.gltf").to_string_lossy()).unwrap_err();
    assert!(e.contains("gone.bin: not found"), "{e}");
    d.write("gone.bin", &short_bin);
    let e = load(&d.path("missing.gltf").to_string_lossy()).unwrap_err();
    assert!(e.contains("holds 50 bytes, the file declares"), "{e}");
    // Bytes past the declared length are no part of the buffer; values
    // that make no sense name the file they were read from.
    let mut long_bin = ext_bin.clone();
    long_bin.extend([0; 8]);
    d.write("gone.bin", &long_bin);
    let s = load(&d.path("missing.gltf").to_string_lossy()).unwrap();
    let want = format!(
        "buffer 0 holds {} bytes, the file declares {}: the first {} are read",
        long_bin.len(),
        ext_bin.len(),
        ext_bin.len()
    );
    assert!(
        s.warnings.iter().any(|w| w.contains(&want)),
        "{:?}",
        s.warnings
    );
    long_bin[80..82].copy_from_slice(&7u16.to_le_bytes());
    d.write("gone.bin", &long_bin);
    let e = load(&d.path("missing.gltf").to_string_lossy()).unwrap_err();
    assert!(
        e.contains("index 0 is 7, out of range (4 vertices); read from buffer 0, "),
        "{e}"
    );
    assert!(e.contains("gone.bin"), "{e}");
    // A later 2.x version reads; a negative light is said, not silently dark.
    let dim = edit(&|j| {
        j["asset"]["version"] = "2.1".into();
        j["extensionsUsed"] = serde_json::json!(["KHR_lights_punctual", "E\u{1b}[2J"]);
        j["extensions"]["KHR_lights_punctual"]["lights"][0]["intensity"] = (-5.0).into();
    });
    let s = load(&d.write("dim.glb", dim)).unwrap();
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("dim.glb: light 0: negative intensity -5")),
        "{:?}",
        s.warnings
    );
    let all = s.warnings.join("\n");
    assert!(all.contains("E\u{fffd}[2J (extensionsUsed)"), "{all}");
    // Cameras and images nothing uses are warned about, whatever is wrong
    // with them.
    let unused = edit(&|j| {
        let camera = serde_json::json!({"type": "perspective", "orthographic": ortho});
        j["cameras"].as_array_mut().unwrap().push(camera);
        let image = serde_json::json!({"bufferView": 3});
        j["images"].as_array_mut().unwrap().push(image);
    });
    let s = load(&d.write("unused.glb", unused)).unwrap();
    let said = |s: &rayterm::scene::Scene, want: &str| {
        assert!(
            s.warnings.iter().any(|w| w.contains(want)),
            "{want}: {:?}",
            s.warnings
        );
    };
    for want in [
        "unused.glb: camera 2: its type is perspective and it has no perspective object; not used",
        "unused.glb: image 1: it has a bufferView and no mimeType, which glTF requires; not used",
    ] {
        said(&s, want);
    }
    // What was silently made of the file is said: a texture without
    // coordinates, a projective matrix, a directional light scaled to
    // nothing (once named a light beyond f32's range).
    let quiet = edit(&|j| {
        j["meshes"][0]["primitives"][0]["attributes"] = serde_json::json!({"POSITION": 0});
        j["nodes"][4] = serde_json::json!({"name": "Rig", "children": [5],
            "matrix": [1, 0, 0, 0.5, 0, 1, 0, 0, 0, 0, 1, 0, 0, 0, 3, 1]});
        j["nodes"][6]["scale"] = serde_json::json!([0.0, 0.0, 0.0]);
        j["extensions"]["KHR_lights_punctual"]["lights"][0]["type"] = "directional".into();
    });
    let s = load(&d.write("quiet.glb", quiet)).unwrap();
    for want in [
        "textures (the base colour's among them) on primitives without TEXCOORD_0 (drawn in the material's colour) \
         (material Checker, mesh TileMesh)",
        "projective node matrices (their last row is not 0 0 0 1: read as their affine part) \
         (node Rig)",
        "directional lights scaled to nothing (their direction is zero) (node Lamp)",
    ] {
        said(&s, want);
    }
    assert!(!all.contains('\u{1b}'), "{all:?}");
    // A byte-order mark before the JSON changes nothing.
    let (j, b) = gltf_parts(serde_json::json!({"uri": "ok.bin"}));
    d.write("ok.bin", &b);
    let mut text = "\u{feff}".as_bytes().to_vec();
    text.extend(serde_json::to_vec(&j).unwrap());
    let s = load(&d.write("bom.gltf", text)).unwrap();
    let plain = load(&d.write("plain.glb", glb(&json, &bin))).unwrap();
    assert_eq!(s.geometry.positions(), plain.geometry.positions());
}

#[test]
fn obj_vertex_colours_shade_as_ply_vertex_colours_do() {
    let d = Dir::new("formats-obj-colours");
    let ply = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
               property float z\nproperty uchar red\nproperty uchar green\nproperty uchar blue\n\
               element face 1\nproperty list uchar int vertex_indices\nend_header\n\
               -1 -1 0 255 0 0\n1 -1 0 0 255 0\n1 1 0 0 0 255\n-1 1 0 255 255 255\n4 0 1 2 3\n";
    let obj = "v -1 -1 0 1 0 0\nv 1 -1 0 0 1 0\nv 1 1 0 0 0 1\nv -1 1 0 1 1 1\nf 1 2 3 4\n";
    let ply = load(&d.write("m.ply", ply)).unwrap();
    let obj = load(&d.write("m.obj", obj)).unwrap();
    assert!(obj.warnings.is_empty(), "{:?}", obj.warnings);
    assert!(obj.meshes[0].colored);
    assert_eq!(obj.geometry.colors(), ply.geometry.colors());
    let img = image(&obj);
    assert!(img == image(&ply), "another image");
    // Interpolated: red near the red corner, blue near the blue one.
    let near = |p: Vec3| pixel_at(&obj, &img, 48, 40, p).0;
    let (r, b) = (
        near(Vec3::new(-0.8, -0.8, 0.0)),
        near(Vec3::new(0.8, 0.8, 0.0)),
    );
    assert!(r.x > 4.0 * r.z && b.z > 4.0 * b.x, "{r} {b}");
}

/// A MeshLab-style quad of two triangles textured with `t.png`: its UVs
/// given by `uv` (`vertex`, or `face` for `texcoord` lists).
fn textured_quad(uv: &str) -> String {
    let (vertex_uv, face_uv, uvs, lists) = match uv {
        "vertex" => (
            "property float u\nproperty float v\n",
            "",
            [" 0 0", " 1 0", " 1 1", " 0 1"],
            ["", ""],
        ),
        _ => (
            "",
            "property list uchar float texcoord\n",
            [""; 4],
            [" 6 0 0 1 0 1 1", " 6 0 0 1 1 0 1"],
        ),
    };
    format!(
        "ply\nformat ascii 1.0\ncomment TextureFile t.png\nelement vertex 4\n\
         property float x\nproperty float y\nproperty float z\n{vertex_uv}element face 2\n\
         property list uchar int vertex_indices\n{face_uv}end_header\n-1 -1 0{}\n1 -1 0{}\n\
         1 1 0{}\n-1 1 0{}\n3 0 1 2{}\n3 0 2 3{}\n",
        uvs[0], uvs[1], uvs[2], uvs[3], lists[0], lists[1]
    )
}

#[test]
fn ply_face_texcoords_and_face_colours_shade() {
    let d = Dir::new("formats-ply-faces");
    d.write("t.png", half_red_png());
    let by_vertex = load(&d.write("v.ply", textured_quad("vertex"))).unwrap();
    let by_face = load(&d.write("f.ply", textured_quad("face"))).unwrap();
    assert!(by_face.warnings.is_empty(), "{:?}", by_face.warnings);
    assert!(by_face.meshes[0].textured);
    let (g, r) = (&by_face.geometry, &by_vertex.geometry);
    assert_eq!(
        (&g.positions(), &g.uvs(), &g.indices()),
        (&r.positions(), &r.uvs(), &r.indices())
    );
    let img = image(&by_face);
    assert!(img == image(&by_vertex), "another image");
    // u < 0.5 is red, the rest blue.
    let at = |x: f32| pixel_at(&by_face, &img, 48, 40, Vec3::new(x, 0.1, 0.0)).0;
    let (left, right) = (at(-0.5), at(0.5));
    assert!(
        left.x > 4.0 * left.z && right.z > 4.0 * right.x,
        "{left} {right}"
    );
    // Face colours: the lower right triangle red, the upper left green.
    let colours = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n\
                   property float y\nproperty float z\nelement face 2\n\
                   property list uchar int vertex_indices\nproperty uchar red\n\
                   property uchar green\nproperty uchar blue\nend_header\n\
                   -1 -1 0\n1 -1 0\n1 1 0\n-1 1 0\n3 0 1 2 255 0 0\n3 0 2 3 0 255 0\n";
    let s = load(&d.write("c.ply", colours)).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let img = image(&s);
    let at = |x: f32, y: f32| pixel_at(&s, &img, 48, 40, Vec3::new(x, y, 0.0)).0;
    let (red, green) = (at(0.5, -0.5), at(-0.5, 0.5));
    assert!(red.x > 0.05 && (red.y, red.z) == (0.0, 0.0), "{red}");
    assert!(
        green.y > 0.05 && (green.x, green.z) == (0.0, 0.0),
        "{green}"
    );
}

#[test]
fn concave_polygons_render_without_filling_their_notches() {
    let d = Dir::new("formats-concave");
    // A U, 3 across, with a notch 1 wide from its top down to y = 1.
    let corners = [
        [0, 0],
        [3, 0],
        [3, 3],
        [2, 3],
        [2, 1],
        [1, 1],
        [1, 3],
        [0, 3],
    ];
    let mut obj = String::new();
    let mut ply = String::from(
        "ply\nformat ascii 1.0\nelement vertex 8\nproperty float x\nproperty float y\n\
         property float z\nelement face 1\nproperty list uchar int vertex_indices\nend_header\n",
    );
    for [x, y] in corners {
        obj += &format!("v {x} {y} 0\n");
        ply += &format!("{x} {y} 0\n");
    }
    obj += "f 1 2 3 4 5 6 7 8\n";
    ply += "8 0 1 2 3 4 5 6 7\n";
    let s = load(&d.write("u.obj", obj)).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let img = image(&s);
    let at = |x: f32, y: f32| pixel_at(&s, &img, 48, 40, Vec3::new(x, y, 0.0)).0;
    assert!(at(0.5, 2.0).max_element() > 0.05, "an arm is dark");
    assert_eq!(at(1.5, 2.2), Vec3::ZERO, "the notch is filled");
    let p = load(&d.write("u.ply", ply)).unwrap();
    assert_eq!(p.geometry.indices(), s.geometry.indices());
    assert!(image(&p) == img, "another image");
}
