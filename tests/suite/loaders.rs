//! Scene files as users hand them over: paths written in a scene are
//! relative to the scene file whatever the working directory and however
//! the scene is named, and a mesh far from the origin renders as it does at
//! the origin (coordinates are read and moved in f64 before rounding).

use crate::common;

use std::path::Path;

use crate::files::{rayterm, Dir};
use glam::{DVec3, Vec3};
use rayterm::render::Features;
use rayterm::scene::load::source::Memory;
use rayterm::scene::load::{self, Opening};
use rayterm::scene::{Builder, Scene};

const CHECKER: &[u8] = include_bytes!("../../data/meshes/checker.png");
const SPHERE: &str = include_str!("../../data/meshes/sphere.obj");

/// A scene in `scenes/` whose OBJ, MTL, texture and patch file sit beside
/// that folder, all reached through `../`.
fn scene_tree(d: &Dir) {
    d.write(
        "top/scenes/s.toml",
        "[camera]\neye = [0, 1.5, 4]\ntarget = [0, 0.5, 0]\n\
         [[mesh]]\nfile = \"../meshes/box.obj\"\n\
         [[mesh]]\nfile = \"../p.bpt\"\nsegments = 2\ntranslate = [1.2, 0, 0]\n\
         material = { texture = \"../textures/t.png\" }\n\
         [[light]]\ntype = \"point\"\nposition = [1, 3, 2]\ncolor = [1, 1, 1]\n",
    );
    d.write(
        "top/meshes/box.obj",
        "mtllib box.mtl\nusemtl tex\nv -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\n\
         vt 0 0\nvt 4 0\nvt 4 4\nvt 0 4\nf 1/1 4/4 3/3 2/2\n",
    );
    d.write(
        "top/meshes/box.mtl",
        "newmtl tex\nKd 1 1 1\nmap_Kd ../textures/t.png\n",
    );
    d.write("top/textures/t.png", CHECKER);
    let mut bpt = String::from("1\n3 3\n");
    for k in 0..16 {
        bpt += &format!(
            "{} {} {}\n",
            (k % 4) as f32 * 0.3,
            ((k * 7) % 5) as f32 * 0.1,
            (k / 4) as f32 * 0.3
        );
    }
    d.write("top/p.bpt", bpt);
}

/// Decoys that a path losing its `../` would load instead.
fn decoys(d: &Dir, at: &str) {
    let other = "v -5 0 -5\nv 5 0 -5\nv 0 3 5\nf 1 3 2\n";
    for rel in ["meshes/box.obj", "box.obj", "p.bpt", "../p.bpt"] {
        let p = format!("{at}/{rel}");
        if rel.ends_with(".bpt") {
            d.write(
                &p,
                "1\n3 3\n".to_string() + &"0 0 0\n1 0 0\n0 1 0\n1 1 1\n".repeat(4),
            );
        } else {
            d.write(&p, other);
        }
    }
}

fn render_from(d: &Dir, cwd: &str, scene: &str) -> Vec<u8> {
    let out = d.path(&format!("out-{}.png", cwd.replace('/', "_")));
    let out = out.to_str().unwrap();
    let r = rayterm(
        &d.path(cwd),
        &["render", scene, "--size", "24x16", "--spp", "1", "-o", out],
    );
    assert!(r.ok(), "{scene} from {cwd}: {}", r.stderr);
    // The files beside the scene's folder are named as lying outside it,
    // each resolved where it is (what the OBJ's material library says of
    // its own texture, outside its folder too, is not shown), and nothing
    // else is said.
    let warnings: Vec<&str> = r.stderr.lines().filter(|l| l.contains("warning")).collect();
    assert!(
        warnings
            .iter()
            .all(|w| w.contains(" lies outside ") || w.contains("1 warning about it not shown")),
        "{scene} from {cwd}: {}",
        r.stderr
    );
    let top = std::fs::canonicalize(d.path("top")).unwrap();
    let outside = [
        ("mesh", "../meshes/box.obj", "meshes/box.obj"),
        ("mesh", "../p.bpt", "p.bpt"),
        ("texture", "../textures/t.png", "textures/t.png"),
    ];
    let text = std::fs::read_to_string(d.path(cwd).join(scene)).unwrap();
    let named = outside
        .into_iter()
        .filter(|(_, written, _)| text.contains(&format!("\"{written}\"")));
    for (what, written, at) in named {
        let want = format!(
            "{what} {written} lies outside {}",
            top.join("scenes").display()
        );
        let resolved = format!("(it resolves to {})", top.join(at).display());
        assert!(
            warnings
                .iter()
                .any(|w| w.contains(&want) && w.contains(&resolved)),
            "{scene} from {cwd}: {want} {resolved}: {}",
            r.stderr
        );
    }
    std::fs::read(out).unwrap()
}

