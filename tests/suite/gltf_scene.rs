//! glTF files as other tools write them: empty scenes, animations aimed
//! by `KHR_animation_pointer`, `EXT_mesh_gpu_instancing`, orthographic
//! cameras (and the scene file's), WebP textures and KTX2 ones.

use crate::common;
use crate::files;

use crate::files::{rayterm, within_deadline, Dir};
use glam::Vec3;
use rayterm::render::{Feature, Features, Plan, PlanPolicy};
use rayterm::scene::{self, Builder, Projection, Scene};
use serde_json::{json, Value};

fn load(spec: &str) -> Result<Scene, String> {
    let s = spec.to_string();
    within_deadline(spec, move || {
        scene::load::open(&s, &Default::default())
            .map(|o| o.scene)
            .map_err(|e| format!("{e:#}"))
    })
}

/// Deterministic: one pass is exact.
fn exact() -> Features {
    Features::all().without(&[Feature::Supersampling, Feature::Bloom])
}

/// A glTF's binary buffer as it is built: views and accessors of it.
#[derive(Default)]
struct Bin {
    bytes: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Bin {
    /// A buffer view of `data`, 4-byte aligned.
    fn view(&mut self, data: &[u8]) -> usize {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        self.views
            .push(json!({"buffer": 0, "byteOffset": self.bytes.len(),
                               "byteLength": data.len()}));
        self.bytes.extend(data);
        self.views.len() - 1
    }

    /// An accessor of `count` elements of `kind` over `data`; `more`
    /// joins its fields.
    fn accessor(
        &mut self,
        data: &[u8],
        component: u32,
        count: usize,
        kind: &str,
        more: Value,
    ) -> usize {
        let view = self.view(data);
        let mut a = json!({"bufferView": view, "componentType": component, "count": count,
                           "type": kind});
        for (k, v) in more.as_object().into_iter().flatten() {
            a[k] = v.clone();
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    fn floats(&mut self, v: &[f32], width: usize, kind: &str) -> usize {
        let data: Vec<u8> = v.iter().flat_map(|x| x.to_le_bytes()).collect();
        self.accessor(&data, 5126, v.len() / width, kind, json!({}))
    }

    /// A mesh's positions (with their bounds, which glTF requires) and
    /// indices: the `attributes` and `indices` of its primitive.
    fn mesh(&mut self, p: &[Vec3], t: &[[u16; 3]]) -> (usize, usize) {
        let flat: Vec<f32> = p.iter().flat_map(|v| v.to_array()).collect();
        let (min, max) = p
            .iter()
            .fold((Vec3::MAX, Vec3::MIN), |(a, b), v| (a.min(*v), b.max(*v)));
        let data: Vec<u8> = flat.iter().flat_map(|x| x.to_le_bytes()).collect();
        let pos = self.accessor(
            &data,
            5126,
            p.len(),
            "VEC3",
            json!({"min": min.to_array(), "max": max.to_array()}),
        );
        let idx: Vec<u8> = t.iter().flatten().flat_map(|i| i.to_le_bytes()).collect();
        let ind = self.accessor(&idx, 5123, t.len() * 3, "SCALAR", json!({}));
        (pos, ind)
    }

    /// `doc` with this buffer, its views and accessors, as a `.glb`.
    fn glb(mut self, mut doc: Value) -> Vec<u8> {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        doc["asset"] = json!({"version": "2.0"});
        doc["buffers"] = json!([{"byteLength": self.bytes.len()}]);
        doc["bufferViews"] = self.views.into();
        doc["accessors"] = self.accessors.into();
        let mut j = serde_json::to_vec(&doc).unwrap();
        while !j.len().is_multiple_of(4) {
            j.push(b' ');
        }
        let total = 12 + 8 + j.len() + 8 + self.bytes.len();
        let mut b = b"glTF".to_vec();
        b.extend(2u32.to_le_bytes());
        b.extend((total as u32).to_le_bytes());
        b.extend((j.len() as u32).to_le_bytes());
        b.extend(b"JSON");
        b.extend(&j);
        b.extend((self.bytes.len() as u32).to_le_bytes());
        b.extend(b"BIN\0");
        b.extend(&self.bytes);
        b
    }
}

/// One triangle, for files about their scenes rather than their meshes.
fn triangle() -> (Vec<Vec3>, Vec<[u16; 3]>) {
    (vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![[0, 1, 2]])
}

/// A UV sphere of radius 1 about the origin, with no zero-area
/// triangles at its poles.
fn sphere() -> (Vec<Vec3>, Vec<[u16; 3]>) {
    let (rings, segments) = (16u16, 32u16);
    let mut p = Vec::new();
    for i in 0..=rings {
        let theta = std::f32::consts::PI * i as f32 / rings as f32;
        let (r, y) = match i {
            0 => (0.0, 1.0),
            i if i == rings => (0.0, -1.0),
            _ => (theta.sin(), theta.cos()),
        };
        for j in 0..segments {
            let phi = std::f32::consts::TAU * j as f32 / segments as f32;
            p.push(Vec3::new(r * phi.cos(), y, r * phi.sin()));
        }
    }
    let at = |i: u16, j: u16| i * segments + j % segments;
    let mut t = Vec::new();
    for i in 0..rings {
        for j in 0..segments {
            if i + 1 < rings {
                t.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
            }
            if i > 0 {
                t.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
            }
        }
    }
    (p, t)
}

/// A file of one triangle mesh placed by node 0, with `doc`'s fields
/// added (they replace the scene's when given).
fn one_mesh(doc: Value) -> Vec<u8> {
    let mut bin = Bin::default();
    let (p, t) = triangle();
    let (pos, ind) = bin.mesh(&p, &t);
    let mut d = json!({
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "Tri", "mesh": 0}],
        "meshes": [{"name": "TriMesh", "primitives": [{"attributes": {"POSITION": pos},
                                                       "indices": ind}]}]
    });
    for (k, v) in doc.as_object().unwrap() {
        d[k] = v.clone();
    }
    bin.glb(d)
}

#[test]
fn empty_scenes_open_and_an_unplaced_default_scene_is_said() {
    let d = Dir::new("gltf-empty-scene");
    // As Blender writes it: a second scene with a name and no nodes.
    let blender = json!({"scenes": [{"name": "Scene", "nodes": [0]}, {"name": "Scene.001"}]});
    let s = load(&d.write("two.glb", one_mesh(blender.clone()))).unwrap();
    assert_eq!(s.geometry.triangle_count(), 1);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    // The same scene as JSON text.
    let mut text = blender.clone();
    text["scene"] = 1.into();
    let glb = one_mesh(text);
    // The empty scene the default: valid, but nothing to show.
    let e = load(&d.write("empty.glb", &glb)).unwrap_err();
    assert!(
        e.contains("empty.glb: no triangles")
            && e.contains("its scene Scene.001 has no nodes, so nothing is placed, though the file has 1 mesh"),
        "{e}"
    );
    // No scenes at all (Blender's exporter writes such files): a library
    // to glTF, whose root nodes are placed as Blender's importer places
    // them, and said; a child is placed under its parent, once.
    let mut bin = Bin::default();
    let (p, t) = triangle();
    let (pos, ind) = bin.mesh(&p, &t);
    let library = bin.glb(json!({
        "nodes": [{"mesh": 0, "children": [1]}, {"mesh": 0, "translation": [3.0, 0.0, 0.0]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}, "indices": ind}]}]
    }));
    let s = load(&d.write("library.glb", library)).unwrap();
    assert_eq!(s.geometry.triangle_count(), 2);
    assert!(
        s.warnings.iter().any(
            |w| w.contains("it has no scenes; its 1 root node is placed as a scene's would be")
        ),
        "{:?}",
        s.warnings
    );
    // In a scene file beside another mesh it is a warning.
    d.write("m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    let toml = d.write(
        "s.toml",
        "[[mesh]]\nfile = \"m.obj\"\n[[mesh]]\nfile = \"empty.glb\"\n",
    );
    let s = load(&toml).unwrap();
    assert_eq!(s.geometry.triangle_count(), 1);
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("empty.glb: its scene Scene.001 has no nodes")),
        "{:?}",
        s.warnings
    );
}

