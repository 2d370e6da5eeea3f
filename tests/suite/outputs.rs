//! `rayterm render -o`: bad outputs are refused before anything renders,
//! devices and FIFOs are never replaced, and no temporary file is left
//! behind by a failure or a signal.

use std::fs;
use std::os::unix::fs::FileTypeExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

fn rayterm(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_rayterm"))
        .args(args)
        .output()
        .unwrap()
}

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rayterm-outputs-{name}-{}", std::process::id()));
    let _ = fs::remove_dir_all(&d);
    fs::create_dir_all(&d).unwrap();
    d
}

/// The files in `d`, hidden ones included.
fn files(d: &Path) -> Vec<String> {
    let mut v: Vec<String> = fs::read_dir(d)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

fn fails_with(args: &[&str], needle: &str) {
    let out = rayterm(args);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{args:?} succeeded");
    assert!(err.contains(needle), "{args:?}: {err}");
    assert!(!err.contains("panicked"), "{err}");
    assert!(out.stdout.is_empty(), "{args:?} rendered: {:?}", out.stdout);
}

#[test]
fn bad_outputs_are_refused_with_the_reason() {
    let d = dir("bad");
    let p = |n: &str| d.join(n).display().to_string();
    fails_with(
        &["render", "cornell", "-o", &p("nope/x.png")],
        "does not exist",
    );
    fails_with(&["render", "cornell", "-o", &p("x.jpg")], "unknown format");
    fails_with(&["render", "cornell", "-o", &p("noext")], "unknown format");
    fails_with(
        &["render", "cornell", "-o", &(p("x.png") + "/")],
        "ends in /",
    );
    let part = ["render", "cornell", "--part", "1/2", "-o"];
    let x_png = p("x.png");
    fails_with(
        &[&part[..], &[&x_png]].concat(),
        "a part is a partial film: name it .exr",
    );
    let nope = p("nope/x.exr");
    let out = rayterm(&[&part[..], &[&nope]].concat());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(
        err.contains("does not exist") && !err.contains("name it"),
        "{err}"
    );
    let (y, ck_png) = (p("y.png"), p("ck.png"));
    let ck = ["render", "cornell", "-o", &y, "--checkpoint", &ck_png];
    fails_with(&ck, "a checkpoint is a partial film");
    fs::create_dir(d.join("sub.png")).unwrap();
    fails_with(
        &["render", "cornell", "-o", &p("sub.png")],
        "is a directory",
    );
    // The scene file itself as the output.
    let scene = d.join("plane.obj");
    fs::write(&scene, "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
    let hdr = d.join("plane.hdr");
    fs::copy(&scene, &hdr).unwrap();
    let _ = fs::remove_file(&scene);
    std::os::unix::fs::symlink(&hdr, &scene).unwrap();
    fails_with(
        &[
            "render",
            scene.to_str().unwrap(),
            "-o",
            hdr.to_str().unwrap(),
        ],
        "is an input",
    );
    assert_eq!(
        fs::read_to_string(&hdr).unwrap(),
        "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n"
    );
    assert_eq!(files(&d), ["plane.hdr", "plane.obj", "sub.png"]);
    fs::remove_dir_all(d).unwrap();
}

#[test]
fn a_texture_the_scene_reads_is_not_overwritten() {
    let d = dir("texture");
    let p = |n: &str| d.join(n).display().to_string();
    fs::write(
        d.join("m.obj"),
        "mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nusemtl a\nf 1/1 2/2 3/3\n",
    )
    .unwrap();
    fs::write(d.join("m.mtl"), "newmtl a\nKd 1 1 1\nmap_Kd t.png\n").unwrap();
    let made = rayterm(&["render", "cornell", "--size", "4x4", "-o", &p("t.png")]);
    assert!(made.status.success());
    let texture = fs::read(d.join("t.png")).unwrap();
    fails_with(
        &["render", &p("m.obj"), "--size", "8x8", "-o", &p("t.png")],
        "is an input",
    );
    assert_eq!(fs::read(d.join("t.png")).unwrap(), texture);
    assert_eq!(files(&d), ["m.mtl", "m.obj", "t.png"]);
    fs::remove_dir_all(d).unwrap();
}

#[test]
fn devices_and_fifos_are_written_in_place_never_replaced() {
    let d = dir("dev");
    let null = d.join("null.png");
    std::os::unix::fs::symlink("/dev/null", &null).unwrap();
    let out = rayterm(&[
        "render",
        "cornell",
        "--size",
        "8x8",
        "-o",
        null.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(fs::metadata("/dev/null")
        .unwrap()
        .file_type()
        .is_char_device());
    // /dev/full takes nothing: an error naming it, and still a device.
    let out = rayterm(&["render", "cornell", "--size", "8x8", "-o", "/dev/full"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success() && err.contains("/dev/full"), "{err}");
    assert!(err.contains("no space left on device"), "{err}");
    assert!(fs::metadata("/dev/full")
        .unwrap()
        .file_type()
        .is_char_device());
    let fifo = d.join("f.png");
    if Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success())
    {
        fails_with(
            &["render", "cornell", "-o", fifo.to_str().unwrap()],
            "FIFO that no process is reading",
        );
        // With a reader, the PNG goes through the FIFO.
        let reader = Command::new("cat")
            .arg(&fifo)
            .stdout(Stdio::piped())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(200));
        let out = rayterm(&[
            "render",
            "cornell",
            "--size",
            "8x8",
            "-o",
            fifo.to_str().unwrap(),
        ]);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        let got = reader.wait_with_output().unwrap().stdout;
        assert_eq!(&got[..8], b"\x89PNG\r\n\x1a\n");
        assert!(fs::metadata(&fifo).unwrap().file_type().is_fifo());
    } else {
        eprintln!("skipping the FIFO cases: mkfifo is not available");
    }
    assert_eq!(files(&d), ["f.png", "null.png"]);
    fs::remove_dir_all(d).unwrap();
}

#[test]
fn a_signal_during_a_render_writes_nothing() {
    let d = dir("signal");
    let out = d.join("x.png");
    for signal in [libc::SIGTERM, libc::SIGHUP, libc::SIGINT] {
        let child = Command::new(env!("CARGO_BIN_EXE_rayterm"))
            .args(["render", "cornell-area", "--spp", "100000", "-o"])
            .arg(&out)
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(1500));
        // SAFETY: signalling the child we started.
        assert_eq!(unsafe { libc::kill(child.id() as i32, signal) }, 0);
        let start = Instant::now();
        let res = child.wait_with_output().unwrap();
        assert!(start.elapsed() < Duration::from_secs(10));
        let err = String::from_utf8_lossy(&res.stderr);
        assert_eq!(res.status.code(), Some(128 + signal), "{err}");
        assert!(err.contains("interrupted: nothing written"), "{err}");
        assert!(files(&d).is_empty(), "{:?}", files(&d));
    }
    // In one pass of 256 samples a pixel (256 light samples each), a row
    // takes many seconds: the render stops within a pixel all the same.
    let child = Command::new(env!("CARGO_BIN_EXE_rayterm"))
        .args([
            "render",
            "cornell-area",
            "--spp",
            "256",
            "--light-samples",
            "256",
        ])
        .args(["--size", "1920x1080", "-o"])
        .arg(&out)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    // SAFETY: signalling the child we started.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGINT) }, 0);
    let start = Instant::now();
    let res = child.wait_with_output().unwrap();
    assert!(start.elapsed() < Duration::from_secs(10));
    assert_eq!(res.status.code(), Some(128 + libc::SIGINT));
    assert!(files(&d).is_empty(), "{:?}", files(&d));
    fs::remove_dir_all(d).unwrap();
}

/// `converge` stopped while it renders its reference: no result printed, no
/// CSV, no cached reference, no temporary file.
#[test]
fn a_signal_during_converge_writes_nothing() {
    let d = dir("converge-signal");
    for signal in [libc::SIGINT, libc::SIGTERM] {
        let child = Command::new(env!("CARGO_BIN_EXE_rayterm"))
            .args(["converge", "cornell-area", "--reference-spp", "1000000"])
            .args(["--csv", "out.csv", "--cache-dir", "cache"])
            .current_dir(&d)
            .stdout(Stdio::piped())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(1500));
        // SAFETY: signalling the child we started.
        assert_eq!(unsafe { libc::kill(child.id() as i32, signal) }, 0);
        let res = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&res.stderr);
        assert_eq!(res.status.code(), Some(128 + signal), "{err}");
        assert!(err.contains("interrupted: nothing written"), "{err}");
        assert!(
            res.stdout.is_empty(),
            "{}",
            String::from_utf8_lossy(&res.stdout)
        );
        let cache = d.join("cache");
        let cached = if cache.exists() {
            files(&cache)
        } else {
            vec![]
        };
        let _ = fs::remove_dir(&cache);
        assert!(
            files(&d).is_empty() && cached.is_empty(),
            "{:?} {cached:?}",
            files(&d)
        );
    }
    fs::remove_dir_all(d).unwrap();
}

