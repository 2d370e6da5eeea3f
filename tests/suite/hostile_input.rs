//! Hostile input for the loaders: special files (FIFOs, devices,
//! directories, symbolic links), oversized and truncated files, byte-order
//! marks and foreign line endings, invalid UTF-8, w components and huge
//! exponents, out-of-range indices, short MTL colours, loose TOML arrays,
//! images without pixels or too large to decode, and patch files that ask
//! for more triangles than memory holds.
//!
//! Every case loads through `rayterm::scene::load` on its own thread with a
//! deadline (a hang fails the test instead of stalling it), or through the
//! built binary with a deadline, and asserts either a clear error naming the
//! file (and line where there is one) or a correct scene; none may panic.

use crate::files::{rayterm, rayterm_within, within_deadline, Dir};
use rayterm::scene::{self, Scene};

const TRI: &str = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
const CHECKER: &[u8] = include_bytes!("../../data/meshes/checker.png");

/// Loads `spec` as the command line would, with a deadline.
fn load(spec: &str) -> Result<Scene, String> {
    let s = spec.to_string();
    within_deadline(spec, move || {
        scene::load::open(&s, &Default::default())
            .map(|o| o.scene)
            .map_err(|e| format!("{e:#}"))
    })
}

/// The load fails, and its message holds every one of `parts`.
fn refused(spec: &str, parts: &[&str]) -> String {
    let e = match load(spec) {
        Ok(s) => panic!("{spec}: loaded, warnings {:?}", s.warnings),
        Err(e) => e,
    };
    for p in parts {
        assert!(e.contains(p), "{spec}: '{p}' missing in: {e}");
    }
    assert!(!e.contains("out of memory"), "{e}");
    // "Not found" only for what is missing, never for another cause.
    if !parts.iter().any(|p| p.contains("not found")) {
        assert!(!e.contains("not found"), "{spec}: misleading: {e}");
    }
    e
}

/// The load succeeds, with a warning holding every one of `parts`.
fn warned(spec: &str, parts: &[&str]) -> Scene {
    let s = load(spec).unwrap_or_else(|e| panic!("{spec}: {e}"));
    assert!(
        s.warnings
            .iter()
            .any(|w| parts.iter().all(|p| w.contains(p))),
        "{spec}: no warning with {parts:?} in {:?}",
        s.warnings
    );
    s
}

/// The load succeeds without a warning.
fn clean(spec: &str) -> Scene {
    let s = load(spec).unwrap_or_else(|e| panic!("{spec}: {e}"));
    assert!(s.warnings.is_empty(), "{spec}: {:?}", s.warnings);
    s
}

/// A scene file with one mesh (and optional extra lines) and a light.
fn scene_with(mesh: &str, extra: &str) -> String {
    format!(
        "[[mesh]]\nfile = \"{mesh}\"\n{extra}\n[[light]]\ntype = \"point\"\nposition = [0, 2, 2]\n\
         color = [1, 1, 1]\n"
    )
}

/// An OBJ using material `a` of `m.mtl` (whatever `m.mtl` is).
const WITH_MTL: &str = "mtllib m.mtl\nusemtl a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nf 1/1 2/1 3/1\n";

/// Writes an OBJ and its `maps.mtl`, whose material `a` has `map_Kd
/// texture`; returns the OBJ's path.
fn with_map(d: &Dir, name: &str, texture: &str) -> String {
    d.write(
        "maps.mtl",
        format!("newmtl a\nKd 1 1 1\nmap_Kd {texture}\n"),
    );
    d.write(name, WITH_MTL.replace("m.mtl", "maps.mtl"))
}

/// A CRC-32 (PNG's), for hand-made image headers.
fn crc32(bytes: &[u8]) -> u32 {
    let mut c = !0u32;
    for &b in bytes {
        c ^= b as u32;
        for _ in 0..8 {
            c = if c & 1 != 0 {
                0xEDB8_8320 ^ (c >> 1)
            } else {
                c >> 1
            };
        }
    }
    !c
}

/// A PNG that declares `w` x `h` RGB pixels and holds none of them: the
/// header is all a size check needs.
fn png_header(w: u32, h: u32) -> Vec<u8> {
    let mut ihdr = b"IHDR".to_vec();
    ihdr.extend(w.to_be_bytes());
    ihdr.extend(h.to_be_bytes());
    ihdr.extend([8, 2, 0, 0, 0]);
    let mut png = b"\x89PNG\r\n\x1a\n".to_vec();
    // IHDR, then the start of an IDAT (a zlib header), then IEND.
    for chunk in [ihdr, b"IDAT\x78\x9c".to_vec(), b"IEND".to_vec()] {
        png.extend((chunk.len() as u32 - 4).to_be_bytes());
        png.extend(&chunk);
        png.extend(crc32(&chunk).to_be_bytes());
    }
    png
}

/// A Radiance HDR header declaring no pixels at all.
const HDR_0X0: &[u8] = b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 0 +X 0\n";

/// `count` small bicubic patches in `.bpt` text.
fn patches(count: usize) -> String {
    let mut s = format!("{count}\n");
    for p in 0..count {
        s += "3 3\n";
        for k in 0..16 {
            s += &format!("{} {} {}\n", k % 4 + p, k / 4, (k * 7 % 5) as f32 * 0.1);
        }
    }
    s
}

