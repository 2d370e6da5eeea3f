//! Stiff shading: shininess 0, 1e-6 and 1e6; lights of 1e-20 and 1e20; lights
//! on surfaces and inside a closed box; a camera inside a mesh. Each must
//! render finite pixels that make sense: within the bound Phong and the
//! reflection weights allow, equal to the unlit image when the light is
//! negligible or shut in, and every camera ray hitting when the camera is
//! inside a closed mesh.

use std::path::Path;

use anyhow::Result;
use glam::Vec3;

use super::{format_figure, Options, Row};
use crate::bvh::{self, TraversalStats};
use crate::render::{Features, Film, Progressive, SceneRequest, Session};
use crate::scene::load::builtin;
use crate::scene::load::obj::{self, MeshData, Parts, Placement};
use crate::scene::{Builder, Camera, Environment, Light, Material, Projection, Scene, Settings};
use glam::Affine3A;

/// Renders `spp` passes with every feature (or `features`) on.
pub(crate) fn render(scene: &Scene, w: u32, h: u32, spp: u32, features: Option<Features>) -> Film {
    let req = SceneRequest {
        size: Some((w, h)),
        builder: Some(Builder::Sah),
        features: features.unwrap_or_else(Features::all),
        seed: 7,
        ..SceneRequest::new(&scene.name)
    };
    let (s, _) = Session::with_scene(scene.clone(), &req);
    Progressive::render(&s.tracer(), spp)
}

const AMBIENT: f32 = 0.05;

fn quad(parts: &mut Parts, corners: [Vec3; 4], mat: u32, name: &str) {
    parts.add_mesh(
        MeshData {
            name: name.into(),
            positions: &corners,
            normals: None,
            uvs: None,
            indices: &[[0, 1, 2], [0, 2, 3]],
            material: mat,
        },
        &Placement::default(),
    );
}

/// A closed cube of half-size `r` around `c`, outward counter-clockwise.
pub(crate) fn cube(c: Vec3, r: f32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let p = (0..8)
        .map(|i| {
            c + r * Vec3::new(
                (i & 1) as f32 * 2.0 - 1.0,
                (i >> 1 & 1) as f32 * 2.0 - 1.0,
                (i >> 2) as f32 * 2.0 - 1.0,
            )
        })
        .collect();
    let faces = [
        [0, 2, 3, 1],
        [4, 5, 7, 6],
        [0, 1, 5, 4],
        [2, 6, 7, 3],
        [0, 4, 6, 2],
        [1, 3, 7, 5],
    ];
    let t = faces
        .iter()
        .flat_map(|[a, b, c, d]| [[*a, *b, *c], [*a, *c, *d]])
        .collect();
    (p, t)
}

/// A floor and a smooth shiny sphere (the built-in mesh, centre (0, 1, 0))
/// under one point light, optionally shut in a closed box.
pub fn stage(ns: f32, light: Vec3, intensity: f32, shut_in: bool) -> Result<Scene> {
    let mut parts = Parts::default();
    let floor = parts.add_material(Material {
        name: "floor".into(),
        kd: Vec3::new(0.7, 0.7, 0.6),
        ..Material::default()
    });
    quad(
        &mut parts,
        [
            Vec3::new(-3.0, 0.0, -3.0),
            Vec3::new(-3.0, 0.0, 3.0),
            Vec3::new(3.0, 0.0, 3.0),
            Vec3::new(3.0, 0.0, -3.0),
        ],
        floor,
        "floor",
    );
    let shiny = Material {
        name: "shiny".into(),
        kd: Vec3::new(0.6, 0.2, 0.2),
        ks: Vec3::splat(0.5),
        ns,
        ..Material::default()
    };
    obj::load_into(
        &mut parts,
        &builtin::files(),
        Path::new("data/meshes/sphere.obj"),
        &Placement {
            transform: Affine3A::from_translation(Vec3::Y),
        },
        Some(&shiny),
    )?;
    if shut_in {
        let (p, t) = cube(light, 0.5);
        let m = parts.add_material(Material::default());
        parts.add_mesh(
            MeshData {
                name: "box".into(),
                positions: &p,
                normals: None,
                uvs: None,
                indices: &t,
                material: m,
            },
            &Placement::default(),
        );
    }
    let camera = Camera {
        eye: Vec3::new(0.0, 2.0, 5.0),
        target: Vec3::new(0.0, 0.8, 0.0),
        up: Vec3::Y,
        projection: Projection::perspective(45.0),
    };
    Ok(Scene {
        lights: vec![Light::Point {
            position: light,
            color: Vec3::splat(intensity),
        }],
        environment: Environment::Color(Vec3::splat(0.02)),
        settings: Settings {
            ambient: Vec3::splat(AMBIENT),
            ..Settings::default()
        },
        ..parts.into_scene("stiff".into(), camera)
    })
}