#[test]
fn scene_paths_are_relative_to_the_scene_file() {
    let d = Dir::new("paths");
    scene_tree(&d);
    decoys(&d, "top/scenes");
    decoys(&d, "top/meshes/sub");
    let absolute = d.path("top/scenes/s.toml");
    let reference = render_from(&d, "top/scenes", "s.toml");
    for (cwd, scene) in [
        ("top", "scenes/s.toml"),
        ("top/scenes", "./s.toml"),
        ("top/meshes", "../scenes/s.toml"),
        ("top/meshes/sub", "../../scenes/s.toml"),
        ("top/meshes/sub", absolute.to_str().unwrap()),
        ("top/scenes", "../scenes/./s.toml"),
    ] {
        assert!(
            render_from(&d, cwd, scene) == reference,
            "{scene} from {cwd} renders another scene"
        );
    }
    // The decoy would show: the same scene with the decoy as its mesh differs.
    d.write(
        "top/scenes/decoyed.toml",
        std::fs::read_to_string(d.path("top/scenes/s.toml"))
            .unwrap()
            .replace("../meshes/box.obj", "meshes/box.obj"),
    );
    assert!(render_from(&d, "top/scenes", "decoyed.toml") != reference);
}

#[test]
fn a_parent_scene_never_picks_up_a_decoy_in_the_working_directory() {
    // `rayterm render ../amb.toml` whose mesh is `../plane.obj`, run from a
    // folder holding a decoy `plane.obj`.
    let d = Dir::new("decoy");
    d.write(
        "plane.obj",
        "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nf 1 4 3 2\n",
    );
    d.write(
        "a/amb.toml",
        "[camera]\neye = [0, 3, 0.1]\ntarget = [0, 0, 0]\n[[mesh]]\nfile = \"../plane.obj\"\n\
         [render]\nambient = [1, 1, 1]\n",
    );
    d.write(
        "a/work/plane.obj",
        "v -9 0 -9\nv 9 0 -9\nv 0 0 9\nf 1 3 2\n",
    );
    let r = rayterm(
        &d.path("a/work"),
        &[
            "render",
            "../amb.toml",
            "--size",
            "8x8",
            "--spp",
            "1",
            "-o",
            "x.png",
        ],
    );
    assert!(r.ok(), "{}", r.stderr);
    // The real plane has two triangles, the decoy one.
    assert!(r.stdout.contains("2 triangles"), "{}", r.stdout);
    // A missing mesh is named with the path it was looked for at.
    std::fs::remove_file(d.path("plane.obj")).unwrap();
    let r = rayterm(&d.path("a/work"), &["render", "../amb.toml", "-o", "x.png"]);
    assert!(!r.ok());
    assert!(
        r.stderr
            .contains("cannot read OBJ mesh ../../plane.obj: not found"),
        "{}",
        r.stderr
    );
}

#[test]
fn built_in_scenes_load_from_any_directory() {
    let d = Dir::new("builtin");
    let r = rayterm(
        &d.0,
        &[
            "render", "env", "--size", "8x8", "--spp", "1", "-o", "x.png",
        ],
    );
    assert!(r.ok(), "{}", r.stderr);
    // Their files on disk, loaded from their own folder and from elsewhere,
    // with no warning: a scene names nothing outside its folder.
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("data");
    let mut runs = vec![(
        d.0.clone(),
        root.join("cornell.toml").to_str().unwrap().to_string(),
    )];
    for (name, _) in rayterm::scene::load::builtin::SCENES {
        runs.push((root.clone(), format!("{name}.toml")));
    }
    runs.push((root.clone(), "./cornell.toml".to_string()));
    for (cwd, scene) in runs {
        let out = d.path("y.png");
        let r = rayterm(
            &cwd,
            &[
                "render",
                &scene,
                "--size",
                "8x8",
                "--spp",
                "1",
                "-o",
                out.to_str().unwrap(),
            ],
        );
        assert!(r.ok(), "{scene} from {}: {}", cwd.display(), r.stderr);
        assert!(
            !r.stderr.contains("warning"),
            "{scene} from {}: {}",
            cwd.display(),
            r.stderr
        );
    }
}

