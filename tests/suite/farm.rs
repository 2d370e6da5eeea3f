//! A render farm's view: progress a log can read, the files a scene reads
//! (`rayterm inputs`), parts checked against the scene (`merge --check`),
//! missing parts named with the commands that render them, staged merges,
//! checkpoints on request and early, and `render --dry-run`.

use std::path::Path;
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::files::{rayterm, Dir, Run};
use glam::Vec3;
use rayterm::raster::ImageFormat;
use serde_json::{json, Value};

const SCENE: [&str; 3] = ["cornell-area", "--size", "40x28"];

fn ok(d: &Path, args: &[&str]) -> Run {
    let r = rayterm(d, args);
    assert!(r.ok(), "{args:?}: {}", r.stderr);
    assert!(!r.stderr.contains("panicked"), "{args:?}: {}", r.stderr);
    r
}

/// A command that fails with status 1 and no panic; its standard error.
fn refused(d: &Path, args: &[&str]) -> String {
    let r = rayterm(d, args);
    assert_eq!(r.code, Some(1), "{args:?}: {}", r.stderr);
    assert!(!r.stderr.contains("panicked"), "{args:?}: {}", r.stderr);
    r.stderr
}

fn render(d: &Path, extra: &[&str], out: &str) -> Run {
    let mut args = vec!["render"];
    args.extend(SCENE);
    args.extend(extra);
    args.extend(["-o", out]);
    ok(d, &args)
}

fn bytes(d: &Path, f: &str) -> Vec<u8> {
    std::fs::read(d.join(f)).unwrap()
}

/// The lines `rayterm inputs` prints.
fn inputs(d: &Path, args: &[&str]) -> Vec<String> {
    let mut all = vec!["inputs"];
    all.extend(args);
    ok(d, &all).stdout.lines().map(str::to_string).collect()
}

