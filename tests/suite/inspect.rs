//! The ray-tree inspector: its trees come from the renderer's own code path
//! (same colours to the bit), describe known scenes correctly, and its JSON
//! is stable.

use std::path::Path;
use std::process::Command;

use rayterm::inspect::{inspect_pixel, PixelTree, RayNode};
use rayterm::render::recorder::RayKind;
use rayterm::render::{Progressive, SceneRequest, Session, Tracer};
use rayterm::scene::load::builtin::SCENES;
use serde_json::Value;

const SEED: u64 = 7;

struct Setup(Session);

fn setup(spec: &str) -> Setup {
    let req = SceneRequest {
        seed: SEED,
        ..SceneRequest::new(spec)
    };
    Setup(Session::open(&req).unwrap().0)
}

impl Setup {
    fn tracer(&self, w: u32, h: u32) -> Tracer<'_> {
        self.0.tracer_for(&self.0.plan, &self.0.camera, (w, h))
    }
}

#[test]
fn tree_colour_is_the_rendered_sample_to_the_bit() {
    let (w, h) = (64, 48);
    for (name, _) in SCENES {
        let s = setup(name);
        let t = s.tracer(w, h);
        let film = Progressive::render(&t, 1);
        assert_eq!(film.bad_count(), 0, "{name}: NaN/Inf samples");
        for y in 0..h {
            for x in 0..w {
                let tree = inspect_pixel(&t, x, y, 0);
                let (got, want) = (tree.color, film.mean(x, y));
                assert_eq!(
                    got.to_array().map(f32::to_bits),
                    want.to_array().map(f32::to_bits),
                    "{name} pixel ({x}, {y}): tree {got} vs film {want}"
                );
                // The root is the camera ray and carries the whole colour.
                assert_eq!(tree.root.kind, RayKind::Camera);
                assert_eq!(tree.root.color, got);
            }
        }
    }
}

/// Every tree of a `w`x`h` image of `spec`.
fn all_trees(spec: &str, w: u32, h: u32) -> Vec<PixelTree> {
    let s = setup(spec);
    let t = s.tracer(w, h);
    (0..h)
        .flat_map(|y| (0..w).map(move |x| (x, y)))
        .map(|(x, y)| inspect_pixel(&t, x, y, 0))
        .collect()
}

fn hit_mesh(n: &RayNode) -> Option<&str> {
    n.hit.as_ref().map(|h| h.mesh.as_str())
}

#[test]
fn cornell_mirror_box_reflects_a_coloured_wall() {
    let trees = all_trees("cornell", 96, 96);
    let on_box: Vec<&PixelTree> = trees
        .iter()
        .filter(|t| hit_mesh(&t.root) == Some("tall_box"))
        .collect();
    assert!(!on_box.is_empty(), "no camera ray hits the tall box");
    let found = on_box.iter().find_map(|t| {
        t.root
            .children
            .iter()
            .find(|c| {
                c.kind == RayKind::Reflection && matches!(hit_mesh(c), Some("left" | "right"))
            })
            .map(|c| (t, c))
    });
    let (t, refl) = found.unwrap_or_else(|| {
        panic!(
            "none of the {} pixels on the tall box reflects the red or green wall",
            on_box.len()
        )
    });
    // The reflected ray carries the mirror's ks, and its colour is the wall's.
    assert_eq!(refl.weight, t.root.hit.as_ref().unwrap().ks);
    let wall = refl.hit.as_ref().unwrap();
    let dominant = if wall.mesh == "left" {
        wall.kd.x
    } else {
        wall.kd.y
    };
    assert_eq!(
        dominant,
        wall.kd.max_element(),
        "{}: {}",
        wall.mesh,
        wall.kd
    );
}

#[test]
fn cornell_floor_in_the_tall_box_shadow_is_occluded_by_it() {
    let trees = all_trees("cornell", 96, 96);
    let floor: Vec<&PixelTree> = trees
        .iter()
        .filter(|t| hit_mesh(&t.root) == Some("floor"))
        .collect();
    let point_light = |t: &PixelTree| {
        let l = &t.root.lights[0];
        assert_eq!(l.kind, "point");
        assert_eq!(l.samples.len(), 1);
        l.samples[0].clone()
    };
    let shadowed: Vec<_> = floor
        .iter()
        .map(|t| point_light(t))
        .filter(|s| s.occluder.as_ref().is_some_and(|(m, _)| m == "tall_box"))
        .collect();
    assert!(
        !shadowed.is_empty(),
        "no floor pixel of {} is shadowed by the tall box",
        floor.len()
    );
    for s in &shadowed {
        assert!(!s.visible && s.shadow_ray.is_some());
        assert_eq!(s.diffuse, glam::Vec3::ZERO);
    }
    // Lit floor exists too, so the test tells the two apart.
    assert!(floor.iter().any(|t| point_light(t).visible));
}

