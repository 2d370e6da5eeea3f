//! Files other readers open as they are: OBJ vertices 32-bit floats cannot
//! hold (the faces using them left out), OBJ and MTL text in UTF-16, PLY
//! triangle strips and faces of fewer than three vertices, `map_Kd` options
//! and escaped spaces. Each opens with a warning naming the file (and
//! line), as does a `map_Kd` of options without a name; attacked (every
//! face using such a vertex, a byte-order mark and nothing else, huge
//! counts, cut files, strips of nothing but restarts), it is refused with a
//! message naming it: through the loader with a deadline, and through the
//! binary, which exits 1 without a panic.

use crate::files::{rayterm, within_deadline, Dir};
use glam::Vec3;
use rayterm::scene::{self, Scene, Wrap};

const CHECKER: &[u8] = include_bytes!("../../data/meshes/checker.png");

fn load(spec: &str) -> Result<Scene, String> {
    let s = spec.to_string();
    within_deadline(spec, move || {
        scene::load::open(&s, &Default::default())
            .map(|o| o.scene)
            .map_err(|e| format!("{e:#}"))
    })
}

/// The load succeeds, with exactly the warnings `want`.
fn warned(spec: &str, want: &[String]) -> Scene {
    let s = load(spec).unwrap_or_else(|e| panic!("{spec}: {e}"));
    assert_eq!(s.warnings, want, "{spec}");
    s
}

/// The binary refuses `file`: exit status 1, a message holding every one
/// of `parts`, no panic.
fn refused(d: &Dir, file: &str, parts: &[&str]) {
    let out = d.path("out.png");
    let args = ["render", file, "--size", "8x6", "--spp", "1", "-o"];
    let r = rayterm(&d.0, &[&args[..], &[out.to_str().unwrap()]].concat());
    assert_eq!(r.code, Some(1), "{file}: {}", r.stderr);
    assert!(!r.stderr.contains("panicked"), "{file}: {}", r.stderr);
    for p in parts {
        assert!(
            r.stderr.contains(p),
            "{file}: '{p}' missing in: {}",
            r.stderr
        );
    }
}

/// Text as UTF-16 with its byte-order mark.
fn utf16(text: &str, big: bool) -> Vec<u8> {
    let mark: &[u8] = if big { &[0xFE, 0xFF] } else { &[0xFF, 0xFE] };
    let units = text.encode_utf16().flat_map(|u| match big {
        true => u.to_be_bytes(),
        false => u.to_le_bytes(),
    });
    mark.iter().copied().chain(units).collect()
}

const QUAD: &str = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";

#[test]
fn obj_faces_using_vertices_beyond_f32_are_left_out() {
    let d = Dir::new("tolerant-nonfinite");
    let obj = d.write(
        "nan.obj",
        format!("{QUAD}v inf nan 0\nv 1e39 0 0\nv 2 0 0 1.#IND\nf 1 2 5\nf 2 6 3\nf 7 3 4\n"),
    );
    let s = warned(
        &obj,
        &[format!(
            "{obj}:6: vertex 'inf' is not a finite number (and 2 more vertices like it): 3 \
             faces using them skipped"
        )],
    );
    assert_eq!(s.geometry.indices().len(), 2);
    assert!(s.geometry.positions().iter().all(|p| p.is_finite()));
    // Every face uses one: nothing left to draw, and said why.
    let all = d.write("all.obj", "v nan 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    refused(
        &d,
        &all,
        &[&format!("{all}: no triangles ({all}:1: vertex 'nan' is not a finite number: 1 face using it skipped)")],
    );
}

#[test]
fn utf16_obj_and_mtl_files_are_decoded() {
    let d = Dir::new("tolerant-utf16");
    let mtl = "newmtl rouge\r\nKd 1 0 0\r\n";
    let obj = format!(
        "mtllib m.mtl\r\nusemtl rouge\r\n{}",
        QUAD.replace('\n', "\r\n")
    );
    for big in [false, true] {
        let order = if big { "big-endian" } else { "little-endian" };
        let m = d.write("m.mtl", utf16(mtl, big));
        let o = d.write("m.obj", utf16(&obj, big));
        let said =
            |f: &str| format!("{f}: UTF-16 text ({order}, as its byte-order mark says): decoded");
        let s = warned(&o, &[said(&o), said(&m)]);
        assert_eq!(s.geometry.indices().len(), 2);
        assert_eq!(
            s.materials[s.geometry.tri_material()[0] as usize].kd,
            Vec3::X
        );
    }
    // A UTF-8 mark goes without a word.
    let o = d.write("utf8.obj", format!("\u{feff}{QUAD}"));
    warned(&o, &[]);
    // A mark and nothing else, or an odd byte after it: an empty file.
    for (name, bytes) in [
        ("mark.obj", vec![0xFF, 0xFE]),
        ("odd.obj", vec![0xFE, 0xFF, b'v']),
    ] {
        let o = d.write(name, bytes);
        refused(&d, &o, &[&format!("{o}: no triangles ({o}: UTF-16 text")]);
    }
}

const STRIP_HEAD: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n\
                          property float y\nproperty float z\nelement tristrips 1\n\
                          property list int int vertex_indices\nend_header\n\
                          0 0 0\n1 0 0\n0 1 0\n1 1 0\n";