#[test]
fn animations_aimed_elsewhere_do_not_refuse_a_file() {
    let d = Dir::new("gltf-animation-pointer");
    // KHR_animation_pointer aims a channel at a material, not a node; a
    // channel with a sampler that does not exist is not read either.
    let doc = json!({
        "extensionsUsed": ["KHR_animation_pointer"],
        "animations": [{"name": "Fade", "channels": [
            {"sampler": 0, "target": {"path": "pointer", "extensions": {"KHR_animation_pointer":
                {"pointer": "/materials/0/pbrMetallicRoughness/baseColorFactor"}}}},
            {"sampler": 7, "target": {"node": 0, "path": "translation"}}
        ], "samplers": [{"input": 0, "output": 0}]}]
    });
    for name in ["pointer.glb", "pointer.gltf"] {
        let bytes = match name.ends_with(".glb") {
            true => one_mesh(doc.clone()),
            // The JSON of the .glb, its buffer inline.
            false => {
                let glb = one_mesh(doc.clone());
                let len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
                let mut j: Value = serde_json::from_slice(&glb[20..20 + len]).unwrap();
                let bin = &glb[20 + len + 8..];
                use base64::Engine;
                let b64 = base64::engine::general_purpose::STANDARD.encode(bin);
                j["buffers"][0]["uri"] =
                    format!("data:application/octet-stream;base64,{b64}").into();
                serde_json::to_vec(&j).unwrap()
            }
        };
        let s = load(&d.write(name, bytes)).unwrap();
        assert_eq!(s.geometry.triangle_count(), 1, "{name}");
        let w = s.warnings.join("\n");
        assert!(
            w.contains("animations (shown at rest)") && w.contains("KHR_animation_pointer"),
            "{name}: {w}"
        );
    }
}

/// Positions of mesh `name`'s first triangle.
fn corners(s: &Scene, name: &str) -> [Vec3; 3] {
    let m = s
        .meshes
        .iter()
        .position(|m| m.name == name)
        .unwrap_or_else(|| {
            panic!(
                "no mesh {name}: {:?}",
                s.meshes.iter().map(|m| &m.name).collect::<Vec<_>>()
            )
        });
    let t = s
        .geometry
        .tri_mesh()
        .iter()
        .position(|&x| x as usize == m)
        .unwrap();
    s.geometry.indices()[t].map(|i| s.geometry.positions()[i as usize])
}

fn near(a: Vec3, b: Vec3) -> bool {
    (a - b).length() < 1e-5
}

/// A triangle placed by an instanced node (three instances: the node's
/// transform, then each instance's, inside it) and by a plain one; `edit`
/// changes the document first.
fn instanced(edit: impl Fn(&mut Value, &mut Bin)) -> Vec<u8> {
    let mut bin = Bin::default();
    let (p, t) = triangle();
    let (pos, ind) = bin.mesh(&p, &t);
    let tr = bin.floats(&[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 5.0, 0.0], 3, "VEC3");
    // 90 degrees about z for instance 1, as normalized shorts.
    let h = (32767.0 * std::f32::consts::FRAC_1_SQRT_2).round() as i16;
    let rot: Vec<u8> = [0, 0, 0, 32767, 0, 0, h, h, 0, 0, 0, 32767]
        .iter()
        .flat_map(|x: &i16| x.to_le_bytes())
        .collect();
    let rot = bin.accessor(&rot, 5122, 3, "VEC4", json!({"normalized": true}));
    let sc = bin.floats(&[1.0, 1.0, 1.0, 1.0, 1.0, 1.0, 3.0, 3.0, 3.0], 3, "VEC3");
    let mut doc = json!({
        "extensionsUsed": ["EXT_mesh_gpu_instancing"],
        "extensionsRequired": ["EXT_mesh_gpu_instancing"],
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [
            {"name": "Forest", "mesh": 0, "translation": [10.0, 0.0, 0.0], "scale": [2.0, 2.0, 2.0],
             "extensions": {"EXT_mesh_gpu_instancing": {"attributes":
                 {"TRANSLATION": tr, "ROTATION": rot, "SCALE": sc, "_ID": tr}}}},
            {"name": "Lone", "mesh": 0}
        ],
        "meshes": [{"name": "Tree", "primitives": [{"attributes": {"POSITION": pos},
                                                    "indices": ind}]}]
    });
    edit(&mut doc, &mut bin);
    bin.glb(doc)
}

#[test]
fn gpu_instancing_places_the_mesh_once_per_instance() {
    let d = Dir::new("gltf-instancing");
    let s = load(&d.write("forest.glb", instanced(|_, _| {}))).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert_eq!(s.geometry.triangle_count(), 4);
    // Instance k: node (translate 10, scale 2) of instance (T, R, S).
    let [a, b, c] = corners(&s, "Tree (node Forest, instance 0)");
    assert!(
        near(a, Vec3::new(10.0, 0.0, 0.0)) && near(b, Vec3::new(12.0, 0.0, 0.0)),
        "{a} {b}"
    );
    assert!(near(c, Vec3::new(10.0, 2.0, 0.0)), "{c}");
    // Turned 90 degrees: x runs along y.
    let [a, b, c] = corners(&s, "Tree (node Forest, instance 1)");
    assert!(near(a, Vec3::new(12.0, 0.0, 0.0)), "{a}");
    assert!((b - Vec3::new(12.0, 2.0, 0.0)).length() < 1e-3, "{b}");
    assert!((c - Vec3::new(10.0, 0.0, 0.0)).length() < 1e-3, "{c}");
    let [a, b, _] = corners(&s, "Tree (node Forest, instance 2)");
    assert!(
        near(a, Vec3::new(10.0, 10.0, 0.0)) && near(b, Vec3::new(16.0, 10.0, 0.0)),
        "{a} {b}"
    );
    let [a, b, _] = corners(&s, "Tree (node Lone)");
    assert!(near(a, Vec3::ZERO) && near(b, Vec3::X), "{a} {b}");
    // Float rotations, and translations alone, read too.
    let floats = instanced(|doc, bin| {
        let r = std::f32::consts::FRAC_1_SQRT_2;
        let rot = bin.floats(
            &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, r, r, 0.0, 0.0, 0.0, 1.0],
            4,
            "VEC4",
        );
        doc["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"]["ROTATION"] =
            rot.into();
    });
    let f = load(&d.write("floats.glb", floats)).unwrap();
    let [_, b, _] = corners(&f, "Tree (node Forest, instance 1)");
    assert!(near(b, Vec3::new(12.0, 2.0, 0.0)), "{b}");
    let moved = instanced(|doc, _| {
        let attributes =
            &mut doc["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"];
        attributes
            .as_object_mut()
            .unwrap()
            .retain(|k, _| k == "TRANSLATION");
    });
    let m = load(&d.write("moved.glb", moved)).unwrap();
    let [_, b, _] = corners(&m, "Tree (node Forest, instance 1)");
    assert!(near(b, Vec3::new(14.0, 0.0, 0.0)), "{b}");
    // As the mesh of a scene file, placed by it after the file's nodes.
    let toml = d.write(
        "s.toml",
        "[[mesh]]\nfile = \"forest.glb\"\ntranslate = [0, 0, 1]\n",
    );
    let t = load(&toml).unwrap();
    let [_, b, _] = corners(&t, "Tree (node Forest, instance 2)");
    assert!(near(b, Vec3::new(16.0, 10.0, 1.0)), "{b}");
}

#[test]
fn bad_instances_say_which_node_and_accessor() {
    let d = Dir::new("gltf-instancing-bad");
    let attr = |doc: &mut Value, k: &str, v: Value| {
        doc["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"][k] = v;
    };
    let cases: Vec<(&str, Vec<u8>, &str)> = vec![
        (
            "count.glb",
            instanced(|doc, bin| {
                let tr = bin.floats(&[0.0; 6], 3, "VEC3");
                attr(doc, "TRANSLATION", tr.into());
            }),
            "node Forest: EXT_mesh_gpu_instancing: ROTATION (accessor 3) has 3 instances, \
             TRANSLATION (accessor 5) 2; glTF requires as many in each",
        ),
        (
            "vec2.glb",
            instanced(|doc, bin| {
                let tr = bin.floats(&[0.0; 6], 2, "VEC2");
                attr(doc, "TRANSLATION", tr.into());
            }),
            "node Forest: EXT_mesh_gpu_instancing: TRANSLATION (accessor 5) is Vec2 F32; glTF allows Vec3 of F32",
        ),
        (
            "raw.glb",
            instanced(|_, bin| bin.accessors[3]["normalized"] = false.into()),
            "node Forest: EXT_mesh_gpu_instancing: ROTATION (accessor 3) is I16 and not normalized",
        ),
        (
            "gone.glb",
            instanced(|doc, _| attr(doc, "SCALE", 40.into())),
            "node Forest: EXT_mesh_gpu_instancing: SCALE is accessor 40, which does not exist (5 accessors)",
        ),
        (
            "short.glb",
            instanced(|_, bin| bin.accessors[2]["count"] = 300.into()),
            "node Forest: EXT_mesh_gpu_instancing: TRANSLATION (accessor 2): its 300 elements end at byte",
        ),
        (
            "nan.glb",
            instanced(|doc, bin| {
                let tr = bin.floats(&[0.0, 0.0, 0.0, f32::NAN, 0.0, 0.0, 0.0, 0.0, 0.0], 3, "VEC3");
                attr(doc, "TRANSLATION", tr.into());
            }),
            "node Forest: EXT_mesh_gpu_instancing: instance 1: TRANSLATION (accessor 5) is (NaN, 0, 0), not a finite number",
        ),
        (
            "zero.glb",
            instanced(|doc, bin| {
                let rot = bin.floats(&[0.0; 12], 4, "VEC4");
                attr(doc, "ROTATION", rot.into());
            }),
            "node Forest: EXT_mesh_gpu_instancing: instance 0: ROTATION (accessor 5) is [0, 0, 0, 0], not a rotation",
        ),
        (
            "none.glb",
            instanced(|doc, _| {
                doc["nodes"][0]["extensions"]["EXT_mesh_gpu_instancing"]["attributes"] = json!({});
            }),
            "node Forest: EXT_mesh_gpu_instancing: it has none of TRANSLATION, ROTATION and SCALE",
        ),
    ];
    for (name, bytes, want) in cases {
        let e = load(&d.write(name, bytes))
            .err()
            .unwrap_or_else(|| panic!("{name} loaded"));
        assert!(
            e.contains(&format!("{name}: {want}")),
            "{name}: {e}\nwanted: {want}"
        );
    }
}