#[test]
fn a_full_disk_leaves_no_temporary_file() {
    let d = dir("full");
    let mounted = Command::new("mount")
        .args(["-t", "tmpfs", "-o", "size=16k", "tmpfs"])
        .arg(&d)
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    if !mounted {
        eprintln!("skipping: cannot mount a small tmpfs here (needs root)");
        fs::remove_dir_all(d).unwrap();
        return;
    }
    for name in ["x.png", "x.hdr"] {
        let out = d.join(name);
        let res = rayterm(&[
            "render",
            "cornell",
            "--size",
            "200x200",
            "-o",
            out.to_str().unwrap(),
        ]);
        let err = String::from_utf8_lossy(&res.stderr);
        assert!(!res.status.success(), "{name} fit in 16 kB?");
        assert!(
            err.contains(name) && err.contains("no space left on device"),
            "{err}"
        );
        assert!(files(&d).is_empty(), "{:?}", files(&d));
    }
    let _ = Command::new("umount").arg(&d).status();
    fs::remove_dir_all(d).unwrap();
}

#[test]
fn absurd_budgets_are_capped_or_refused_and_empty_references_too() {
    let d = dir("budgets");
    let p = |n: &str| d.join(n).display().to_string();
    let out = rayterm(&[
        "render",
        "cornell-area",
        "--size",
        "8x8",
        "--time",
        "1e300",
        "--max-spp",
        "2",
        "-o",
        &p("t.png"),
    ]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{err}");
    let said = String::from_utf8_lossy(&out.stdout);
    assert!(said.contains(", 2 spp,"), "{said}");
    assert!(said.contains("before the --time of 1e300 s"), "{said}");
    fs::write(
        d.join("zero.hdr"),
        "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 0 +X 0\n",
    )
    .unwrap();
    let out = rayterm(&["converge", "cornell-area", "--reference", &p("zero.hdr")]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(
        err.contains("zero.hdr") && !err.contains("--size 0x0"),
        "{err}"
    );
    assert!(!err.contains("panicked"), "{err}");
    // A budget too short for one sample per pixel is not scored as an error.
    let cache = p("cache");
    let args = ["converge", "cornell-area", "--reference-spp", "8"];
    let out = rayterm(&[&args[..], &["--cache-dir", &cache, "--times", "1e-9"]].concat());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(err.contains("too short for one sample per pixel"), "{err}");
    fs::remove_dir_all(d).unwrap();
}

/// A file replaced keeps its permissions; a symbolic link named as the
/// output becomes the file, its target untouched.
#[test]
fn a_replaced_output_keeps_its_permissions() {
    use std::os::unix::fs::PermissionsExt;
    let d = dir("modes");
    let (kept, real, link) = (d.join("kept.png"), d.join("real.png"), d.join("link.png"));
    fs::write(&kept, b"old").unwrap();
    fs::set_permissions(&kept, fs::Permissions::from_mode(0o640)).unwrap();
    fs::write(&real, b"old").unwrap();
    std::os::unix::fs::symlink(&real, &link).unwrap();
    for out in [&kept, &link] {
        let o = rayterm(&[
            "render",
            "cornell",
            "--size",
            "8x8",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    assert_eq!(
        fs::metadata(&kept).unwrap().permissions().mode() & 0o777,
        0o640
    );
    assert!(fs::read(&kept).unwrap().starts_with(b"\x89PNG"));
    assert!(fs::symlink_metadata(&link).unwrap().is_file());
    assert_eq!(fs::read(&real).unwrap(), b"old");
    fs::remove_dir_all(d).unwrap();
}

/// One sample of this scene is thousands of glossy hits with 4096 light
/// samples each, minutes of work: a signal stops it within the sample,
/// and nothing is written.
#[test]
fn a_signal_stops_a_render_within_one_sample() {
    let d = dir("sample");
    fs::write(
        d.join("planes.obj"),
        "v -1e3 0 -1e3\nv 1e3 0 -1e3\nv 1e3 0 1e3\nv -1e3 0 1e3\n\
         v -1e3 1 -1e3\nv 1e3 1 -1e3\nv 1e3 1 1e3\nv -1e3 1 1e3\n\
         f 1 2 3\nf 1 3 4\nf 5 6 7\nf 5 7 8\n",
    )
    .unwrap();
    fs::write(
        d.join("s.toml"),
        "[camera]\neye = [0.0, 0.5, 0.0]\ntarget = [1.0, 0.2, 0.0]\nfov = 40.0\n\
         [[mesh]]\nfile = \"planes.obj\"\n\
         material = { name = \"g\", kd = [0.1, 0.1, 0.1], ks = [0.9, 0.9, 0.9], ns = 10.0 }\n\
         [[light]]\ntype = \"parallelogram\"\ncorner = [-0.5, 0.9, -0.5]\n\
         edge1 = [1.0, 0.0, 0.0]\nedge2 = [0.0, 0.0, 1.0]\n\
         colors = [[1.0, 1.0, 1.0], [1.0, 1.0, 1.0], [1.0, 1.0, 1.0], [1.0, 1.0, 1.0]]\n\
         [render]\nmax_depth = 64\nglossy_samples = 256\nlight_samples = 4096\n",
    )
    .unwrap();
    let out = d.join("out.png");
    let child = Command::new(env!("CARGO_BIN_EXE_rayterm"))
        .args(["render", "--size", "4x4", "--spp", "1", "--threads", "1"])
        .arg(d.join("s.toml"))
        .arg("-o")
        .arg(&out)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    // SAFETY: signalling the child we started.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGINT) }, 0);
    let start = Instant::now();
    let res = child.wait_with_output().unwrap();
    assert!(
        start.elapsed() < Duration::from_secs(5),
        "{:?}",
        start.elapsed()
    );
    assert_eq!(res.status.code(), Some(128 + libc::SIGINT));
    assert!(!out.exists());
    fs::remove_dir_all(d).unwrap();
}

/// Frames that memory cannot hold are refused up front by the benchmarks
/// too (as by `render`), with what they would need; nothing aborts.
#[test]
fn films_too_large_for_memory_are_refused_by_every_command() {
    let available = fs::read_to_string("/proc/meminfo")
        .ok()
        .and_then(|m| {
            let line = m
                .lines()
                .find(|l| l.starts_with("MemAvailable:"))?
                .to_owned();
            line.split_whitespace().nth(1)?.parse::<u64>().ok()
        })
        .map_or(u64::MAX, |kib| kib * 1024);
    let cases: [(&[&str], u64); 2] = [
        (
            &[
                "bench",
                "--size",
                "16384x16384",
                "--reps",
                "1",
                "--scene",
                "cornell",
            ],
            56 << 30,
        ),
        (
            &["bench", "tui", "cornell", "--terminal", "16384x16384"],
            150 << 30,
        ),
    ];
    for (args, need) in cases {
        if need < available {
            eprintln!("skipping {args:?}: this machine could hold it");
            continue;
        }
        let out = rayterm(args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(err.contains("film would need"), "{args:?}: {err}");
        assert!(
            !err.contains("panicked") && !err.contains("backtrace"),
            "{err}"
        );
    }
}

/// Standard output or error that cannot be written (a full disk behind a
/// redirection): a clear error and a failing status, never a panic; a
/// note that cannot be written is dropped and the work still done.
#[test]
fn a_stream_that_cannot_be_written_is_an_error_not_a_panic() {
    let d = dir("full-streams");
    let full = || {
        fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .unwrap()
    };
    let run = |args: &[&str], out: fs::File, err: Stdio| {
        Command::new(env!("CARGO_BIN_EXE_rayterm"))
            .args(args)
            .current_dir(&d)
            .stdout(out)
            .stderr(err)
            .output()
            .unwrap()
    };
    for args in [
        &["scenes"][..],
        &[
            "render", "cornell", "--size", "8x8", "--spp", "1", "-o", "a.png",
        ],
        &["stability", "--help"],
    ] {
        let out = run(args, full(), Stdio::piped());
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.contains("cannot write to standard output"),
            "{args:?}: {err}"
        );
        assert!(!err.contains("panicked"), "{err}");
    }
    // Standard error full: the summary still reaches standard output.
    let out = Command::new(env!("CARGO_BIN_EXE_rayterm"))
        .args([
            "render", "cornell", "--size", "8x8", "--spp", "1", "-o", "b.png",
        ])
        .current_dir(&d)
        .stderr(full())
        .output()
        .unwrap();
    assert!(out.status.success(), "{out:?}");
    assert!(String::from_utf8_lossy(&out.stdout).contains("-> b.png"));
    assert!(d.join("b.png").is_file());
    fs::remove_dir_all(d).unwrap();
}

/// `-o /dev/stdout`: the stream holds the image and nothing else; the
/// summary goes to standard error.
#[test]
fn an_image_on_standard_output_is_not_followed_by_the_summary() {
    let out = rayterm(&[
        "render",
        "cornell",
        "--size",
        "8x8",
        "--spp",
        "1",
        "-o",
        "/dev/stdout",
    ]);
    assert!(out.status.success(), "{out:?}");
    let png = &out.stdout;
    assert!(
        png.starts_with(b"\x89PNG"),
        "{:?}",
        &png[..8.min(png.len())]
    );
    assert!(
        png.ends_with(b"IEND\xaeB`\x82"),
        "{:?}",
        &png[png.len().saturating_sub(16)..]
    );
    assert!(String::from_utf8_lossy(&out.stderr).contains("-> /dev/stdout"));
}

/// A scene path that is not UTF-8 is refused naming it, for a command and
/// for the TUI's shorthand alike.
#[test]
fn a_scene_path_that_is_not_utf8_is_named_in_the_error() {
    use std::os::unix::ffi::OsStrExt;
    let name = std::ffi::OsStr::from_bytes(b"caf\xe9.obj");
    for args in [vec!["render".as_ref(), name], vec![name]] {
        let out = Command::new(env!("CARGO_BIN_EXE_rayterm"))
            .args(&args)
            .stdin(Stdio::null())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{err}");
        assert!(err.contains("caf\u{fffd}.obj is not UTF-8 text"), "{err}");
    }
}

/// `-o /dev/stdout` with standard output redirected to a file writes the
/// image into it (it neither refuses nor replaces the link with a file),
/// and a descriptor that cannot take it is named.
#[test]
fn an_image_to_a_descriptor_goes_where_the_descriptor_points() {
    let d = dir("descriptor");
    let file = d.join("redirected.png");
    let args = ["render", "cornell", "--size", "8x8", "--spp", "1", "-o"];
    for name in ["/dev/stdout", "/dev/fd/1", "/proc/self/fd/1"] {
        let out = Command::new(env!("CARGO_BIN_EXE_rayterm"))
            .args(args)
            .arg(name)
            .stdout(fs::File::create(&file).unwrap())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{name}: {err}");
        let png = fs::read(&file).unwrap();
        assert!(
            png.starts_with(b"\x89PNG"),
            "{name}: {:?}",
            &png[..png.len().min(8)]
        );
        assert!(err.contains(&format!("-> {name}")), "{err}");
    }
    assert_eq!(files(&d), ["redirected.png"]);
    assert!(fs::symlink_metadata("/dev/stdout").is_ok_and(|m| m.file_type().is_symlink()));
    let out = Command::new(env!("CARGO_BIN_EXE_rayterm"))
        .args(args)
        .arg("/dev/stdin")
        .stdin(fs::File::open(&file).unwrap())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(
        err.contains("/dev/stdin: descriptor 0 is open for reading only"),
        "{err}"
    );
    fs::remove_dir_all(d).unwrap();
}

/// A temporary file a killed render left under this process's id (a
/// container's PID 1 again) or a dead one's never makes a write fail, and
/// goes; a name too long to have a temporary beside it is no reason to
/// fail after the render.
#[test]
fn stale_temporary_files_and_long_names_do_not_fail_the_write() {
    let d = dir("stale");
    let out = d.join("x.png");
    for stale in [
        ".x.png.1.tmp",
        ".x.png.2147483646.tmp",
        ".x.png.2147483646-00c0ffee.tmp",
    ] {
        fs::write(d.join(stale), b"left by a killed render").unwrap();
    }
    let o = out.display().to_string();
    let r = rayterm(&["render", "cornell", "--size", "8x8", "--spp", "1", "-o", &o]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    // PID 1 lives (init): its file stays unless rayterm is PID 1 itself.
    let left = files(&d);
    assert!(
        left == ["x.png"] || left == [".x.png.1.tmp", "x.png"],
        "{left:?}"
    );
    let long = d.join("y".repeat(250) + ".png");
    let l = long.display().to_string();
    let r = rayterm(&["render", "cornell", "--size", "8x8", "--spp", "1", "-o", &l]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(fs::read(&long).unwrap().starts_with(b"\x89PNG"));
    fs::remove_dir_all(d).unwrap();
}