/// A 2x2 PNG of one colour.
fn png(c: [u8; 3]) -> Vec<u8> {
    let img = image::RgbImage::from_pixel(2, 2, image::Rgb(c));
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

const OBJ: &str = "mtllib box.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\n\
                   usemtl Wood\nf 1/1 2/2 3/3\n";

#[test]
fn progress_off_a_terminal_is_lines_or_json() {
    let d = Dir::new("farm-progress");
    // Standard error is a file here: lines, from the start to the end.
    let r = render(&d.0, &["--spp", "8"], "a.png");
    let lines: Vec<&str> = r.stderr.lines().collect();
    assert_eq!(
        lines.first(),
        Some(&"render: cornell-area at 40x28, 8 spp"),
        "{}",
        r.stderr
    );
    assert!(
        lines.last().unwrap().starts_with("progress: done, 8 spp, "),
        "{}",
        r.stderr
    );
    assert!(r.stdout.contains("-> a.png"));
    // JSON: every line an object, the first the start, the last the end.
    let r = render(&d.0, &["--spp", "8", "--progress", "json"], "b.png");
    let objects: Vec<Value> = r
        .stderr
        .lines()
        .map(|l| serde_json::from_str(l).unwrap_or_else(|_| panic!("not JSON: {l}")))
        .collect();
    assert_eq!(objects[0]["event"], "start");
    assert_eq!(objects[0]["total_spp"], 8);
    assert_eq!(
        (objects[0]["width"].clone(), objects[0]["height"].clone()),
        (json!(40), json!(28))
    );
    let last = objects.last().unwrap();
    assert_eq!(
        (last["event"].as_str(), last["spp"].as_f64()),
        (Some("done"), Some(8.0))
    );
    for o in &objects[1..objects.len() - 1] {
        assert_eq!(o["event"], "progress", "{o}");
        let p = o["percent"].as_f64().unwrap();
        assert!((0.0..=100.0).contains(&p), "{o}");
    }
    // None: nothing on standard error.
    let r = render(&d.0, &["--spp", "8", "--progress", "none"], "c.png");
    assert_eq!(r.stderr, "");
    assert!(bytes(&d.0, "a.png") == bytes(&d.0, "c.png"));
}

/// A resumed render's log says what it resumed from, in words and in
/// JSON, and the checkpoints it writes.
#[test]
fn a_resumed_render_says_where_it_resumed_from() {
    let d = Dir::new("farm-resume");
    render(&d.0, &["--spp", "4", "--checkpoint", "c.exr"], "a.png");
    let r = render(
        &d.0,
        &["--spp", "8", "--resume", "c.exr", "--checkpoint", "c.exr"],
        "b.png",
    );
    assert!(
        r.stderr.starts_with(
            "render: cornell-area at 40x28, 8 spp; resumed from c.exr, which holds samples 0..4 ("
        ),
        "{}",
        r.stderr
    );
    assert!(
        r.stderr.contains("checkpoint: c.exr holds samples 0.."),
        "{}",
        r.stderr
    );
    let r = render(
        &d.0,
        &[
            "--spp",
            "12",
            "--resume",
            "c.exr",
            "--checkpoint",
            "c.exr",
            "--progress",
            "json",
        ],
        "c.png",
    );
    let start: Value = serde_json::from_str(r.stderr.lines().next().unwrap()).unwrap();
    assert_eq!(start["resumed_from"]["file"], "c.exr");
    assert_eq!(start["resumed_from"]["samples"], json!([0, 8]));
    assert!(r.stderr.contains(r#""event":"checkpoint""#), "{}", r.stderr);
}

#[test]
fn inputs_lists_the_files_of_an_obj_with_its_mtl_and_texture() {
    let d = Dir::new("farm-inputs-obj");
    d.write("box.obj", OBJ);
    d.write("box.mtl", "newmtl Wood\nKd 1 1 1\nmap_Kd tex/wood.png\n");
    d.write("tex/wood.png", png([200, 120, 40]));
    assert_eq!(
        inputs(&d.0, &["box.obj"]),
        ["box.obj", "box.mtl", "tex/wood.png"]
    );
    // An absolute scene path gives absolute inputs.
    let abs = d.path("box.obj").display().to_string();
    let listed = inputs(&d.0, &[&abs]);
    assert_eq!(listed[2], d.path("tex/wood.png").display().to_string());
    // A built-in scene reads no file; a missing MTL is warned about and
    // not listed.
    assert!(inputs(&d.0, &["cornell"]).is_empty());
    std::fs::remove_file(d.path("box.mtl")).unwrap();
    let r = ok(&d.0, &["inputs", "box.obj"]);
    assert_eq!(r.stdout, "box.obj\n");
    assert!(r.stderr.contains("box.mtl"), "{}", r.stderr);
    // A scene that cannot be read is an error naming it.
    let err = refused(&d.0, &["inputs", "gone.obj"]);
    assert!(err.contains("gone.obj"), "{err}");
}

#[test]
fn inputs_lists_a_scene_files_meshes_and_environment_map() {
    let d = Dir::new("farm-inputs-toml");
    d.write("meshes/box.obj", OBJ);
    d.write("meshes/box.mtl", "newmtl Wood\nKd 1 1 1\nmap_Kd wood.png\n");
    d.write("meshes/wood.png", png([200, 120, 40]));
    d.write("meshes/tri.stl", stl());
    let sky = ImageFormat::Hdr
        .encode_linear(4, 2, &[Vec3::new(0.5, 0.6, 0.9); 8])
        .unwrap();
    d.write("env/sky.hdr", sky);
    d.write(
        "scene.toml",
        "[[mesh]]\nfile = \"meshes/box.obj\"\n\n[[mesh]]\nfile = \"meshes/tri.stl\"\n\n\
         [environment]\nmap = \"env/sky.hdr\"\n",
    );
    let listed = inputs(&d.0, &["scene.toml"]);
    let mut sorted = listed.clone();
    sorted.sort();
    assert_eq!(
        sorted,
        [
            "env/sky.hdr",
            "meshes/box.mtl",
            "meshes/box.obj",
            "meshes/tri.stl",
            "meshes/wood.png",
            "scene.toml"
        ],
        "{listed:?}"
    );
    assert_eq!(listed[0], "scene.toml");
    // --env's map is one too.
    let with_env = inputs(&d.0, &["meshes/tri.stl", "--env", "env/sky.hdr"]);
    assert_eq!(with_env.len(), 2, "{with_env:?}");
    assert!(
        with_env.contains(&"env/sky.hdr".to_string()),
        "{with_env:?}"
    );
}

/// A binary STL of one triangle.
fn stl() -> Vec<u8> {
    let mut b = vec![0u8; 80];
    b.extend(1u32.to_le_bytes());
    for v in [[0f32, 0., 1.], [0., 0., 0.], [1., 0., 0.], [0., 1., 0.]] {
        for x in v {
            b.extend(x.to_le_bytes());
        }
    }
    b.extend([0, 0]);
    b
}

#[test]
fn inputs_lists_a_gltf_with_its_buffer_and_images() {
    let d = Dir::new("farm-inputs-gltf");
    let mut bin = Vec::new();
    for v in [[0f32, 0., 0.], [1., 0., 0.], [0., 1., 0.]] {
        for x in v {
            bin.extend(x.to_le_bytes());
        }
    }
    for uv in [[0f32, 0.], [1., 0.], [0., 1.]] {
        for x in uv {
            bin.extend(x.to_le_bytes());
        }
    }
    d.write("model/tri.bin", &bin);
    d.write("model/textures/base.png", png([255, 0, 0]));
    d.write("model/textures/normal.png", png([128, 128, 255]));
    let doc = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "TEXCOORD_0": 1}, "material": 0}]}],
        "materials": [{
            "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}},
            "normalTexture": {"index": 1}
        }],
        "textures": [{"source": 0}, {"source": 1}],
        "images": [{"uri": "textures/base.png"}, {"uri": "textures/normal.png"}],
        "buffers": [{"uri": "tri.bin", "byteLength": bin.len()}],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 24}
        ],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
             "min": [0, 0, 0], "max": [1, 1, 0]},
            {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC2"}
        ]
    });
    d.write("model/tri.gltf", serde_json::to_vec(&doc).unwrap());
    let mut listed = inputs(&d.0, &["model/tri.gltf"]);
    assert_eq!(listed[0], "model/tri.gltf");
    listed.sort();
    assert_eq!(
        listed,
        [
            "model/textures/base.png",
            "model/textures/normal.png",
            "model/tri.bin",
            "model/tri.gltf"
        ]
    );
}

