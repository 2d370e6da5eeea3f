//! The material extensions about specular reflection, whose data the
//! `gltf` crate leaves as JSON: `KHR_materials_specular` (a dielectric's
//! specular weight and colour) and `KHR_materials_pbrSpecularGlossiness`
//! (an older model, converted to metallic-roughness by [`specgloss`]).
//!
//! [`specgloss`]: super::specgloss

use std::sync::Arc;

use anyhow::Result;
use glam::Vec3;
use serde_json::Value;

use super::specgloss;
use super::texcoord::Transform;
use super::{Reader, TEXTURE_TRANSFORM};
use crate::scene::load::parts::Parts;
use crate::scene::texture::Encoding;
use crate::scene::Pbr;

pub(super) const SPECULAR: &str = "KHR_materials_specular";
pub(super) const SPEC_GLOSS: &str = "KHR_materials_pbrSpecularGlossiness";

/// `N` numbers of an extension's object at `key`, `default` where it has
/// none; `Err` where what it has is not `N` finite numbers.
fn numbers<const N: usize>(v: &Value, key: &str, default: [f32; N]) -> Result<[f32; N], String> {
    let Some(x) = v.get(key) else {
        return Ok(default);
    };
    let read: Option<Vec<f32>> = match (N, x) {
        (1, Value::Number(n)) => n.as_f64().map(|n| vec![n as f32]),
        (_, Value::Array(a)) => a.iter().map(|n| Some(n.as_f64()? as f32)).collect(),
        _ => None,
    };
    match read {
        Some(r) if r.len() == N && r.iter().all(|x| x.is_finite()) => {
            Ok(std::array::from_fn(|i| r[i]))
        }
        _ => Err(format!("its {key} is {x}, not {N} finite number(s)")),
    }
}

/// A whole number from 0 at `key` of a textureInfo an extension gives as
/// JSON (`1.0` too, as the core textures read it); `None` when absent.
fn whole(info: &Value, key: &str) -> Result<Option<u32>, String> {
    match info.get(key) {
        None => Ok(None),
        Some(v) => v
            .as_f64()
            .filter(|x| x.fract() == 0.0 && (0.0..=u32::MAX as f64).contains(x))
            .map(|x| Some(x as u32))
            .ok_or_else(|| format!("its {key} is {v}, not a whole number from 0")),
    }
}

/// The UV sets the texture slots of these extensions read.
pub(super) fn sets(m: &::gltf::Material) -> Vec<u32> {
    let slots = [
        (SPECULAR, "specularTexture"),
        (SPECULAR, "specularColorTexture"),
        (SPEC_GLOSS, "diffuseTexture"),
        (SPEC_GLOSS, "specularGlossinessTexture"),
    ];
    slots
        .iter()
        .filter_map(|(ext, slot)| m.extensions()?.get(*ext)?.get(*slot))
        .map(|info| {
            let t = info
                .pointer(&format!("/extensions/{TEXTURE_TRANSFORM}"))
                .and_then(|t| Transform::of_json(t).ok());
            let tex_coord = whole(info, "texCoord").ok().flatten().unwrap_or(0);
            Transform::set(t.as_ref(), tex_coord)
        })
        .collect()
}

/// A specular-glossiness material's factors in metallic-roughness terms:
/// base colour (and the diffuse factor's alpha), metallic, roughness; and
/// its diffuse factor.
pub(super) struct Converted {
    pub(super) base: [f32; 4],
    pub(super) metallic: f32,
    pub(super) roughness: f32,
    diffuse: Vec3,
}

