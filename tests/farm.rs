//! A render farm's view: the files a scene reads (`rayterm inputs`).

mod files;

use std::path::Path;

use files::{rayterm, Dir, Run};
use glam::Vec3;
use rayterm::raster::Format;
use serde_json::json;

fn ok(d: &Path, args: &[&str]) -> Run {
    let r = rayterm(d, args);
    assert!(r.ok(), "{args:?}: {}", r.stderr);
    assert!(!r.stderr.contains("panicked"), "{args:?}: {}", r.stderr);
    r
}

/// A command that fails with status 1 and no panic; its standard error.
fn refused(d: &Path, args: &[&str]) -> String {
    let r = rayterm(d, args);
    assert_eq!(r.code, Some(1), "{args:?}: {}", r.stderr);
    assert!(!r.stderr.contains("panicked"), "{args:?}: {}", r.stderr);
    r.stderr
}

/// The lines `rayterm inputs` prints.
fn inputs(d: &Path, args: &[&str]) -> Vec<String> {
    let mut all = vec!["inputs"];
    all.extend(args);
    ok(d, &all).stdout.lines().map(str::to_string).collect()
}

/// A 2x2 PNG of one colour.
fn png(c: [u8; 3]) -> Vec<u8> {
    let img = image::RgbImage::from_pixel(2, 2, image::Rgb(c));
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

const OBJ: &str = "mtllib box.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
                   usemtl Wood\nf 1/1 2/2 3/3\n";

#[test]
fn inputs_lists_the_files_of_an_obj_with_its_mtl_and_texture() {
    let d = Dir::new("farm-inputs-obj");
    d.write("box.obj", OBJ);
    d.write("box.mtl", "newmtl Wood\nKd 1 1 1\nmap_Kd tex/wood.png\n");
    d.write("tex/wood.png", png([200, 120, 40]));
    assert_eq!(
        inputs(&d.0, &["box.obj"]),
        ["box.obj", "box.mtl", "tex/wood.png"]
    );
    // An absolute scene path gives absolute inputs.
    let abs = d.path("box.obj").display().to_string();
    let listed = inputs(&d.0, &[&abs]);
    assert_eq!(listed[2], d.path("tex/wood.png").display().to_string());
    // A built-in scene reads no file; a missing MTL is warned about and
    // not listed.
    assert!(inputs(&d.0, &["cornell"]).is_empty());
    std::fs::remove_file(d.path("box.mtl")).unwrap();
    let r = ok(&d.0, &["inputs", "box.obj"]);
    assert_eq!(r.stdout, "box.obj\n");
    assert!(r.stderr.contains("box.mtl"), "{}", r.stderr);
    // A scene that cannot be read is an error naming it.
    let err = refused(&d.0, &["inputs", "gone.obj"]);
    assert!(err.contains("gone.obj"), "{err}");
}

#[test]
fn inputs_lists_a_scene_files_meshes_and_environment_map() {
    let d = Dir::new("farm-inputs-toml");
    d.write("meshes/box.obj", OBJ);
    d.write("meshes/box.mtl", "newmtl Wood\nKd 1 1 1\nmap_Kd wood.png\n");
    d.write("meshes/wood.png", png([200, 120, 40]));
    d.write("meshes/tri.stl", stl());
    let sky = Format::Hdr
        .encode_linear(4, 2, &[Vec3::new(0.5, 0.6, 0.9); 8])
        .unwrap();
    d.write("env/sky.hdr", sky);
    d.write(
        "scene.toml",
        "[[mesh]]\nfile = \"meshes/box.obj\"\n\n[[mesh]]\nfile = \"meshes/tri.stl\"\n\n\
         [environment]\nmap = \"env/sky.hdr\"\n",
    );
    let listed = inputs(&d.0, &["scene.toml"]);
    let mut sorted = listed.clone();
    sorted.sort();
    assert_eq!(
        sorted,
        [
            "env/sky.hdr",
            "meshes/box.mtl",
            "meshes/box.obj",
            "meshes/tri.stl",
            "meshes/wood.png",
            "scene.toml"
        ],
        "{listed:?}"
    );
    assert_eq!(listed[0], "scene.toml");
    // --env's map is one too.
    let with_env = inputs(&d.0, &["meshes/tri.stl", "--env", "env/sky.hdr"]);
    assert_eq!(with_env.len(), 2, "{with_env:?}");
    assert!(
        with_env.contains(&"env/sky.hdr".to_string()),
        "{with_env:?}"
    );
}

/// A binary STL of one triangle.
fn stl() -> Vec<u8> {
    let mut b = vec![0u8; 80];
    b.extend(1u32.to_le_bytes());
    for v in [[0f32, 0., 1.], [0., 0., 0.], [1., 0., 0.], [0., 1., 0.]] {
        for x in v {
            b.extend(x.to_le_bytes());
        }
    }
    b.extend([0, 0]);
    b
}

#[test]
fn inputs_lists_a_gltf_with_its_buffer_and_images() {
    let d = Dir::new("farm-inputs-gltf");
    let mut bin = Vec::new();
    for v in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]] {
        for x in v {
            bin.extend(x.to_le_bytes());
        }
    }
    for uv in [[0f32, 0.], [1., 0.], [0., 1.]] {
        for x in uv {
            bin.extend(x.to_le_bytes());
        }
    }
    d.write("model/tri.bin", &bin);
    d.write("model/textures/base.png", png([255, 0, 0]));
    d.write("model/textures/normal.png", png([128, 128, 255]));
    let doc = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": 0}]}],
        "materials": [{
            "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}},
            "normalTexture": {"index": 1}
        }],
        "textures": [{"source": 0}, {"source": 1}],
        "images": [{"uri": "textures/base.png"}, {"uri": "textures/normal.png"}],
        "buffers": [{"uri": "tri.bin", "byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 24}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}
        ]
    });
    d.write("model/tri.gltf", serde_json::to_vec(&doc).unwrap());
    let mut listed = inputs(&d.0, &["model/tri.gltf"]);
    assert_eq!(listed[0], "model/tri.gltf");
    listed.sort();
    assert_eq!(
        listed,
        [
            "model/textures/base.png",
            "model/textures/normal.png",
            "model/tri.bin",
            "model/tri.gltf"
        ]
    );
}