/// `merge --check SCENE` passes parts of the scene as it loads here, and
/// names the file that differs, or the one the parts did not read.
#[test]
fn merge_check_names_the_input_that_differs() {
    let d = Dir::new("farm-check");
    d.write("box.obj", OBJ);
    d.write("box.mtl", "newmtl Wood\nKd 1 1 1\nmap_Kd wood.png\n");
    d.write("wood.png", png([200, 120, 40]));
    let part = |k: &str, out: &str| {
        ok(
            &d.0,
            &[
                "render", "box.obj", "--size", "24x16", "--spp", "4", "--part", k, "-o", out,
            ],
        )
    };
    part("1/2", "p1.exr");
    part("2/2", "p2.exr");
    let r = ok(
        &d.0,
        &[
            "merge", "--check", "box.obj", "p1.exr", "p2.exr", "-o", "m.png",
        ],
    );
    assert!(
        r.stderr
            .contains("check: the parts were rendered from box.obj"),
        "{}",
        r.stderr
    );
    // Another texture here: named, and nothing written.
    d.write("wood.png", png([20, 120, 240]));
    let err = refused(
        &d.0,
        &[
            "merge", "--check", "box.obj", "p1.exr", "p2.exr", "-o", "n.png",
        ],
    );
    assert!(err.contains("wood.png: differs (CRC-32 "), "{err}");
    assert!(!err.contains("box.mtl:"), "{err}");
    assert!(!d.path("n.png").exists());
    // Parts rendered without the MTL (forgotten on the farm).
    d.write("wood.png", png([200, 120, 40]));
    std::fs::rename(d.path("box.mtl"), d.path("box.mtl.away")).unwrap();
    part("1/2", "q1.exr");
    part("2/2", "q2.exr");
    std::fs::rename(d.path("box.mtl.away"), d.path("box.mtl")).unwrap();
    let err = refused(
        &d.0,
        &[
            "merge", "--check", "box.obj", "q1.exr", "q2.exr", "-o", "n.png",
        ],
    );
    assert!(
        err.contains("box.mtl: read here, not by the parts"),
        "{err}"
    );
    assert!(
        err.contains("wood.png: read here, not by the parts"),
        "{err}"
    );
    // The options the parts recorded are the ones checked: another size
    // is no other scene, a missing feature is.
    let err = refused(
        &d.0,
        &[
            "merge", "--check", "cornell", "p1.exr", "p2.exr", "-o", "n.png",
        ],
    );
    assert!(err.contains("not rendered from cornell"), "{err}");
    let err = refused(
        &d.0,
        &["merge", "--check", "nothing.obj", "p1.exr", "-o", "n.png"],
    );
    assert!(err.contains("nothing.obj"), "{err}");
}