#[test]
fn special_files_are_refused_by_name() {
    let d = Dir::new("hostile-special");
    d.write("tri.obj", TRI);
    d.write("with.obj", WITH_MTL);
    // FIFOs: never opened for a blocking read.
    if let Some(fifo) = d.fifo("fifo.toml") {
        refused(
            &fifo,
            &[
                "cannot read scene file",
                "fifo.toml",
                "not a regular file (a FIFO)",
            ],
        );
        d.link("fifo.obj", &fifo);
        refused(
            d.path("fifo.obj").to_str().unwrap(),
            &["fifo.obj", "not a regular file (a symbolic link to a FIFO)"],
        );
        d.link("m.mtl", &fifo);
        refused(
            d.path("with.obj").to_str().unwrap(),
            &["with.obj:1: mtllib", "material library", "m.mtl", "a FIFO"],
        );
        let s = d.write(
            "fifo-tex.toml",
            scene_with("tri.obj", "material = { texture = \"fifo.toml\" }"),
        );
        warned(
            &s,
            &[
                "texture",
                "fifo.toml",
                "a FIFO",
                "using the material colour",
            ],
        );
        warned(
            &with_map(&d, "fifo-map.obj", &fifo),
            &[
                "maps.mtl:3: texture",
                "fifo.toml",
                "not a regular file (a FIFO)",
                "using the material colour",
            ],
        );
        let s = d.write("fifo-bpt.toml", scene_with("fifo.bpt", ""));
        d.link("fifo.bpt", &fifo);
        refused(
            &s,
            &["fifo-bpt.toml:1:1: mesh fifo.bpt", "patch file", "a FIFO"],
        );
        let faces = FACES.replace("F", "fifo.toml");
        let s = d.write("fifo-env.toml", scene_with("tri.obj", &faces));
        refused(&s, &["environment face posx", "fifo.toml", "a FIFO"]);
        std::fs::remove_file(d.path("m.mtl")).unwrap();
    }
    // Devices, named directly and through symbolic links.
    for dev in ["/dev/zero", "/dev/null", "/dev/urandom"] {
        refused(
            dev,
            &[
                dev,
                "not a regular file (a character device); a scene is a built-in name",
            ],
        );
    }
    d.link("zero.obj", "/dev/zero");
    refused(
        d.path("zero.obj").to_str().unwrap(),
        &[
            "zero.obj",
            "not a regular file (a symbolic link to a character device)",
        ],
    );
    d.link("null.toml", "/dev/null");
    refused(
        d.path("null.toml").to_str().unwrap(),
        &["null.toml", "a character device"],
    );
    d.link("m.mtl", "/dev/zero");
    refused(
        d.path("with.obj").to_str().unwrap(),
        &["m.mtl", "a character device"],
    );
    let s = d.write(
        "zero-tex.toml",
        scene_with("tri.obj", "material = { texture = \"/dev/zero\" }"),
    );
    warned(
        &s,
        &["/dev/zero", "not a regular file (a character device)"],
    );
    warned(
        &with_map(&d, "zero-map.obj", "/dev/zero"),
        &[
            "maps.mtl:3: texture /dev/zero",
            "not a regular file (a character device)",
        ],
    );
    std::fs::remove_file(d.path("m.mtl")).unwrap();
    // Directories.
    std::fs::create_dir_all(d.path("dir.toml")).unwrap();
    refused(
        d.path("dir.toml").to_str().unwrap(),
        &["dir.toml", "not a regular file (a directory)"],
    );
    std::fs::create_dir_all(d.path("m.mtl")).unwrap();
    refused(
        d.path("with.obj").to_str().unwrap(),
        &["m.mtl", "a directory"],
    );
    std::fs::remove_dir(d.path("m.mtl")).unwrap();
    let s = d.write("dir-mesh.toml", scene_with("dir.toml", ""));
    refused(
        &s,
        &[
            "dir-mesh.toml:1:1: mesh dir.toml",
            "OBJ mesh",
            "a directory",
        ],
    );
    let s = d.write(
        "dir-tex.toml",
        scene_with("tri.obj", "material = { texture = \".\" }"),
    );
    warned(&s, &["texture", "a directory"]);
    warned(
        &with_map(&d, "dir-map.obj", "."),
        &["maps.mtl:3: texture", "not a regular file (a directory)"],
    );
    // Missing files, dangling and looping links.
    let s = d.write("missing.toml", scene_with("nowhere.obj", ""));
    refused(
        &s,
        &[
            "missing.toml:1:1: mesh nowhere.obj",
            "nowhere.obj: not found",
        ],
    );
    d.link("dangling.obj", d.path("gone.obj"));
    refused(
        d.path("dangling.obj").to_str().unwrap(),
        &["dangling.obj: not found"],
    );
    d.link("loop-a.obj", d.path("loop-b.obj"));
    d.link("loop-b.obj", d.path("loop-a.obj"));
    refused(
        d.path("loop-a.obj").to_str().unwrap(),
        &["cannot read OBJ mesh", "loop-a.obj"],
    );
    warned(
        d.path("with.obj").to_str().unwrap(),
        &["with.obj:1: material library", "m.mtl not found"],
    );
    warned(
        &with_map(&d, "gone-map.obj", "gone.png"),
        &["maps.mtl:3: texture", "gone.png: not found"],
    );
    // Unreadable (where permissions apply: not as root).
    use std::os::unix::fs::PermissionsExt;
    let locked = d.write("locked.obj", TRI);
    std::fs::set_permissions(&locked, std::fs::Permissions::from_mode(0o000)).unwrap();
    if std::fs::read(&locked).is_err() {
        refused(&locked, &["locked.obj: permission denied"]);
    } else {
        eprintln!("skipping the permission case: running with privileges that read anything");
    }
}

/// Environment faces, `F` replaced by a file name.
const FACES: &str = "[environment]\nfaces = { posx = \"F\", negx = \"F\", posy = \"F\", \
                     negy = \"F\", posz = \"F\", negz = \"F\" }";

#[test]
fn oversized_files_are_refused_before_reading() {
    let d = Dir::new("hostile-size");
    d.write("tri.obj", TRI);
    let big = d.sparse("big.toml", (16 << 20) + 1);
    refused(
        &big,
        &["big.toml: too large (16777217 bytes, limit 16777216 = 16.0 MiB)"],
    );
    let big = d.sparse("big.obj", (1 << 30) + 1);
    refused(
        &big,
        &[
            "cannot read OBJ mesh",
            "big.obj: too large (1073741825 bytes",
        ],
    );
    d.sparse("m.mtl", (16 << 20) + 1);
    let obj = d.write("with.obj", WITH_MTL);
    refused(&obj, &["material library", "m.mtl: too large"]);
    d.sparse("big.bpt", (64 << 20) + 1);
    let s = d.write("bpt.toml", scene_with("big.bpt", ""));
    refused(&s, &["patch file", "big.bpt: too large"]);
    d.sparse("big.png", (256 << 20) + 1);
    let s = d.write(
        "tex.toml",
        scene_with("tri.obj", "material = { texture = \"big.png\" }"),
    );
    warned(&s, &["image", "big.png: too large"]);
}

#[test]
fn ply_stl_and_gltf_files_are_read_as_carefully_as_obj() {
    let d = Dir::new("hostile-mesh");
    for name in ["m.ply", "m.stl", "m.glb", "m.gltf"] {
        if let Some(fifo) = d.fifo(&format!("fifo-{name}")) {
            refused(&fifo, &[&fifo, "not a regular file (a FIFO)"]);
        }
        std::fs::create_dir_all(d.path(&format!("dir-{name}"))).unwrap();
        refused(
            d.path(&format!("dir-{name}")).to_str().unwrap(),
            &["not a regular file (a directory)"],
        );
        let big = d.sparse(&format!("big-{name}"), (2 << 30) + 1);
        refused(&big, &[&big, "too large (2147483649 bytes"]);
        let empty = d.write(&format!("empty-{name}"), "");
        refused(&empty, &[&empty]);
        let s = d.write("s.toml", scene_with(&format!("big-{name}"), ""));
        refused(&s, &["s.toml:1:1: mesh big-", "too large"]);
    }
    let dev = d.link("zero.ply", "/dev/zero");
    refused(
        &dev,
        &["not a regular file (a symbolic link to a character device)"],
    );
    // Counts that would allocate far more than the file holds.
    let ply = d.write(
        "huge.ply",
        "ply\nformat binary_little_endian 1.0\nelement vertex 4294967295\nproperty float x\n\
         property float y\nproperty float z\nend_header\n",
    );
    refused(
        &ply,
        &[
            &ply,
            "4294967295 vertices: more than 32-bit indices address",
        ],
    );
    let ply = d.write(
        "many.ply",
        "ply\nformat binary_little_endian 1.0\nelement vertex 3\nproperty float x\n\
         property float y\nproperty float z\nelement face 4000000000\n\
         property list uchar int vertex_indices\nend_header\n",
    );
    refused(
        &ply,
        &[
            &ply,
            "truncated: the header declares element vertex 3, element face 4000000000:",
        ],
    );
    let mut stl = vec![b' '; 80];
    stl.extend(u32::MAX.to_le_bytes());
    let stl = d.write("many.stl", stl);
    refused(
        &stl,
        &[
            &stl,
            "truncated binary STL: the header counts 4294967295 triangles",
        ],
    );
    // A mesh without triangles says so.
    let ply = d.write(
        "points.ply",
        "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty float y\n\
         property float z\nend_header\n0 0 0\n",
    );
    refused(&ply, &[&ply, "no triangles"]);
}

