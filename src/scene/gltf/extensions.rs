//! The glTF extensions rayterm reads. A file that lists one of them in
//! `extensionsRequired` is accepted (the crate's validation refuses those
//! it does not know itself), and one listed in `extensionsUsed` is not
//! among what the warnings call not shown. A reader of another extension
//! adds its name to [`READ`].

use anyhow::{bail, Result};
use std::path::Path;

use super::named;

/// The extensions rayterm reads.
pub(super) const READ: &[&str] = &[
    "KHR_lights_punctual",
    "EXT_mesh_gpu_instancing",
    "EXT_texture_webp",
];

/// Whether rayterm reads the extension `name`.
pub(super) fn reads(name: &str) -> bool {
    READ.contains(&name)
}

/// Leaves in `extensionsRequired` only what rayterm does not read, which
/// the crate's validation then refuses by name.
pub(super) fn accept_required(json: &mut ::gltf::json::Root) {
    json.extensions_required.retain(|e| !reads(e));
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