impl Reader<'_> {
    /// An extension's number(s) at `key`, or `default` with a warning
    /// naming `user` and the extension where they are not numbers.
    fn ext_numbers<const N: usize>(
        &self,
        parts: &mut Parts,
        (ext, v): (&str, &Value),
        key: &str,
        default: [f32; N],
        user: &str,
    ) -> [f32; N] {
        numbers(v, key, default).unwrap_or_else(|why| {
            parts.warnings.push(format!(
                "{}: {user}: {ext}: {why}; the default {default:?} is used",
                self.at()
            ));
            default
        })
    }

    /// Material `m`'s extension `ext`, where it is a JSON object as glTF
    /// requires; anything else is left out with a warning naming `user`.
    pub(super) fn ext_object<'m>(
        &self,
        parts: &mut Parts,
        m: &'m ::gltf::Material,
        ext: &str,
        user: &str,
    ) -> Option<&'m Value> {
        let v = m.extensions()?.get(ext)?;
        if !v.is_object() {
            parts.warnings.push(format!(
                "{}: {user}: {ext} is {}, not an object: left out",
                self.at(),
                crate::words::quoted(&v.to_string())
            ));
            return None;
        }
        Some(v)
    }

    /// The texture of a textureInfo an extension gives as JSON (`index`,
    /// `texCoord` and its own `KHR_texture_transform`).
    pub(super) fn json_texture(
        &mut self,
        parts: &mut Parts,
        info: Option<&Value>,
        user: &str,
        encoding: Encoding,
        tint: Vec3,
    ) -> Result<Option<u32>> {
        let Some(info) = info else {
            return Ok(None);
        };
        let read = whole(info, "index").and_then(|i| Ok((i, whole(info, "texCoord")?)));
        let (index, tex_coord) = match read {
            Ok(r) => r,
            Err(why) => {
                parts
                    .warnings
                    .push(format!("{}: {user}: a texture left out: {why}", self.at()));
                return Ok(None);
            }
        };
        let Some(texture) = index.and_then(|i| self.doc.textures().nth(i as usize)) else {
            parts.warnings.push(format!(
                "{}: {user}: a texture index {} that is not one of the file's {} textures: \
                 left out",
                self.at(),
                info.get("index").map_or("(none)".into(), Value::to_string),
                self.doc.textures().len()
            ));
            return Ok(None);
        };
        let transform = info
            .pointer(&format!("/extensions/{TEXTURE_TRANSFORM}"))
            .map(Transform::of_json);
        let tex_coord = tex_coord.unwrap_or(0);
        self.texture_of(parts, texture, tex_coord, transform, user, encoding, tint)
    }

    /// `KHR_materials_specular` of material `m` into `p`.
    pub(super) fn specular(
        &mut self,
        parts: &mut Parts,
        m: &::gltf::Material,
        p: &mut Pbr,
        user: &str,
    ) -> Result<()> {
        let Some(v) = self.ext_object(parts, m, SPECULAR, user) else {
            return Ok(());
        };
        let [weight] = self.ext_numbers(parts, (SPECULAR, v), "specularFactor", [1.0], user);
        let tint = self.ext_numbers(parts, (SPECULAR, v), "specularColorFactor", [1.0; 3], user);
        p.specular = weight.clamp(0.0, 1.0);
        p.specular_color = Vec3::from_array(tint).max(Vec3::ZERO);
        // The weight is the texture's alpha, the colour its RGB (sRGB).
        p.specular_texture = self.json_texture(
            parts,
            v.get("specularTexture"),
            user,
            Encoding::Alpha,
            Vec3::ONE,
        )?;
        p.specular_color_texture = self.json_texture(
            parts,
            v.get("specularColorTexture"),
            user,
            Encoding::Srgb,
            Vec3::ONE,
        )?;
        Ok(())
    }

    /// The metallic-roughness factors of a `KHR_materials_pbrSpecularGlossiness`
    /// object `v`.
    pub(super) fn spec_gloss_factors(&self, parts: &mut Parts, v: &Value, user: &str) -> Converted {
        let e = (SPEC_GLOSS, v);
        let diffuse = self.ext_numbers(parts, e, "diffuseFactor", [1.0; 4], user);
        let specular = self.ext_numbers(parts, e, "specularFactor", [1.0; 3], user);
        let [gloss] = self.ext_numbers(parts, e, "glossinessFactor", [1.0], user);
        let diffuse3 = Vec3::new(diffuse[0], diffuse[1], diffuse[2]).clamp(Vec3::ZERO, Vec3::ONE);
        let specular = Vec3::from_array(specular).clamp(Vec3::ZERO, Vec3::ONE);
        let (base, metallic, roughness) =
            specgloss::convert(diffuse3, specular, gloss.clamp(0.0, 1.0));
        Converted {
            base: [base.x, base.y, base.z, diffuse[3]],
            metallic,
            roughness,
            diffuse: diffuse3,
        }
    }

    /// A specular-glossiness texture converted texel by texel into a
    /// metallic-roughness one (green roughness, blue metalness), its
    /// specular colour (sRGB) and glossiness (alpha) times the factors,
    /// beside the diffuse factor; `None` where it has none or it cannot
    /// be read. The factors then are 1: the texture holds the values.
    pub(super) fn spec_gloss_texture(
        &mut self,
        parts: &mut Parts,
        v: &Value,
        c: &Converted,
        user: &str,
    ) -> Result<Option<u32>> {
        let info = v.get("specularGlossinessTexture");
        let rgb = self.json_texture(parts, info, user, Encoding::Srgb, Vec3::ONE)?;
        let alpha = self.json_texture(parts, info, user, Encoding::Alpha, Vec3::ONE)?;
        let (Some(rgb), Some(alpha)) = (rgb, alpha) else {
            return Ok(None);
        };
        let e = (SPEC_GLOSS, v);
        let specular =
            Vec3::from_array(self.ext_numbers(parts, e, "specularFactor", [1.0; 3], user));
        let [gloss] = self.ext_numbers(parts, e, "glossinessFactor", [1.0], user);
        let (s, g) = (
            &parts.textures[rgb as usize],
            &parts.textures[alpha as usize],
        );
        let texels = s
            .texels
            .iter()
            .zip(g.texels.iter())
            .map(|(s, g)| {
                let s = (*s * specular).clamp(Vec3::ZERO, Vec3::ONE);
                let (_, m, r) = specgloss::convert(c.diffuse, s, (g.x * gloss).clamp(0.0, 1.0));
                Vec3::new(0.0, r, m)
            })
            .collect();
        parts.textures[alpha as usize].texels = Arc::new(texels);
        Ok(Some(alpha))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn extension_numbers_take_defaults_and_refuse_what_is_not_one() {
        let v = serde_json::json!({"a": 0.5, "c": [1, 0.5, 0], "bad": "x", "short": [1, 2]});
        assert_eq!(numbers(&v, "a", [1.0]), Ok([0.5]));
        assert_eq!(numbers(&v, "b", [1.0]), Ok([1.0]));
        assert_eq!(numbers(&v, "c", [0.0; 3]), Ok([1.0, 0.5, 0.0]));
        assert!(numbers(&v, "bad", [1.0]).unwrap_err().contains("\"x\""));
        assert!(numbers(&v, "short", [1.0; 3]).is_err());
    }

    #[test]
    fn texture_indices_and_sets_are_whole_numbers_or_said() {
        let v = serde_json::json!({"i": 0, "f": 1.0, "x": "x", "m": -1, "h": 1e30, "p": 0.5});
        assert_eq!(whole(&v, "i"), Ok(Some(0)));
        assert_eq!(whole(&v, "f"), Ok(Some(1)));
        assert_eq!(whole(&v, "none"), Ok(None));
        for bad in ["x", "m", "h", "p"] {
            assert!(
                whole(&v, bad).unwrap_err().contains("not a whole number"),
                "{bad}"
            );
        }
    }
}