#[test]
fn ply_triangle_strips_and_short_faces_are_read_as_other_readers_read_them() {
    let d = Dir::new("tolerant-ply");
    let p = d.write("strip.ply", format!("{STRIP_HEAD}4 0 1 2 3\n"));
    let s = warned(&p, &[]);
    assert_eq!(s.geometry.indices(), [[0, 1, 2], [2, 1, 3]]);
    let face = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\nproperty float y\n\
                property float z\nelement face 3\nproperty list uchar int vertex_indices\n\
                end_header\n0 0 0\n1 0 0\n1 1 0\n0 1 0\n2 0 1\n4 0 1 2 3\n0\n";
    let p = d.write("short.ply", face);
    let s = warned(
        &p,
        &[format!(
            "{p}:14: element face 0: a face of 2 vertices (and 1 more of fewer than 3): skipped"
        )],
    );
    assert_eq!(s.geometry.indices().len(), 2);
    // Attacked: nothing but restarts, an index past the vertices, a count
    // past the file (ASCII; binary, where it is past memory too).
    for (name, body, want) in [
        ("restarts.ply", "3 -1 -1 -1\n", "no triangles"),
        (
            "range.ply",
            "3 0 1 4\n",
            ":14: element tristrips 0 (of 1), vertex_indices: vertex index 4 is out of range",
        ),
        (
            "long.ply",
            "1000 0 1 2\n",
            ":14: element tristrips 0 (of 1), vertex_indices: the line ends",
        ),
    ] {
        let p = d.write(name, format!("{STRIP_HEAD}{body}"));
        refused(&d, &p, &[&p, want]);
    }
    let mut binary = STRIP_HEAD
        .split_once("end_header\n")
        .unwrap()
        .0
        .replace("ascii", "binary_little_endian")
        .into_bytes();
    binary.extend(b"end_header\n");
    binary.extend([0f32; 12].iter().flat_map(|x| x.to_le_bytes()));
    binary.extend(i32::MAX.to_le_bytes());
    binary.extend(1i32.to_le_bytes());
    let p = d.write("cut.ply", &binary);
    refused(
        &d,
        &p,
        &[
            &format!("{p} (byte "),
            "element tristrips 0 (of 1), vertex_indices: ",
        ],
    );
}

#[test]
fn map_kd_options_and_escaped_spaces_are_read() {
    let d = Dir::new("tolerant-mtl");
    d.write("my texture.png", CHECKER);
    d.write(
        "m.mtl",
        "newmtl a\nmap_Kd -s 1 1 1 -o 0 0 0 -bm 0.5 -clamp on my\\ texture.png\n\
         newmtl b\nmap_Kd -blendu off -colorspace sRGB my texture.png\n\
         newmtl c\nKd 0.5 0.5 0.5\nmap_Kd -clamp on -s 2 2\n",
    );
    let o = d.write(
        "m.obj",
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 2 0\nvt 0 2\n\
         usemtl a\nf 1/1 2/2 3/3\nusemtl b\nf 1/1 3/3 2/2\nusemtl c\nf 1 2 3\n",
    );
    let m = d.path("m.mtl").display().to_string();
    let s = warned(
        &o,
        &[
            format!("{m}:2: map_Kd options ignored: -s 1 1 1, -o 0 0 0, -bm 0.5 (the texture is applied as is)"),
            format!("{m}:4: map_Kd options ignored: -blendu off, -colorspace sRGB (the texture is applied as is)"),
            format!("{m}:7: map_Kd names no file: ignored (Kd is used)"),
        ],
    );
    let wrap = |name: &str| {
        let m = s.materials.iter().find(|m| m.name == name).unwrap();
        m.texture.map(|t| s.textures[t as usize].wrap)
    };
    // One image, its texels held once, clamped where `-clamp on` says so.
    assert_eq!(wrap("a"), Some([Wrap::Clamp; 2]));
    assert_eq!(wrap("b"), Some([Wrap::Repeat; 2]));
    assert_eq!(wrap("c"), None);
    let [a, b] = ["a", "b"].map(|n| {
        let t = s
            .materials
            .iter()
            .find(|m| m.name == n)
            .unwrap()
            .texture
            .unwrap();
        s.textures[t as usize].texels.clone()
    });
    assert!(std::sync::Arc::ptr_eq(&a, &b));
}

/// An OBJ of lines and points alone is refused saying so (its curves are
/// not drawn); beside faces they are no fault and go unsaid.
#[test]
fn an_obj_of_lines_and_points_says_why_it_draws_nothing() {
    let d = Dir::new("obj-lines");
    let wire = d.write(
        "wire.obj",
        "v 0 0 0\nv 1 0 0\nv 1 1 0\nl 1 2 3\np 1\nl 2 3\n",
    );
    refused(
        &d,
        &wire,
        &[
            "wire.obj: no triangles",
            "wire.obj:4: 3 lines and points: not drawn (rayterm draws faces)",
        ],
    );
    let both = d.write("both.obj", format!("{QUAD}l 1 2\np 3\n"));
    warned(&both, &[]);
}