/// With shadows off no shadow ray is traced: the tree says the light
/// was not shadow-tested and counts it, not that it lies behind the surface.
#[test]
fn shadows_off_is_said_as_such_not_as_behind_the_surface() {
    let req = SceneRequest {
        seed: SEED,
        features: rayterm::render::Features::all().without(&[rayterm::render::Feature::Shadows]),
        ..SceneRequest::new("cornell")
    };
    let s = Session::open(&req).unwrap().0;
    let t = s.tracer_for(&s.plan, &s.camera, (32, 32));
    let tree = inspect_pixel(&t, 16, 16, 0);
    let sample = &tree.root.lights[0].samples[0];
    assert!(sample.visible && sample.shadow_ray.is_none(), "{sample:?}");
    let text = rayterm::inspect::text::to_text(&tree, true);
    assert!(text.contains("not shadow-tested (shadows off)"), "{text}");
    assert!(!text.contains("behind the surface"), "{text}");
}

#[test]
fn json_round_trips_through_serde() {
    // Scenes whose trees use every optional part: area light samples,
    // environment misses, UVs and texels, glossy children.
    for spec in ["cornell", "cornell-area", "cube-textured", "env", "mirrors"] {
        let s = setup(spec);
        let t = s.tracer(32, 24);
        for (x, y) in [(3, 4), (16, 12), (20, 18), (31, 0)] {
            let tree = inspect_pixel(&t, x, y, 0);
            let text = serde_json::to_string(&tree).unwrap();
            let back: PixelTree = serde_json::from_str(&text).unwrap();
            assert_eq!(back, tree, "{spec} ({x}, {y})");
        }
    }
}

/// Differences between `got` and `want`, numbers within a relative and
/// absolute tolerance (integers exactly), each named by its JSON path.
fn diff(path: &str, got: &Value, want: &Value, out: &mut Vec<String>) {
    match (got, want) {
        (Value::Object(a), Value::Object(b)) => {
            for k in a.keys().filter(|k| !b.contains_key(*k)) {
                out.push(format!("{path}.{k}: not in the snapshot"));
            }
            for (k, bv) in b {
                match a.get(k) {
                    Some(av) => diff(&format!("{path}.{k}"), av, bv, out),
                    None => out.push(format!("{path}.{k}: missing")),
                }
            }
        }
        (Value::Array(a), Value::Array(b)) if a.len() == b.len() => {
            for (i, (av, bv)) in a.iter().zip(b).enumerate() {
                diff(&format!("{path}[{i}]"), av, bv, out);
            }
        }
        (Value::Number(a), Value::Number(b)) if a.is_f64() || b.is_f64() => {
            let (a, b) = (a.as_f64().unwrap(), b.as_f64().unwrap());
            if (a - b).abs() > 1e-5 + 1e-4 * b.abs() {
                out.push(format!("{path}: {a} vs {b}"));
            }
        }
        _ if got != want => out.push(format!("{path}: {got} vs {want}")),
        _ => {}
    }
}

#[test]
fn diff_tolerates_float_noise_only() {
    let a: Value = serde_json::from_str(r#"{"a": [1.0, 2.5], "n": 3, "s": "x"}"#).unwrap();
    let close: Value =
        serde_json::from_str(r#"{"a": [1.000001, 2.5000002], "n": 3, "s": "x"}"#).unwrap();
    let mut out = Vec::new();
    diff("", &close, &a, &mut out);
    assert!(out.is_empty(), "{out:?}");
    for bad in [
        r#"{"a": [1.01, 2.5], "n": 3, "s": "x"}"#,
        r#"{"a": [1.0], "n": 3, "s": "x"}"#,
        r#"{"a": [1.0, 2.5], "n": 4, "s": "x"}"#,
        r#"{"a": [1.0, 2.5], "n": 3, "s": "y"}"#,
        r#"{"a": [1.0, 2.5], "n": 3}"#,
        r#"{"a": [1.0, 2.5], "n": 3, "s": "x", "extra": null}"#,
    ] {
        let mut out = Vec::new();
        diff("", &serde_json::from_str(bad).unwrap(), &a, &mut out);
        assert_eq!(out.len(), 1, "{bad}: {out:?}");
    }
}

/// Set `RAYTERM_UPDATE_SNAPSHOTS=1` to rewrite the snapshot after an
/// intended change (a scene edit, a new field), then review its diff.
#[test]
fn cornell_json_matches_the_snapshot() {
    let out = Command::new(env!("CARGO_BIN_EXE_rayterm"))
        .args([
            "inspect", "cornell", "--pixel", "200,300", "--size", "400x400", "--json",
        ])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let got: Value = serde_json::from_slice(&out.stdout).unwrap();
    // The CLI's JSON is a PixelTree.
    serde_json::from_value::<PixelTree>(got.clone()).unwrap();
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/snapshots/cornell_200_300.json");
    if std::env::var_os("RAYTERM_UPDATE_SNAPSHOTS").is_some() {
        std::fs::write(&path, &out.stdout).unwrap();
        eprintln!("wrote {}", path.display());
        return;
    }
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| {
        panic!(
            "{}: {e} (run with RAYTERM_UPDATE_SNAPSHOTS=1 to create it)",
            path.display()
        )
    });
    let want: Value = serde_json::from_str(&text).unwrap();
    let mut errs = Vec::new();
    diff("", &got, &want, &mut errs);
    assert!(
        errs.is_empty(),
        "inspect JSON differs from {}:\n{}",
        path.display(),
        errs.join("\n")
    );
}
