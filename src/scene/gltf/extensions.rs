//! The extensions of a glTF file, checked before the crate validates it
//! (which refuses every required extension it does not know itself):
//! those rayterm reads, required ones it does not (refused, named), and
//! Draco-compressed primitives (refused as such rather than for the
//! bufferViews their accessors lack).

use std::path::Path;

use anyhow::{bail, Result};

use super::named;

/// The extensions whose data rayterm reads: a file may require them. Any
/// other is listed as not shown where used, and refused where required.
pub(super) const READ: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_mesh_quantization",
    "EXT_meshopt_compression",
    "KHR_texture_transform",
];

const DRACO: &str = "KHR_draco_mesh_compression";

/// Refuses a file that requires an extension rayterm does not read, or
/// whose primitives hold their data only as Draco; then leaves the crate
/// only the required extensions it knows.
pub(super) fn check(path: &Path, json: &mut ::gltf::json::Root) -> Result<()> {
    let unread: Vec<&str> = json
        .extensions_required
        .iter()
        .map(String::as_str)
        .filter(|e| !READ.contains(e))
        .collect();
    if !unread.is_empty() {
        let draco = match unread.contains(&DRACO) {
            true => " (Draco mesh compression)",
            false => "",
        };
        let list: Vec<String> = unread.iter().map(|e| crate::words::quoted(e)).collect();
        bail!(
            "{}: requires extension{} {}{draco}, which rayterm does not read",
            path.display(),
            if list.len() > 1 { "s" } else { "" },
            list.join(", ")
        );
    }
    // Draco where only used: the accessors' own data (a fallback) is read,
    // and there must be some.
    for (m, mesh) in json.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let draco = prim
                .extensions
                .as_ref()
                .is_some_and(|e| e.others.contains_key(DRACO));
            let accessors = prim.attributes.values().chain(&prim.indices);
            let bare = accessors
                .filter_map(|i| json.accessors.get(i.value()))
                .any(|a| a.buffer_view.is_none() && a.sparse.is_none());
            if draco && bare {
                bail!(
                    "{}: mesh {} primitive {p} is compressed with Draco ({DRACO}), which rayterm \
                     does not read, and has no uncompressed data",
                    path.display(),
                    named(mesh.name.as_deref(), m)
                );
            }
        }
    }
    json.extensions_required
        .retain(|e| ::gltf::json::extensions::ENABLED_EXTENSIONS.contains(&e.as_str()));
    Ok(())
}

/// Removes the vertex attributes whose names glTF does not define (not
/// `POSITION`, `TEXCOORD_n`... nor custom ones starting with `_`), which
/// nothing reads and the crate refuses; where the first was, if any, and
/// how many.
pub(super) fn undefined_attributes(json: &mut ::gltf::json::Root) -> Option<(String, usize)> {
    use ::gltf::json::validation::Checked;
    let mut first = None;
    let mut count = 0;
    for (m, mesh) in json.meshes.iter_mut().enumerate() {
        let name = named(mesh.name.as_deref(), m);
        for (p, prim) in mesh.primitives.iter_mut().enumerate() {
            if prim.attributes.remove(&Checked::Invalid).is_some() {
                first.get_or_insert_with(|| format!("mesh {name} primitive {p}"));
                count += 1;
            }
        }
    }
    first.map(|f| (f, count))
}