/// Missing parts are named as parts, with commands that render them;
/// run as printed, they complete the merge.
#[test]
fn missing_parts_are_named_with_the_commands_that_render_them() {
    let d = Dir::new("farm-missing");
    std::fs::create_dir(d.path("parts")).unwrap();
    for k in [1, 2] {
        render(
            &d.0,
            &[
                "--spp",
                "12",
                "--part",
                &format!("{k}/4"),
                "--progress",
                "none",
            ],
            &format!("parts/part-{k}.exr"),
        );
    }
    let err = refused(
        &d.0,
        &[
            "merge",
            "parts/part-1.exr",
            "parts/part-2.exr",
            "-o",
            "m.png",
        ],
    );
    assert!(
        err.contains("parts 3/4 and 4/4 are missing (samples 6..12 of 0..12)"),
        "{err}"
    );
    let commands: Vec<&str> = err
        .lines()
        .map(str::trim)
        .filter(|l| l.starts_with("rayterm render "))
        .collect();
    assert_eq!(
        commands,
        [
            "rayterm render cornell-area --size 40x28 --spp 12 --part 3/4 -o parts/part-3.exr",
            "rayterm render cornell-area --size 40x28 --spp 12 --part 4/4 -o parts/part-4.exr"
        ],
        "{err}"
    );
    // A preview of what there is says what it lacks.
    let r = ok(
        &d.0,
        &[
            "merge",
            "parts/part-1.exr",
            "parts/part-2.exr",
            "--allow-missing",
            "-o",
            "preview.png",
        ],
    );
    assert!(
        r.stderr.contains("parts 3/4 and 4/4 are missing"),
        "{}",
        r.stderr
    );
    for c in commands {
        let words: Vec<&str> = c.split(' ').skip(1).collect();
        ok(&d.0, &words);
    }
    ok(
        &d.0,
        &[
            "merge",
            "parts/part-4.exr",
            "parts/part-1.exr",
            "parts/part-3.exr",
            "parts/part-2.exr",
            "-o",
            "m.png",
        ],
    );
    render(&d.0, &["--spp", "12"], "single.png");
    assert!(bytes(&d.0, "m.png") == bytes(&d.0, "single.png"));
}