/// Instances are counted against the memory available before anything is
/// read: a mesh of a million triangles placed by a million instances
/// (about 2e14 bytes) is refused at once, in a process whose address
/// space could not hold a fraction of it.
#[test]
fn instances_count_in_the_memory_check() {
    let d = Dir::new("gltf-instancing-memory");
    let mut bin = Bin::default();
    let (p, _) = triangle();
    let flat: Vec<u8> = p
        .iter()
        .flat_map(|v| v.to_array())
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let pos = bin.accessor(
        &flat,
        5126,
        3,
        "VEC3",
        json!({"min": [0, 0, 0], "max": [1, 1, 0]}),
    );
    let ind = bin.accessor(&vec![0u8; 3_000_000], 5121, 3_000_000, "SCALAR", json!({}));
    let tr = bin.accessor(&vec![0u8; 12_000_000], 5126, 1_000_000, "VEC3", json!({}));
    let doc = json!({
        "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "Crowd", "mesh": 0,
                   "extensions": {"EXT_mesh_gpu_instancing": {"attributes": {"TRANSLATION": tr}}}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}, "indices": ind}]}]
    });
    d.write("crowd.glb", bin.glb(doc));
    let r = files::rayterm_within(
        1 << 30,
        &d.0,
        &["render", "crowd.glb", "--size", "8x8", "-o", "x.png"],
    );
    assert!(
        !r.ok()
            && r.stderr
                .contains("crowd.glb: its meshes, each instance counted"),
        "{}",
        r.stderr
    );
}

/// Two spheres of radius 1 at different depths (`Near` at z = 0, `Far` at
/// z = -6), seen from z = 10 by an orthographic camera 4 units high
/// (`Ortho`) and a perspective one (`Persp`).
fn spheres() -> Vec<u8> {
    let mut bin = Bin::default();
    let (p, t) = sphere();
    let (pos, ind) = bin.mesh(&p, &t);
    bin.glb(json!({
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2, 3]}],
        "nodes": [
            {"name": "Ortho", "camera": 0, "translation": [0.0, 0.0, 10.0]},
            {"name": "Persp", "camera": 1, "translation": [0.0, 0.0, 10.0]},
            {"name": "Near", "mesh": 0, "translation": [-2.0, 0.0, 0.0]},
            {"name": "Far", "mesh": 0, "translation": [2.0, 0.0, -6.0]}
        ],
        "cameras": [
            {"type": "orthographic", "orthographic": {"xmag": 4.0, "ymag": 2.0, "znear": 0.1, "zfar": 100.0}},
            {"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}
        ],
        // Glowing, so that every pixel that sees a ball is lit.
        "materials": [{"emissiveFactor": [1.0, 1.0, 1.0]}],
        "meshes": [{"name": "Ball", "primitives": [{"attributes": {"POSITION": pos}, "indices": ind,
                                                    "material": 0}]}]
    }))
}

/// The pixels of the left and right halves of a 64x32 render that see
/// something (the default sky of a file without lights left out).
fn covered(s: &Scene) -> (Vec<bool>, usize, usize) {
    let features = exact().without(&[Feature::Environment]);
    let img = common::render(s, 64, 32, 1, features, Builder::Sah, 1).image;
    let seen: Vec<bool> = img.iter().map(|c| c.max_element() > 0.0).collect();
    let half = |left: bool| {
        (0..64 * 32)
            .filter(|&i| seen[i] && (i % 64 < 32) == left)
            .count()
    };
    (seen.clone(), half(true), half(false))
}

#[test]
fn an_orthographic_camera_shows_equal_things_equally_large_at_any_depth() {
    let d = Dir::new("gltf-ortho");
    let file = d.write("spheres.glb", spheres());
    let s = load(&file).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert_eq!(
        s.camera.projection,
        Projection::Orthographic { half_height: 2.0 }
    );
    let (ortho, near_px, far_px) = covered(&s);
    // 8 pixels a unit: each sphere's disc is about pi * 8^2 pixels.
    assert!((180..=220).contains(&near_px), "{near_px}");
    assert_eq!(near_px, far_px);
    let through = scene::load::Opening {
        camera: Some("Persp".into()),
        ..Default::default()
    };
    let p = scene::load::open(&file, &through).unwrap().scene;
    let (_, near_px, far_px) = covered(&p);
    // At distances 10 and 16: about (16 / 10)^2 = 2.56 times the pixels.
    assert!(near_px as f64 > 2.0 * far_px as f64, "{near_px} {far_px}");
    // The scene file's orthographic camera sees what the glTF's does.
    let toml = d.write(
        "s.toml",
        "[camera]\neye = [0, 0, 10]\ntarget = [0, 0, 0]\nprojection = \"orthographic\"\nheight = 4\n\
         [[mesh]]\nfile = \"spheres.glb\"\n[[light]]\ntype = \"point\"\nposition = [0, 0, 10]\n\
         color = [1, 1, 1]\n[render]\nambient = [0.1, 0.1, 0.1]\n",
    );
    let t = load(&toml).unwrap();
    assert_eq!(
        t.camera.projection,
        Projection::Orthographic { half_height: 2.0 }
    );
    assert!(
        covered(&t).0 == ortho,
        "the scene file's camera sees otherwise"
    );
    // Its rays start apart, so a pass traces them one by one: the image of
    // single rays, supersampled, on any number of threads.
    let plan = Plan::new(
        &s,
        Features::all().without(&[Feature::Bloom]),
        PlanPolicy::Prune,
    );
    assert!(!plan.packets);
    let bvh = rayterm::bvh::build(&s.geometry, Builder::Sah);
    let a = common::render_with(&s, &bvh, &plan, 40, 30, 20, 9).image;
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let b = pool.install(|| common::render_with(&s, &bvh, &plan, 40, 30, 20, 9).image);
    assert!(a == b, "the image depends on the threads");
    let mut packets = plan.clone();
    packets.packets = true;
    let c = common::render_with(&s, &bvh, &packets, 40, 30, 20, 9).image;
    assert!(a == c, "packets of rays that start apart find other hits");
    // The inspector's camera ray is the orthographic one: along -z from
    // the view plane, through the far sphere's centre.
    let r = rayterm(
        &d.0,
        &[
            "inspect",
            "spheres.glb",
            "--pixel",
            "48,16",
            "--size",
            "64x32",
        ],
    );
    assert!(r.ok(), "{}", r.stderr);
    let ray = r
        .stdout
        .lines()
        .find(|l| l.starts_with("camera ray"))
        .unwrap_or_default();
    assert!(ray.contains(", 10.000) d=(0, 0, -1.0000)"), "{}", r.stdout);
    assert!(r.stdout.contains("(node Far)"), "{}", r.stdout);
}

