//! Checks of a glTF document before it is read: cameras and images the
//! crate's accessors can read, values in the ranges glTF allows,
//! transforms and lights that 32-bit floats hold, and node hierarchies
//! that are trees.

use std::collections::BTreeMap;
use std::path::Path;

use anyhow::{bail, Result};
use glam::{DAffine3, Vec3};

use super::named;

/// Cameras and images the crate's accessors would panic on, by index, each
/// with why: `projection()` unwraps the object a camera's type names,
/// `source()` an image's uri or bufferView, and a bufferView's mimeType.
/// Those the scene uses are errors, the others warnings.
#[derive(Default)]
pub(super) struct Broken {
    pub(crate) cameras: BTreeMap<usize, String>,
    pub(crate) images: BTreeMap<usize, String>,
}

impl Broken {
    pub(crate) fn of(json: &::gltf::json::Root) -> Broken {
        use ::gltf::json::camera::Type;
        use ::gltf::json::validation::Checked;
        let mut b = Broken::default();
        for (i, c) in json.cameras.iter().enumerate() {
            let why = match (&c.type_, &c.perspective, &c.orthographic) {
                (Checked::Valid(Type::Perspective), None, _) => {
                    "its type is perspective and it has no perspective object"
                }
                (Checked::Valid(Type::Orthographic), _, None) => {
                    "its type is orthographic and it has no orthographic object"
                }
                _ => continue,
            };
            b.cameras.insert(i, why.to_string());
        }
        for (i, image) in json.images.iter().enumerate() {
            let why = match (&image.uri, &image.buffer_view, &image.mime_type) {
                (None, None, _) => "it has neither a uri nor a bufferView",
                (_, Some(_), None) => "it has a bufferView and no mimeType, which glTF requires",
                _ => continue,
            };
            b.images.insert(i, why.to_string());
        }
        b
    }

    /// The warnings for those left unused (a used one is an error).
    pub(crate) fn unused(&self, path: &Path, json: &::gltf::json::Root) -> Vec<String> {
        let cameras = self.cameras.iter().map(|(&i, why)| {
            let name = named(json.cameras[i].name.as_deref(), i);
            format!("camera {name}: {why}")
        });
        let images = self.images.iter().map(|(&i, why)| {
            let name = named(json.images[i].name.as_deref(), i);
            format!("image {name}: {why}")
        });
        cameras
            .chain(images)
            .map(|w| format!("{}: {w}; not used, so ignored", path.display()))
            .collect()
    }
}

/// An error for a material factor or camera field outside the range glTF
/// allows: such values would render as nonsense (an infinite colour, a
/// view of nothing) rather than fail.
pub(super) fn check_values(path: &Path, doc: &::gltf::Document, broken: &Broken) -> Result<()> {
    let unit = |v: f32| (0.0..=1.0).contains(&v);
    for (i, m) in doc.materials().enumerate() {
        let pbr = m.pbr_metallic_roughness();
        let fields = [
            ("baseColorFactor", pbr.base_color_factor().to_vec()),
            ("metallicFactor", vec![pbr.metallic_factor()]),
            ("roughnessFactor", vec![pbr.roughness_factor()]),
        ];
        for (field, v) in fields {
            if let Some(bad) = v.iter().find(|&&x| !unit(x)) {
                bail!(
                    "{}: material {}: {field} {bad} is outside 0 to 1",
                    path.display(),
                    named(m.name(), i)
                );
            }
        }
        if let Some(bad) = m.emissive_factor().iter().find(|&&x| !unit(x)) {
            bail!(
                "{}: material {}: emissiveFactor {bad} is outside 0 to 1",
                path.display(),
                named(m.name(), i)
            );
        }
    }
    for c in doc
        .cameras()
        .filter(|c| !broken.cameras.contains_key(&c.index()))
    {
        match c.projection() {
            ::gltf::camera::Projection::Perspective(p) => {
                // The range a scene file's camera allows.
                let y = p.yfov();
                if !(1.0..179.0).contains(&y.to_degrees()) {
                    bail!(
                        "{}: camera {}: yfov {y} radians is not between 1 and 179 degrees",
                        path.display(),
                        named(c.name(), c.index())
                    );
                }
            }
            ::gltf::camera::Projection::Orthographic(o) => {
                // glTF forbids zero; a negative one (which it advises
                // against) is read as its size.
                let y = o.ymag();
                if y == 0.0 || !y.is_finite() {
                    bail!(
                        "{}: camera {}: ymag {y} is not a height (it must be a nonzero number)",
                        path.display(),
                        named(c.name(), c.index())
                    );
                }
            }
        }
    }
    Ok(())
}