/// A merge into a partial film merges again with the other parts into
/// the single render's image, whichever parts were merged first; parts
/// with a gap between them make no partial film.
#[test]
fn staged_merges_equal_one_render() {
    let d = Dir::new("farm-staged");
    for k in 1..=4 {
        render(
            &d.0,
            &["--spp", "12", "--part", &format!("{k}/4")],
            &format!("p{k}.exr"),
        );
    }
    render(&d.0, &["--spp", "12"], "single.png");
    render(&d.0, &["--spp", "12"], "single.exr");
    let r = ok(
        &d.0,
        &["merge", "p2.exr", "p1.exr", "--partial", "-o", "s12.exr"],
    );
    assert!(
        r.stdout.contains("into samples 0..6")
            && r.stdout
                .contains("still to merge with it: samples 6..12 of 0..12"),
        "{}",
        r.stdout
    );
    ok(
        &d.0,
        &["merge", "p3.exr", "p4.exr", "--partial", "-o", "s34.exr"],
    );
    ok(
        &d.0,
        &["merge", "s12.exr", "p3.exr", "p4.exr", "-o", "a.png"],
    );
    ok(&d.0, &["merge", "s34.exr", "s12.exr", "-o", "b.png"]);
    ok(
        &d.0,
        &["merge", "p1.exr", "s34.exr", "p2.exr", "-o", "c.exr"],
    );
    for f in ["a.png", "b.png"] {
        assert!(bytes(&d.0, f) == bytes(&d.0, "single.png"), "{f}");
    }
    assert!(bytes(&d.0, "c.exr") == bytes(&d.0, "single.exr"));
    // A stage again with a part it holds overlaps; a gap is refused; a
    // partial film is .exr.
    let err = refused(&d.0, &["merge", "s12.exr", "p2.exr", "-o", "x.png"]);
    assert!(err.contains("overlap"), "{err}");
    let err = refused(
        &d.0,
        &["merge", "p1.exr", "p3.exr", "--partial", "-o", "x.exr"],
    );
    assert!(
        err.contains("samples 3..6 are missing between the parts"),
        "{err}"
    );
    let err = refused(
        &d.0,
        &["merge", "p1.exr", "p2.exr", "--partial", "-o", "x.png"],
    );
    assert!(err.contains("x.png"), "{err}");
    assert!(!d.path("x.exr").exists() && !d.path("x.png").exists());
}

/// Bad checkpoint intervals are refused by name.
#[test]
fn checkpoint_intervals_must_be_seconds_above_zero() {
    let d = Dir::new("farm-every");
    for bad in ["0", "-1", "nan", "inf", "soon"] {
        let r = rayterm(
            &d.0,
            &[
                "render",
                "cornell-area",
                "--checkpoint",
                "c.exr",
                "--checkpoint-every",
                bad,
                "-o",
                "a.png",
            ],
        );
        assert_eq!(r.code, Some(2), "{bad}: {}", r.stderr);
        assert!(
            r.stderr.contains("--checkpoint-every"),
            "{bad}: {}",
            r.stderr
        );
    }
    let r = rayterm(
        &d.0,
        &[
            "render",
            "cornell-area",
            "--checkpoint-every",
            "3",
            "-o",
            "a.png",
        ],
    );
    assert!(r.stderr.contains("--checkpoint"), "{}", r.stderr);
    assert!(!d.path("c.exr").exists() && !d.path("a.png").exists());
}

/// The first checkpoint follows the first pass, whatever the interval;
/// SIGUSR1 asks for another at once; the render ends on SIGTERM with its
/// film in the checkpoint, which resumes into the uninterrupted render.
#[test]
fn sigusr1_writes_a_checkpoint_and_the_first_comes_early() {
    let d = Dir::new("farm-usr1");
    let mut args = vec!["--spp", "1000000", "--checkpoint", "c.exr"];
    args.extend([
        "--checkpoint-every",
        "100000",
        "--progress",
        "json",
        "-o",
        "never.png",
    ]);
    let mut child = spawn(&d, &args);
    let samples = |d: &Dir| -> Option<u32> {
        let h = rayterm::render::partial::Header::read(&d.path("c.exr")).ok()?;
        Some(h.range.end)
    };
    let wait_for = |what: &str, until: &dyn Fn() -> bool| {
        let start = Instant::now();
        while !until() {
            assert!(start.elapsed() < Duration::from_secs(60), "{what}");
            std::thread::sleep(Duration::from_millis(20));
        }
    };
    wait_for("no first checkpoint", &|| samples(&d).is_some());
    let first = samples(&d).unwrap();
    // SAFETY: signalling the child this test started.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGUSR1) }, 0);
    wait_for("no checkpoint on SIGUSR1", &|| {
        samples(&d).is_some_and(|n| n > first)
    });
    assert!(
        child.try_wait().unwrap().is_none(),
        "SIGUSR1 ended the render"
    );
    // SAFETY: as above.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGTERM) }, 0);
    let out = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(128 + libc::SIGTERM), "{err}");
    let events = err.matches(r#""event":"checkpoint""#).count();
    assert!(events >= 2, "{err}");
    let held = samples(&d).unwrap();
    let spp = (held + 2).to_string();
    render(&d.0, &["--spp", &spp, "--resume", "c.exr"], "resumed.png");
    render(&d.0, &["--spp", &spp], "whole.png");
    assert!(bytes(&d.0, "resumed.png") == bytes(&d.0, "whole.png"));
}

