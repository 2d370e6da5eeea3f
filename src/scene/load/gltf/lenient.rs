//! Documents that glTF allows and the `gltf` crate's types refuse, read
//! again with what the crate requires filled in: a scene without `nodes`
//! (Blender writes an empty one), an animation channel whose target has no
//! `node` (`KHR_animation_pointer` aims it elsewhere). rayterm shows a file
//! at rest, so such a channel is simply left out. An integer written as
//! a float (`1.0`, `1e0`: the same JSON number) is read as the integer.
//! And the crate's
//! validation, which [`document`] runs forgiving what glTF allows.

use ::gltf::json::{self, Value};
use serde_json::Map;

/// The document in `body` (JSON or `.glb`) read with the fills above, or
/// `None` when it needs none (the crate's first error then stands). Only a
/// document the crate refused comes here, so a readable one is parsed once.
pub(super) fn reread(body: &[u8]) -> Option<Result<::gltf::Gltf, ::gltf::Error>> {
    let glb = match body.starts_with(b"glTF") {
        true => Some(::gltf::Glb::from_slice(body).ok()?),
        false => None,
    };
    let text = glb.as_ref().map_or(body, |g| &g.json);
    let mut doc: Value = json::deserialize::from_slice(text).ok()?;
    if !fill(&mut doc) {
        return None;
    }
    let root: json::Root = match json::deserialize::from_value(doc) {
        Ok(r) => r,
        Err(e) => return Some(Err(::gltf::Error::Deserialize(e))),
    };
    Some(Ok(::gltf::Gltf {
        document: ::gltf::Document::from_json_without_validation(root),
        blob: glb.and_then(|g| g.bin).map(|b| b.into_owned()),
    }))
}

/// The document of `json`, validated as the crate validates it but for two
/// things glTF allows: an accessor with neither a `bufferView` nor
/// `sparse` (its values are zeros, which [`super::accessor`] reads) and a
/// primitive without `POSITION` (which glTF asks readers not to draw).
pub(super) fn document(json: json::Root) -> Result<::gltf::Document, ::gltf::Error> {
    use json::validation::{Error, Validate};
    let mut errors = Vec::new();
    json.validate(&json, json::Path::new, &mut |path, error| {
        errors.push((path(), error))
    });
    errors.retain(|(path, error)| !(matches!(error, Error::Missing) && allowed(path.as_str())));
    match errors.is_empty() {
        true => Ok(::gltf::Document::from_json_without_validation(json)),
        false => Err(::gltf::Error::Validation(errors)),
    }
}

/// Whether a missing field at `path` is one glTF allows to be missing:
/// `accessors[A].bufferView` (the crate reports it only where `sparse` is
/// missing too) or `meshes[M].primitives[P].attributes["POSITION"]`.
fn allowed(path: &str) -> bool {
    let index = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
    if let Some(a) = path
        .strip_prefix("accessors[")
        .and_then(|p| p.strip_suffix("].bufferView"))
    {
        return index(a);
    }
    path.strip_prefix("meshes[")
        .and_then(|p| p.strip_suffix("].attributes[\"POSITION\"]"))
        .and_then(|p| p.split_once("].primitives["))
        .is_some_and(|(m, p)| index(m) && index(p))
}

/// Fills in what the crate requires; whether anything was.
fn fill(doc: &mut Value) -> bool {
    let mut filled = false;
    fn objects<'v>(doc: &'v mut Value, key: &str) -> Vec<&'v mut Map<String, Value>> {
        match doc.get_mut(key) {
            Some(Value::Array(a)) => a.iter_mut().filter_map(Value::as_object_mut).collect(),
            _ => Vec::new(),
        }
    }
    for scene in objects(doc, "scenes") {
        if !scene.contains_key("nodes") {
            scene.insert("nodes".into(), Value::Array(Vec::new()));
            filled = true;
        }
    }
    filled |= integers(doc);
    for animation in objects(doc, "animations") {
        if let Some(Value::Array(channels)) = animation.get_mut("channels") {
            let before = channels.len();
            channels.retain(|c| c.pointer("/target/node").is_some());
            filled |= channels.len() != before;
        }
    }
    filled
}

/// Writes every whole number written as a float (`1.0`, `1e0`) as an
/// integer, which the crate's integer fields require and its float fields
/// take alike; whether any was.
fn integers(v: &mut Value) -> bool {
    match v {
        Value::Number(n) if !n.is_u64() && !n.is_i64() => {
            let Some(f) = n.as_f64().filter(|f| f.fract() == 0.0 && f.abs() < 9.0e15) else {
                return false;
            };
            *v = Value::from(f as i64);
            true
        }
        Value::Array(a) => a.iter_mut().fold(false, |any, x| integers(x) | any),
        Value::Object(o) => o.values_mut().fold(false, |any, x| integers(x) | any),
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_what_the_crate_requires_is_filled_in() {
        let mut doc = serde_json::json!({
            "scenes": [{"nodes": [0]}, {"name": "Scene.001"}],
            "animations": [{"channels": [
                {"sampler": 0, "target": {"node": 0, "path": "rotation"}},
                {"sampler": 1, "target": {"path": "pointer"}}
            ]}]
        });
        assert!(fill(&mut doc));
        assert_eq!(doc["scenes"][1]["nodes"], serde_json::json!([]));
        assert_eq!(doc["scenes"][0]["nodes"], serde_json::json!([0]));
        let channels = doc["animations"][0]["channels"].as_array().unwrap();
        assert_eq!(channels.len(), 1);
        assert_eq!(channels[0]["sampler"], 0);
        assert!(!fill(&mut doc), "filled twice");
        // Whole numbers written as floats become integers; others stay.
        let mut floats = serde_json::json!({"accessors": [{"count": 3.0, "bufferView": 1e0,
                                                          "min": [0.5, -2.0]}]});
        assert!(fill(&mut floats));
        assert_eq!(
            floats,
            serde_json::json!({"accessors": [{"count": 3, "bufferView": 1, "min": [0.5, -2]}]})
        );
        // glTF 1.0 keeps scenes in an object: nothing to fill.
        let mut old = serde_json::json!({"scenes": {"s": {}}});
        assert!(!fill(&mut old));
    }

    #[test]
    fn only_what_gltf_allows_is_forgiven() {
        for ok in [
            "accessors[0].bufferView",
            "accessors[12].bufferView",
            "meshes[0].primitives[3].attributes[\"POSITION\"]",
        ] {
            assert!(allowed(ok), "{ok}");
        }
        for refused in [
            "accessors[0].byteOffset",
            "accessors[].bufferView",
            "accessors[x].bufferView",
            "images[0].bufferView",
            "meshes[0].primitives[0].attributes[\"NORMAL\"]",
            "meshes[0].primitives[0].indices",
            "meshes[0].attributes[\"POSITION\"]",
        ] {
            assert!(!allowed(refused), "{refused}");
        }
    }
}