#[test]
fn orthographic_camera_settings_are_checked() {
    let d = Dir::new("gltf-ortho-bad");
    let head = "[[mesh]]\nfile = \"m.obj\"\n[camera]\neye = [0, 0, 5]\ntarget = [0, 0, 0]\n";
    d.write("m.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    for (body, want) in [
        (
            "projection = \"orthographic\"\n",
            "s.toml:3:1: camera: an orthographic camera needs height",
        ),
        (
            "projection = \"orthographic\"\nheight = 0\n",
            "s.toml:7:10: camera: height must be more than 0",
        ),
        (
            "projection = \"orthographic\"\nheight = 2\nfov = 30\n",
            "s.toml:8:7: camera: fov is for perspective cameras",
        ),
        (
            "height = 2\n",
            "s.toml:6:10: camera: height is for orthographic cameras",
        ),
        ("projection = \"fisheye\"\n", "s.toml:6:14"),
    ] {
        let e = load(&d.write("s.toml", format!("{head}{body}"))).unwrap_err();
        assert!(e.contains(want), "{body}: {e}\nwanted: {want}");
    }
    let ok = load(&d.write(
        "s.toml",
        format!("{head}projection = \"perspective\"\nfov = 30\n"),
    ))
    .unwrap();
    assert_eq!(ok.camera.projection, Projection::perspective(30.0));
    // A glTF camera's ymag must be a size; the node's scale scales it.
    let edit = |f: &dyn Fn(&mut Value)| {
        let glb = spheres();
        let len = u32::from_le_bytes(glb[12..16].try_into().unwrap()) as usize;
        let mut j: Value = serde_json::from_slice(&glb[20..20 + len]).unwrap();
        f(&mut j);
        let bin = glb[20 + len + 8..].to_vec();
        let mut b = Bin {
            bytes: bin,
            ..Default::default()
        };
        b.views = j["bufferViews"].as_array().unwrap().clone();
        b.accessors = j["accessors"].as_array().unwrap().clone();
        b.glb(j)
    };
    let zero = edit(&|j| j["cameras"][0]["orthographic"]["ymag"] = 0.0.into());
    let e = load(&d.write("zero.glb", zero)).unwrap_err();
    assert!(
        e.contains("zero.glb: camera 0: ymag 0 is not a height"),
        "{e}"
    );
    let scaled = edit(&|j| j["nodes"][0]["scale"] = json!([3.0, 3.0, 3.0]));
    let s = load(&d.write("scaled.glb", scaled)).unwrap();
    assert_eq!(
        s.camera.projection,
        Projection::Orthographic { half_height: 6.0 }
    );
}

/// A 4x4 lossy WebP of pure green, as libwebp 1.6.0 writes it (through
/// Pillow 13: `Image.new("RGB", (4, 4), (0, 255, 0)).save(f, "WEBP",
/// quality=90)`); it decodes to (0, 255, 1).
const GREEN_WEBP: &[u8] = b"RIFF@\x00\x00\x00WEBPVP8 4\x00\x00\x00\x10\x02\x00\x9d\x01*\x04\x00\
\x04\x00\x00\xc0\x12%\xa0\x02t\xba\x01\xf8\x01\xfa\x00\x03\xc8\x00\xfe\xee\xbd\x9f\xffr\xf6\x9f\xa2|?\
\xee\xa2\xbf\xfeP~\x11\x886\xff\xe5b\x00\x00\x00";

/// A 4x4 PNG of pure red.
fn red_png() -> Vec<u8> {
    let img = image::RgbImage::from_pixel(4, 4, image::Rgb([255, 0, 0]));
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    png
}

/// A textured quad facing +z whose texture 0 is made by `texture` from
/// image 0 (a red PNG) and image 1 (the green WebP), both in the buffer.
fn textured(texture: Value, more: Value) -> Vec<u8> {
    let mut bin = Bin::default();
    let p = [
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
    ];
    let (pos, ind) = bin.mesh(&p, &[[0, 1, 2], [0, 2, 3]]);
    let uv = bin.floats(&[0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0], 2, "VEC2");
    let png = bin.view(&red_png());
    let webp = bin.view(GREEN_WEBP);
    let mut doc = json!({
        "scene": 0, "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos, "TEXCOORD_0": uv},
                                    "indices": ind, "material": 0}]}],
        "materials": [{"name": "Leaf", "pbrMetallicRoughness": {"baseColorTexture": {"index": 0},
                                                                "metallicFactor": 0.0}}],
        "textures": [texture],
        "images": [{"bufferView": png, "mimeType": "image/png"},
                   {"bufferView": webp, "mimeType": "image/webp"}]
    });
    for (k, v) in more.as_object().unwrap() {
        doc[k] = v.clone();
    }
    bin.glb(doc)
}

/// The colour of the only texture of `s`'s only textured material.
fn texel(s: &Scene) -> Vec3 {
    let m = s.materials.iter().find(|m| m.name == "Leaf").unwrap();
    let t = &s.textures[m.texture.expect("no texture") as usize];
    t.texels[0]
}

#[test]
fn webp_textures_are_read_and_ktx2_is_named() {
    let d = Dir::new("gltf-webp");
    let webp = json!({"EXT_texture_webp": {"source": 1}});
    // A WebP with a PNG fallback, the extension required or not: the WebP.
    for (name, texture, required) in [
        (
            "fallback.glb",
            json!({"source": 0, "extensions": webp}),
            json!([]),
        ),
        (
            "required.glb",
            json!({"extensions": webp}),
            json!(["EXT_texture_webp"]),
        ),
        ("plain.glb", json!({"source": 1}), json!([])),
    ] {
        let more = json!({"extensionsUsed": ["EXT_texture_webp"], "extensionsRequired": required});
        let s = load(&d.write(name, textured(texture, more))).unwrap();
        assert!(s.warnings.is_empty(), "{name}: {:?}", s.warnings);
        let c = texel(&s);
        assert!(c.y > 0.99 && c.x < 0.01 && c.z < 0.01, "{name}: {c}");
    }
    // A WebP image that does not exist is named.
    let gone = textured(
        json!({"source": 0, "extensions": {"EXT_texture_webp": {"source": 9}}}),
        json!({}),
    );
    let e = load(&d.write("gone.glb", gone)).unwrap_err();
    assert!(
        e.contains(
            "gone.glb: texture 0: its EXT_texture_webp source 9 is not one of the file's 2 images"
        ),
        "{e}"
    );
    // KTX2: its PNG fallback is used; without one, the material's colour,
    // and the warning names KTX2.
    let ktx2 = json!({"KHR_texture_basisu": {"source": 1}});
    let more = json!({"extensionsUsed": ["KHR_texture_basisu"]});
    let s = load(&d.write(
        "ktx-fallback.glb",
        textured(json!({"source": 0, "extensions": ktx2}), more.clone()),
    ))
    .unwrap();
    assert!(texel(&s).x > 0.99, "{}", texel(&s));
    let mut required = more.clone();
    required["extensionsRequired"] = json!(["KHR_texture_basisu"]);
    let dds = json!({"MSFT_texture_dds": {"source": 1}});
    let dds_required = json!({"extensionsUsed": ["MSFT_texture_dds"],
                              "extensionsRequired": ["MSFT_texture_dds"]});
    for (name, texture, m, want) in [
        (
            "ktx.glb",
            ktx2.clone(),
            more,
            "KTX2 textures (Basis Universal, KHR_texture_basisu)",
        ),
        (
            "ktx-required.glb",
            ktx2,
            required,
            "KTX2 textures (Basis Universal, KHR_texture_basisu)",
        ),
        (
            "dds.glb",
            dds,
            dds_required,
            "DDS textures (MSFT_texture_dds)",
        ),
    ] {
        let s = load(&d.write(name, textured(json!({"extensions": texture}), m))).unwrap();
        let leaf = s.materials.iter().find(|m| m.name == "Leaf").unwrap();
        assert!(leaf.texture.is_none());
        let w = s.warnings.join("\n");
        let want = format!(
            "{want} without a PNG, JPEG or WebP source (drawn in the material's colour) \
             (texture 0 of material Leaf)"
        );
        assert!(w.contains(&want), "{name}: {w}");
    }
    // A KTX2 file named as a texture's image says what it is.
    let direct = textured(json!({"source": 1}), json!({}));
    let direct = {
        let mut b = direct;
        let at = b.windows(4).position(|w| w == b"RIFF").unwrap();
        b[at..at + 12].copy_from_slice(b"\xABKTX 20\xBB\r\n\x1A\n");
        b
    };
    let s = load(&d.write("direct.glb", direct)).unwrap();
    let w = s.warnings.join("\n");
    assert!(
        w.contains("image 1: a KTX2 (Basis Universal) image, which rayterm does not decode"),
        "{w}"
    );
    // Extensions rayterm does not read are still refused when required.
    let other = textured(
        json!({"source": 0}),
        json!({"extensionsRequired": ["EXT_made_up"]}),
    );
    let e = load(&d.write("other.glb", other)).unwrap_err();
    assert!(e.contains("EXT_made_up"), "{e}");
}