#[test]
fn byte_order_marks_and_line_endings_change_nothing() {
    let d = Dir::new("hostile-text");
    let mtl = "newmtl a\nKd 1 0 0\nnewmtl b\nKd 0 0 1\n";
    let obj =
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nusemtl a\nf 1 2 3\nusemtl b\nf 2 4 3\n";
    let toml = scene_with("m.obj", "[render]\nspp = 3");
    d.write("plain/m.mtl", mtl);
    d.write("plain/m.obj", obj);
    let plain = clean(&d.write("plain/s.toml", &toml));
    assert_eq!(plain.geometry.positions()[0], glam::Vec3::ZERO);
    for (name, f) in [
        (
            "bom",
            (|t: &str| format!("\u{feff}{t}")) as fn(&str) -> String,
        ),
        ("crlf", |t: &str| t.replace('\n', "\r\n")),
        ("cr", |t: &str| t.replace('\n', "\r")),
    ] {
        d.write(&format!("{name}/m.mtl"), f(mtl));
        d.write(&format!("{name}/m.obj"), f(obj));
        let s = clean(&d.write(&format!("{name}/s.toml"), f(&toml)));
        assert_eq!(s.geometry.positions(), plain.geometry.positions(), "{name}");
        assert_eq!(s.geometry.indices(), plain.geometry.indices(), "{name}");
        assert_eq!(s.materials, plain.materials, "{name}: first material kept");
        assert_eq!(s.settings.spp, 3, "{name}");
        // A bare OBJ and a patch file alike.
        let bare = clean(&d.write(&format!("{name}/bare.obj"), f(TRI)));
        assert_eq!(bare.geometry.positions()[1], glam::Vec3::X, "{name}");
        d.write(&format!("{name}/p.bpt"), f(&patches(1)));
        clean(&d.write(&format!("{name}/p.toml"), f(&scene_with("p.bpt", ""))));
    }
}

#[test]
fn invalid_utf8_names_the_file_and_line() {
    let d = Dir::new("hostile-utf8");
    let bad = |t: &str| {
        let mut b = t.as_bytes().to_vec();
        b.extend(b"# caf\xe9\n");
        b
    };
    // OBJ and MTL files, which tools write in Latin-1 too, are read
    // lossily, as other readers read them.
    warned(
        &d.write("a.obj", bad(TRI)),
        &["a.obj:5: not valid UTF-8 (byte 0xe9 at column 6): read as U+FFFD"],
    );
    let s = d.write("s.toml", bad(&scene_with("tri.obj", "")));
    refused(&s, &["s.toml:8: not valid UTF-8"]);
    d.write("tri.obj", TRI);
    d.write("m.mtl", bad("newmtl a\nKd 1 1 1\n"));
    warned(
        &d.write("with.obj", WITH_MTL),
        &["m.mtl:3: not valid UTF-8 (byte 0xe9 at column 6): read as U+FFFD"],
    );
    d.write("p.bpt", bad(&patches(1)));
    refused(
        &d.write("p.toml", scene_with("p.bpt", "")),
        &["p.bpt:19: not valid UTF-8"],
    );
    // A NUL byte is valid UTF-8 but no number.
    refused(
        &d.write("nul.obj", "v 0 0 0\nv 1\u{0} 0 0\n"),
        &["nul.obj:2: '1\u{fffd}' is not a number"],
    );
}

#[test]
fn truncated_and_empty_files_name_the_line() {
    let d = Dir::new("hostile-truncated");
    d.write("tri.obj", TRI);
    refused(
        &d.write("a.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2"),
        &[
            "a.obj: no triangles",
            "a.obj:4: 1 face with fewer than 3 vertices: skipped",
        ],
    );
    refused(
        &d.write("b.obj", "v 0 0 0\nv 1 0"),
        &["b.obj:2: a vertex takes 3 coordinates"],
    );
    refused(
        &d.write("s.toml", "[[mesh]]\nfile = \"tri.o"),
        &["s.toml:2:", "invalid basic string"],
    );
    refused(
        &d.write("t.toml", "[[mesh]]\nfile = \"tri.obj\"\n[[li"),
        &["t.toml:3:"],
    );
    d.write("m.mtl", "newmtl a\nKd 0.5 0.5");
    refused(
        &d.write("with.obj", WITH_MTL),
        &["m.mtl:2: Kd takes 1 or 3 numbers (r [g b]), found 2"],
    );
    let cut = &patches(1)[..120];
    d.write("p.bpt", cut);
    refused(
        &d.write("p.toml", scene_with("p.bpt", "")),
        &["p.bpt:", "truncated file"],
    );
    d.write("t.png", &CHECKER[..CHECKER.len() / 2]);
    let s = d.write(
        "tex.toml",
        scene_with("tri.obj", "material = { texture = \"t.png\" }"),
    );
    warned(&s, &["t.png", "using the material colour"]);
    refused(&d.write("empty.obj", ""), &["empty.obj: no triangles"]);
    refused(
        &d.write("empty.toml", ""),
        &["empty.toml: the scene has no triangles"],
    );
    d.write("m.mtl", "");
    warned(
        &d.write("with.obj", WITH_MTL),
        &["with.obj:2: usemtl a: no such material"],
    );
}

#[test]
fn w_components_are_ignored_and_huge_exponents_checked_after_every_step() {
    let d = Dir::new("hostile-numbers");
    let obj = |name: &str, v2: &str| d.write(name, format!("v 0 0 0\n{v2}\nv 0 1 0\nf 1 2 3\n"));
    // w is a curve weight that polygons ignore, however small or zero.
    for (name, w) in [("w.obj", "1e-45"), ("w0.obj", "0"), ("w300.obj", "1e-300")] {
        let s = clean(&obj(name, &format!("v 2 0 0 {w}")));
        assert_eq!(
            s.geometry.positions()[1],
            glam::Vec3::new(2.0, 0.0, 0.0),
            "{name}"
        );
    }
    // A vertex f32 cannot hold leaves out the faces using it: here the
    // one face, so nothing is left to draw.
    for (name, v, why) in [
        (
            "e39.obj",
            "v 1e39 0 0",
            "'1e39' is too large: 32-bit floats are finite only up to",
        ),
        ("e308.obj", "v 0 1e308 0", "'1e308' is too large"),
        (
            "e99999.obj",
            "v 0 0 1e99999",
            "'1e99999' is not a finite number",
        ),
        ("neg.obj", "v -1e400 0 0", "'-1e400' is not a finite number"),
        ("nan.obj", "v NaN 0 0", "'NaN' is not a finite number"),
    ] {
        refused(
            &obj(name, v),
            &[
                &format!("{name}: no triangles ("),
                &format!("{name}:2: vertex {why}"),
                "1 face using it skipped",
            ],
        );
    }
    for (name, v, why) in [
        ("vn.obj", "vn 0 0 1e39", "'1e39' is too large"),
        ("vt.obj", "vt 1e39 0", "'1e39' is too large"),
    ] {
        refused(&obj(name, v), &[&format!("{name}:2: {why}")]);
    }
    // A tiny exponent reads as zero; a huge but representable one warns,
    // and the scene is scaled down to render.
    clean(&obj("tiny.obj", "v 1 1e-400 0"));
    let s = warned(
        &obj("e30.obj", "v 1e30 0 0"),
        &["e30.obj:2: absurd value 1e30"],
    );
    assert!(s.warnings.iter().any(|w| w.contains("scaled by 2^-")));
    assert!(s.geometry.bounds().extent().max_element() < 2.0);
    // Placement in the scene file: beyond f32 only once scaled or moved.
    d.write("tri.obj", TRI);
    let s = d.write(
        "scale.toml",
        scene_with("tri.obj", "scale = 3e38\ntranslate = [1e38, 0, 0]"),
    );
    refused(
        &s,
        &[
            "scale.toml:1:1: mesh tri.obj",
            "tri.obj:2: vertex (1, 0, 0) lands at (4e38, 0, 0)",
        ],
    );
    let s = d.write(
        "rot.toml",
        scene_with("sq.obj", "scale = 3e38\nrotate = [0, 0, 45]"),
    );
    d.write("sq.obj", "v 0 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3\n");
    refused(
        &s,
        &[
            "rot.toml:1:1: mesh sq.obj",
            "sq.obj:2: vertex (1, 1, 0) lands at (",
            ", 4.2426",
        ],
    );
    let s = d.write(
        "e39.toml",
        scene_with("tri.obj", "translate = [0, 1e39, 0]"),
    );
    refused(&s, &["e39.toml:3:", "32-bit floats are finite only up to"]);
    let s = d.write("big.toml", scene_with("tri.obj", "scale = 3e38"));
    let s = warned(
        &s,
        &["big.toml: the scene is 3e38 across", "scaled by 2^-127"],
    );
    assert!(s.geometry.positions().iter().all(|p| p.is_finite()));
    let s = d.write("tiny.toml", scene_with("tri.obj", "scale = 1e-30"));
    let s = warned(
        &s,
        &["tiny.toml: the scene is 1e-30 across", "scaled by 2^100"],
    );
    assert_eq!(
        s.geometry.triangle_count(),
        1,
        "a tiny triangle is no degenerate one"
    );
    // At 1e30 even f64 cannot tell the vertices of a unit triangle apart:
    // the error says why the scene came out empty.
    let s = d.write(
        "far30.toml",
        scene_with("tri.obj", "translate = [1e30, 1e30, 1e30]"),
    );
    refused(
        &s,
        &[
            "far30.toml: the scene has no triangles (",
            "coordinates reach 1e30",
            "skipped 1 degenerate",
        ],
    );
    // Huge exponents in MTL and patch files.
    d.write("m.mtl", "newmtl a\nNs 1e99999\n");
    refused(&d.write("with.obj", WITH_MTL), &["m.mtl:2: '1e99999'"]);
    d.write("p.bpt", patches(1).replacen("0 0 0", "0 1e300 0", 1));
    refused(
        &d.write("p.toml", scene_with("p.bpt", "")),
        &["p.bpt:3:", "out of range"],
    );
}