/// The built-in sphere (2 across) under a point light, moved by `offset`:
/// written into the OBJ text (`in_obj`) or as a TOML `translate`, with the
/// camera and light moved alike in the scene file.
fn far_sphere(offset: DVec3, in_obj: bool) -> Scene {
    let shift = |p: DVec3| if in_obj { p + offset } else { p };
    let mut obj = String::new();
    for line in SPHERE.lines() {
        match line.strip_prefix("v ") {
            Some(rest) => {
                let c: Vec<f64> = rest
                    .split_whitespace()
                    .map(|w| w.parse().unwrap())
                    .collect();
                let p = shift(DVec3::new(c[0], c[1], c[2]));
                obj += &format!("v {} {} {}\n", p.x, p.y, p.z);
            }
            None => obj += &format!("{line}\n"),
        }
    }
    let (e, t, l) = (
        offset + DVec3::new(0.7, 1.1, 3.4),
        offset + DVec3::new(0.0, 0.1, 0.0),
        offset + DVec3::new(-2.0, 3.0, 2.5),
    );
    let translate = if in_obj {
        String::new()
    } else {
        format!("translate = [{}, {}, {}]\n", offset.x, offset.y, offset.z)
    };
    let toml = format!(
        "[camera]\neye = [{}, {}, {}]\ntarget = [{}, {}, {}]\nfov = 40\n\
         [[mesh]]\nfile = \"s.obj\"\n{translate}\
         [[light]]\ntype = \"point\"\nposition = [{}, {}, {}]\ncolor = [1, 1, 1]\n\
         [render]\nambient = [0.1, 0.1, 0.1]\n",
        e.x, e.y, e.z, t.x, t.y, t.z, l.x, l.y, l.z
    );
    let src = Memory::default().with("s.toml", toml).with("s.obj", obj);
    let how = Opening {
        source: Some(&src),
        ..Default::default()
    };
    load::open("s.toml", &how).unwrap().scene
}

/// Mean absolute difference relative to the mean of `a`.
fn relative_difference(a: &[Vec3], b: &[Vec3]) -> f32 {
    let diff: f32 = a
        .iter()
        .zip(b)
        .map(|(x, y)| (*x - *y).abs().element_sum())
        .sum();
    let mean: f32 = a.iter().map(|x| x.element_sum()).sum();
    diff / mean
}

#[test]
fn far_meshes_render_as_at_the_origin() {
    let (w, h) = (48, 40);
    let render = |s: &Scene| common::render(s, w, h, 4, Features::all(), Builder::Sah, 7).image;
    let origin = far_sphere(DVec3::ZERO, true);
    assert!(origin.warnings.is_empty(), "{:?}", origin.warnings);
    let reference = render(&origin);
    let lit = reference.iter().filter(|c| c.max_element() > 0.2).count();
    assert!(
        lit > (w * h / 8) as usize,
        "the sphere fills part of the view: {lit}"
    );
    for sizes in [1e5, 1e7] {
        // The offset in multiples of the sphere's size (2), on every axis.
        let offset = DVec3::new(1.0, -0.5, 0.75) * sizes * 2.0;
        for in_obj in [true, false] {
            let far = far_sphere(offset, in_obj);
            let how = if in_obj { "in the OBJ" } else { "by translate" };
            assert_eq!(
                far.geometry.triangle_count(),
                origin.geometry.triangle_count(),
                "{sizes:e} {how}: {:?}",
                far.warnings
            );
            assert!(
                far.warnings
                    .iter()
                    .any(|w| w.contains("far from the origin")),
                "{:?}",
                far.warnings
            );
            let d = relative_difference(&reference, &render(&far));
            assert!(
                d < 0.01,
                "{sizes:e} sizes away {how}: {:.3} % different",
                d * 100.0
            );
        }
    }
    // The control: the same sphere rounded to f32 where it lies, as it was
    // read before, collapses (its vertices 2 apart at 2e7).
    let mut rounded = far_sphere(DVec3::new(1.0, -0.5, 0.75) * 2e7, true);
    let shift = DVec3::new(1.0, -0.5, 0.75) * 2e7;
    rounded.move_vertices(|p| ((p.as_dvec3() + shift).as_vec3().as_dvec3() - shift).as_vec3());
    assert!(relative_difference(&reference, &render(&rounded)) > 0.05);
}