#[test]
fn webp_files_are_textures_of_gltf_and_obj_alike() {
    let d = Dir::new("webp-files");
    d.write("leaf.webp", GREEN_WEBP);
    let bytes = textured(json!({"source": 2}), json!({}));
    let len = u32::from_le_bytes(bytes[12..16].try_into().unwrap()) as usize;
    let mut j: Value = serde_json::from_slice(&bytes[20..20 + len]).unwrap();
    j["images"]
        .as_array_mut()
        .unwrap()
        .push(json!({"uri": "leaf.webp"}));
    let mut b = Bin {
        bytes: bytes[20 + len + 8..].to_vec(),
        ..Default::default()
    };
    b.views = j["bufferViews"].as_array().unwrap().clone();
    b.accessors = j["accessors"].as_array().unwrap().clone();
    let s = load(&d.write("file.glb", b.glb(j))).unwrap();
    assert!(texel(&s).y > 0.99, "{}", texel(&s));
    // An OBJ's map_Kd, through the same loader.
    d.write("leaf.mtl", "newmtl Leaf\nKd 1 1 1\nmap_Kd leaf.webp\n");
    let obj = d.write(
        "leaf.obj",
        "mtllib leaf.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl Leaf\nf 1/1 2/2 3/3\n",
    );
    let s = load(&obj).unwrap();
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    assert!(texel(&s).y > 0.99, "{}", texel(&s));
}

/// Lights keep the extension's units: point and spot lights in candela
/// (colour times intensity) with their range and cone, directional
/// lights in lux along the node's -Z.
#[test]
fn lights_keep_their_units_cones_and_ranges() {
    use rayterm::scene::Light;
    let d = Dir::new("gltf-light-units");
    // A quarter turn about +X: the node's -Z points down.
    let down = [
        -std::f32::consts::FRAC_1_SQRT_2,
        0.0,
        0.0,
        std::f32::consts::FRAC_1_SQRT_2,
    ];
    let file = d.write(
        "lights.glb",
        one_mesh(json!({
            "extensionsUsed": ["KHR_lights_punctual"],
            "extensions": {"KHR_lights_punctual": {"lights": [
                {"type": "point", "color": [1.0, 0.5, 0.0], "intensity": 10.0, "range": 7.0},
                {"type": "spot", "intensity": 4.0,
                 "spot": {"innerConeAngle": 0.1, "outerConeAngle": 0.5}},
                {"type": "directional", "intensity": 3.0}
            ]}},
            "scenes": [{"nodes": [0, 1, 2, 3]}],
            "nodes": [{"name": "Tri", "mesh": 0},
                      {"translation": [0.0, 2.0, 0.0],
                       "extensions": {"KHR_lights_punctual": {"light": 0}}},
                      {"translation": [0.0, 3.0, 0.0], "rotation": down,
                       "extensions": {"KHR_lights_punctual": {"light": 1}}},
                      {"rotation": down, "extensions": {"KHR_lights_punctual": {"light": 2}}}]
        })),
    );
    let s = load(&file).unwrap();
    assert_eq!(s.lights.len(), 3, "{:?}", s.lights);
    match &s.lights[0] {
        Light::Photometric {
            intensity,
            range,
            cone: None,
            ..
        } => {
            assert_eq!(*intensity, Vec3::new(10.0, 5.0, 0.0));
            assert_eq!(*range, Some(7.0));
        }
        l => panic!("{l:?}"),
    }
    match &s.lights[1] {
        Light::Photometric {
            intensity,
            cone: Some(c),
            range: None,
            ..
        } => {
            assert_eq!(*intensity, Vec3::splat(4.0));
            assert!(near(c.axis, Vec3::NEG_Y), "{:?}", c.axis);
            assert!((c.cos_inner - 0.1f32.cos()).abs() < 1e-6);
            assert!((c.cos_outer - 0.5f32.cos()).abs() < 1e-6);
        }
        l => panic!("{l:?}"),
    }
    match &s.lights[2] {
        Light::Directional {
            direction,
            illuminance,
        } => {
            assert!(near(*direction, Vec3::NEG_Y), "{direction:?}");
            assert_eq!(*illuminance, Vec3::splat(3.0));
        }
        l => panic!("{l:?}"),
    }
    assert!(
        !s.warnings
            .iter()
            .any(|w| w.contains("spot") || w.contains("range")),
        "{:?}",
        s.warnings
    );
}

/// A 2x2 PNG of one grey level.
fn grey_png(level: u8) -> Vec<u8> {
    let img = image::RgbImage::from_pixel(2, 2, image::Rgb([level, level, level]));
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    png
}

/// Every core texture of a metallic-roughness material is read: colours
/// (base, emissive) sRGB-decoded, data (metallic-roughness, normal,
/// occlusion) as stored; emissive strength multiplies the emissive
/// colour; a primitive without a material takes the specification's
/// default, a rough white metal.
#[test]
fn metallic_roughness_materials_take_every_core_texture() {
    let d = Dir::new("gltf-pbr-textures");
    let mut bin = Bin::default();
    let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let (pos, ind) = bin.mesh(&p, &[[0, 1, 2]]);
    let uv = bin.floats(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0], 2, "VEC2");
    let png = bin.view(&grey_png(128));
    let tex = |i: usize| json!({"index": i});
    let doc = json!({
        "scene": 0, "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"mesh": 1, "translation": [2.0, 0.0, 0.0]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos, "TEXCOORD_0": uv},
                                    "indices": ind, "material": 0}]},
                   {"primitives": [{"attributes": {"POSITION": pos}, "indices": ind}]}],
        "extensionsUsed": ["KHR_materials_emissive_strength"],
        "materials": [{
            "name": "Worn",
            "pbrMetallicRoughness": {"baseColorTexture": tex(0),
                                     "baseColorFactor": [0.5, 1.0, 1.0, 1.0],
                                     "metallicFactor": 0.25, "roughnessFactor": 0.75,
                                     "metallicRoughnessTexture": tex(0)},
            "normalTexture": {"index": 0, "scale": 0.5},
            "occlusionTexture": {"index": 0, "strength": 0.3},
            "emissiveTexture": tex(0),
            "emissiveFactor": [1.0, 0.5, 0.0],
            "extensions": {"KHR_materials_emissive_strength": {"emissiveStrength": 4.0}}
        }],
        "textures": [{"source": 0}],
        "images": [{"bufferView": png, "mimeType": "image/png"}]
    });
    let file = d.write("worn.glb", bin.glb(doc));
    let s = load(&file).unwrap();
    let m = s.materials.iter().find(|m| m.name == "Worn").unwrap();
    let p = m.pbr.as_ref().expect("a metallic-roughness material");
    assert_eq!((p.metallic, p.roughness), (0.25, 0.75));
    assert_eq!(p.emissive, Vec3::new(4.0, 2.0, 0.0));
    let texel = |id: u32| {
        let t = &s.textures[id as usize];
        t.texels[0] * t.tint
    };
    // sRGB 128 is 0.2158 linear; stored data 128 is 0.502.
    let srgb = 0.21586;
    let linear = 128.0 / 255.0;
    let base = texel(m.texture.unwrap());
    assert!(near(base, Vec3::new(0.5, 1.0, 1.0) * srgb), "{base}");
    assert!(near(
        texel(p.metallic_roughness.unwrap()),
        Vec3::splat(linear)
    ));
    let (normal, scale) = p.normal.unwrap();
    assert!(near(texel(normal), Vec3::splat(linear)) && scale == 0.5);
    let (occlusion, strength) = p.occlusion.unwrap();
    assert!(near(texel(occlusion), Vec3::splat(linear)) && strength == 0.3);
    let emitted = texel(p.emissive_texture.unwrap());
    assert!(near(emitted, Vec3::new(4.0, 2.0, 0.0) * srgb), "{emitted}");
    assert!(m.emissive());
    let default = &s.materials[s.geometry.tri_material()[1] as usize];
    let dp = default
        .pbr
        .as_ref()
        .expect("the default is metallic-roughness");
    assert_eq!(
        (default.kd, dp.metallic, dp.roughness),
        (Vec3::ONE, 1.0, 1.0)
    );
    assert!(
        !s.warnings.iter().any(|w| w.contains("not shown")),
        "{:?}",
        s.warnings
    );
}

