//! Which texture coordinates a material's texture reads: its `texCoord`
//! (`TEXCOORD_0` or `TEXCOORD_1`), and `KHR_texture_transform`'s offset,
//! rotation, scale and `texCoord` override, on every texture slot.

use glam::{Affine2, Mat2, Vec2};
use serde_json::Value;

use crate::scene::texture::UvMap;

/// A texture slot's `KHR_texture_transform`, as the extension writes it
/// (glTF's coordinates, v down).
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct Transform {
    offset: [f32; 2],
    rotation: f32,
    scale: [f32; 2],
    tex_coord: Option<u32>,
}

impl Transform {
    /// From a textureInfo the crate has read.
    pub(super) fn of_info(t: &::gltf::texture::TextureTransform) -> Self {
        Self {
            offset: t.offset(),
            rotation: t.rotation(),
            scale: t.scale(),
            tex_coord: t.tex_coord(),
        }
    }

    /// From the JSON of a slot the crate leaves as extension data (the
    /// normal and occlusion textures, those of other extensions); numbers
    /// missing take the extension's defaults, and a value that is not one
    /// is `Err` (what it is, for the warning).
    pub(super) fn of_json(v: &Value) -> Result<Self, String> {
        let pair = |key: &str, default: [f32; 2]| match v.get(key) {
            None => Ok(default),
            Some(p) => match p.as_array().map(|a| a.iter().map(Value::as_f64).collect()) {
                Some(Some::<Vec<f64>>(a)) if a.len() == 2 => Ok([a[0] as f32, a[1] as f32]),
                _ => Err(format!("its {key} is {p}, not two numbers")),
            },
        };
        let rotation = match v.get("rotation") {
            None => 0.0,
            Some(r) => r
                .as_f64()
                .ok_or_else(|| format!("its rotation is {r}, not a number"))?
                as f32,
        };
        let tex_coord = match v.get("texCoord") {
            None => None,
            Some(t) => Some(
                t.as_u64()
                    .and_then(|t| u32::try_from(t).ok())
                    .ok_or_else(|| format!("its texCoord is {t}, not a set's number"))?,
            ),
        };
        Ok(Self {
            offset: pair("offset", [0.0, 0.0])?,
            rotation,
            scale: pair("scale", [1.0, 1.0])?,
            tex_coord,
        })
    }

    /// The UV set it reads for a slot whose `texCoord` is `tex_coord`.
    pub(super) fn set(t: Option<&Self>, tex_coord: u32) -> u32 {
        t.and_then(|t| t.tex_coord).unwrap_or(tex_coord)
    }

    /// The transform of rayterm's coordinates (v up) that it makes:
    /// scaled, turned, then offset in glTF's (v down). `None` for the
    /// identity, which leaves coordinates as they are, bit for bit; `Err`
    /// for one that is not finite.
    fn affine(&self) -> Result<Option<Affine2>, ()> {
        let ([ox, oy], [sx, sy], r) = (self.offset, self.scale, self.rotation);
        if ![ox, oy, sx, sy, r].iter().all(|x| x.is_finite()) {
            return Err(());
        }
        if (ox, oy, sx, sy, r) == (0.0, 0.0, 1.0, 1.0, 0.0) {
            return Ok(None);
        }
        // The extension's u' = cos·sx·u + sin·sy·v + ox,
        // v' = -sin·sx·u + cos·sy·v + oy; glTF's v is 1 - rayterm's.
        let (sin, cos) = r.sin_cos();
        let gltf = Affine2::from_mat2_translation(
            Mat2::from_cols(
                Vec2::new(cos * sx, -sin * sx),
                Vec2::new(sin * sy, cos * sy),
            ),
            Vec2::new(ox, oy),
        );
        let flip =
            Affine2::from_mat2_translation(Mat2::from_diagonal(Vec2::new(1.0, -1.0)), Vec2::Y);
        Ok(Some(flip * gltf * flip))
    }
}