#[test]
fn indices_are_checked_exactly() {
    let d = Dir::new("hostile-indices");
    let base = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nvn 0 0 1\nvn 0 0 1\nvt 0 0\n";
    let obj = |name: &str, f: &str| d.write(name, format!("{base}{f}\n"));
    for (name, face, want) in [
        (
            "wrap.obj",
            "f 1//6148914691236517207 2//1 3//1",
            "normal index 6148914691236517207 is out of range",
        ),
        (
            "v.obj",
            "f 1 2 4",
            "the face refers to vertex 4 but the file defines 3",
        ),
        (
            "u32.obj",
            "f 1 2 4294967296",
            "vertex index 4294967296 is out of range",
        ),
        (
            "u32m.obj",
            "f 1 2 4294967295",
            "the face refers to vertex 4294967295 but the file defines 3",
        ),
        (
            "i64.obj",
            "f 1 2 99999999999999999999",
            "'99999999999999999999' is not a valid vertex index",
        ),
        ("zero.obj", "f 0 1 2", "vertex index 0 (indices start at 1)"),
        (
            "rel.obj",
            "f -1 -2 -4",
            "relative vertex index -4 reaches before the first vertex",
        ),
        ("relvn.obj", "f 1//-4 2//1 3//1", "relative normal index -4"),
        (
            "min.obj",
            "f -9223372036854775808 1 2",
            "relative vertex index -9223372036854775808",
        ),
        (
            "slash.obj",
            "f 1/1/1/1 2 3",
            "'1/1/1/1' is not a face vertex",
        ),
    ] {
        refused(&obj(name, face), &[&format!("{name}:8: "), want]);
    }
    // Texture coordinates and normals beyond those defined: the face is
    // read without them, as tinyobjloader reads it.
    for (name, face, want) in [
        (
            "vn.obj",
            "f 1//4 2//1 3//1",
            "the face refers to normal 4 but the file defines 3",
        ),
        (
            "vt.obj",
            "f 1/2 2/1 3/1",
            "the face refers to texture coordinate 2 but the file defines 1",
        ),
    ] {
        let s = warned(
            &obj(name, face),
            &[&format!("{name}:8: "), want, "read without"],
        );
        assert_eq!(s.geometry.indices().len(), 1);
    }
    // Relative and forward references that land in range load.
    clean(&obj("ok.obj", "f -3/-1/-3 -2/1/-2 -1/1/-1"));
    clean(&d.write("fwd.obj", "f 1 2 3\nv 0 0 0\nv 1 0 0\nv 0 1 0\n"));
}

#[test]
fn mtl_statements_rayterm_cannot_use_are_errors_or_warnings() {
    let d = Dir::new("hostile-mtl");
    let obj = d.write("with.obj", WITH_MTL);
    let mtl = |text: &str| d.write("m.mtl", format!("newmtl a\n{text}\n"));
    for (text, want) in [
        (
            "Kd 0.5 0.5",
            "m.mtl:2: Kd takes 1 or 3 numbers (r [g b]), found 2",
        ),
        ("Kd", "m.mtl:2: Kd takes 1 or 3 numbers (r [g b]), found 0"),
        ("Ks 1 2 3 4", "m.mtl:2: Ks takes 1 or 3 numbers"),
        ("Ka 0.5 0.5", "m.mtl:2: Ka takes 1 or 3 numbers"),
        ("Ns", "m.mtl:2: Ns takes one number, found 0"),
    ] {
        mtl(text);
        refused(&obj, &[want]);
    }
    // A texture that names no file is ignored, as a missing one is.
    for text in ["Kd 0.25\nmap_Kd", "Kd 0.25\nmap_Kd -s 2 2 2"] {
        mtl(text);
        let s = warned(&obj, &["m.mtl:3: map_Kd names no file: ignored"]);
        assert_eq!(s.materials[0].kd, glam::Vec3::splat(0.25));
        assert!(s.textures.is_empty());
    }
    mtl("Kd 0.5");
    let s = clean(&obj);
    assert_eq!(s.materials[0].kd, glam::Vec3::splat(0.5));
    d.write("t.png", CHECKER);
    mtl("Kd -1 0.5 0.5\nmap_Kd -s 2 2 1 -o 0.5 0.5 t.png");
    let s = warned(&obj, &["m.mtl:2: negative colour Kd -1 0.5 0.5"]);
    assert!(s
        .warnings
        .iter()
        .any(|w| w.contains("m.mtl:3: map_Kd options ignored: -s 2 2 1, -o 0.5 0.5")));
    assert_eq!(s.textures.len(), 1, "the texture after the options is read");
    d.write("with.obj", WITH_MTL.replace("usemtl a", "usemtl b"));
    mtl("Kd 1 1 1");
    warned(
        &obj,
        &["with.obj:2: usemtl b: no such material in", "m.mtl"],
    );
}