/// A material whose only textures are data or emission (no base colour
/// texture) still has them looked up: the plan keeps texture lookups,
/// and the emission is the factor times the texture.
#[test]
fn textures_other_than_the_base_colours_are_looked_up() {
    let d = Dir::new("gltf-pbr-no-base-texture");
    let mut bin = Bin::default();
    let p = [
        Vec3::new(-1.0, -1.0, 0.0),
        Vec3::new(1.0, -1.0, 0.0),
        Vec3::new(1.0, 1.0, 0.0),
        Vec3::new(-1.0, 1.0, 0.0),
    ];
    let (pos, ind) = bin.mesh(&p, &[[0, 1, 2], [0, 2, 3]]);
    let uv = bin.floats(&[0.0, 1.0, 1.0, 1.0, 1.0, 0.0, 0.0, 0.0], 2, "VEC2");
    let png = bin.view(&grey_png(128));
    let doc = json!({
        "scene": 0, "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0.0, 0.0, 3.0]}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos, "TEXCOORD_0": uv},
                                    "indices": ind, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.0, 0.0, 0.0, 1.0]},
                       "normalTexture": {"index": 0},
                       "emissiveFactor": [1.0, 1.0, 1.0], "emissiveTexture": {"index": 0}}],
        "textures": [{"source": 0}],
        "images": [{"bufferView": png, "mimeType": "image/png"}]
    });
    let s = load(&d.write("glow.glb", bin.glb(doc))).unwrap();
    let plan = Plan::new(&s, Features::all(), PlanPolicy::Prune);
    assert!(plan.decision(Feature::Textures).runs());
    assert!(plan.decision(Feature::NormalMaps).runs());
    assert!(plan.decision(Feature::Emission).runs());
    // A black rough metal: what the centre shows is its emission, sRGB
    // 128 (0.2158), not the factor's 1.
    let off = exact().without(&[Feature::Environment, Feature::Shadows]);
    let img = common::render(&s, 9, 9, 1, off, Builder::Sah, 1).image;
    let c = img[4 * 9 + 4];
    assert!((c - Vec3::splat(0.21586)).abs().max_element() < 1e-3, "{c}");
}

/// A 4x4 floor under a 2x2 leaf one unit above it, seen straight down by
/// an orthographic camera, lit by a directional light of 2 lux slanting
/// down toward -x (the leaf's shadow falls one unit toward -x). The leaf's
/// material is `leaf`; its texture's left half (x < 0) has alpha 0, its
/// right half alpha 255.
fn leaf_over_floor(leaf: Value) -> Vec<u8> {
    let mut bin = Bin::default();
    let quad = |y: f32, r: f32| {
        [
            Vec3::new(-r, y, -r),
            Vec3::new(r, y, -r),
            Vec3::new(r, y, r),
            Vec3::new(-r, y, r),
        ]
    };
    let faces = [[0, 2, 1], [0, 3, 2]];
    let (floor, floor_ind) = bin.mesh(&quad(0.0, 3.0), &faces);
    let (leaf_pos, leaf_ind) = bin.mesh(&quad(1.0, 1.0), &faces);
    let uv = bin.floats(&[0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0], 2, "VEC2");
    let img = image::RgbaImage::from_fn(8, 8, |x, _| {
        image::Rgba([255, 255, 255, if x < 4 { 0 } else { 255 }])
    });
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let png = bin.view(&png);
    let light = glam::Quat::from_rotation_arc(Vec3::NEG_Z, Vec3::new(-1.0, -1.0, 0.0).normalize());
    let down = glam::Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2);
    let grey = json!({"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0],
                                               "metallicFactor": 0.0}});
    bin.glb(json!({
        "scene": 0, "scenes": [{"nodes": [0, 1, 2, 3]}],
        "nodes": [{"mesh": 0}, {"mesh": 1},
                  {"camera": 0, "translation": [0.0, 5.0, 0.0], "rotation": down.to_array()},
                  {"extensions": {"KHR_lights_punctual": {"light": 0}},
                   "rotation": light.to_array()}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": floor}, "indices": floor_ind,
                                    "material": 0}]},
                   {"primitives": [{"attributes": {"POSITION": leaf_pos, "TEXCOORD_0": uv},
                                    "indices": leaf_ind, "material": 1}]}],
        "materials": [grey, leaf],
        "textures": [{"source": 0}],
        "images": [{"bufferView": png, "mimeType": "image/png"}],
        "cameras": [{"type": "orthographic",
                     "orthographic": {"xmag": 2.0, "ymag": 2.0, "znear": 0.1, "zfar": 10.0}}],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "directional", "intensity": 2.0}]}}
    }))
}

/// The mean colour over world x in `x0..x1`, z in -0.9..0.9, of a 64x64
/// render from above with `features` (Whitted: direct light only).
fn strip(file: &str, features: Features) -> impl Fn(f32, f32) -> Vec3 {
    let req = rayterm::render::SceneRequest {
        size: Some((64, 64)),
        features,
        integrator: Some(scene::Integrator::Whitted),
        ..rayterm::render::SceneRequest::new(file)
    };
    let s = rayterm::render::Session::open(&req).unwrap().0;
    let img = rayterm::render::Progressive::render(&s.tracer(), 1).image();
    move |x0: f32, x1: f32| {
        // Column c sees x = -2 + 4 (c + 0.5) / 64; rows likewise see z.
        let seen = |i: usize| -2.0 + 4.0 * (i as f32 + 0.5) / 64.0;
        let (mut sum, mut n) = (Vec3::ZERO, 0.0);
        for (i, p) in img.iter().enumerate() {
            let (x, z) = (seen(i % 64), seen(i / 64));
            if x > x0 && x < x1 && z.abs() < 0.9 {
                (sum, n) = (sum + *p, n + 1.0);
            }
        }
        sum / n
    }
}

/// Alpha MASK from a texture: camera rays see the floor through the
/// cut-out half, and the light passes it too, so its shadow has the
/// opaque half's shape; with alpha off the leaf is whole again. BLEND at
/// one half lets half the light through.
#[test]
fn alpha_cut_outs_are_passed_by_camera_and_shadow_rays() {
    let d = Dir::new("gltf-alpha");
    let leaf = |mode: &str, factor: f32| {
        json!({"name": "Leaf", "alphaMode": mode, "alphaCutoff": 0.5,
               "pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.0, 0.0, factor],
                                        "baseColorTexture": {"index": 0},
                                        "metallicFactor": 0.0}})
    };
    let mask = d.write("mask.glb", leaf_over_floor(leaf("MASK", 1.0)));
    let s = load(&mask).unwrap();
    let m = s.materials.iter().find(|m| m.name == "Leaf").unwrap();
    let a = m.alpha.expect("MASK is an alpha test");
    assert_eq!((a.cutoff, a.factor), (Some(0.5), 1.0));
    assert!(a.texture.is_some(), "{:?}", s.warnings);
    assert!(
        !s.warnings.iter().any(|w| w.contains("alpha")),
        "{:?}",
        s.warnings
    );

    let on = strip(&mask, exact());
    // Right of the leaf (x > 1) the floor is in no shadow; left of it
    // (x < -1), where the cut-out half's shadow would fall, nor is it.
    let grey_lit = on(1.1, 1.9).x;
    assert!(grey_lit > 0.1, "{grey_lit}");
    let lit = on(-1.9, -1.1);
    assert!((lit.x - grey_lit).abs() < 1e-5, "{lit} against {grey_lit}");
    // Seen through the cut-out: the floor, in the opaque half's shadow.
    let through = on(-0.9, -0.1);
    assert!(through.max_element() < 1e-4, "{through}");
    // The opaque half: red.
    let red = on(0.1, 0.9);
    // (Its specular lobe, white, adds a little green and blue.)
    assert!(red.x > 0.1 && red.x > 20.0 * red.y.max(red.z), "{red}");

    // Alpha off: the whole leaf is there, and its whole shadow too.
    let off = strip(&mask, exact().without(&[Feature::Alpha]));
    assert!(off(-1.9, -1.1).max_element() < 1e-4, "{}", off(-1.9, -1.1));
    let whole = off(-0.9, -0.1);
    assert!(whole.x > 0.1 && whole.x > 20.0 * whole.y, "{whole}");

    // BLEND: the texture's alpha times the factor's one half; where the
    // texture is opaque, half the shadow rays pass.
    let blend = d.write("blend.glb", leaf_over_floor(leaf("BLEND", 0.5)));
    let half = strip(&blend, exact());
    // The cut-out half still casts nothing; the opaque half's shadow,
    // seen through the cut-out, is half as dark as it was.
    let clear = half(-1.9, -1.1);
    assert!(
        (clear.x - grey_lit).abs() < 1e-5,
        "{clear}: the cut-out half casts nothing"
    );
    let shaded = half(-0.9, -0.1);
    assert!(
        (shaded.x / grey_lit - 0.5).abs() < 0.05 && shaded.y / grey_lit > 0.45,
        "{shaded}: half the light of {grey_lit}"
    );
    let plan = Plan::new(&load(&blend).unwrap(), exact(), PlanPolicy::Prune);
    assert!(plan.decision(Feature::Alpha).runs());
}

