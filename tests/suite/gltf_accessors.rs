//! glTF files as other tools write them: attributes rayterm does not use
//! (custom `_NAME` ones among them), sparse accessors, quantized attributes
//! (`KHR_mesh_quantization`), views compressed with meshoptimizer
//! (`EXT_meshopt_compression`: real files gltfpack wrote, in
//! tests/files/gltfpack), required extensions rayterm does not read, and
//! Draco. Each opens, or is refused with a message that says why.

use crate::files::{within_deadline, Dir};
use glam::{Vec2, Vec3};
use rayterm::scene::{self, Scene};
use serde_json::{json, Value};

fn load(spec: &str) -> Result<Scene, String> {
    let s = spec.to_string();
    within_deadline(spec, move || {
        scene::load::open(&s, &Default::default())
            .map(|o| o.scene)
            .map_err(|e| format!("{e:#}"))
    })
}

/// A buffer being filled, and the views of what was put in it.
#[derive(Default)]
struct Bin {
    bytes: Vec<u8>,
    views: Vec<Value>,
}

impl Bin {
    /// Puts `data` in a view of its own (4-byte aligned); its index.
    fn put(&mut self, data: &[u8]) -> usize {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        self.views
            .push(json!({"buffer": 0, "byteOffset": self.bytes.len(), "byteLength": data.len()}));
        self.bytes.extend(data);
        self.views.len() - 1
    }
}