/// `mtllib` with forty names on one line, longer than a file name may be:
/// the line is split into its names (as when no file has the whole line
/// as its name), where the system's "file name too long" stopped the load.
#[test]
fn a_long_mtllib_line_names_several_libraries() {
    let d = Dir::new("long-mtllib");
    let mut names = String::new();
    for i in 0..40 {
        d.write(
            &format!("material-library-{i}.mtl"),
            format!("newmtl m{i}\nKd 1 0 0\n"),
        );
        names += &format!("material-library-{i}.mtl ");
    }
    assert!(names.len() > 255);
    d.write(
        "many.obj",
        format!("mtllib {names}\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl m3\nf 1 2 3\n"),
    );
    let r = rayterm(
        &d.path(""),
        &[
            "render", "many.obj", "--size", "8x8", "--spp", "1", "-o", "o.png",
        ],
    );
    assert!(r.ok(), "{}", r.stderr);
    assert!(!r.stderr.contains("warning"), "{}", r.stderr);
}

/// A PNG of `w` x `h` texels of colour `f(x, y)`.
fn png(w: u32, h: u32, f: impl Fn(u32, u32) -> [u8; 3]) -> Vec<u8> {
    let img = image::RgbImage::from_fn(w, h, |x, y| image::Rgb(f(x, y)));
    let mut out = Vec::new();
    img.write_to(&mut std::io::Cursor::new(&mut out), image::ImageFormat::Png)
        .unwrap();
    out
}

/// The MTL PBR extension makes a material physically based: Pr, Pm, Ke
/// and their maps, a normal map from `norm` or from a `map_Bump` whose
/// image is one (with its `-bm` scale), MikkTSpace tangents for its
/// meshes; a grey `map_Bump` is a height map, said and left out. A plain
/// Phong material beside it stays Phong, its Ke and map_Bump ignored as
/// before.
#[test]
fn mtl_pbr_materials_are_physically_based() {
    mtl_normal_maps_that_are_not_say_why();
    let d = Dir::new("mtl-pbr");
    d.write("rough.png", png(2, 2, |x, _| [255 * x as u8; 3]));
    d.write(
        "bumps.png",
        png(4, 4, |x, y| [100 + 20 * x as u8, 90 + 30 * y as u8, 240]),
    );
    d.write("height.png", png(4, 4, |x, y| [(40 * (x + y)) as u8; 3]));
    d.write("glow.png", png(2, 2, |_, _| [255, 128, 0]));
    d.write(
        "m.mtl",
        "newmtl metal\nKd 0.9 0.6 0.3\nKs 1 1 1\nNs 100\nPr 0.25\nPm 1\nKe 2 2 2\n\
         map_Ke glow.png\nmap_Bump -bm 0.5 bumps.png\n\
         newmtl mapped\nNs 225\nmap_Pr rough.png\nmap_Pm rough.png\nbump height.png\n\
         newmtl derived\nPm 0.5\nNs 225\nnorm bumps.png\n\
         newmtl phong\nKd 0.5 0.5 0.5\nKs 0.2\nNs 10\nKe 1 0 0\nmap_Bump bumps.png\n",
    );
    let quad = |m: &str| format!("usemtl {m}\nf -4/-4/1 -3/-3/1 -2/-2/1 -1/-1/1\n");
    let mut obj = String::from("mtllib m.mtl\nvn 0 0 1\n");
    for (i, m) in ["metal", "mapped", "derived", "phong"].iter().enumerate() {
        let x = 3.0 * i as f32;
        obj += &format!(
            "v {x} 0 0\nv {} 0 0\nv {} 1 0\nv {x} 1 0\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n",
            x + 1.0,
            x + 1.0
        );
        obj += &format!("o {m}\n{}", quad(m));
    }
    let file = d.write("m.obj", obj);
    let s = load::open(&file, &Opening::default()).unwrap().scene;
    let material = |name: &str| s.materials.iter().find(|m| m.name == name).unwrap();
    let metal = material("metal");
    let p = metal
        .pbr
        .as_ref()
        .expect("Pr and Pm make it physically based");
    assert_eq!((p.roughness, p.metallic), (0.25, 1.0));
    assert_eq!(
        (metal.kd, metal.ks, metal.ns),
        (Vec3::new(0.9, 0.6, 0.3), Vec3::ZERO, 0.0)
    );
    // Ke tints its map, as glTF's emissive factor does.
    assert_eq!(p.emissive, Vec3::splat(2.0));
    let glow = &s.textures[p.emissive_texture.unwrap() as usize];
    assert_eq!(glow.tint, Vec3::splat(2.0));
    assert!(metal.emissive());
    let (bumps, scale) = p.normal.expect("a bluish map_Bump is a normal map");
    assert_eq!(scale, 0.5);
    assert_eq!(s.textures[bumps as usize].texels.len(), 16);
    // Maps replace their numbers; roughness maps are looked up.
    let mapped = material("mapped");
    let p = mapped.pbr.as_ref().unwrap();
    assert_eq!((p.roughness, p.metallic), (1.0, 1.0));
    assert!(p.roughness_texture.is_some() && p.metallic_texture.is_some());
    assert!(p.normal.is_none(), "a grey bump map is a height map");
    // No Pr: the roughness Blender's exporter wrote as Ns (1 - r)² 900.
    let derived = material("derived").pbr.as_ref().unwrap();
    assert!(
        (derived.roughness - 0.5).abs() < 1e-6,
        "{}",
        derived.roughness
    );
    assert_eq!(
        (derived.metallic, derived.normal.map(|n| n.1)),
        (0.5, Some(1.0))
    );
    // Phong stays Phong.
    let phong = material("phong");
    assert!(phong.pbr.is_none());
    assert_eq!((phong.ks, phong.ns), (Vec3::splat(0.2), 10.0));
    let all = s.warnings.join("\n");
    for want in [
        "m.mtl:14: bump height.png is a height map (its texels are grey): no normal map for \
         this material",
        "Ke (emission) (line 23)",
        "map_Bump (line 24)",
    ] {
        assert!(all.contains(want), "{want}: {all}");
    }
    // The normal-mapped meshes (metal, derived) have tangents: +x, along u.
    let g = &s.geometry;
    assert_eq!(g.tangents().len(), 8);
    assert!(g
        .tangents()
        .iter()
        .all(|t| (*t - glam::Vec4::new(1.0, 0.0, 0.0, 1.0))
            .abs()
            .max_element()
            < 1e-6));
}