/// Valid files other readers open, which the glTF crate alone refuses or
/// rayterm once did: whole numbers written as floats (`0.0` for an
/// index), bytes after a .glb's declared end, and a buffer nothing reads
/// that cannot be read (an http: URI): each opens, the last two with a
/// warning naming what was left out.
#[test]
fn whole_floats_trailing_bytes_and_unread_buffers_open() {
    let d = Dir::new("gltf-lenient");
    let floats = one_mesh(json!({"scene": 0.0, "scenes": [{"nodes": [0.0]}]}));
    let s = load(&d.write("floats.glb", &floats)).unwrap();
    assert_eq!(s.geometry.triangle_count(), 1);

    let mut trailing = one_mesh(json!({}));
    trailing.extend(b"\0\0\0");
    let s = load(&d.write("trailing.glb", &trailing)).unwrap();
    assert_eq!(s.geometry.triangle_count(), 1);
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("trailing.glb: 3 bytes after the end its header declares")),
        "{:?}",
        s.warnings
    );

    let mut bin = Bin::default();
    let (p, t) = triangle();
    let (pos, ind) = bin.mesh(&p, &t);
    use base64::Engine;
    let data = base64::engine::general_purpose::STANDARD.encode(&bin.bytes);
    let text = json!({
        "asset": {"version": "2.0"},
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}, "indices": ind}]}],
        "buffers": [{"byteLength": bin.bytes.len(),
                     "uri": format!("data:application/octet-stream;base64,{data}")},
                    {"byteLength": 4, "uri": "http://example.com/unused.bin"}],
        "bufferViews": bin.views, "accessors": bin.accessors
    });
    let s = load(&d.write("unread.gltf", text.to_string())).unwrap();
    assert_eq!(s.geometry.triangle_count(), 1);
    assert!(
        s.warnings
            .iter()
            .any(|w| w.contains("buffer 1: http: URIs are not read")
                && w.contains("no view reads it: left out")),
        "{:?}",
        s.warnings
    );
}

/// `KHR_materials_unlit`: the surface shows its base colour exactly,
/// whatever the lights (none here), under either integrator; the
/// extension goes unmentioned in the warnings.
#[test]
fn unlit_materials_show_their_base_colour() {
    let d = Dir::new("gltf-unlit");
    let base = [0.25, 0.5, 0.75];
    let big = [
        Vec3::new(-50.0, -50.0, -1.0),
        Vec3::new(50.0, -50.0, -1.0),
        Vec3::new(0.0, 50.0, -1.0),
    ];
    let mut bin = Bin::default();
    let (pos, ind) = bin.mesh(&big, &[[0, 1, 2]]);
    let file = d.write(
        "unlit.glb",
        bin.glb(json!({
            "scene": 0, "scenes": [{"nodes": [0, 1]}],
            "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0.0, 0.0, 2.0]}],
            "meshes": [{"primitives": [{"attributes": {"POSITION": pos}, "indices": ind,
                                        "material": 0}]}],
            "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [base[0], base[1], base[2], 1.0]},
                           "extensions": {"KHR_materials_unlit": {}}}],
            "cameras": [{"type": "perspective", "perspective": {"yfov": 0.5, "znear": 0.1}}],
            "extensionsUsed": ["KHR_materials_unlit"]
        })),
    );
    let s = load(&file).unwrap();
    assert!(s.materials.iter().any(|m| m.unlit));
    assert!(
        !s.warnings.iter().any(|w| w.contains("unlit")),
        "{:?}",
        s.warnings
    );
    for integrator in [scene::Integrator::Whitted, scene::Integrator::Path] {
        let req = rayterm::render::SceneRequest {
            size: Some((8, 8)),
            features: exact(),
            integrator: Some(integrator),
            ..rayterm::render::SceneRequest::new(&file)
        };
        let session = rayterm::render::Session::open(&req).unwrap().0;
        let img = rayterm::render::Progressive::render(&session.tracer(), 2).image();
        for p in img {
            assert_eq!(p, Vec3::from_array(base), "{integrator:?}");
        }
    }
}

/// `KHR_materials_ior` sets a dielectric's reflectance at normal
/// incidence, `((ior - 1) / (ior + 1))²`; 0 means it reflects all; the
/// default (1.5, or no extension) gives 0.04; a value below 1 is said
/// and left at the default.
#[test]
fn the_index_of_refraction_sets_a_dielectrics_reflectance() {
    let d = Dir::new("gltf-ior");
    let mat = |name: &str, ior: Value| {
        let mut m = json!({"name": name, "pbrMetallicRoughness": {"metallicFactor": 0.0}});
        if !ior.is_null() {
            m["extensions"] = json!({"KHR_materials_ior": ior});
        }
        m
    };
    let mut bin = Bin::default();
    let (p, t) = triangle();
    let (pos, ind) = bin.mesh(&p, &t);
    let names = ["plain", "glass", "diamond", "all", "bad"];
    let materials = vec![
        mat("plain", Value::Null),
        mat("glass", json!({})),
        mat("diamond", json!({"ior": 2.0})),
        mat("all", json!({"ior": 0.0})),
        mat("bad", json!({"ior": 0.5})),
    ];
    let prims: Vec<Value> = (0..names.len())
        .map(|i| json!({"attributes": {"POSITION": pos}, "indices": ind, "material": i}))
        .collect();
    let file = d.write(
        "ior.glb",
        bin.glb(json!({
            "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": prims}], "materials": materials,
            "extensionsUsed": ["KHR_materials_ior"]
        })),
    );
    let s = load(&file).unwrap();
    let f0 = |name: &str| {
        let m = s.materials.iter().find(|m| m.name == name).unwrap();
        m.pbr.as_ref().unwrap().dielectric_f0
    };
    assert_eq!(
        (f0("plain"), f0("glass"), f0("all"), f0("bad")),
        (0.04, 0.04, 1.0, 0.04)
    );
    assert!(
        (f0("diamond") - 1.0 / 9.0).abs() < 1e-7,
        "{}",
        f0("diamond")
    );
    assert!(
        s.warnings.iter().any(|w| w.contains("material bad")
            && w.contains("ior 0.5 is not 0 or a number of at least 1")),
        "{:?}",
        s.warnings
    );
    assert!(
        !s.warnings.iter().any(|w| w.contains("not shown")),
        "{:?}",
        s.warnings
    );
}

/// A 2x2 square facing the camera on +z, its normal map tilting every
/// normal toward the texture's up (+v, world +y here), under a directional
/// light from above and in front. Its two halves meet at x = 0, sharing
/// the vertices there; with `mirror`, the right half's u runs back
/// (u = 1 - |x|), as NormalTangentMirrorTest's halves do; else
/// u = (x + 1) / 2.
/// `tangent_w`, when given, is the file's TANGENT: +x with that w.
fn bumped_square(mirror: bool, tangent_w: Option<f32>, texel: [u8; 3]) -> Vec<u8> {
    let mut bin = Bin::default();
    let xs = [-1.0, 0.0, 1.0];
    let p: Vec<Vec3> = [-1.0, 1.0]
        .iter()
        .flat_map(|&y| xs.map(|x| Vec3::new(x, y, 0.0)))
        .collect();
    let (pos, ind) = bin.mesh(&p, &[[0, 1, 4], [0, 4, 3], [1, 2, 5], [1, 5, 4]]);
    let uv: Vec<f32> = p
        .iter()
        .flat_map(|p| {
            let u = if mirror {
                1.0 - p.x.abs()
            } else {
                (p.x + 1.0) / 2.0
            };
            [u, (1.0 - p.y) / 2.0]
        })
        .collect();
    let uv = bin.floats(&uv, 2, "VEC2");
    let normal = bin.floats(&[0.0, 0.0, 1.0].repeat(6), 3, "VEC3");
    let mut attributes = json!({"POSITION": pos, "NORMAL": normal, "TEXCOORD_0": uv});
    if let Some(w) = tangent_w {
        attributes["TANGENT"] = bin.floats(&[1.0, 0.0, 0.0, w].repeat(6), 4, "VEC4").into();
    }
    let img = image::RgbImage::from_pixel(2, 2, image::Rgb(texel));
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let png = bin.view(&png);
    let light = glam::Quat::from_rotation_arc(Vec3::NEG_Z, Vec3::new(0.0, -1.0, -1.0).normalize());
    bin.glb(json!({
        "scene": 0, "scenes": [{"nodes": [0, 1, 2]}],
        "nodes": [{"mesh": 0}, {"camera": 0, "translation": [0.0, 0.0, 3.0]},
                  {"extensions": {"KHR_lights_punctual": {"light": 0}},
                   "rotation": light.to_array()}],
        "meshes": [{"primitives": [{"attributes": attributes, "indices": ind, "material": 0}]}],
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [0.5, 0.5, 0.5, 1.0],
                                                "metallicFactor": 0.0, "roughnessFactor": 1.0},
                       "normalTexture": {"index": 0}}],
        "textures": [{"source": 0}],
        "images": [{"bufferView": png, "mimeType": "image/png"}],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.9, "znear": 0.1}}],
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "directional", "intensity": 3.0}]}}
    }))
}

