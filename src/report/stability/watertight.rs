//! Watertightness: rays from inside the tessellated sphere and the teapot,
//! in random directions and aimed at vertices, along edges and at random
//! surface points, must all hit.
//!
//! The Newell teapot is not closed: its data leaves a gap between the lid
//! and the rim and leaves the spout and handle ends open (`16 N` boundary
//! edges at `N` segments per patch edge). Random rays from inside the body
//! that leave through the lid gap are counted apart (any other escape is a
//! crack); rays aimed at the surface must all hit; and a separate case checks
//! that the tessellation adds no hairline cracks of its own at patch seams.

use std::path::Path;

use anyhow::{Context, Result};
use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::topology::{aimed, Crossing, Topology};
use super::{Options, Row};
use crate::bvh::{self, Bvh, TraversalStats};
use crate::geometry::sampling::Rng;
use crate::geometry::Ray;
use crate::scene::load::builtin;
use crate::scene::load::obj::{self, Parts, Placement};
use crate::scene::{Builder, Geometry};

/// Rays shot and rays that hit nothing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Escapes {
    pub(crate) rays: u64,
    pub escaped: u64,
}

impl std::ops::AddAssign for Escapes {
    fn add_assign(&mut self, o: Self) {
        self.rays += o.rays;
        self.escaped += o.escaped;
    }
}

/// Shoots every ray and counts those that hit nothing.
pub fn escapes(bvh: &Bvh, rays: &[Ray]) -> Escapes {
    let escaped = rays
        .par_iter()
        .filter(|r| {
            bvh.intersect::<false>(r, &mut TraversalStats::default())
                .is_none()
        })
        .count();
    Escapes {
        rays: rays.len() as u64,
        escaped: escaped as u64,
    }
}

/// Uniform random directions from `origin`.
pub fn random_rays(origin: Vec3, n: u32, rng: &mut Rng) -> Vec<Ray> {
    (0..n)
        .map(|_| {
            let z = 2.0 * rng.next_f32() - 1.0;
            let phi = std::f32::consts::TAU * rng.next_f32();
            let s = (1.0 - z * z).max(0.0).sqrt();
            Ray::new(origin, Vec3::new(s * phi.cos(), s * phi.sin(), z))
        })
        .collect()
}

/// Rays from each origin aimed at its targets of `kind`.
pub fn aimed_rays(
    topo: &Topology,
    origins: &[Vec3],
    kind: Crossing,
    count: u32,
    rng: &mut Rng,
) -> Vec<Ray> {
    origins
        .iter()
        .flat_map(|&o| {
            topo.targets(o, kind, 3, count, rng)
                .into_iter()
                .filter_map(move |t: DVec3| aimed(o, t))
                .collect::<Vec<_>>()
        })
        .collect()
}

/// The built-in unit sphere (1472 triangles, welded), as loaded by the scenes.
pub fn sphere() -> Result<Vec<[Vec3; 3]>> {
    let mut parts = Parts::default();
    obj::load_into(
        &mut parts,
        &builtin::files(),
        Path::new("data/meshes/sphere.obj"),
        &Placement::default(),
        None,
    )?;
    let g = parts.geometry;
    Ok((0..g.triangle_count()).map(|i| g.triangle(i)).collect())
}

/// The teapot of `teapot:N`, without its floor.
pub fn teapot(segments: u32) -> Result<Vec<[Vec3; 3]>> {
    let s = crate::scene::load::open(&format!("teapot:{segments}"), &Default::default())?.scene;
    let mesh = s
        .meshes
        .iter()
        .position(|m| m.name == "teapot")
        .context("teapot:N has no mesh named teapot")?;
    let g = &s.geometry;
    Ok((0..g.triangle_count())
        .filter(|&i| g.tri_mesh[i] as usize == mesh)
        .map(|i| g.triangle(i))
        .collect())
}

/// Points inside the unit sphere, off its centre and axes.
const SPHERE_INSIDE: [Vec3; 3] = [
    Vec3::new(0.01, -0.02, 0.03),
    Vec3::new(0.5, 0.3, -0.2),
    Vec3::new(-0.6, -0.55, 0.1),
];
/// Points inside the teapot's body (it spans y = 0 .. 1.2, radius up to 1).
const TEAPOT_INSIDE: [Vec3; 3] = [
    Vec3::new(0.013, 0.6, -0.021),
    Vec3::new(0.3, 0.9, 0.2),
    Vec3::new(-0.4, 0.4, -0.45),
];

/// Whether a ray leaves upward through the teapot's lid gap: the ring
/// between the lid (r = 0.65) and the rim (r = 0.7) at y = 1.2, widened for
/// coarse tessellations.
pub fn through_lid_gap(r: &Ray) -> bool {
    if r.dir.y <= 0.0 {
        return false;
    }
    let p = r.at((1.2 - r.origin.y) / r.dir.y);
    (0.55..0.75).contains(&p.x.hypot(p.z))
}