/// What a slot reads, as the scene's textures hold it: `Err` with why not
/// where rayterm cannot (a set past `TEXCOORD_1`, a transform that is not
/// finite).
pub(super) fn uv_map(tex_coord: u32, t: Option<&Transform>) -> Result<UvMap, String> {
    let set = Transform::set(t, tex_coord);
    let set = match set {
        0 | 1 => set as u8,
        n => {
            return Err(format!(
                "textures on TEXCOORD_{n} (rayterm reads TEXCOORD_0 and TEXCOORD_1)"
            ))
        }
    };
    let transform = match t.map(Transform::affine) {
        None => None,
        Some(Ok(m)) => m,
        Some(Err(())) => return Err("textures whose KHR_texture_transform is not finite".into()),
    };
    Ok(UvMap { set, transform })
}

/// The UV sets a material's texture slots read, the core's and those of
/// the extensions rayterm reads (a slot whose transform cannot be read,
/// its own `texCoord`).
pub(super) fn sets(m: &::gltf::Material) -> Vec<u32> {
    let pbr = m.pbr_metallic_roughness();
    let info = |i: Option<::gltf::texture::Info>| {
        i.map(|i| {
            let t = i.texture_transform().map(|t| Transform::of_info(&t));
            Transform::set(t.as_ref(), i.tex_coord())
        })
    };
    let raw = |tex_coord: u32, ext: Option<&Value>| {
        let t = ext.and_then(|v| Transform::of_json(v).ok());
        Transform::set(t.as_ref(), tex_coord)
    };
    const EXT: &str = "KHR_texture_transform";
    [
        info(pbr.base_color_texture()),
        info(pbr.metallic_roughness_texture()),
        info(m.emissive_texture()),
        m.normal_texture()
            .map(|n| raw(n.tex_coord(), n.extension_value(EXT))),
        m.occlusion_texture()
            .map(|o| raw(o.tex_coord(), o.extension_value(EXT))),
    ]
    .into_iter()
    .flatten()
    .chain(super::specular::sets(m))
    .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The transform of rayterm's coordinates is the extension's own,
    /// between the two conventions for v.
    #[test]
    fn the_affine_map_is_the_extensions_in_rayterms_coordinates() {
        let t = Transform {
            offset: [0.5, -0.25],
            rotation: 0.3,
            scale: [2.0, 0.5],
            tex_coord: None,
        };
        let m = t.affine().unwrap().unwrap();
        let (sin, cos) = 0.3f32.sin_cos();
        for (u, v) in [(0.0, 0.0), (0.25, 0.75), (1.0, 0.5), (-3.0, 2.0)] {
            // The extension's formula on glTF's (u, v).
            let (su, sv) = (u * 2.0, v * 0.5);
            let want = Vec2::new(cos * su + sin * sv + 0.5, -sin * su + cos * sv - 0.25);
            let got = m.transform_point2(Vec2::new(u, 1.0 - v));
            assert!((got - Vec2::new(want.x, 1.0 - want.y)).abs().max_element() < 1e-5);
        }
        let id = Transform {
            offset: [0.0; 2],
            rotation: 0.0,
            scale: [1.0; 2],
            tex_coord: Some(1),
        };
        assert_eq!(
            uv_map(0, Some(&id)),
            Ok(UvMap {
                set: 1,
                transform: None
            })
        );
        assert!(uv_map(2, None).unwrap_err().contains("TEXCOORD_2"));
        let inf = Transform {
            scale: [f32::INFINITY, 1.0],
            ..id
        };
        assert!(uv_map(0, Some(&inf)).is_err());
    }

    #[test]
    fn transforms_in_extension_data_take_the_extensions_defaults() {
        let t = Transform::of_json(&serde_json::json!({"texCoord": 1, "offset": [0.5, 0]}));
        assert_eq!(
            t,
            Ok(Transform {
                offset: [0.5, 0.0],
                rotation: 0.0,
                scale: [1.0, 1.0],
                tex_coord: Some(1),
            })
        );
        let e = Transform::of_json(&serde_json::json!({"scale": 2})).unwrap_err();
        assert!(e.contains("scale is 2"), "{e}");
    }
}