/// The mean colour of a patch in the left half and one in the right half
/// of a 32x32 render of `file` (Whitted, exact).
fn halves(file: &str) -> (Vec3, Vec3) {
    let req = rayterm::render::SceneRequest {
        size: Some((32, 32)),
        features: exact(),
        integrator: Some(scene::Integrator::Whitted),
        ..rayterm::render::SceneRequest::new(file)
    };
    let s = rayterm::render::Session::open(&req).unwrap().0;
    let img = rayterm::render::Progressive::render(&s.tracer(), 1).image();
    let patch = |c0: usize| {
        let mut sum = Vec3::ZERO;
        for y in 12..20 {
            for x in c0..c0 + 4 {
                sum += img[y * 32 + x];
            }
        }
        sum / 32.0
    };
    (patch(8), patch(20))
}

/// A normal map over texture coordinates mirrored at a seam: the vertices
/// on the seam get a tangent frame per side (MikkTSpace's, the file having
/// none), so both halves bump the same way and look alike, as
/// NormalTangentMirrorTest asks. The tilt toward the light is seen.
#[test]
fn a_normal_map_over_mirrored_coordinates_bumps_both_halves_alike() {
    let d = Dir::new("gltf-tangent-mirror");
    let tilted = [128, 200, 200];
    let (left, right) = halves(&d.write("mirror.glb", bumped_square(true, None, tilted)));
    let (flat, _) = halves(&d.write("flat.glb", bumped_square(true, None, [128, 128, 255])));
    assert!(left.x > flat.x * 1.05, "{left} against flat {flat}");
    assert!(
        (left - right).abs().max_element() < 1e-4,
        "{left} against {right}"
    );
    let s = load(d.path("mirror.glb").to_str().unwrap()).unwrap();
    // The seam's two vertices were split, each half keeping its frame.
    assert_eq!(s.geometry.positions().len(), 8);
    assert_eq!(s.geometry.tangents().len(), 8);
}

/// A file's TANGENT is what the normal map turns by: with w = 1 it is the
/// frame MikkTSpace makes for these coordinates; w = -1 turns the
/// bitangent over, so the bump tilts away from the light.
#[test]
fn a_files_tangents_are_honoured_and_w_flips_the_bump() {
    let d = Dir::new("gltf-tangent-w");
    let tilted = [128, 200, 200];
    let (generated, _) = halves(&d.write("gen.glb", bumped_square(false, None, tilted)));
    let (up, up_right) = halves(&d.write("up.glb", bumped_square(false, Some(1.0), tilted)));
    let (down, _) = halves(&d.write("down.glb", bumped_square(false, Some(-1.0), tilted)));
    assert!(
        (up - generated).abs().max_element() < 1e-4,
        "{up} against {generated}"
    );
    assert!(
        (up - up_right).abs().max_element() < 1e-4,
        "{up} against {up_right}"
    );
    assert!(down.x < up.x * 0.8, "w = -1: {down}, w = 1: {up}");
}

/// Tangents MikkTSpace makes are those Blender wrote: its Suzanne (the
/// glTF-Blender-IO exporter's round-trip test, with TANGENT) read with and
/// without its TANGENT attribute.
#[test]
fn generated_tangents_match_blenders() {
    let d = Dir::new("gltf-tangent-blender");
    let dir = format!("{}/tests/files/blender", env!("CARGO_MANIFEST_DIR"));
    let with = load(&format!("{dir}/suzanne.gltf")).unwrap();
    let mut doc: Value =
        serde_json::from_str(&std::fs::read_to_string(format!("{dir}/suzanne.gltf")).unwrap())
            .unwrap();
    for p in doc["meshes"][0]["primitives"].as_array_mut().unwrap() {
        p["attributes"].as_object_mut().unwrap().remove("TANGENT");
    }
    std::fs::copy(format!("{dir}/suzanne.bin"), d.path("suzanne.bin")).unwrap();
    let without = load(&d.write("suzanne.gltf", serde_json::to_vec(&doc).unwrap())).unwrap();
    let (a, b) = (&with.geometry, &without.geometry);
    assert_eq!(a.positions().len(), b.positions().len());
    assert_eq!(a.tangents().len(), a.positions().len());
    let (mut sum, mut worst, mut n) = (0.0, 0.0f32, 0.0);
    for (ta, tb) in a.indices().iter().zip(b.indices()) {
        for k in 0..3 {
            let (x, y) = (a.tangents()[ta[k] as usize], b.tangents()[tb[k] as usize]);
            assert_eq!(x.w, y.w);
            let angle = x.truncate().angle_between(y.truncate()).to_degrees();
            (sum, worst, n) = (sum + angle, worst.max(angle), n + 1.0);
        }
    }
    // Blender makes them on its quads, before triangulating: a few degrees
    // apart at most.
    assert!(
        sum / n < 1.0 && worst < 10.0,
        "mean {} worst {worst}",
        sum / n
    );
}

/// `KHR_materials_specular` and `KHR_materials_pbrSpecularGlossiness` are
/// read: the specular weight and colour and their textures; a
/// specular-glossiness material converted to metallic-roughness, its
/// specular-glossiness texture texel by texel. Neither is listed as not
/// shown.
#[test]
fn specular_extensions_are_read() {
    let d = Dir::new("gltf-specular");
    let mut bin = Bin::default();
    let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
    let (pos, ind) = bin.mesh(&p, &[[0, 1, 2]]);
    let uv = bin.floats(&[0.0, 0.0, 1.0, 0.0, 0.0, 1.0], 2, "VEC2");
    // White, fully glossy: a specular-glossiness texel of a white metal.
    let img = image::RgbaImage::from_pixel(2, 2, image::Rgba([255, 255, 255, 255]));
    let mut png = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .unwrap();
    let png = bin.view(&png);
    let prim = |m: usize| {
        json!({"attributes": {"POSITION": pos, "TEXCOORD_0": uv},
                                 "indices": ind, "material": m})
    };
    let doc = json!({
        "scene": 0, "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"mesh": 0}, {"mesh": 1, "translation": [2.0, 0.0, 0.0]}],
        "meshes": [{"primitives": [prim(0)]}, {"primitives": [prim(1)]}],
        "extensionsUsed": ["KHR_materials_specular", "KHR_materials_pbrSpecularGlossiness"],
        "materials": [
            {"name": "Satin",
             "pbrMetallicRoughness": {"metallicFactor": 0.0},
             "extensions": {"KHR_materials_specular": {
                 "specularFactor": 0.5, "specularColorFactor": [1.0, 0.5, 0.25],
                 "specularTexture": {"index": 0},
                 "specularColorTexture": {"index": 0, "texCoord": 0}}}},
            {"name": "Plastic",
             "extensions": {"KHR_materials_pbrSpecularGlossiness": {
                 "diffuseFactor": [0.5, 0.2, 0.1, 1.0], "specularFactor": [0.04, 0.04, 0.04],
                 "glossinessFactor": 0.3, "diffuseTexture": {"index": 0},
                 "specularGlossinessTexture": {"index": 0}}}}],
        "textures": [{"source": 0}],
        "images": [{"bufferView": png, "mimeType": "image/png"}]
    });
    let s = load(&d.write("specular.glb", bin.glb(doc))).unwrap();
    assert!(
        !s.warnings.iter().any(|w| w.contains("not shown")),
        "{:?}",
        s.warnings
    );
    let material = |name: &str| s.materials.iter().find(|m| m.name == name).unwrap();
    let satin = material("Satin").pbr.as_ref().unwrap();
    assert_eq!(
        (satin.specular, satin.specular_color),
        (0.5, Vec3::new(1.0, 0.5, 0.25))
    );
    let weight = &s.textures[satin.specular_texture.unwrap() as usize];
    assert_eq!(weight.texels[0], Vec3::ONE, "the alpha channel");
    assert!(satin.specular_color_texture.is_some());
    // The plastic's factors: no metal, its diffuse colour as base, its
    // glossiness 0.3 a roughness of 0.7.
    let plastic = material("Plastic");
    assert!((plastic.kd - Vec3::new(0.5, 0.2, 0.1)).abs().max_element() < 1e-5);
    let p = plastic.pbr.as_ref().unwrap();
    assert!(plastic.texture.is_some());
    // Its texture, white and fully glossy times the factors: specular
    // 0.04 is still no metal, glossiness 0.3 still a roughness of 0.7.
    let mr = &s.textures[p.metallic_roughness.unwrap() as usize];
    assert_eq!((p.metallic, p.roughness), (1.0, 1.0));
    assert!(
        (mr.texels[0] - Vec3::new(0.0, 0.7, 0.0))
            .abs()
            .max_element()
            < 1e-5,
        "{}",
        mr.texels[0]
    );
}
