//! Turntables: the camera orbits its target in N frames; frames rendered
//! one job each (`--frame K/N`) and joined by `rayterm animate` make the
//! very file `--turntable N` makes, GIF and APNG; bad requests are refused
//! by name with nothing written.

use std::path::Path;

use crate::files::{rayterm, Dir};

const SCENE: [&str; 5] = ["teapot", "--size", "40x30", "--spp", "2"];

fn ok(d: &Path, args: &[&str]) {
    let out = rayterm(d, args);
    assert!(out.ok(), "{args:?}: {}", out.stderr);
}

fn render(d: &Path, more: &[&str]) {
    ok(d, &[&["render"], &SCENE[..], more].concat());
}

/// The error a command must fail with, having left the folder as it was.
fn refused(d: &Path, args: &[&str]) -> String {
    let files = || -> Vec<_> {
        std::fs::read_dir(d)
            .unwrap()
            .map(|e| e.unwrap().path())
            .collect()
    };
    let before = files();
    let out = rayterm(d, args);
    assert!(!out.ok(), "{args:?} succeeded");
    assert!(!out.stderr.contains("panicked"), "{args:?}: {}", out.stderr);
    assert_eq!(before, files(), "{args:?} left files");
    out.stderr
}

#[test]
fn frames_rendered_apart_join_into_the_turntable_itself() {
    let dir = Dir::new("turntable-join");
    let d = dir.0.as_path();
    for ext in ["gif", "apng"] {
        render(d, &["--turntable", "4", "-o", &format!("whole.{ext}")]);
        let mut frames = Vec::new();
        for k in 1..=4 {
            let f = format!("f{k}.png");
            render(d, &["--frame", &format!("{k}/4"), "-o", &f]);
            frames.push(f);
        }
        let joined = format!("joined.{ext}");
        let names: Vec<&str> = frames.iter().map(String::as_str).collect();
        ok(d, &[&["animate"], &names[..], &["-o", &joined]].concat());
        let (a, b) = (
            std::fs::read(d.join(format!("whole.{ext}"))).unwrap(),
            std::fs::read(d.join(&joined)).unwrap(),
        );
        assert!(a == b, "{ext}: the joined frames differ from the turntable");
    }
    // Frame 1 is the scene's own view; the others turn away from it.
    render(d, &["-o", "plain.png"]);
    let read = |f: &str| std::fs::read(d.join(f)).unwrap();
    assert_eq!(read("plain.png"), read("f1.png"));
    assert_ne!(read("f1.png"), read("f2.png"));
    assert_ne!(read("f2.png"), read("f3.png"));
}

#[test]
fn the_apng_holds_every_frame_at_the_rate_asked() {
    let dir = Dir::new("turntable-apng");
    let d = dir.0.as_path();
    render(d, &["--turntable", "3", "--fps", "24", "-o", "spin.png"]);
    let bytes = std::fs::read(d.join("spin.png")).unwrap();
    let mut r = png::Decoder::new(std::io::Cursor::new(&bytes))
        .read_info()
        .unwrap();
    let ctl = r.info().animation_control.unwrap();
    assert_eq!((ctl.num_frames, ctl.num_plays), (3, 0));
    let mut buf = vec![0; r.output_buffer_size().unwrap()];
    let mut frames = Vec::new();
    for _ in 0..3 {
        r.next_frame(&mut buf).unwrap();
        let fc = r.info().frame_control.unwrap();
        assert_eq!(
            (fc.delay_num, fc.delay_den, fc.width, fc.height),
            (1, 24, 40, 30)
        );
        frames.push(buf.clone());
    }
    assert!(frames[0] != frames[1] && frames[1] != frames[2]);
}

#[test]
fn bad_requests_are_refused_by_name_and_leave_nothing() {
    let dir = Dir::new("turntable-bad");
    let d = dir.0.as_path();
    let render = |more: &[&str]| refused(d, &[&["render"], &SCENE[..], more].concat());
    let e = render(&["--turntable", "4", "-o", "spin.exr"]);
    assert!(e.contains("spin.exr") && e.contains(".gif"), "{e}");
    for bad in [
        ["--turntable", "1"],
        ["--frame", "0/4"],
        ["--frame", "5/4"],
        ["--fps", "10"],
    ] {
        let e = render(&[bad[0], bad[1], "-o", "x.png"]);
        assert!(e.contains(bad[0]), "{bad:?}: {e}");
    }
    let e = render(&["--turntable", "4", "--part", "1/2", "-o", "x.gif"]);
    assert!(e.contains("--part"), "{e}");
    // Frames of two sizes, a missing frame, a frame that is no PNG.
    ok(
        d,
        &[
            "render", "cornell", "--size", "8x8", "--spp", "1", "-o", "a.png",
        ],
    );
    ok(
        d,
        &[
            "render", "cornell", "--size", "8x6", "--spp", "1", "-o", "b.png",
        ],
    );
    std::fs::write(d.join("c.png"), b"not a picture").unwrap();
    let e = refused(d, &["animate", "a.png", "b.png", "-o", "x.gif"]);
    assert!(
        e.contains("b.png is 8x6") && e.contains("a.png is 8x8"),
        "{e}"
    );
    let e = refused(d, &["animate", "a.png", "gone.png", "-o", "x.gif"]);
    assert!(e.contains("gone.png"), "{e}");
    let e = refused(d, &["animate", "a.png", "c.png", "-o", "x.gif"]);
    assert!(e.contains("c.png"), "{e}");
    // A frame is never its own output.
    let e = refused(d, &["animate", "a.png", "a.png", "-o", "a.png"]);
    assert!(e.contains("a.png"), "{e}");
}

/// Parts of one frame merge into that frame; a part of another frame is
/// another render, refused by its content hash.
#[test]
fn parts_of_a_frame_merge_and_parts_of_two_frames_do_not() {
    let dir = Dir::new("turntable-parts");
    let d = dir.0.as_path();
    for (frame, part, out) in [
        ("2/4", "1/2", "a1.exr"),
        ("2/4", "2/2", "a2.exr"),
        ("3/4", "2/2", "b2.exr"),
    ] {
        render(d, &["--frame", frame, "--part", part, "-o", out]);
    }
    ok(d, &["merge", "a1.exr", "a2.exr", "-o", "merged.png"]);
    render(d, &["--frame", "2/4", "-o", "single.png"]);
    let read = |f: &str| std::fs::read(d.join(f)).unwrap();
    assert!(read("merged.png") == read("single.png"));
    let e = refused(d, &["merge", "a1.exr", "b2.exr", "-o", "mixed.png"]);
    assert!(e.contains("content hash"), "{e}");
}