/// The largest radiance Whitted-Phong can return here: per bounce at most
/// `kd (ambient + sum of lights) + ks sum of lights` (or the environment),
/// and bounces weighted by ks add up to at most `1 / (1 - ks)`.
pub fn bound(scene: &Scene) -> f32 {
    let lights: f32 = scene
        .lights
        .iter()
        .map(|l| match l {
            Light::Point { color, .. } => color.max_element(),
            // Lux and candela at a unit's distance; the battery's stiff
            // scenes hold Phong lights only.
            Light::Photometric { intensity: c, .. } | Light::Directional { illuminance: c, .. } => {
                c.max_element()
            }
            Light::Segment {
                color_a, color_b, ..
            } => color_a.max(*color_b).max_element(),
            Light::Parallelogram { colors, .. } => {
                colors.iter().fold(0.0f32, |m, c| m.max(c.max_element()))
            }
        })
        .sum();
    let kd = scene
        .materials
        .iter()
        .fold(0.0f32, |m, x| m.max(x.kd.max_element()));
    let ks = scene
        .materials
        .iter()
        .fold(0.0f32, |m, x| m.max(x.ks.max_element()));
    let env = match &scene.environment {
        Environment::Color(c) => c.max_element(),
        Environment::CubeMap(_) => 1.0,
        Environment::Light(light) => light.brightest(),
    };
    let amb = scene.settings.ambient.max_element();
    (kd * (amb + lights) + ks * lights).max(env) / (1.0 - ks).max(1e-3)
}

/// Pixels outside `[0, max]`.
fn outside(img: &[Vec3], max: f32) -> u64 {
    img.iter()
        .filter(|c| c.min_element() < 0.0 || c.max_element() > max * (1.0 + 1e-5))
        .count() as u64
}

/// Largest channel difference between two images.
fn max_diff(a: &[Vec3], b: &[Vec3]) -> f32 {
    a.iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).abs().max_element())
        .fold(0.0, f32::max)
}

