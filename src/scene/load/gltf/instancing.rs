//! `EXT_mesh_gpu_instancing`: a node that places its mesh once per
//! instance, each instance moved by its own translation, rotation and
//! scale (the `TRANSLATION`, `ROTATION` and `SCALE` accessors) inside the
//! node's world transform. The instances share their primitives' decoded
//! accessors, as every placement of a primitive does.

use ::gltf::accessor::{DataType, Dimensions};
use anyhow::{anyhow, bail, Result};
use glam::{DAffine3, DQuat, DVec3};

use super::Reader;
use crate::scene::show::show3;

/// The extension's name, as a node's `extensions` holds it.
const NAME: &str = "EXT_mesh_gpu_instancing";

/// A node's instance accessors, each checked.
struct Attributes<'a> {
    translation: Option<::gltf::Accessor<'a>>,
    rotation: Option<::gltf::Accessor<'a>>,
    scale: Option<::gltf::Accessor<'a>>,
    count: usize,
}

impl<'a> Reader<'a> {
    /// `FILE: node N: EXT_mesh_gpu_instancing`, as messages name a node's
    /// instances.
    fn instancing_at(&self, node_name: &str) -> String {
        format!("{}: node {node_name}: {NAME}", self.at())
    }

    /// The instance accessors of `node`, checked as every accessor is
    /// (types glTF allows, elements inside their buffer), or `None` when it
    /// does not use the extension.
    fn attributes(&self, node: &::gltf::Node, node_name: &str) -> Result<Option<Attributes<'a>>> {
        let Some(ext) = node.extension_value(NAME) else {
            return Ok(None);
        };
        let here = self.instancing_at(node_name);
        let Some(attributes) = ext.get("attributes").and_then(|a| a.as_object()) else {
            bail!("{here}: it has no attributes");
        };
        let mut counts = Vec::new();
        let mut find = |what: &str, types: &[DataType], dims: Dimensions| -> Result<_> {
            let Some(v) = attributes.get(what) else {
                return Ok(None);
            };
            let a = v
                .as_u64()
                .and_then(|i| self.doc.accessors().nth(usize::try_from(i).ok()?))
                .ok_or_else(|| {
                    anyhow!(
                        "{here}: {what} is accessor {}, which does not exist ({} accessors)",
                        crate::words::quoted(&v.to_string()),
                        self.doc.accessors().len()
                    )
                })?;
            self.check_accessor(&here, what, &a, types, &[dims])?;
            if a.data_type() != DataType::F32 && !a.normalized() {
                bail!(
                    "{here}: {what} (accessor {}) is {:?} and not normalized, which glTF \
                     requires of an integer rotation",
                    a.index(),
                    a.data_type()
                );
            }
            counts.push((what.to_string(), a.index(), a.count()));
            Ok(Some(a))
        };
        use DataType::{F32, I16, I8};
        let translation = find("TRANSLATION", &[F32], Dimensions::Vec3)?;
        let rotation = find("ROTATION", &[F32, I8, I16], Dimensions::Vec4)?;
        let scale = find("SCALE", &[F32], Dimensions::Vec3)?;
        let Some(&(_, _, count)) = counts.first() else {
            bail!("{here}: it has none of TRANSLATION, ROTATION and SCALE");
        };
        if let Some((what, index, n)) = counts.iter().find(|c| c.2 != count) {
            let (first, i) = (&counts[0].0, counts[0].1);
            bail!(
                "{here}: {what} (accessor {index}) has {n} instances, {first} (accessor {i}) \
                 {count}; glTF requires as many in each"
            );
        }
        Ok(Some(Attributes {
            translation,
            rotation,
            scale,
            count,
        }))
    }

    /// How many times `node` places its mesh: once, or once per instance.
    pub(super) fn copies(&self, node: &::gltf::Node, node_name: &str) -> Result<usize> {
        Ok(self.attributes(node, node_name)?.map_or(1, |a| a.count))
    }

    /// Where `node` places its mesh: `world`, or each instance's
    /// transform inside it, each with the name messages give the node.
    pub(super) fn placements(
        &mut self,
        node: &::gltf::Node,
        node_name: &str,
        world: DAffine3,
    ) -> Result<Vec<(DAffine3, String)>> {
        let Some(a) = self.attributes(node, node_name)? else {
            return Ok(vec![(world, node_name.to_string())]);
        };
        let here = self.instancing_at(node_name);
        // Read as every accessor is: sparse, normalised or compressed.
        let used: Vec<_> = [&a.translation, &a.rotation, &a.scale]
            .into_iter()
            .flatten()
            .cloned()
            .collect();
        self.unpack(&used)?;
        let read = |acc: &Option<::gltf::Accessor>, what: &str, default: &[f64]| -> Result<_> {
            let mut out: Vec<[f64; 4]> = Vec::with_capacity(a.count);
            match acc {
                Some(acc) => self.each(&here, what, acc, |e| {
                    let mut v = [0.0; 4];
                    v[..e.len().min(4)].copy_from_slice(&e[..e.len().min(4)]);
                    out.push(v);
                })?,
                None => {
                    let mut v = [0.0; 4];
                    v[..default.len()].copy_from_slice(default);
                    out.resize(a.count, v);
                }
            }
            Ok(out)
        };
        let v3 = |v: &[f64; 4]| DVec3::new(v[0], v[1], v[2]);
        let translations: Vec<DVec3> = read(&a.translation, "TRANSLATION", &[0.0; 3])?
            .iter()
            .map(v3)
            .collect();
        let scales: Vec<DVec3> = read(&a.scale, "SCALE", &[1.0; 3])?.iter().map(v3).collect();
        let rotations = read(&a.rotation, "ROTATION", &[0.0, 0.0, 0.0, 1.0])?;
        // A value named in a message, unless its buffer lies outside the
        // glTF's folder.
        let shown = |acc: &Option<::gltf::Accessor<'a>>, what: &str, k: usize, v: String| {
            let i = acc.as_ref().map_or(0, |a| a.index());
            let v = self.shown(acc.as_ref(), v);
            format!("{here}: instance {k}: {what} (accessor {i}) is {v}")
        };
        let mut out = Vec::with_capacity(a.count);
        for (k, ((t, r), s)) in translations.iter().zip(&rotations).zip(&scales).enumerate() {
            if !t.is_finite() {
                bail!(
                    "{}, not a finite number",
                    shown(&a.translation, "TRANSLATION", k, show3(*t))
                );
            }
            if !s.is_finite() {
                bail!(
                    "{}, not a finite number",
                    shown(&a.scale, "SCALE", k, show3(*s))
                );
            }
            let q = DQuat::from_array(*r);
            if !q.is_finite() || q.length_squared() == 0.0 {
                let v = format!("[{}]", r.map(|x| x.to_string()).join(", "));
                bail!("{}, not a rotation", shown(&a.rotation, "ROTATION", k, v));
            }
            // Unit quaternions as glTF requires, to the precision they were stored in.
            let placed = world * DAffine3::from_scale_rotation_translation(*s, q.normalize(), *t);
            if !placed.is_finite() {
                bail!(
                    "{here}: instance {k}: its transform with the node's overflows 64-bit floats"
                );
            }
            out.push((placed, format!("{node_name}, instance {k}")));
        }
        if out.len() != a.count {
            bail!("{here}: an instance cannot be read");
        }
        Ok(out)
    }
}