fn f32s(v: &[f32]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn u16s(v: &[u16]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

fn i16s(v: &[i16]) -> Vec<u8> {
    v.iter().flat_map(|x| x.to_le_bytes()).collect()
}

const QUAD: [f32; 12] = [
    -0.5, -0.5, 0.0, 0.5, -0.5, 0.0, 0.5, 0.5, 0.0, -0.5, 0.5, 0.0,
];

/// A unit quad: accessor 0 its positions (floats), 1 its u16 indices;
/// more accessors and attributes are added by the tests.
fn quad() -> (Value, Bin) {
    let mut bin = Bin::default();
    let p = bin.put(&f32s(&QUAD));
    let i = bin.put(&u16s(&[0, 1, 2, 0, 2, 3]));
    let json = json!({
        "asset": {"version": "2.0"}, "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {"bufferView": p, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [-0.5, -0.5, 0.0], "max": [0.5, 0.5, 0.0]},
            {"bufferView": i, "componentType": 5123, "count": 6, "type": "SCALAR"}
        ]
    });
    (json, bin)
}

/// Adds an accessor to `json`; its index.
fn accessor(json: &mut Value, a: Value) -> usize {
    let list = json["accessors"].as_array_mut().unwrap();
    list.push(a);
    list.len() - 1
}

/// The .glb of `json` over `bin`.
fn glb(json: &Value, bin: &Bin) -> Vec<u8> {
    let mut json = json.clone();
    json["bufferViews"] = bin.views.clone().into();
    json["buffers"] = json!([{"byteLength": bin.bytes.len()}]);
    glb_of(&json, &bin.bytes)
}

fn glb_of(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(json).unwrap();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut bin = bin.to_vec();
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let mut b = b"glTF".to_vec();
    b.extend(2u32.to_le_bytes());
    b.extend(((12 + 8 + j.len() + 8 + bin.len()) as u32).to_le_bytes());
    b.extend((j.len() as u32).to_le_bytes());
    b.extend(b"JSON");
    b.extend(&j);
    b.extend((bin.len() as u32).to_le_bytes());
    b.extend(b"BIN\0");
    b.extend(&bin);
    b
}

/// The JSON and binary chunk of a .glb.
fn chunks(glb: &[u8]) -> (Value, Vec<u8>) {
    let n = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
    let json = serde_json::from_slice(&glb[20..20 + n]).unwrap();
    (json, glb[20 + n + 8..].to_vec())
}

fn warned(s: &Scene, want: &str) -> bool {
    s.warnings.iter().any(|w| w.contains(want))
}

fn near3(a: Vec3, b: Vec3, tolerance: f32) -> bool {
    (a - b).abs().max_element() <= tolerance
}

#[test]
fn attributes_rayterm_does_not_use_are_ignored() {
    let d = Dir::new("gltf-attributes");
    let (plain, bin) = quad();
    let mut json = plain.clone();
    let uv = accessor(
        &mut json,
        json!({"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC2"}),
    );
    // Cesium's feature ids, Blender's custom attributes, and semantics
    // glTF defines that rayterm does not draw.
    json["meshes"][0]["primitives"][0]["attributes"] = json!({
        "POSITION": 0, "_FEATURE_ID_0": 0, "_PRESSURE": 0, "TEXCOORD_1": uv,
        "JOINTS_0": 0, "WEIGHTS_0": 0, "COLOR_1": 0, "TANGENT": 0
    });
    let s = load(&d.write("custom.glb", glb(&json, &bin))).unwrap();
    let reference = load(&d.write("plain.glb", glb(&plain, &bin))).unwrap();
    assert_eq!(s.geometry.positions(), reference.geometry.positions());
    assert_eq!(s.geometry.indices(), reference.geometry.indices());
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    // A name glTF does not define at all: read all the same, and said.
    json["meshes"][0]["primitives"][0]["attributes"]["FOO"] = 0.into();
    let s = load(&d.write("foo.glb", glb(&json, &bin))).unwrap();
    assert_eq!(s.geometry.positions(), reference.geometry.positions());
    assert!(
        warned(
            &s,
            "vertex attributes whose names glTF does not define (mesh 0 primitive 0)"
        ),
        "{:?}",
        s.warnings
    );
}

#[test]
fn sparse_accessors_are_read_with_their_substitutions() {
    let d = Dir::new("gltf-sparse");
    let (mut json, mut bin) = quad();
    // Positions 1 and 2 lifted; over the base view.
    let ix = bin.put(&[1u8, 2]);
    let values = bin.put(&f32s(&[0.5, -0.5, 0.25, 0.5, 0.5, 0.25]));
    json["accessors"][0]["sparse"] = json!({"count": 2,
        "indices": {"bufferView": ix, "componentType": 5121}, "values": {"bufferView": values}});
    // Without a view, the base values are zeros.
    let all = bin.put(&u16s(&[0, 1, 2, 3]));
    let up = bin.put(&f32s(&[0.0, 0.0, 1.0].repeat(4)));
    let normal = accessor(
        &mut json,
        json!({"componentType": 5126, "count": 4, "type": "VEC3",
        "sparse": {"count": 4, "indices": {"bufferView": all, "componentType": 5123},
                   "values": {"bufferView": up}}}),
    );
    let three = bin.put(&u16s(&[3]));
    let red = bin.put(&[255u8, 0, 0, 0]);
    let color = accessor(
        &mut json,
        json!({"componentType": 5121, "normalized": true, "count": 4,
        "type": "VEC3", "sparse": {"count": 1, "indices": {"bufferView": three, "componentType": 5123},
                                   "values": {"bufferView": red}}}),
    );
    let two = bin.put(&[2u8]);
    let uv = bin.put(&f32s(&[0.25, 0.75]));
    let uvs = accessor(
        &mut json,
        json!({"componentType": 5126, "count": 4, "type": "VEC2",
        "sparse": {"count": 1, "indices": {"bufferView": two, "componentType": 5121},
                   "values": {"bufferView": uv}}}),
    );
    // The second triangle made (0, 3, 1) from (0, 2, 3).
    let at = bin.put(&u16s(&[4, 5]));
    let corners = bin.put(&u16s(&[3, 1]));
    json["accessors"][1]["sparse"] = json!({"count": 2,
        "indices": {"bufferView": at, "componentType": 5123}, "values": {"bufferView": corners}});
    json["meshes"][0]["primitives"][0]["attributes"] =
        json!({"POSITION": 0, "NORMAL": normal, "COLOR_0": color, "TEXCOORD_0": uvs});
    let s = load(&d.write("sparse.glb", glb(&json, &bin))).unwrap();
    let g = &s.geometry;
    assert_eq!(
        g.positions(),
        [
            Vec3::new(-0.5, -0.5, 0.0),
            Vec3::new(0.5, -0.5, 0.25),
            Vec3::new(0.5, 0.5, 0.25),
            Vec3::new(-0.5, 0.5, 0.0)
        ]
    );
    assert_eq!(g.indices(), [[0, 1, 2], [0, 3, 1]]);
    assert!(
        g.normals().iter().all(|&n| near3(n, Vec3::Z, 1e-6)),
        "{:?}",
        g.normals()
    );
    assert_eq!(g.colors(), [Vec3::ZERO, Vec3::ZERO, Vec3::ZERO, Vec3::X]);
    // glTF's v runs down the image, rayterm's up.
    assert_eq!(g.uvs(), [Vec2::Y, Vec2::Y, Vec2::new(0.25, 0.25), Vec2::Y]);

    // Sparse indices are checked as every index is; their views as every view.
    let (base, bin) = (json, bin);
    let edit = |name: &str, f: &dyn Fn(&mut Value, &mut Bin)| {
        let (mut j, mut b) = (
            base.clone(),
            Bin {
                bytes: bin.bytes.clone(),
                views: bin.views.clone(),
            },
        );
        f(&mut j, &mut b);
        load(&d.write(name, glb(&j, &b)))
            .err()
            .unwrap_or_else(|| panic!("{name} loaded"))
    };
    let here = "mesh 0 primitive 0 (node 0): POSITION (accessor 0)";
    let e = edit("down.glb", &|j, b| {
        j["accessors"][0]["sparse"]["indices"]["bufferView"] = b.put(&[2u8, 1]).into();
    });
    assert!(
        e.contains(&format!(
            "down.glb: {here}: sparse index 1 is 1, not above the one before (2)"
        )),
        "{e}"
    );
    let e = edit("range.glb", &|j, b| {
        j["accessors"][0]["sparse"]["indices"]["bufferView"] = b.put(&[1u8, 9]).into();
    });
    assert!(
        e.contains(&format!(
            "{here}: sparse index 1 is 9, out of range (4 elements)"
        )),
        "{e}"
    );
    let e = edit("short.glb", &|j, b| {
        j["accessors"][0]["sparse"]["values"]["bufferView"] = b.put(&f32s(&[0.0; 4])).into();
    });
    assert!(
        e.contains(&format!(
            "{here}: its 2 sparse values end at byte 24 of a 16-byte buffer view"
        )),
        "{e}"
    );
    let e = edit("many.glb", &|j, _| {
        j["accessors"][0]["sparse"]["count"] = 5.into()
    });
    assert!(
        e.contains(&format!("{here}: 5 sparse values for 4 elements")),
        "{e}"
    );
    let e = edit("kind.glb", &|j, _| {
        j["accessors"][0]["sparse"]["indices"]["componentType"] = 5126.into()
    });
    assert!(e.contains("kind.glb: not a valid glTF file"), "{e}");
    // Counts without a view to bound them are checked before anything is
    // allocated for them.
    let e = edit("huge.glb", &|j, _| {
        j["accessors"][normal]["count"] = 1_000_000_000_000u64.into()
    });
    assert!(
        e.contains(&format!(
            "NORMAL (accessor {normal}) has 1000000000000 values for 4 positions"
        )),
        "{e}"
    );
    let e = edit("vast.glb", &|j, _| {
        j["accessors"][0] = json!({"componentType": 5126, "count": 4_000_000_000u64, "type": "VEC3",
            "min": [0, 0, 0], "max": [1, 1, 1],
            "sparse": {"count": 1, "indices": {"bufferView": two, "componentType": 5121},
                       "values": {"bufferView": up}}});
        j["meshes"][0]["primitives"][0]["attributes"] = json!({"POSITION": 0});
    });
    assert!(e.contains("vast.glb: its meshes, each instance counted: 2 triangles and 4000000000 vertices would need"), "{e}");
}

#[test]
fn accessors_without_a_view_are_zeros() {
    let d = Dir::new("gltf-viewless");
    let (mut json, mut bin) = quad();
    // Positions on a zero base, three of them moved by sparse values: the
    // first corner stays at the origin.
    let moved = bin.put(&[1u8, 2, 3]);
    let values = bin.put(&f32s(&[1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0]));
    json["accessors"][0] = json!({"componentType": 5126, "count": 4, "type": "VEC3",
        "min": [0, 0, 0], "max": [1, 1, 0],
        "sparse": {"count": 3, "indices": {"bufferView": moved, "componentType": 5121},
                   "values": {"bufferView": values}}});
    // Neither a view nor sparse values: zeros, as glTF says.
    let uv = accessor(
        &mut json,
        json!({"componentType": 5126, "count": 4, "type": "VEC2"}),
    );
    json["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = uv.into();
    let s = load(&d.write("zeros.glb", glb(&json, &bin))).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let g = &s.geometry;
    assert_eq!(
        g.positions(),
        [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y]
    );
    assert_eq!(g.indices(), [[0, 1, 2], [0, 2, 3]]);
    // glTF's v runs down the image, rayterm's up.
    assert_eq!(g.uvs(), [Vec2::Y; 4]);

    // Positions all zeros: a file of nothing but degenerate triangles.
    let mut flat = json.clone();
    flat["accessors"][0] = json!({"componentType": 5126, "count": 4, "type": "VEC3",
        "min": [0, 0, 0], "max": [0, 0, 0]});
    let e = load(&d.write("flat.glb", glb(&flat, &bin))).unwrap_err();
    assert!(
        e.contains("flat.glb: no triangles (mesh 0 (node 0): skipped 2 degenerate"),
        "{e}"
    );
    // Without a view, counts are still checked before anything is
    // allocated for them.
    let mut huge = flat.clone();
    huge["accessors"][0]["count"] = 4_000_000_000u64.into();
    huge["meshes"][0]["primitives"][0]["attributes"] = json!({"POSITION": 0});
    let e = load(&d.write("huge.glb", glb(&huge, &bin))).unwrap_err();
    assert!(
        e.contains("huge.glb: its meshes, each instance counted: 2 triangles and 4000000000 vertices would need"),
        "{e}"
    );
    let mut many = json.clone();
    many["accessors"][uv]["count"] = 1_000_000_000_000u64.into();
    let e = load(&d.write("many.glb", glb(&many, &bin))).unwrap_err();
    assert!(
        e.contains(&format!(
            "TEXCOORD_0 (accessor {uv}) has 1000000000000 values for 4 positions"
        )),
        "{e}"
    );

    // A primitive without POSITION is not drawn, as glTF asks; the mesh's
    // others are.
    let mut partial = json.clone();
    partial["meshes"][0]["primitives"]
        .as_array_mut()
        .unwrap()
        .push(json!({"attributes": {"TEXCOORD_0": uv}}));
    let s = load(&d.write("partial.glb", glb(&partial, &bin))).unwrap();
    assert_eq!(s.geometry.indices().len(), 2);
    assert!(
        warned(&s, "partial.glb: not shown, rayterm has no equivalent: primitives without POSITION (mesh 0 primitive 1)"),
        "{:?}",
        s.warnings
    );
    // A missing field glTF requires is still refused.
    let mut typeless = json.clone();
    typeless["accessors"][uv]
        .as_object_mut()
        .unwrap()
        .remove("type");
    let e = load(&d.write("typeless.glb", glb(&typeless, &bin))).unwrap_err();
    assert!(e.contains("typeless.glb: not a valid glTF file"), "{e}");
}

#[test]
fn accessors_not_aligned_to_their_components_are_read_with_a_warning() {
    let d = Dir::new("gltf-misaligned");
    let (plain, _) = quad();
    let mut json = plain.clone();
    let mut bin = Bin::default();
    // Positions one byte into their view, indices one byte into theirs.
    let p = bin.put(&[[7u8].as_slice(), &f32s(&QUAD)].concat());
    let i = bin.put(&[[7u8].as_slice(), &u16s(&[0, 1, 2, 0, 2, 3])].concat());
    json["accessors"][0]["bufferView"] = p.into();
    json["accessors"][0]["byteOffset"] = 1.into();
    json["accessors"][1]["bufferView"] = i.into();
    json["accessors"][1]["byteOffset"] = 1.into();
    let s = load(&d.write("misaligned.glb", glb(&json, &bin))).unwrap();
    let (_, aligned) = quad();
    let reference = load(&d.write("aligned.glb", glb(&plain, &aligned))).unwrap();
    assert_eq!(s.geometry.positions(), reference.geometry.positions());
    assert_eq!(s.geometry.indices(), reference.geometry.indices());
    assert_eq!(
        s.warnings,
        [format!(
            "{}: mesh 0 primitive 0 (node 0): POSITION (accessor 0): its elements are not \
             aligned to their 4-byte components (offset 1, stride 12), which glTF requires \
             (and 1 more accessor): read all the same",
            d.path("misaligned.glb").display()
        )]
    );
    // A stride that is no multiple of the components is read alike.
    let mut strided = plain.clone();
    let mut bin = Bin::default();
    let mut bytes = Vec::new();
    for v in QUAD.chunks(3) {
        bytes.extend(f32s(v));
        bytes.push(0);
    }
    let p = bin.put(&bytes);
    bin.views[p]["byteStride"] = 13.into();
    bin.put(&u16s(&[0, 1, 2, 0, 2, 3]));
    strided["accessors"][0]["bufferView"] = p.into();
    let s = load(&d.write("strided.glb", glb(&strided, &bin))).unwrap();
    assert_eq!(s.geometry.positions(), reference.geometry.positions());
    assert!(
        warned(
            &s,
            "(offset 0, stride 13), which glTF requires: read all the same"
        ),
        "{:?}",
        s.warnings
    );
}

#[test]
fn quantized_attributes_are_read_as_normalised_or_plain_integers() {
    let d = Dir::new("gltf-quantized");
    let (mut json, mut bin) = quad();
    // gltfpack's layout: unsigned 16-bit positions, which the node's
    // transform scales back; normalised 8-bit normals; 16-bit UVs.
    let p = bin.put(&u16s(&[0, 0, 0, 1000, 0, 0, 1000, 1000, 0, 0, 1000, 0]));
    json["accessors"][0] = json!({"bufferView": p, "componentType": 5123, "count": 4, "type": "VEC3",
                                  "min": [0, 0, 0], "max": [1000, 1000, 0]});
    // Each 3-byte normal padded to 4 bytes, as vertex attributes are.
    let n = bin.put(&[0u8, 0, 127, 0, 0, 127, 0, 0, 129, 0, 0, 0, 0, 0, 127, 0]);
    bin.views[n]["byteStride"] = 4.into();
    let normal = accessor(
        &mut json,
        json!({"bufferView": n, "componentType": 5120, "normalized": true,
                                            "count": 4, "type": "VEC3"}),
    );
    let t = bin.put(&u16s(&[0, 0, 65535, 0, 65535, 65535, 0, 32768]));
    let uv = accessor(
        &mut json,
        json!({"bufferView": t, "componentType": 5123, "normalized": true,
                                        "count": 4, "type": "VEC2"}),
    );
    json["meshes"][0]["primitives"][0]["attributes"] =
        json!({"POSITION": 0, "NORMAL": normal, "TEXCOORD_0": uv});
    json["nodes"][0] =
        json!({"mesh": 0, "translation": [-0.5, -0.5, 0.0], "scale": [0.001, 0.001, 0.001]});
    json["extensionsUsed"] = json!(["KHR_mesh_quantization"]);
    json["extensionsRequired"] = json!(["KHR_mesh_quantization"]);
    let s = load(&d.write("quantized.glb", glb(&json, &bin))).unwrap();
    let g = &s.geometry;
    for (got, want) in g.positions().iter().zip(QUAD.chunks(3)) {
        assert!(
            near3(*got, Vec3::from_slice(want), 1e-6),
            "{:?}",
            g.positions()
        );
    }
    // -127 and 127 are -1 and 1 (placed normals are unit length).
    let want = [Vec3::Z, Vec3::Y, Vec3::NEG_X, Vec3::Z];
    for (got, want) in g.normals().iter().zip(want) {
        assert!(near3(*got, want, 1e-6), "{:?}", g.normals());
    }
    assert!(near3(
        g.uvs()[3].extend(0.0),
        Vec3::new(0.0, 1.0 - 32768.0 / 65535.0, 0.0),
        1e-6
    ));
    assert_eq!(g.uvs()[2], Vec2::new(1.0, 0.0));
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);

    // Signed normalised positions: -128 clamps to -1 as -127 does; plain
    // signed 16-bit UVs are their integers.
    let p = bin.put(&[
        128u8, 129, 0, 0, 127, 129, 0, 0, 127, 127, 0, 0, 129, 127, 0, 0,
    ]);
    bin.views[p]["byteStride"] = 4.into();
    json["accessors"][0] = json!({"bufferView": p, "componentType": 5120, "normalized": true,
        "count": 4, "type": "VEC3", "min": [-1, -1, 0], "max": [1, 1, 0]});
    let t = bin.put(&i16s(&[2, 3, -2, 0, 0, 0, 0, 0]));
    json["accessors"][uv] =
        json!({"bufferView": t, "componentType": 5122, "count": 4, "type": "VEC2"});
    json["nodes"][0] = json!({"mesh": 0});
    let s = load(&d.write("signed.glb", glb(&json, &bin))).unwrap();
    let g = &s.geometry;
    assert_eq!(g.positions()[0], Vec3::new(-1.0, -1.0, 0.0));
    assert_eq!(g.positions()[2], Vec3::new(1.0, 1.0, 0.0));
    assert_eq!(g.uvs()[0], Vec2::new(2.0, -2.0));
    assert_eq!(g.uvs()[1], Vec2::new(-2.0, 1.0));

    // What neither glTF nor the extension allows is refused, naming both.
    json["accessors"][normal]["componentType"] = 5121.into();
    let e = load(&d.write("unsigned.glb", glb(&json, &bin))).unwrap_err();
    assert!(
        e.contains(&format!(
            "NORMAL (accessor {normal}) is Vec3 U8; glTF allows Vec3 of F32, I8, I16"
        )),
        "{e}"
    );
}

#[test]
fn required_extensions_are_read_or_named() {
    let d = Dir::new("gltf-required");
    let (json, bin) = quad();
    let with = |name: &str, used: Value, required: Value| {
        let mut j = json.clone();
        j["extensionsUsed"] = used;
        j["extensionsRequired"] = required;
        d.write(name, glb(&j, &bin))
    };
    let e = load(&with(
        "frob.glb",
        json!(["EXT_frobnicate"]),
        json!(["EXT_frobnicate"]),
    ))
    .unwrap_err();
    assert!(
        e.ends_with("frob.glb: requires extension EXT_frobnicate, which rayterm does not read"),
        "{e}"
    );
    let both = json!(["KHR_mesh_quantization", "EXT_a", "EXT_b"]);
    let e = load(&with("two.glb", both.clone(), both)).unwrap_err();
    assert!(
        e.contains("two.glb: requires extensions EXT_a, EXT_b, which rayterm does not read"),
        "{e}"
    );
    // Required extensions that change only how surfaces look open, drawn
    // without them, as other viewers draw them; with one that may change
    // the geometry the file is still refused.
    let looks = json!(["KHR_materials_sheen", "KHR_materials_clearcoat"]);
    let s = load(&with("looks.glb", looks.clone(), looks)).unwrap();
    assert_eq!(s.geometry.indices().len(), 2);
    assert!(
        warned(
            &s,
            "looks.glb: requires KHR_materials_sheen, KHR_materials_clearcoat, which rayterm \
             does not read: its surfaces are drawn without them"
        ),
        "{:?}",
        s.warnings
    );
    let mixed = json!(["KHR_materials_sheen", "EXT_frobnicate"]);
    let e = load(&with("mixed.glb", mixed.clone(), mixed)).unwrap_err();
    assert!(
        e.ends_with("requires extension EXT_frobnicate, which rayterm does not read"),
        "{e}"
    );
    let draco = json!(["KHR_draco_mesh_compression"]);
    let e = load(&with("draco.glb", draco.clone(), draco)).unwrap_err();
    assert!(
        e.contains(
            "draco.glb: requires extension KHR_draco_mesh_compression (Draco mesh compression), \
                    which rayterm does not read"
        ),
        "{e}"
    );
    let read = json!([
        "KHR_lights_punctual",
        "KHR_mesh_quantization",
        "EXT_meshopt_compression",
        "KHR_materials_unlit",
        "KHR_materials_specular",
        "KHR_materials_pbrSpecularGlossiness"
    ]);
    let s = load(&with("read.glb", read.clone(), read)).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);

    // Draco where only used: the uncompressed data beside it is read.
    let mut j = json.clone();
    j["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
    j["meshes"][0]["primitives"][0]["extensions"] = json!({"KHR_draco_mesh_compression":
        {"bufferView": 0, "attributes": {"POSITION": 0}}});
    let s = load(&d.write("fallback.glb", glb(&j, &bin))).unwrap();
    assert_eq!(s.geometry.indices().len(), 2);
    assert!(
        warned(&s, "KHR_draco_mesh_compression (extensionsUsed)"),
        "{:?}",
        s.warnings
    );
    // ... and without any, the message is about Draco, once, not about
    // each accessor's missing bufferView.
    let mut many = j.clone();
    for i in 0..200 {
        many["accessors"]
            .as_array_mut()
            .unwrap()
            .push(json!({"componentType": 5126, "count": 4, "type": "VEC3"}));
        many["meshes"][0]["primitives"][0]["attributes"][format!("_X{i}")] = (i + 2).into();
    }
    for a in many["accessors"].as_array_mut().unwrap() {
        a.as_object_mut().unwrap().remove("bufferView");
    }
    let e = load(&d.write("bare.glb", glb(&many, &bin))).unwrap_err();
    assert!(
        e.ends_with(
            "bare.glb: mesh 0 primitive 0 is compressed with Draco (KHR_draco_mesh_compression), \
                     which rayterm does not read, and has no uncompressed data"
        ),
        "{e}"
    );
    assert!(e.len() < 400, "{e}");
}

#[test]
fn a_texture_transform_moves_the_coordinates_of_its_texture() {
    let d = Dir::new("gltf-texture-transform");
    let (mut json, mut bin) = quad();
    let png = {
        let img = image::RgbImage::from_fn(2, 2, |x, _| image::Rgb([255 * x as u8, 0, 0]));
        let mut png = Vec::new();
        img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .unwrap();
        png
    };
    let image = bin.put(&png);
    let corners = [[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]];
    let t = bin.put(&f32s(&corners.concat()));
    let uv = accessor(
        &mut json,
        json!({"bufferView": t, "componentType": 5126, "count": 4, "type": "VEC2"}),
    );
    // A second set: the first's halved.
    let half: Vec<f32> = corners.concat().iter().map(|x| x / 2.0).collect();
    let t1 = bin.put(&f32s(&half));
    let uv1 = accessor(
        &mut json,
        json!({"bufferView": t1, "componentType": 5126, "count": 4, "type": "VEC2"}),
    );
    json["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_0"] = uv.into();
    json["meshes"][0]["primitives"][0]["attributes"]["TEXCOORD_1"] = uv1.into();
    json["meshes"][0]["primitives"][0]["material"] = 0.into();
    let transform =
        json!({"offset": [0.5, 0.0], "scale": [0.5, 2.0], "rotation": std::f32::consts::FRAC_PI_2});
    let on_second = json!({"offset": [0.25, 0.0], "texCoord": 1});
    let slot = |t: &Value| json!({"index": 0, "extensions": {"KHR_texture_transform": t}});
    json["materials"] = json!([{
        "pbrMetallicRoughness": {"baseColorTexture": slot(&transform),
                                 "metallicRoughnessTexture": {"index": 0, "texCoord": 1}},
        "normalTexture": slot(&on_second),
        "occlusionTexture": slot(&transform),
        "emissiveTexture": slot(&on_second),
        "emissiveFactor": [1.0, 1.0, 1.0]}]);
    json["textures"] = json!([{"source": 0}]);
    json["images"] = json!([{"bufferView": image, "mimeType": "image/png"}]);
    json["extensionsUsed"] = json!(["KHR_texture_transform"]);
    json["extensionsRequired"] = json!(["KHR_texture_transform"]);
    let s = load(&d.write("moved.glb", glb(&json, &bin))).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let (m, g) = (&s.materials[0], &s.geometry);
    let p = m.pbr.as_ref().unwrap();
    let texture = |id: Option<u32>| &s.textures[id.unwrap() as usize];
    // The file's coordinates are kept, v up as rayterm has them; each
    // texture moves those of its set as its own transform says.
    let file = |[u, v]: [f32; 2]| Vec2::new(u, 1.0 - v);
    assert_eq!(g.uvs(), corners.map(file));
    assert_eq!(g.uvs1(), corners.map(|c| file(c.map(|x| x / 2.0))));
    // glTF's (u, v) scaled to (u / 2, 2v), turned a quarter to (2v, -u / 2),
    // moved by (0.5, 0); then v up.
    let turned = |u: f32, v: f32| Vec2::new(2.0 * v + 0.5, 1.0 + u / 2.0);
    let shifted = |u: f32, v: f32| Vec2::new(u / 2.0 + 0.25, 1.0 - v / 2.0);
    for (t, set, want) in [
        (texture(m.texture), 0, &turned as &dyn Fn(f32, f32) -> Vec2),
        (texture(p.occlusion.map(|o| o.0)), 0, &turned),
        (texture(p.normal.map(|n| n.0)), 1, &shifted),
        (texture(p.emissive_texture), 1, &shifted),
    ] {
        assert_eq!(t.uv.set, set);
        let read = [g.uvs(), g.uvs1()][set as usize];
        for (got, [u, v]) in read.iter().zip(corners) {
            let got = t.uv.apply(*got);
            assert!(
                (got - want(u, v)).abs().max_element() < 1e-6,
                "{got} {u} {v}"
            );
        }
    }
    let mr = texture(p.metallic_roughness);
    assert_eq!((mr.uv.set, mr.uv.transform), (1, None));
    // A second set no texture reads is not kept.
    let mut one = json.clone();
    one["materials"] = json!([{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]);
    let s = load(&d.write("one.glb", glb(&one, &bin))).unwrap();
    assert!(s.geometry.uvs1().is_empty());
    // A set the primitive lacks, or past the second, is said.
    let attributes = "/meshes/0/primitives/0/attributes";
    json.pointer_mut(attributes)
        .unwrap()
        .as_object_mut()
        .unwrap()
        .remove("TEXCOORD_1");
    let info = "/materials/0/pbrMetallicRoughness/baseColorTexture";
    json.pointer_mut(info).unwrap()["extensions"]["KHR_texture_transform"]["texCoord"] = 2.into();
    let s = load(&d.write("second.glb", glb(&json, &bin))).unwrap();
    for want in [
        "textures on primitives without TEXCOORD_1 (drawn in the material's colour) (material 0",
        "textures on TEXCOORD_2 (rayterm reads TEXCOORD_0 and TEXCOORD_1) (material 0)",
    ] {
        assert!(warned(&s, want), "{:?}", s.warnings);
    }
    assert!(s.materials[0].texture.is_none());
}

fn fixture(name: &str) -> String {
    format!("{}/tests/files/gltfpack/{name}", env!("CARGO_MANIFEST_DIR"))
}

#[test]
fn gltfpack_compressed_files_read_as_their_uncompressed_original() {
    // One mesh written by gltfpack without quantization (the reference),
    // and compressed: quantized with filters (-cc), floats with the
    // exponential filter (-vpf), and with a fallback buffer (-cf) whose
    // file is not there (it needs not be read).
    let reference = load(&fixture("sphere.glb")).unwrap();
    let r = &reference.geometry;
    assert_eq!((r.positions().len(), r.indices().len()), (162, 320));
    for name in ["sphere-cc.glb", "sphere-cc-vpf.glb", "sphere-cf.glb"] {
        let s = load(&fixture(name)).unwrap_or_else(|e| panic!("{e}"));
        let g = &s.geometry;
        assert_eq!(g.positions().len(), r.positions().len(), "{name}");
        assert_eq!(g.indices().len(), r.indices().len(), "{name}");
        // The same triangles, each perhaps in another place and started at
        // another corner (gltfpack orders them for its codec): positions
        // within 14 bits over a size of about 2, normals within 8-bit
        // octahedral ones.
        let same = |a: &[u32; 3], b: &[u32; 3], k: usize| {
            (0..3).all(|c| {
                let (i, j) = (a[(c + k) % 3] as usize, b[c] as usize);
                near3(g.positions()[i], r.positions()[j], 2e-4)
                    && near3(g.normals()[i], r.normals()[j], 0.03)
            })
        };
        for (t, a) in g.indices().iter().enumerate() {
            let found = r.indices().iter().any(|b| (0..3).any(|k| same(a, b, k)));
            assert!(
                found,
                "{name}: triangle {t} {:?} is not in the original",
                g.triangle(t)
            );
        }
        assert!(
            !s.warnings.iter().any(|w| w.contains("meshopt")),
            "{:?}",
            s.warnings
        );
    }

    // Damaged compressed views are named.
    let d = Dir::new("gltf-meshopt");
    let (json, bin) = chunks(&std::fs::read(fixture("sphere-cc.glb")).unwrap());
    let ext = "/bufferViews/3/extensions/EXT_meshopt_compression";
    let edit = |name: &str, f: &dyn Fn(&mut Value)| {
        let mut j = json.clone();
        f(j.pointer_mut(ext).unwrap());
        load(&d.write(name, glb_of(&j, &bin)))
            .err()
            .unwrap_or_else(|| panic!("{name} loaded"))
    };
    let e = edit("cut.glb", &|x| x["byteLength"] = 340.into());
    assert!(
        e.contains("cut.glb: buffer view 3 (EXT_meshopt_compression, Triangles): "),
        "{e}"
    );
    let e = edit("beyond.glb", &|x| x["byteOffset"] = 4000.into());
    assert!(
        e.contains("buffer view 3 (EXT_meshopt_compression): its compressed bytes end at byte"),
        "{e}"
    );
    let e = edit("mode.glb", &|x| x["mode"] = "ZIP".into());
    assert!(
        e.contains("buffer view 3 (EXT_meshopt_compression): its mode ZIP is not one glTF defines"),
        "{e}"
    );
    // A count the compressed bytes cannot hold is refused before the
    // view is made.
    let mut j = json.clone();
    j["bufferViews"][0]["byteLength"] = 8_000_000_000u64.into();
    j["bufferViews"][0]["extensions"]["EXT_meshopt_compression"]["count"] = 1_000_000_000.into();
    j["accessors"][0]["count"] = 1_000_000_000.into();
    let e = load(&d.write("count.glb", glb_of(&j, &bin))).unwrap_err();
    assert!(
        e.contains(
            "buffer view 0 (EXT_meshopt_compression): 896 bytes cannot encode 1000000000 elements"
        ),
        "{e}"
    );
}
