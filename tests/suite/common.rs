//! Small scenes built in code, and helpers to render them.

use glam::Vec3;
use rayterm::bvh::Bvh;
use rayterm::render::{Features, Film, Plan, Progressive, SceneRequest, Session, Tracer};
use rayterm::scene::load::obj::{MeshData, Parts, Placement};
use rayterm::scene::{Builder, Camera, Light, Material, Projection, Scene};

/// Positions, triangles and material of one mesh.
pub type TestMesh = (Vec<Vec3>, Vec<[u32; 3]>, Material);

/// A scene from meshes built in code.
pub fn scene(meshes: &[TestMesh], lights: Vec<Light>, camera: Camera) -> Scene {
    let mut parts = Parts::default();
    for (i, (p, t, m)) in meshes.iter().enumerate() {
        let mat = parts.add_material(m.clone());
        parts.add_mesh(
            MeshData {
                name: format!("mesh{i}"),
                positions: p,
                normals: None,
                uvs: None,
                indices: t,
                material: mat,
            },
            &Placement::default(),
        );
    }
    let mut s = parts.into_scene("test".into(), camera);
    s.lights = lights;
    s
}

/// Axis-aligned quad in the plane y = `y`, from (x0, z0) to (x1, z1), facing +y.
pub fn quad_y(x0: f32, z0: f32, x1: f32, z1: f32, y: f32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    (
        vec![
            Vec3::new(x0, y, z0),
            Vec3::new(x0, y, z1),
            Vec3::new(x1, y, z1),
            Vec3::new(x1, y, z0),
        ],
        vec![[0, 1, 2], [0, 2, 3]],
    )
}

pub fn material(kd: Vec3, ks: Vec3, ns: f32) -> Material {
    Material {
        name: "m".into(),
        kd,
        ks,
        ns,
        ..Material::default()
    }
}

/// Camera straight above the origin looking down.
pub fn top_camera(height: f32) -> Camera {
    Camera {
        eye: Vec3::new(0.0, height, 0.0),
        target: Vec3::ZERO,
        up: Vec3::NEG_Z,
        projection: Projection::perspective(30.0),
    }
}

pub struct Rendered {
    pub film: Film,
    pub image: Vec<Vec3>,
}

/// Renders `spp` samples per pixel with `features`.
pub fn render(
    scene: &Scene,
    w: u32,
    h: u32,
    spp: u32,
    features: Features,
    builder: Builder,
    seed: u64,
) -> Rendered {
    let req = SceneRequest {
        size: Some((w, h)),
        builder: Some(builder),
        features,
        seed,
        ..SceneRequest::new(&scene.name)
    };
    let (s, _) = Session::with_scene(scene.clone(), &req);
    let film = Progressive::render(&s.tracer(), spp);
    let image = film.image();
    Rendered { film, image }
}

pub fn render_with(
    scene: &Scene,
    bvh: &Bvh,
    plan: &Plan,
    w: u32,
    h: u32,
    spp: u32,
    seed: u64,
) -> Rendered {
    let tracer = Tracer::new(scene, bvh, plan, scene.camera.frame(w, h), seed);
    let film = Progressive::render(&tracer, spp);
    let image = film.image();
    Rendered { film, image }
}

/// Directory of the shared test meshes, when present beside the project.
pub fn shared_meshes() -> Option<std::path::PathBuf> {
    let p = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/data/meshes");
    if p.is_dir() {
        Some(p)
    } else {
        eprintln!("skipping: ../shared/data/meshes not found");
        None
    }
}
