//! The extensions of a glTF file, checked before the crate validates it
//! (which refuses every required extension it does not know itself):
//! those rayterm reads; required ones that only change how surfaces look
//! (materials, texture containers), drawn without them and said so;
//! others refused, named; Draco-compressed primitives refused as such
//! rather than for the bufferViews their accessors lack.

use std::path::Path;

use anyhow::{bail, Result};

use super::named;

/// The extensions whose data rayterm reads: a file may require them. Any
/// other is listed as not shown where used.
pub(super) const READ: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_mesh_quantization",
    "EXT_meshopt_compression",
    "KHR_texture_transform",
    "EXT_mesh_gpu_instancing",
    "EXT_texture_webp",
    "KHR_materials_emissive_strength",
    "KHR_materials_unlit",
    "KHR_materials_ior",
    "KHR_materials_specular",
    "KHR_materials_pbrSpecularGlossiness",
];

const DRACO: &str = "KHR_draco_mesh_compression";

/// Whether rayterm reads the extension `name`.
pub(super) fn reads(name: &str) -> bool {
    READ.contains(&name)
}

/// Whether a required extension changes only how surfaces look, so that
/// the geometry drawn without it is right: material models, texture
/// containers, shading techniques. A file that requires one opens with a
/// warning, as other viewers open it (its geometry is what rayterm shows
/// right today); any other unread required extension may change the
/// geometry itself, and refuses the file.
fn looks_only(name: &str) -> bool {
    name.starts_with("KHR_materials_")
        || [
            "KHR_texture_basisu",
            "MSFT_texture_dds",
            "EXT_texture_avif",
            "KHR_techniques_webgl",
            "KHR_technique_webgl",
        ]
        .contains(&name)
}

/// Refuses a file that requires an extension rayterm does not read and
/// that may change its geometry, or whose primitives hold their data only
/// as Draco; notes in `warnings` the required ones it draws without; then
/// leaves the crate only the required extensions it knows. Returns those
/// it draws without, said once here.
pub(super) fn check(
    path: &Path,
    json: &mut ::gltf::json::Root,
    warnings: &mut Vec<String>,
) -> Result<Vec<String>> {
    let (looks, unread): (Vec<String>, Vec<String>) = json
        .extensions_required
        .iter()
        .filter(|e| !reads(e))
        .cloned()
        .partition(|e| looks_only(e));
    if !unread.is_empty() {
        let draco = match unread.iter().any(|e| e == DRACO) {
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
    if !looks.is_empty() {
        let list: Vec<String> = looks.iter().map(|e| crate::words::quoted(e)).collect();
        warnings.push(format!(
            "{}: requires {}, which rayterm does not read: its surfaces are drawn without \
             {} (the geometry is the file's)",
            path.display(),
            list.join(", "),
            if list.len() > 1 { "them" } else { "it" }
        ));
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
    Ok(looks)
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

/// Makes each texture with an `EXT_texture_webp` image look up that image:
/// rayterm decodes WebP, so a PNG or JPEG `source` beside it (the fallback
/// for readers that do not) is left unused. A WebP image that does not
/// exist is an error naming the texture.
pub(super) fn prefer_webp(path: &Path, json: &mut ::gltf::json::Root) -> Result<()> {
    let images = json.images.len();
    for (i, t) in json.textures.iter_mut().enumerate() {
        let Some(ext) = t
            .extensions
            .as_ref()
            .and_then(|e| e.others.get("EXT_texture_webp"))
        else {
            continue;
        };
        match ext.get("source").and_then(|s| s.as_u64()) {
            Some(s) if s < images as u64 => t.source = ::gltf::json::Index::new(s as u32),
            _ => bail!(
                "{}: texture {}: its EXT_texture_webp source {} is not one of the file's {images} \
                 images",
                path.display(),
                named(t.name.as_deref(), i),
                ext.get("source")
                    .map_or("(none)".into(), |s| crate::words::quoted(&s.to_string()))
            ),
        }
    }
    Ok(())
}

/// What a texture without an image rayterm can read is, as the warnings
/// list it: named by the extension that alone gives its image.
pub(super) fn sourceless(t: &::gltf::Texture) -> String {
    let by = t
        .extensions()
        .and_then(|e| e.keys().find(|k| !reads(k)))
        .map(String::as_str);
    let what = match by {
        Some("KHR_texture_basisu") => {
            "KTX2 textures (Basis Universal, KHR_texture_basisu) without a PNG, JPEG or WebP \
             source"
                .into()
        }
        Some("MSFT_texture_dds") => "DDS textures (MSFT_texture_dds) without a PNG, JPEG or \
                                     WebP source"
            .into(),
        Some(ext) => format!("textures given only by {}", crate::words::quoted(ext)),
        None => "textures without an image".into(),
    };
    what + " (drawn in the material's colour)"
}