/// A normal-map statement whose image is not one, or whose `-bm` is not a
/// finite number, says so by line rather than drawing a flat or untouched
/// surface in silence.
fn mtl_normal_maps_that_are_not_say_why() {
    let d = Dir::new("mtl-bad-normals");
    d.write("red.png", png(4, 4, |_, _| [255, 0, 0]));
    d.write(
        "bumps.png",
        png(4, 4, |x, y| [100 + 20 * x as u8, 90 + 30 * y as u8, 240]),
    );
    d.write(
        "m.mtl",
        "newmtl a\nPr 0.5\nnorm red.png\n\
         newmtl b\nPr 0.5\nmap_Bump -bm nan bumps.png\n\
         newmtl c\nPr 0.5\nmap_Bump -bm X bumps.png\n",
    );
    let mut obj = String::from("mtllib m.mtl\nvn 0 0 1\nvt 0 0\nvt 1 0\nvt 1 1\n");
    for (i, m) in ["a", "b", "c"].iter().enumerate() {
        obj += &format!("v {i} 0 0\nv {} 0 0\nv {i} 1 0\nusemtl {m}\n", i + 1);
        obj += "f -3/1/1 -2/2/1 -1/3/1\n";
    }
    let file = d.write("m.obj", obj);
    let s = load::open(&file, &Opening::default()).unwrap().scene;
    let all = s.warnings.join("\n");
    for want in [
        "m.mtl:3: norm red.png is not a normal map (its texels are not the bluish of one)",
        "m.mtl:6: map_Bump options ignored: -bm nan (not a finite number)",
        "m.mtl:9: map_Bump options ignored: -bm (no number after it: X is read as part of the \
         file's name)",
    ] {
        assert!(all.contains(want), "{want:?} not in\n{all}");
    }
    let a = s.materials.iter().find(|m| m.name == "a").unwrap();
    assert!(a.pbr.as_ref().unwrap().normal.is_none());
    // A true normal map on a mesh whose texture coordinates span nothing.
    d.write("n.mtl", "newmtl n\nPr 0.5\nnorm bumps.png\n");
    let flat = d.write(
        "flat.obj",
        "mtllib n.mtl\nvn 0 0 1\nvt 0.5 0.5\nv 0 0 0\nv 1 0 0\nv 0 1 0\no flat\nusemtl n\n\
         f 1/1/1 2/1/1 3/1/1\n",
    );
    let s = load::open(&flat, &Opening::default()).unwrap().scene;
    assert!(
        s.warnings.iter().any(|w| w.contains(
            "flat: the normal map of material n needs texture coordinates that span an area"
        )),
        "{:?}",
        s.warnings
    );
}