/// SIGUSR1 to a render with no checkpoint does not end it.
#[test]
fn sigusr1_without_a_checkpoint_is_noted() {
    let d = Dir::new("farm-usr1-none");
    let mut child = spawn(
        &d,
        &["--spp", "1000000", "--progress", "json", "-o", "never.png"],
    );
    // Once it renders (its start line is written before the first pass).
    let mut line = String::new();
    let mut err = std::io::BufReader::new(child.stderr.take().unwrap());
    std::io::BufRead::read_line(&mut err, &mut line).unwrap();
    assert!(line.contains(r#""event":"start""#), "{line}");
    // SAFETY: signalling the child this test started.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGUSR1) }, 0);
    let mut rest = String::new();
    let start = Instant::now();
    while !rest.contains("SIGUSR1: this render has no --checkpoint") {
        assert!(start.elapsed() < Duration::from_secs(60), "{rest}");
        std::io::BufRead::read_line(&mut err, &mut rest).unwrap();
    }
    assert!(child.try_wait().unwrap().is_none());
    // SAFETY: as above.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGTERM) }, 0);
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(128 + libc::SIGTERM));
    assert!(!d.path("never.png").exists());
}

/// `rayterm render ARGS` in `d`, its standard error piped.
fn spawn(d: &Dir, args: &[&str]) -> std::process::Child {
    Command::new(env!("CARGO_BIN_EXE_rayterm"))
        .arg("render")
        .args(SCENE)
        .args(args)
        .current_dir(&d.0)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
}

/// `--dry-run` reports and writes nothing; a checkpointed render needs
/// more than one that writes an image, as its film keeps statistics.
#[test]
fn a_dry_run_estimates_and_renders_nothing() {
    let d = Dir::new("farm-dry");
    let figure = |out: &str, row: &str| -> String {
        out.lines()
            .find(|l| l.trim_start().starts_with(row))
            .unwrap_or_else(|| panic!("no {row} in {out}"))
            .trim_start()[row.len()..]
            .trim()
            .to_string()
    };
    let plain = ok(
        &d.0,
        &[
            "render",
            "cornell-area",
            "--size",
            "1920x1080",
            "--spp",
            "64",
            "--dry-run",
            "-o",
            "a.png",
        ],
    );
    assert!(plain
        .stdout
        .starts_with("cornell-area at 1920x1080: a dry run, nothing rendered"));
    assert_eq!(figure(&plain.stdout, "triangles"), "32 (40 vertices)");
    assert_eq!(figure(&plain.stdout, "checkpoints"), "none");
    let ck = ok(
        &d.0,
        &[
            "render",
            "cornell-area",
            "--size",
            "1920x1080",
            "--spp",
            "64",
            "--dry-run",
            "--checkpoint",
            "c.exr",
            "-o",
            "a.png",
        ],
    );
    let mib = |s: &str| -> f64 {
        let w: Vec<&str> = s.split_whitespace().collect();
        let n: f64 = w[1].parse().unwrap();
        n * match w[2] {
            "KiB" => 1.0 / 1024.0,
            "MiB" => 1.0,
            "GiB" => 1024.0,
            u => panic!("{u}"),
        }
    };
    let (a, b) = (
        mib(&figure(&plain.stdout, "peak memory")),
        mib(&figure(&ck.stdout, "peak memory")),
    );
    assert!(b > 4.0 * a, "{a} MiB against {b} MiB");
    assert!(
        figure(&ck.stdout, "checkpoints").starts_with("at most 301 MiB a file"),
        "{}",
        ck.stdout
    );
    assert!(!d.path("a.png").exists() && !d.path("c.exr").exists());
    assert_eq!(std::fs::read_dir(&d.0).unwrap().count(), 0);
}