/// The stiff-shading rows.
pub fn stiff_shading(o: &Options) -> Result<Vec<Row>> {
    let (w, h) = (o.width / 2, o.height / 2);
    let (w, h) = (w.max(8), h.max(8));
    let light = Vec3::new(2.0, 4.0, 3.0);
    let mut rows = Vec::new();
    let mut case = |name: &str, scene: &Scene, extra: Option<(u64, String)>| {
        let f = render(scene, w, h, 4, None);
        let img = f.image();
        let b = bound(scene);
        let off = outside(&img, b);
        let samples = f.width as u64 * f.height as u64 * f.spp as u64;
        let (x, what) = extra.unwrap_or((0, String::new()));
        rows.push(Row::zero(
            format!("stiff: {name}"),
            f.bad_count + off + x,
            format!(
                "{} of {samples} samples non-finite, {off} pixels outside [0, {}]{what}",
                f.bad_count,
                format_figure(b as f64)
            ),
        ));
        img
    };
    for ns in [0.0, 1e-6, 1e6] {
        case(
            &format!(
                "shininess {}",
                if ns == 0.0 {
                    "0".into()
                } else {
                    format!("{ns:e}")
                }
            ),
            &stage(ns, light, 1.0, false)?,
            None,
        );
    }
    let dark = stage(30.0, light, 0.0, false)?;
    let dark_img = render(&dark, w, h, 4, None).image();
    let faint = stage(30.0, light, 1e-20, false)?;
    let fi = render(&faint, w, h, 4, None).image();
    let d = max_diff(&fi, &dark_img);
    case(
        "light 1e-20",
        &faint,
        Some(((d > 1e-6) as u64, format!(", {d:.1e} from the unlit image"))),
    );
    case("light 1e20", &stage(30.0, light, 1e20, false)?, None);

    // Lights in the floor's plane, at a floor corner and at the sphere's pole.
    let mut on = stage(30.0, Vec3::new(1.5, 0.0, 1.5), 1.0, false)?;
    on.lights.push(Light::Point {
        position: Vec3::new(3.0, 0.0, 3.0),
        color: Vec3::ONE,
    });
    on.lights.push(Light::Point {
        position: Vec3::new(0.0, 2.0, 0.0),
        color: Vec3::ONE,
    });
    case("light on a surface", &on, None);

    // A light shut in a closed box: the image is the unlit one.
    let boxed = stage(30.0, light, 1.0, true)?;
    let mut unlit = boxed.clone();
    unlit.lights.clear();
    let ui = render(&unlit, w, h, 4, None).image();
    let bi = render(&boxed, w, h, 4, None).image();
    let d = max_diff(&bi, &ui);
    case(
        "light inside a box",
        &boxed,
        Some(((d > 1e-6) as u64, format!(", {d:.1e} from the unlit image"))),
    );

    // The camera at the sphere's centre: every camera ray must hit it.
    let mut inside = stage(30.0, light, 1.0, false)?;
    inside.camera = Camera {
        eye: Vec3::new(0.0, 1.0, 0.0),
        target: Vec3::new(1.0, 1.2, 0.3),
        up: Vec3::Y,
        projection: Projection::perspective(90.0),
    };
    let b = bvh::build(&inside.geometry, Builder::Sah);
    let frame = inside.camera.frame(w, h);
    let misses = (0..w * h)
        .filter(|i| {
            let r = frame.ray((i % w) as f64 + 0.5, (i / w) as f64 + 0.5);
            b.intersect::<false>(&r, &mut TraversalStats::default())
                .is_none()
        })
        .count() as u64;
    case(
        "camera inside a mesh",
        &inside,
        Some((misses, format!(", {misses} camera rays escaped"))),
    );
    // Paths of up to 64 bounces in the closed box around the light, the
    // camera in with it: Russian roulette ends them, and no sample may be
    // non-finite or negative. (Their light adds up over bounces, past the
    // bound of one Whitted bounce, so that is not checked here.)
    let mut long = stage(30.0, light, 1.0, true)?;
    long.settings.integrator = Some(crate::scene::Integrator::Path);
    long.settings.max_depth = crate::scene::MAX_DEPTH;
    long.camera = Camera {
        eye: light + Vec3::new(0.2, -0.2, 0.2),
        target: light + Vec3::new(-0.3, -0.4, -0.1),
        up: Vec3::Y,
        projection: Projection::perspective(90.0),
    };
    let f = render(&long, w, h, 4, None);
    let negative = f.image().iter().filter(|c| c.min_element() < 0.0).count() as u64;
    let samples = f.width as u64 * f.height as u64 * f.spp as u64;
    rows.push(Row::zero(
        "stiff: long paths",
        f.bad_count + negative,
        format!(
            "{} of {samples} samples non-finite, {negative} pixels negative (paths of up to {} \
             bounces in a closed box)",
            f.bad_count,
            crate::scene::MAX_DEPTH
        ),
    ));
    Ok(rows)
}