fn row(case: String, e: Escapes, what: &str) -> Row {
    Row::zero(
        case,
        e.escaped,
        format!("{} of {} rays {what} escaped", e.escaped, e.rays),
    )
}

/// The watertightness rows.
pub fn watertight(o: &Options) -> Result<Vec<Row>> {
    let mut rng = Rng::for_sample(0, 2, o.seed);
    let mut rows = Vec::new();

    let sphere = sphere()?;
    let topo = Topology::new(sphere.clone());
    let bvh = bvh::build(&Geometry::from_triangles(&sphere), Builder::Sah);
    let per_origin = o.rays / SPHERE_INSIDE.len() as u32;
    let random: Vec<Ray> = SPHERE_INSIDE
        .iter()
        .flat_map(|&p| random_rays(p, per_origin, &mut rng))
        .collect();
    rows.push(row(
        "watertight sphere: random directions".into(),
        escapes(&bvh, &random),
        "in random directions from 3 points inside",
    ));
    for (kind, name) in [
        (Crossing::Vertex, "vertices"),
        (Crossing::Edge, "edges"),
        (Crossing::Surface, "surface points"),
    ] {
        let rays = aimed_rays(&topo, &SPHERE_INSIDE, kind, per_origin, &mut rng);
        rows.push(row(
            format!("watertight sphere: {name}"),
            escapes(&bvh, &rays),
            &format!("from 3 points inside aimed at {name}"),
        ));
    }

    // The same sphere a million units from the origin, where a unit is 1/16 ulp.
    let off = Vec3::new(1e6, -5e5, 7.5e5);
    let far: Vec<[Vec3; 3]> = sphere.iter().map(|t| t.map(|p| p + off)).collect();
    let far_topo = Topology::new(far.clone());
    let far_bvh = bvh::build(&Geometry::from_triangles(&far), Builder::Sah);
    let far_inside = SPHERE_INSIDE.map(|p| p + off);
    let mut e = Escapes::default();
    for &p in &far_inside {
        e += escapes(&far_bvh, &random_rays(p, per_origin, &mut rng));
    }
    for kind in [Crossing::Vertex, Crossing::Edge, Crossing::Surface] {
        let rays = aimed_rays(&far_topo, &far_inside, kind, per_origin, &mut rng);
        e += escapes(&far_bvh, &rays);
    }
    rows.push(row(
        "watertight sphere offset 1e6: all".into(),
        e,
        "in random directions and aimed at vertices, edges and surface points",
    ));

    let n = o.teapot_segments;
    let pot = teapot(n)?;
    let topo = Topology::new(pot.clone());
    let bvh = bvh::build(&Geometry::from_triangles(&pot), Builder::Sah);
    let per_origin = o.rays / TEAPOT_INSIDE.len() as u32;
    // Random directions from inside: the data leaves a gap under the lid,
    // so rays leaving through it are counted apart; any other escape is a crack.
    let random: Vec<Ray> = TEAPOT_INSIDE
        .iter()
        .flat_map(|&p| random_rays(p, per_origin, &mut rng))
        .collect();
    let escaped: Vec<&Ray> = random
        .par_iter()
        .filter(|r| {
            bvh.intersect::<false>(r, &mut TraversalStats::default())
                .is_none()
        })
        .collect();
    let gap = escaped.iter().filter(|r| through_lid_gap(r)).count();
    let elsewhere = escaped.len() - gap;
    rows.push(Row::zero(
        format!("watertight teapot:{n}: random directions"),
        elsewhere as u64,
        format!(
            "{elsewhere} of {} rays from 3 points inside escaped other than through the \
             data's lid gap ({gap} through it)",
            random.len()
        ),
    ));
    for (kind, name) in [
        (Crossing::Vertex, "vertices"),
        (Crossing::Edge, "edges"),
        (Crossing::Surface, "surface points"),
    ] {
        let rays = aimed_rays(&topo, &TEAPOT_INSIDE, kind, per_origin, &mut rng);
        rows.push(row(
            format!("watertight teapot:{n}: {name}"),
            escapes(&bvh, &rays),
            &format!("from 3 points inside aimed at {name}"),
        ));
    }
    let open = topo.boundary_edges().len();
    rows.push(Row::zero(
        format!("teapot:{n} seams: hairline cracks"),
        topo.hairline_cracks(1e-5) as u64,
        format!(
            "open edges that welding within 1e-5 would close; {open} open edges in all \
             ({} expected from the data: lid gap, spout and handle ends)",
            16 * n
        ),
    ));
    Ok(rows)
}