/// Refuses a node whose transform 32-bit floats cannot hold (`1e39`
/// reads as infinity), or whose placement overflows f64 with its
/// parents': named here, not by the NaN positions it would give.
pub(super) fn check_transform(
    path: &Path,
    node: &::gltf::Node,
    name: &str,
    world: DAffine3,
) -> Result<()> {
    use ::gltf::scene::Transform;
    let fields = match node.transform() {
        Transform::Matrix { matrix } => vec![("matrix", matrix.concat())],
        Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => vec![
            ("translation", translation.to_vec()),
            ("rotation", rotation.to_vec()),
            ("scale", scale.to_vec()),
        ],
    };
    let shown = |v: &[f32]| v.iter().map(f32::to_string).collect::<Vec<_>>().join(", ");
    if let Some((field, v)) = fields
        .iter()
        .find(|(_, v)| !v.iter().all(|x| x.is_finite()))
    {
        bail!(
            "{}: node {name}: {field} [{}] is beyond 32-bit floats (finite only up to 3.4e38)",
            path.display(),
            shown(v)
        );
    }
    if !world.is_finite() {
        bail!(
            "{}: node {name}: its transform with its parents' overflows 64-bit floats",
            path.display()
        );
    }
    Ok(())
}

/// Refuses a light whose intensity or colour 32-bit floats cannot hold
/// (`1e39` reads as infinity), and warns of a negative one: either would
/// otherwise light the scene with nothing, unsaid.
pub(super) fn check_lights(
    path: &Path,
    doc: &::gltf::Document,
    warnings: &mut Vec<String>,
) -> Result<()> {
    for l in doc.lights().into_iter().flatten() {
        let name = named(l.name(), l.index());
        let (c, i) = (l.color(), l.intensity());
        let shown = format!("intensity {i}, color [{}, {}, {}]", c[0], c[1], c[2]);
        if !(Vec3::from_array(c) * i).is_finite() {
            bail!(
                "{}: light {name}: {shown}: beyond 32-bit floats (finite only up to 3.4e38)",
                path.display()
            );
        }
        if i < 0.0 || c.iter().any(|&x| x < 0.0) {
            warnings.push(format!(
                "{}: light {name}: negative {shown}: a light cannot shine less than nothing \
                 (a negative intensity gives no light)",
                path.display()
            ));
        }
    }
    Ok(())
}

/// Refuses a node hierarchy that is not a forest of trees below the
/// scene's roots, as glTF requires: a node with two parents, or a root
/// that is also a child, would be visited many times (exponentially many
/// in a chain of shared nodes) or forever (a cycle).
pub(super) fn check_trees(
    path: &Path,
    doc: &::gltf::Document,
    roots: &[::gltf::Node],
) -> Result<()> {
    let mut parents = vec![0usize; doc.nodes().len()];
    for n in doc.nodes() {
        for c in n.children() {
            parents[c.index()] += 1;
        }
    }
    let name = |n: &::gltf::Node| named(n.name(), n.index());
    if let Some(n) = doc.nodes().find(|n| parents[n.index()] > 1) {
        bail!(
            "{}: node {} is the child of {} nodes; glTF node hierarchies are trees \
             (one parent at most)",
            path.display(),
            name(&n),
            parents[n.index()]
        );
    }
    let mut seen = vec![false; parents.len()];
    for n in roots {
        if parents[n.index()] > 0 {
            bail!(
                "{}: node {} is a root of the scene and the child of another node \
                 (a cycle in the node hierarchy?)",
                path.display(),
                name(n)
            );
        }
        if std::mem::replace(&mut seen[n.index()], true) {
            bail!(
                "{}: node {} is listed twice among the scene's nodes",
                path.display(),
                name(n)
            );
        }
    }
    Ok(())
}
