//! `--aov`: albedo, normal and depth beside the picture in an EXR, read
//! back channel by channel.

use std::path::Path;
use std::process::Command;

fn rayterm(args: &[&str]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_rayterm"))
        .args(args)
        .output()
        .expect("rayterm runs")
}

/// Every channel of the EXR's first layer, by name.
fn channels(path: &Path) -> Vec<(String, Vec<f32>)> {
    let img = exr::prelude::read_all_flat_layers_from_file(path).expect("an EXR");
    let layer = &img.layer_data[0];
    layer
        .channel_data
        .list
        .iter()
        .map(|c| {
            let v: Vec<f32> = c.sample_data.values_as_f32().collect();
            (c.name.to_string(), v)
        })
        .collect()
}

fn get<'a>(ch: &'a [(String, Vec<f32>)], name: &str) -> &'a [f32] {
    &ch.iter()
        .find(|c| c.0 == name)
        .unwrap_or_else(|| panic!("no {name}"))
        .1
}

#[test]
fn aovs_sit_beside_the_same_picture() {
    let dir = tempdir();
    let plain = dir.join("plain.exr");
    let with = dir.join("with.exr");
    let common = ["render", "cornell", "--size", "32x24", "--spp", "4"];
    let run = |out: &Path, more: &[&str]| {
        let mut args: Vec<&str> = common.to_vec();
        args.extend(["-o", out.to_str().unwrap()]);
        args.extend(more);
        let o = rayterm(&args);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    };
    run(&plain, &[]);
    run(&with, &["--aov", "albedo,normal,depth"]);
    let (a, b) = (channels(&plain), channels(&with));
    // The picture is the same to the bit.
    for c in ["R", "G", "B"] {
        assert_eq!(get(&a, c), get(&b, c), "{c}");
    }
    let names: Vec<&str> = b.iter().map(|c| c.0.as_str()).collect();
    for c in [
        "albedo.R", "albedo.G", "albedo.B", "normal.X", "normal.Y", "normal.Z", "Z",
    ] {
        assert!(names.contains(&c), "{names:?}");
    }
    // Most camera rays hit the box, near, a surface whose colour is a
    // material's and whose normal is a unit one (a pixel's few samples
    // may straddle an edge, so most, not all); the rest leave through its
    // open front, infinitely far.
    let (w, h) = (32, 24);
    let z = get(&b, "Z");
    assert!(z
        .iter()
        .all(|d| *d == f32::INFINITY || (*d > 0.0 && *d < 10.0)));
    assert!(z.iter().filter(|d| d.is_finite()).count() > w * h * 3 / 4);
    let normal = |i: usize| {
        glam::Vec3::new(
            get(&b, "normal.X")[i],
            get(&b, "normal.Y")[i],
            get(&b, "normal.Z")[i],
        )
    };
    assert!((0..w * h).all(|i| normal(i).length() <= 1.0 + 1e-3));
    let unit = (0..w * h)
        .filter(|&i| (normal(i).length() - 1.0).abs() < 1e-3)
        .count();
    assert!(unit > w * h / 2, "{unit} unit normals");
    // Pixels wholly on the red and the green wall have their MTL colours.
    let albedo = |i: usize| {
        glam::Vec3::new(
            get(&b, "albedo.R")[i],
            get(&b, "albedo.G")[i],
            get(&b, "albedo.B")[i],
        )
    };
    for kd in [
        glam::Vec3::new(0.63, 0.065, 0.05),
        glam::Vec3::new(0.14, 0.45, 0.091),
    ] {
        let n = (0..w * h)
            .filter(|&i| (albedo(i) - kd).abs().max_element() < 1e-6)
            .count();
        assert!(n >= 10, "{n} pixels of albedo {kd}");
    }
}

#[test]
fn aovs_need_an_exr() {
    let dir = tempdir();
    let png = dir.join("x.png");
    let o = rayterm(&[
        "render",
        "cornell",
        "--size",
        "8x8",
        "--aov",
        "depth",
        "-o",
        png.to_str().unwrap(),
    ]);
    assert_eq!(o.status.code(), Some(1));
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(err.contains("--aov") && err.contains("x.png"), "{err}");
    assert!(!png.exists());
}

fn tempdir() -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!(
        "rayterm-aov-{}-{:?}",
        std::process::id(),
        std::thread::current().id()
    ));
    std::fs::create_dir_all(&d).unwrap();
    d
}