#[test]
fn scene_file_arrays_and_settings_are_strict() {
    let d = Dir::new("hostile-toml");
    d.write("tri.obj", TRI);
    let light = "[[light]]\ntype = \"parallelogram\"\ncorner = [0, 1, 0]\nedge1 = [1, 0, 0]\n\
                 edge2 = [0, 0, 1]\n";
    for (name, extra, want) in [
        (
            "pos.toml",
            "[[light]]\ntype = \"point\"\nposition = [0, 1, 2, 3]\ncolor = [1, 1, 1]",
            "pos.toml:5:12: invalid length 4, expected an array of 3 values",
        ),
        (
            "size.toml",
            "[render]\nsize = [64, 48, 7]",
            "size.toml:4:8: invalid length 3, expected an array of 2 values",
        ),
        (
            "short.toml",
            "translate = [1, 2]",
            "short.toml:3:13: invalid length 2",
        ),
        (
            "spp.toml",
            "[render]\nspp = 0",
            "spp.toml:4:7: render.spp must be from 1 to 1048576, not 0",
        ),
        (
            "depth.toml",
            "[render]\nmax_depth = 100",
            "depth.toml:4:13: render.max_depth must be from 0 to 64",
        ),
        (
            "nan.toml",
            "scale = nan",
            "nan.toml:3:9: NaN is not a finite number",
        ),
    ] {
        refused(&d.write(name, scene_with("tri.obj", extra)), &[want]);
    }
    d.write("p.bpt", patches(1));
    refused(
        &d.write("seg.toml", scene_with("p.bpt", "segments = 5000")),
        &["seg.toml:3:12: segments must be from 1 to 1024, not 5000"],
    );
    let colors = format!("{light}colors = [[1, 1, 1], [1, 1, 1], [1, 1, 1], [1, 1, 1], [1, 1, 1]]");
    refused(
        &d.write(
            "colors.toml",
            format!("[[mesh]]\nfile = \"tri.obj\"\n{colors}\n"),
        ),
        &["colors.toml:8:10: invalid length 5, expected an array of 4 values"],
    );
    let s = d.write(
        "neg.toml",
        "[[mesh]]\nfile = \"tri.obj\"\nmaterial = { kd = [-0.5, 0.5, 0.5] }\n[[light]]\n\
         type = \"point\"\nposition = [0, 1, 1]\ncolor = [1, 1, -1]\n[render]\nambient = [-0.1, 0, 0]\n",
    );
    let s = warned(&s, &["neg.toml:3:19: negative kd [-0.5, 0.5, 0.5]"]);
    let all = s.warnings.join("\n");
    assert!(
        all.contains("neg.toml:7:9: negative color")
            && all.contains("neg.toml:9:11: negative ambient"),
        "{all}"
    );
    // A light so bright that shading overflows warns, as an MTL's does.
    let s = d.write(
        "bright.toml",
        "[[mesh]]\nfile = \"tri.obj\"\n[[light]]\ntype = \"parallelogram\"\ncorner = [0, 1, 1]\n\
         edge1 = [1, 0, 0]\nedge2 = [0, 0, 1]\ncolors = [[1, 1, 1], [1e30, 1, 1], [1, 1, 1], [1, 1, 1]]\n\
         [[light]]\ntype = \"point\"\nposition = [0, 1, 1]\ncolor = [3e38, 1, 1]\n",
    );
    let s = warned(
        &s,
        &["bright.toml:12:9: absurd color [3e38, 1, 1]: beyond 1e18"],
    );
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("bright.toml:8:10: absurd colors: beyond 1e18")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn images_without_pixels_or_beyond_the_budget_are_refused() {
    let d = Dir::new("hostile-images");
    d.write("tri.obj", TRI);
    d.write("zero.hdr", HDR_0X0);
    let s = d.write(
        "tex0.toml",
        scene_with("tri.obj", "material = { texture = \"zero.hdr\" }"),
    );
    warned(&s, &["texture", "zero.hdr: the image has no pixels (0x0)"]);
    let s = d.write(
        "env0.toml",
        scene_with("tri.obj", &FACES.replace("F", "zero.hdr")),
    );
    refused(
        &s,
        &[
            "env0.toml: environment",
            "environment face posx",
            "zero.hdr: the image has no pixels (0x0)",
        ],
    );
    d.write("zero.png", png_header(0, 0));
    let s = d.write(
        "png0.toml",
        scene_with("tri.obj", "material = { texture = \"zero.png\" }"),
    );
    // The decoder's own words, once (not repeated as an error chain).
    warned(
        &s,
        &["zero.png: Format error decoding Png: Invalid image dimensions; using the material colour"],
    );
    // 60 bytes of HDR header can declare 100000 x 100000: 251 GiB to decode and store.
    d.write(
        "huge.hdr",
        b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 100000 +X 100000\n",
    );
    warned(
        &with_map(&d, "hdr.obj", "huge.hdr"),
        &[
            "maps.mtl:3: texture",
            "huge.hdr: a 100000x100000 texture would need 251 GiB of memory, over the 1.50 GiB \
             limit per texture",
        ],
    );
    let s = d.write(
        "envhdr.toml",
        scene_with("tri.obj", &FACES.replace("F", "huge.hdr")),
    );
    refused(
        &s,
        &["environment face posx", "huge.hdr", "would need 251 GiB"],
    );
    // 420 kB of PNG could declare 12000 x 12000: 2 GiB to decode and store.
    d.write("huge.png", png_header(12000, 12000));
    let s = d.write(
        "texbig.toml",
        scene_with("tri.obj", "material = { texture = \"huge.png\" }"),
    );
    warned(
        &s,
        &["huge.png: a 12000x12000 texture would need 2.01 GiB of memory, over the 1.50 GiB limit per texture"],
    );
    let s = d.write(
        "envbig.toml",
        scene_with("tri.obj", &FACES.replace("F", "huge.png")),
    );
    refused(&s, &["huge.png", "would need 2.01 GiB"]);
    // So large that the decoder refuses the header itself: the limit is
    // still named.
    d.write("vast.png", png_header((1 << 31) - 1, (1 << 31) - 1));
    let s = d.write(
        "texvast.toml",
        scene_with("tri.obj", "material = { texture = \"vast.png\" }"),
    );
    warned(&s, &["vast.png", "more than the 1.50 GiB per texture"]);
    d.write("max.png", png_header(u32::MAX >> 1, u32::MAX >> 1));
    let s = d.write(
        "texmax.toml",
        scene_with("tri.obj", "material = { texture = \"max.png\" }"),
    );
    warned(&s, &["max.png"]);
    // An image that is no image.
    d.write("junk.png", b"\x89PNG\r\n\x1a\nnot a png at all");
    let s = d.write(
        "junk.toml",
        scene_with("tri.obj", "material = { texture = \"junk.png\" }"),
    );
    warned(&s, &["junk.png", "using the material colour"]);
}

#[test]
fn patch_files_asking_for_too_much_memory_are_refused_up_front() {
    let d = Dir::new("hostile-patches");
    d.write("many.bpt", patches(2000));
    let s = d.write("seg.toml", scene_with("many.bpt", "segments = 1024"));
    refused(
        &s,
        &["many.bpt: 2000 patches at 1024 segments per edge make 4194304000 triangles, which would need 781 GiB of memory", "is available; lower segments"],
    );
    d.write("more.bpt", patches(4200));
    let s = d.write("idx.toml", scene_with("more.bpt", "segments = 1024"));
    refused(&s, &["4200 patches", "more than 32-bit indices address"]);
    // The same file at a sane level loads.
    let s = clean(&d.write("ok.toml", scene_with("many.bpt", "segments = 1")));
    assert_eq!(s.geometry.triangle_count(), 4000);
}

/// The binary under hostile input: no hang, no panic, the message on stderr.
#[test]
fn the_binary_says_what_is_wrong_and_never_hangs() {
    let d = Dir::new("hostile-binary");
    let run = |args: &[&str]| {
        let mut all = vec!["render"];
        all.extend(args);
        all.extend(["--size", "8x8", "--spp", "1", "-o", "out.png"]);
        let r = rayterm(&d.0, &all);
        assert!(!r.stderr.contains("panicked"), "{args:?}: {}", r.stderr);
        r
    };
    let fails = |args: &[&str], parts: &[&str]| {
        let _ = std::fs::remove_file(d.path("out.png"));
        let r = run(args);
        assert!(
            !d.path("out.png").exists(),
            "{args:?}: an image from a failed load"
        );
        assert_eq!(r.code, Some(1), "{args:?}: {}", r.stderr);
        for p in parts {
            assert!(
                r.stderr.contains(p),
                "{args:?}: '{p}' missing in {}",
                r.stderr
            );
        }
    };
    d.write("tri.obj", TRI);
    if d.fifo("fifo.toml").is_some() {
        fails(&["fifo.toml"], &["fifo.toml: not a regular file (a FIFO)"]);
        d.link("m.mtl", d.path("fifo.toml"));
        d.write("with.obj", WITH_MTL);
        fails(
            &["with.obj"],
            &["with.obj:1: mtllib", "m.mtl: not a regular file"],
        );
        d.write(
            "tex.toml",
            scene_with("tri.obj", "material = { texture = \"fifo.toml\" }"),
        );
        let r = run(&["tex.toml"]);
        assert!(
            r.ok() && r.stderr.contains("warning: tex.toml: texture fifo.toml"),
            "{}",
            r.stderr
        );
    }
    d.link("zero.obj", "/dev/zero");
    fails(
        &["zero.obj"],
        &["zero.obj: not a regular file (a symbolic link to a character device)"],
    );
    fails(
        &["/dev/zero"],
        &["/dev/zero: not a regular file (a character device)"],
    );
    d.write(
        "huge.hdr",
        b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 100000 +X 100000\n",
    );
    let r = run(&[&with_map(&d, "hdr.obj", "huge.hdr")]);
    assert!(
        r.ok()
            && r.stderr
                .contains("huge.hdr: a 100000x100000 texture would need 251 GiB"),
        "{}",
        r.stderr
    );
    d.write("bom.obj", format!("\u{feff}{TRI}"));
    let r = run(&["bom.obj"]);
    assert!(
        r.ok() && r.stdout.contains("1 triangle,"),
        "{} {}",
        r.stdout,
        r.stderr
    );
    d.write(
        "idx.obj",
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 1\nf 1//6148914691236517207 2//1 3//1\n",
    );
    fails(
        &["idx.obj"],
        &["idx.obj:5: normal index 6148914691236517207 is out of range"],
    );
    d.write("many.bpt", patches(2000));
    d.write("seg.toml", scene_with("many.bpt", "segments = 1024"));
    fails(&["seg.toml"], &["would need 781 GiB of memory"]);
    d.write("zero.hdr", HDR_0X0);
    d.write(
        "env0.toml",
        scene_with("tri.obj", &FACES.replace("F", "zero.hdr")),
    );
    fails(&["env0.toml"], &["zero.hdr: the image has no pixels (0x0)"]);
}

#[test]
fn control_characters_and_empty_names_are_handled() {
    let d = Dir::new("hostile-names");
    d.write("tri.obj", TRI);
    // Escape sequences in names and statements never reach a terminal.
    let obj = d.write(
        "esc.obj",
        "o \u{1b}]0;title\u{7}\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\nfoo\u{1b}[2J 1\n",
    );
    let s = warned(&obj, &["foo\u{fffd}[2J (line 6)"]);
    assert_eq!(s.meshes[0].name, "\u{fffd}]0;title\u{fffd}");
    let s = d.write(
        "esc.toml",
        "name = \"\\u001b[2J\"\ndescription = \"a\\u009bb\"\n[[mesh]]\nfile = \"tri.obj\"\n\
         material = { name = \"m\\u0007\" }\n[[light]]\ntype = \"point\"\nposition = [0, 1, 1]\n\
         color = [1, 1, 1]\n",
    );
    let s = clean(&s);
    let text = format!("{}{}{}", s.name, s.description, s.materials[0].name);
    assert!(!text.chars().any(char::is_control), "{text:?}");
    // Empty file names.
    let s = d.write("nomesh.toml", scene_with("", ""));
    refused(&s, &["nomesh.toml:1:1: mesh: the file name is empty"]);
    let s = d.write(
        "notex.toml",
        scene_with("tri.obj", "material = { texture = \" \" }"),
    );
    warned(
        &s,
        &["notex.toml: material texture: the file name is empty"],
    );
    let s = d.write(
        "noface.toml",
        scene_with("tri.obj", &FACES.replace("F", "")),
    );
    refused(&s, &["environment face posx: the file name is empty"]);
    d.write("m.mtl", "newmtl a\nmap_Kd   \n");
    warned(
        &d.write("with.obj", WITH_MTL),
        &["m.mtl:2: map_Kd names no file: ignored"],
    );
}

#[test]
fn paths_on_the_command_line_are_printed_without_control_characters() {
    let d = Dir::new("hostile-paths");
    d.write("t\u{1b}[2J.obj", TRI);
    let r = rayterm(
        &d.0,
        &[
            "render",
            "t\u{1b}[2J.obj",
            "--size",
            "8x8",
            "--spp",
            "1",
            "-o",
            "e\u{1b}[2J.png",
        ],
    );
    assert!(r.ok(), "{}", r.stderr);
    assert!(
        r.stdout.contains("t\u{fffd}[2J.obj: 1 triangle"),
        "{}",
        r.stdout
    );
    assert!(r.stdout.contains("-> e\u{fffd}[2J.png"), "{}", r.stdout);
    let r = rayterm(
        &d.0,
        &["render", "t\u{1b}[2J.obj", "-o", "no\u{1b}]0;x\u{7}/e.png"],
    );
    assert!(!r.ok());
    assert!(
        r.stderr.contains("no\u{fffd}]0;x\u{fffd}/e.png"),
        "{}",
        r.stderr
    );
    for text in [&r.stdout, &r.stderr] {
        assert!(!text.contains(['\u{1b}', '\u{7}']), "{text:?}");
    }
}

#[test]
fn extreme_arguments_are_bounded_or_refused_before_loading() {
    let d = Dir::new("hostile-arguments");
    let run = |args: &[&str]| {
        let r = rayterm(&d.0, args);
        assert!(!r.stderr.contains("panicked"), "{args:?}: {}", r.stderr);
        r
    };
    // A frame smaller than the benchmark's pixel sample.
    let r = run(&[
        "bench", "--size", "1x1", "--reps", "1", "--scene", "cornell",
    ]);
    assert!(r.ok() && r.stdout.contains("cornell"), "{}", r.stderr);
    // However short the time, the image has one full pass.
    let r = run(&[
        "render", "cornell", "--size", "8x8", "--time", "1e-9", "-o", "t.png",
    ]);
    assert!(r.ok() && r.stdout.contains(", 1 spp,"), "{}", r.stdout);
    // The cap that ended a timed render is named.
    let r = run(&[
        "render",
        "cornell",
        "--size",
        "8x8",
        "--time",
        "100",
        "--max-spp",
        "3",
        "-o",
        "t.png",
    ]);
    assert!(
        r.ok()
            && r.stdout.contains("3 spp")
            && r.stdout
                .contains("stopped at the --max-spp cap of 3 before the --time of 100 s"),
        "{}",
        r.stdout
    );
    // An adaptive target (the default) is judged once every pixel has its
    // first 4, a sample in each quadrant.
    let r = run(&[
        "render",
        "cornell-area",
        "--size",
        "8x8",
        "--target-error",
        "0.9",
        "-o",
        "t.png",
    ]);
    assert!(r.ok() && r.stdout.contains(", 4 spp,"), "{}", r.stdout);
    // Sample counts beyond the renderer's cap, and targets beyond any render,
    // are refused before the scene loads.
    for (args, why) in [
        (
            &["converge", "cornell", "--spp", "1,2000000"][..],
            "--spp budgets must be 1 to 1048576",
        ),
        (
            &["converge", "cornell", "--target", "1e-20"][..],
            "--target must be a fraction from 1e-6",
        ),
        (
            &["converge", "cornell", "--reference-spp", "2000000"][..],
            "2000000",
        ),
        (
            &["inspect", "cornell", "--pixel", "1,1", "--spp", "2000000"][..],
            "2000000",
        ),
    ] {
        let r = run(args);
        assert!(
            !r.ok() && r.stderr.contains(why),
            "{args:?}: '{why}' missing in {}",
            r.stderr
        );
    }
    // A light the automatic rescale puts out of range: the file is named,
    // and the rescale that did it.
    d.write("tri.obj", TRI);
    d.write("tiny.toml", scene_with("tri.obj", "scale = 1e-300"));
    std::fs::remove_file(d.path("t.png")).unwrap();
    let r = run(&["render", "tiny.toml", "--size", "8x8", "-o", "t.png"]);
    assert!(
        r.code == Some(1)
            && r.stderr
                .contains("tiny.toml: light 1 is beyond f32's range")
            && r.stderr
                .contains("note: tiny.toml: the scene is 1e-300 across"),
        "{}",
        r.stderr
    );
    assert!(!d.path("t.png").exists());
}

#[test]
fn cube_faces_of_unequal_sizes_are_warned_about() {
    let d = Dir::new("hostile-faces");
    let hdr = |w: usize, h: usize| {
        let mut b = format!("#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y {h} +X {w}\n").into_bytes();
        b.extend([128u8, 128, 128, 129].repeat(w * h));
        b
    };
    d.write("tri.obj", TRI);
    d.write("a.hdr", hdr(2, 2));
    d.write("b.hdr", hdr(1, 1));
    clean(&d.write(
        "same.toml",
        scene_with("tri.obj", &FACES.replace("F", "a.hdr")),
    ));
    let mixed = FACES.replacen("F", "b.hdr", 2).replace("F", "a.hdr");
    warned(
        &d.write("mixed.toml", scene_with("tri.obj", &mixed)),
        &["mixed.toml: environment faces are not squares of one size (posx 1x1, negx 1x1, posy 2x2, "],
    );
}

/// A fault repeated throughout a file is one warning that says how often
/// it came, not one line per repeat.
#[test]
fn a_repeated_fault_is_one_warning_with_its_count() {
    let d = Dir::new("repeats");
    let obj = d.write(
        "r.obj",
        format!("{}{TRI}", "mtllib nowhere.mtl\n".repeat(1000)),
    );
    let s = load(&obj).unwrap_or_else(|e| panic!("{e}"));
    let about: Vec<_> = s
        .warnings
        .iter()
        .filter(|w| w.contains("nowhere.mtl"))
        .collect();
    assert_eq!(about.len(), 1, "{} warnings", s.warnings.len());
    assert!(about[0].contains("r.obj:1: "), "{about:?}");
    assert!(about[0].ends_with("(and 999 more like it)"), "{about:?}");
}

/// An `[environment]` table that gives nothing is said to leave the
/// background black, rather than passed over.
#[test]
fn an_empty_environment_is_a_warning() {
    let d = Dir::new("empty-env");
    d.write("tri.obj", TRI);
    let s = d.write("env.toml", scene_with("tri.obj", "[environment]\n"));
    warned(&s, &["env.toml: environment: none of color", "stays black"]);
    let s = d.write(
        "sky.toml",
        scene_with("tri.obj", "[environment]\nsky = true\n"),
    );
    clean(&s);
}

#[test]
fn ply_elements_without_properties_are_skipped_without_looping() {
    let d = Dir::new("hostile-ply-empty");
    let head = |format: &str| {
        format!(
            "ply\nformat {format} 1.0\nelement vertex 3\nproperty float x\nproperty float y\n\
             property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
             element junk 9223372036854775807\nend_header\n"
        )
    };
    let mut binary = head("binary_little_endian").into_bytes();
    for x in [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0] {
        binary.extend(x.to_le_bytes());
    }
    binary.push(3);
    for i in 0i32..3 {
        binary.extend(i.to_le_bytes());
    }
    let ascii = head("ascii") + "0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n";
    for (name, bytes) in [("junk.ply", binary), ("junk-ascii.ply", ascii.into_bytes())] {
        let s = warned(
            &d.write(name, bytes),
            &[
                name,
                "ignored, not used: element junk (9223372036854775807)",
            ],
        );
        assert_eq!(s.geometry.indices().len(), 1, "{name}");
    }
}

/// A binary PLY of `n` vertices of `char` coordinates, all zero but the
/// first triangle's (3 bytes each: the file is sparse), and that triangle.
fn char_ply(d: &Dir, name: &str, n: u64) -> String {
    use std::io::{Seek, Write};
    let head = format!(
        "ply\nformat binary_little_endian 1.0\nelement vertex {n}\nproperty char x\n\
         property char y\nproperty char z\nelement face 1\n\
         property list uchar int vertex_indices\nend_header\n"
    );
    let p = d.path(name);
    let mut f = std::fs::File::create(&p).unwrap();
    f.write_all(head.as_bytes()).unwrap();
    f.write_all(&[0, 0, 0, 1, 0, 0, 0, 1, 0]).unwrap();
    f.seek(std::io::SeekFrom::Start(head.len() as u64 + 3 * n))
        .unwrap();
    f.write_all(&[3]).unwrap();
    for i in 0i32..3 {
        f.write_all(&i.to_le_bytes()).unwrap();
    }
    p.to_str().unwrap().to_string()
}

/// Under an address space limit (`ulimit -v`), what a scene would need is
/// refused with the reason before it is allocated, never an allocation
/// abort: vertices as well as triangles, glTF instances of one large
/// accessor each counted, the meshes of a scene file together; and a
/// texture many materials share is held once.
#[test]
fn memory_is_checked_for_the_whole_scene_under_an_address_space_limit() {
    const LIMIT: u64 = 1 << 30;
    let d = Dir::new("hostile-memory");
    let render = |scene: &str| {
        let args = [
            "render", scene, "--size", "8x8", "--spp", "1", "-o", "out.png",
        ];
        rayterm_within(LIMIT, &d.0, &args)
    };
    let refused = |scene: &str, parts: &[&str]| {
        let r = render(scene);
        assert_eq!(r.code, Some(1), "{scene}: {}", r.stderr);
        for p in parts {
            assert!(
                r.stderr.contains(p),
                "{scene}: '{p}' missing in: {}",
                r.stderr
            );
        }
        assert!(!d.path("out.png").exists());
    };
    // 30 million vertices in 90 MB: 2 GiB once read.
    let ply = char_ply(&d, "chars.ply", 30_000_000);
    refused(
        &ply,
        &[
            "chars.ply: 1 triangles and 30000000 vertices would need 2.01 GiB of memory;",
            "is available",
        ],
    );
    // Three meshes that fit one at a time and not together.
    for name in ["a.ply", "b.ply", "c.ply"] {
        char_ply(&d, name, 10_000_000);
    }
    let toml = ["a", "b", "c"]
        .map(|m| format!("[[mesh]]\nfile = \"{m}.ply\"\n"))
        .concat();
    let s = d.write("three.toml", toml);
    refused(
        &s,
        &[
            "three.toml:",
            "mesh ",
            ".ply: 1 triangles and 10000000 vertices would need",
        ],
    );
    // 300 instances of a 100,000-vertex accessor: 30 million vertices.
    let n = 100_000u32;
    let mut bin = Vec::new();
    for i in 0..n {
        for x in [i as f32, (i % 7) as f32, 0.0] {
            bin.extend(x.to_le_bytes());
        }
    }
    for i in [0u32, 1, 2] {
        bin.extend(i.to_le_bytes());
    }
    d.write("inst.bin", &bin);
    let gltf = serde_json::json!({
        "asset": {"version": "2.0"}, "scene": 0,
        "scenes": [{"nodes": (0..300).collect::<Vec<_>>()}],
        "nodes": (0..300).map(|k| serde_json::json!({"mesh": 0, "translation": [k, 0, 0]})).collect::<Vec<_>>(),
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": n, "type": "VEC3",
             "min": [0, 0, 0], "max": [n, 6, 0]},
            {"bufferView": 1, "componentType": 5125, "count": 3, "type": "SCALAR"}],
        "bufferViews": [{"buffer": 0, "byteLength": 12 * n},
                        {"buffer": 0, "byteOffset": 12 * n, "byteLength": 12}],
        "buffers": [{"uri": "inst.bin", "byteLength": bin.len()}]
    });
    let g = d.write("inst.gltf", serde_json::to_vec(&gltf).unwrap());
    refused(
        &g,
        &["inst.gltf: its meshes, each instance counted: 300 triangles and 30000000 vertices would need"],
    );
    // A 2000x2000 texture in 50 materials: 46 MiB once, not 2.3 GiB.
    let img = image::RgbImage::from_fn(2000, 2000, |x, y| image::Rgb([x as u8, y as u8, 7]));
    img.save(d.path("big.png")).unwrap();
    let mut tri = Vec::new();
    for x in [
        0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0,
    ] {
        tri.extend(x.to_le_bytes());
    }
    d.write("tex.bin", &tri);
    let gltf = serde_json::json!({
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": (0..50).map(|m| serde_json::json!(
            {"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": m})).collect::<Vec<_>>()}],
        "materials": (0..50).map(|m| serde_json::json!({"pbrMetallicRoughness": {
            "baseColorTexture": {"index": 0}, "baseColorFactor": [1.0, m as f64 / 50.0, 1.0, 1.0]}}))
            .collect::<Vec<_>>(),
        "textures": [{"source": 0}], "images": [{"uri": "big.png"}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}],
        "bufferViews": [{"buffer": 0, "byteLength": 36},
                        {"buffer": 0, "byteOffset": 36, "byteLength": 24}],
        "buffers": [{"uri": "tex.bin", "byteLength": 60}]
    });
    let t = d.write("tex.gltf", serde_json::to_vec(&gltf).unwrap());
    let r = render(&t);
    assert!(r.ok(), "{}", r.stderr);
}

