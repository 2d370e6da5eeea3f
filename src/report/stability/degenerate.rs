//! Degenerate geometry: zero-area, needle and collinear triangles,
//! duplicated vertices, zero-length and NaN vertex normals, coplanar
//! overlapping triangles. Loading must report the zero-area triangles with
//! their count; rendering (also of the same triangles put straight into a
//! scene, past the loader) must give no NaN.

use std::path::Path;

use anyhow::Result;
use glam::{Vec2, Vec3};

use super::stiff::render;
use super::{Options, Row};
use crate::scene::load::obj::{self, Parts, Placement};
use crate::scene::load::source::Memory;
use crate::scene::{Camera, Environment, Geometry, Light, MeshInfo, Projection, Scene, Settings};

/// An OBJ of good, degenerate and nearly degenerate triangles; the comments
/// say which. [`ZERO_AREA`] of its faces have no area.
pub(crate) const OBJ: &str = "\
mtllib d.mtl
usemtl floor
v -2 0 -2
v 2 0 -2
v 2 0 2
v -2 0 2
vn 0 1 0
vn 0 0 0
# a floor: one triangle with a unit normal, one with zero-length normals
f 1//1 3//1 2//1
f 1//2 4//2 3//2
usemtl shiny
v 0 0.5 0
v 1 0.5 0
v 2 0.5 0
v 1 0.5 0
# repeated index, collinear, duplicated vertex, a single point: no area
f 5 5 6
f 5 6 7
f 6 8 5
f 7 7 7
# needles: long and thin, with area
v -1 0.3 -1
v 1 0.3 1
v 1 0.3 1.0001
f 9 10 11
v -1.5 0.2 0
v 1.5 0.2 0
v 0 0.2 0.000001
f 12 13 14
# nearly collinear in 3D
v 0 0 0
v 1 1 1
v 2 2 2.0000002
f 15 16 17
# coplanar and overlapping, in two materials
usemtl floor
v -1 0.1 -1
v 1 0.1 -1
v 0 0.1 1
f 18 19 20
usemtl shiny
v -1 0.1 1
v 1 0.1 1
v 0 0.1 -1
f 21 22 23
";

pub(crate) const MTL: &str = "\
newmtl floor
Kd 0.7 0.7 0.7
newmtl shiny
Kd 0.2 0.3 0.6
Ks 0.6 0.6 0.6
Ns 30
";

/// Faces of [`OBJ`] without area.
pub(crate) const ZERO_AREA: u64 = 4;

/// Zero-area triangles the loader says it skipped, summed over its warnings.
pub(crate) fn reported_degenerate(warnings: &[String]) -> u64 {
    warnings
        .iter()
        .filter_map(|w| {
            let rest = w.split("skipped ").nth(1)?;
            let (n, tail) = rest.split_once(' ')?;
            tail.starts_with("degenerate")
                .then(|| n.parse::<u64>().ok())?
        })
        .sum()
}

fn camera() -> Camera {
    Camera {
        eye: Vec3::new(0.3, 3.0, 3.5),
        target: Vec3::new(0.0, 0.2, 0.0),
        up: Vec3::Y,
        projection: Projection::perspective(50.0),
    }
}

fn scene_from(parts: Parts, name: &str) -> Scene {
    Scene {
        lights: vec![Light::Point {
            position: Vec3::new(1.0, 2.5, 1.5),
            color: Vec3::ONE,
        }],
        environment: Environment::Color(Vec3::splat(0.1)),
        settings: Settings {
            ambient: Vec3::splat(0.05),
            ..Settings::default()
        },
        ..parts.into_scene(name.into(), camera())
    }
}

/// The same triangles put straight into the geometry, degenerate ones and
/// NaN and zero normals included, as if a loader had let them through.
fn raw_scene(loaded: &Scene) -> Scene {
    let mut g = Geometry::default();
    let mut positions = Vec::new();
    for line in OBJ.lines() {
        let mut w = line.split_whitespace();
        if w.next() == Some("v") {
            let c: Vec<f32> = w.filter_map(|x| x.parse().ok()).collect();
            positions.push(Vec3::new(c[0], c[1], c[2]));
        }
    }
    let normals = [
        Vec3::NAN,
        Vec3::ZERO,
        Vec3::Y,
        Vec3::new(f32::NAN, 1.0, 0.0),
    ];
    for line in OBJ.lines() {
        let mut w = line.split_whitespace();
        if w.next() != Some("f") {
            continue;
        }
        let idx: Vec<u32> = w
            .filter_map(|x| x.split('/').next()?.parse::<u32>().ok())
            .collect();
        for &i in &idx {
            g.positions.push(positions[i as usize - 1]);
            g.normals.push(normals[g.normals.len() % normals.len()]);
            g.uvs.push(Vec2::new(f32::NAN, 0.5));
        }
        let b = g.positions.len() as u32 - 3;
        g.indices.push([b, b + 1, b + 2]);
        g.tri_material.push((g.indices.len() % 2) as u32);
        g.tri_mesh.push(0);
    }
    Scene {
        name: "degenerate (raw)".into(),
        geometry: g,
        meshes: vec![MeshInfo {
            name: "raw".into(),
            smooth: true,
            textured: true,
            colored: false,
            uv1: None,
            tangent: None,
        }],
        ..loaded.clone()
    }
}

/// The degenerate-geometry rows.
pub fn degenerate(o: &Options) -> Result<Vec<Row>> {
    let src = Memory::default().with("d.obj", OBJ).with("d.mtl", MTL);
    let mut parts = Parts::default();
    obj::load_into(
        &mut parts,
        &src,
        Path::new("d.obj"),
        &Placement::default(),
        None,
    )?;
    let reported = reported_degenerate(&parts.warnings);
    let warning = parts
        .warnings
        .iter()
        .find(|w| w.contains("degenerate"))
        .cloned()
        .unwrap_or_else(|| "no warning".into());
    let loaded = scene_from(parts, "degenerate");
    let raw = raw_scene(&loaded);
    let mut bad = 0;
    let mut samples = 0;
    for s in [&loaded, &raw] {
        let f = render(s, o.width, o.height, 4, None);
        bad += f.bad_count;
        samples += f.width as u64 * f.height as u64 * f.spp as u64;
    }
    Ok(vec![
        Row::zero(
            "degenerate: zero-area triangles reported",
            reported.abs_diff(ZERO_AREA),
            format!("{reported} of {ZERO_AREA} reported at load ({warning})"),
        ),
        Row::zero(
            "degenerate: non-finite samples",
            bad,
            format!(
                "{bad} of {samples} samples, loaded and raw (degenerate triangles, NaN and zero \
                 normals, NaN UVs)"
            ),
        ),
    ])
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn counts_are_read_from_warnings() {
        let w = vec![
            "a: skipped 3 degenerate (zero-area) triangles".to_string(),
            "b: skipped 1 degenerate (zero-area) triangle".to_string(),
            "c.obj:3: absurd value 1e30".to_string(),
        ];
        assert_eq!(reported_degenerate(&w), 4);
    }
}