/// A glTF of one triangle whose buffer is the file at `uri`.
fn gltf_with_buffer(uri: &str) -> String {
    serde_json::json!({
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}}]}],
        "accessors": [{"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                       "min": [0, 0, 0], "max": [1, 1, 0]}],
        "bufferViews": [{"buffer": 0, "byteLength": 36}],
        "buffers": [{"uri": uri, "byteLength": 36}]
    })
    .to_string()
}

/// Files outside a scene's folder: a glTF may not name them (unless
/// allowed), a scene file or material library may, with a warning naming
/// where they resolve; and no message ever quotes what such a file holds
/// (`/etc/passwd`, `/proc/self/environ`), nor more than a few hundred
/// characters of anything.
#[test]
fn files_outside_the_scene_are_refused_or_named_and_never_quoted() {
    let d = Dir::new("hostile-outside");
    const SECRET: &str = "hunter2";
    let secret = d.write("secret.txt", format!("root:x:0:0:{SECRET}:/root:/bin/sh\n"));
    let mut bin = vec![0xff; 4];
    bin.extend(format!("{SECRET}{SECRET}{SECRET}{SECRET}{SECRET}").as_bytes());
    d.write("secret.bin", bin);
    d.write("scene/tri.obj", TRI);
    let never_quoted = |what: &str, text: &str| {
        assert!(!text.contains(SECRET), "{what}: {text}");
        assert!(!text.contains("root:x"), "{what}: {text}");
    };
    // glTF URIs are relative references within the glTF's folder.
    d.link("scene/link.bin", d.path("secret.bin"));
    for (name, uri) in [
        ("up.gltf", "../secret.bin".to_string()),
        ("absolute.gltf", d.path("secret.bin").display().to_string()),
        (
            "file.gltf",
            format!("file://{}", d.path("secret.bin").display()),
        ),
        ("link.gltf", "link.bin".to_string()),
    ] {
        let g = d.write(&format!("scene/{name}"), gltf_with_buffer(&uri));
        let e = refused(
            &g,
            &[name, "buffer 0: its uri ", &uri, "leaves the glTF's folder"],
        );
        never_quoted(name, &e);
    }
    // Allowed, it is read, and what it holds is still not quoted.
    let r = rayterm(
        &d.path("scene"),
        &["render", "up.gltf", "--allow-outside", "-o", "x.png"],
    );
    assert_eq!(r.code, Some(1), "{}", r.stderr);
    assert!(
        r.stderr
            .contains("position 0 is (not shown: its buffer lies outside the glTF's folder)"),
        "{}",
        r.stderr
    );
    never_quoted("--allow-outside", &r.stderr);
    // Scene files and material libraries may name files outside, said.
    for (name, file) in [
        ("passwd.toml", secret.as_str()),
        ("up.toml", "../secret.txt"),
    ] {
        let s = d.write(&format!("scene/{name}"), scene_with(file, ""));
        let e = refused(&s, &[name, "lies outside", "not shown"]);
        never_quoted(name, &e);
    }
    // Its error says where, not what.
    d.write(
        "bad.obj",
        format!("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 {SECRET}\n"),
    );
    let s = d.write("scene/bad.toml", scene_with("../bad.obj", ""));
    let e = refused(
        &s,
        &[
            "bad.toml:1:1: mesh ../bad.obj: ",
            "bad.obj:4: not read as an OBJ mesh; why is not shown",
        ],
    );
    never_quoted("bad.toml", &e);
    let s = d.write("scene/environ.toml", scene_with("/proc/self/environ", ""));
    let e = refused(
        &s,
        &[
            "environ.toml:1:1: mesh /proc/self/environ",
            "it holds more than its size says",
        ],
    );
    assert!(!e.contains("PATH="), "{e}");
    for (name, obj, mtl) in [
        (
            "lib.obj",
            "mtllib ../secret.txt\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n",
            None,
        ),
        (
            "map.obj",
            WITH_MTL,
            Some("newmtl a\nmap_Kd ../secret.txt\n"),
        ),
    ] {
        if let Some(mtl) = mtl {
            d.write("scene/m.mtl", mtl);
        }
        let s = warned(
            &d.write(&format!("scene/{name}"), obj),
            &["lies outside", "secret.txt"],
        );
        never_quoted(name, &s.warnings.join("\n"));
    }
    // A ten-megabyte key is not echoed whole.
    let key = "k".repeat(10 << 20);
    let s = d.write("scene/key.toml", format!("{key} = 1\n"));
    let e = refused(&s, &["key.toml:1:1: unknown field `kkk"]);
    assert!(e.len() < 2000, "{} bytes", e.len());
}

/// A comb of `teeth` teeth as one OBJ polygon: concave, so clipped.
fn comb(teeth: usize) -> String {
    let mut obj = String::from("v 0 -1 0\n");
    for k in 0..teeth {
        obj += &format!("v {k} 0 0\nv {k}.5 5 0\n");
    }
    obj += &format!("v {teeth} -1 0\nf");
    for i in (1..=2 * teeth + 2).rev() {
        obj += &format!(" {i}");
    }
    obj + "\n"
}

#[test]
fn huge_concave_polygons_load_in_time() {
    let d = Dir::new("hostile-polygons");
    // Clipped: every tooth apart, no warning.
    let s = clean(&d.write("comb.obj", comb(30_000)));
    assert_eq!(s.geometry.indices().len(), 2 * 30_000);
    // Too many corners to clip: a fan, said once.
    let s = warned(
        &d.write("huge.obj", comb(40_000)),
        &[
            "huge.obj:80003: a polygon",
            "more than 65536 corners: triangulated as a fan",
        ],
    );
    assert!(!s.geometry.indices().is_empty());
}
