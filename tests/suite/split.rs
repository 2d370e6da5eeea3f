//! Split renders: parts of a render's samples merge into exactly the image
//! one render makes; mismatched, overlapping, missing and damaged parts are
//! refused with a message naming them; a checkpoint resumes into the render
//! that was never interrupted; the commands of docs/split-renders.md (GNU
//! parallel, a checkpoint) and the Slurm scripts of `examples/slurm` run as written.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};
use std::time::{Duration, Instant};

const BIN: &str = env!("CARGO_BIN_EXE_rayterm");
const SCENE: [&str; 3] = ["cornell-area", "--size", "40x28"];

fn dir(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("rayterm-split-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

fn rayterm(d: &Path, args: &[&str]) -> Output {
    Command::new(BIN)
        .args(args)
        .current_dir(d)
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

fn ok(d: &Path, args: &[&str]) -> String {
    let out = rayterm(d, args);
    assert!(
        out.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The one-line error of a command that must fail, having written nothing
/// to `output`.
fn refused(d: &Path, args: &[&str], output: &str) -> String {
    let out = rayterm(d, args);
    let err = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!out.status.success(), "{args:?} succeeded");
    assert!(!err.contains("panicked"), "{args:?}: {err}");
    assert!(!d.join(output).exists(), "{args:?} wrote {output}");
    err
}

/// Renders and returns the summary line.
fn render(d: &Path, extra: &[&str], out: &str) -> String {
    let mut args = vec!["render"];
    args.extend(SCENE);
    args.extend(extra);
    args.extend(["-o", out]);
    ok(d, &args)
}

/// The `error 1.234%` a summary line reports.
fn error_of(line: &str) -> &str {
    let at = line.find("error ").expect("an error figure");
    line[at..].split([',', ' ']).nth(1).unwrap()
}

fn bytes(d: &Path, f: &str) -> Vec<u8> {
    std::fs::read(d.join(f)).unwrap()
}

/// Sample ranges that split 0..`total` into `n` uneven parts.
fn uneven(total: u32, n: u32) -> Vec<String> {
    let cuts: Vec<u32> = (1..n).map(|i| i * i * (total - n) / (n * n) + i).collect();
    let mut at = 0;
    let mut out = Vec::new();
    for c in cuts.into_iter().chain([total]) {
        if c > at {
            out.push(format!("{at}..{c}"));
            at = c;
        }
    }
    assert_eq!(out.len(), n as usize, "{out:?}");
    out
}

#[test]
fn merged_parts_equal_one_render_to_the_byte() {
    let d = dir("exact");
    let spp = 37;
    let single = render(&d, &["--spp", &spp.to_string()], "single.png");
    render(&d, &["--spp", &spp.to_string()], "single.exr");
    let (png, exr) = (bytes(&d, "single.png"), bytes(&d, "single.exr"));
    for n in [1, 2, 4, 7] {
        let ranges = uneven(spp, n);
        let mut parts = Vec::new();
        for (i, r) in ranges.iter().enumerate() {
            let name = format!("p{n}-{i}.exr");
            render(&d, &["--samples", r], &name);
            parts.push(name);
        }
        // Any order: reversed, and the first part moved to the end.
        parts.reverse();
        parts.rotate_left(1);
        for out in ["merged.png", "merged.exr"] {
            let mut args = vec!["merge"];
            args.extend(parts.iter().map(String::as_str));
            args.extend(["-o", out]);
            let line = ok(&d, &args);
            assert!(line.contains(&format!("{spp} spp")), "{line}");
            // The merge measures the error band by band: the render's own.
            assert_eq!(error_of(&line), error_of(&single), "{line}");
        }
        assert!(bytes(&d, "merged.png") == png, "{n} parts: the PNG differs");
        assert!(bytes(&d, "merged.exr") == exr, "{n} parts: the EXR differs");
    }
    // --part K/N splits the scene's or --spp's samples the same way.
    for k in 1..=3 {
        render(
            &d,
            &["--spp", &spp.to_string(), "--part", &format!("{k}/3")],
            &format!("k{k}.exr"),
        );
    }
    ok(&d, &["merge", "k2.exr", "k3.exr", "k1.exr", "-o", "k.png"]);
    assert!(bytes(&d, "k.png") == png, "--part: the PNG differs");
    std::fs::remove_dir_all(d).unwrap();
}

#[test]
fn parts_of_other_renders_overlaps_and_gaps_are_refused() {
    let d = dir("refused");
    render(&d, &["--spp", "8", "--part", "1/2"], "a1.exr");
    render(&d, &["--spp", "8", "--part", "2/2"], "a2.exr");
    render(&d, &["--samples", "0..4", "--seed", "9"], "seed.exr");
    ok(
        &d,
        &[
            "render",
            "cornell-area",
            "--size",
            "40x20",
            "--samples",
            "4..8",
            "-o",
            "size.exr",
        ],
    );
    ok(
        &d,
        &[
            "render",
            "cornell",
            "--size",
            "40x28",
            "--samples",
            "4..8",
            "-o",
            "scene.exr",
        ],
    );
    render(&d, &["--samples", "2..6"], "over.exr");
    render(&d, &["--spp", "16", "--part", "2/2"], "other-total.exr");
    for (part, says) in [
        ("seed.exr", "differ in seed: 9 against 1"),
        ("size.exr", "differ in size: 40x20 against 40x28"),
        ("scene.exr", "differ in scene"),
        ("over.exr", "overlap"),
        ("other-total.exr", "is a part of 16 samples"),
        ("a1.exr", "a1.exr is given twice"),
        ("./a1.exr", "is given twice"),
    ] {
        let err = refused(&d, &["merge", "a1.exr", part, "-o", "m.png"], "m.png");
        let named = part.trim_start_matches("./");
        assert!(err.contains(says) && err.contains(named), "{part}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{err}");
    }
    let err = refused(&d, &["merge", "a2.exr", "-o", "m.png"], "m.png");
    assert!(
        err.contains("part 1/2 is missing (samples 0..4 of 0..8)")
            && err
                .contains("rayterm render cornell-area --size 40x28 --spp 8 --part 1/2 -o a1.exr")
            && err.contains("--allow-missing"),
        "{err}"
    );
    let out = rayterm(&d, &["merge", "a2.exr", "--allow-missing", "-o", "m.png"]);
    assert!(out.status.success() && d.join("m.png").exists());
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("the image has 4 of 8 spp"), "{err}");
    // The output may not replace a part.
    let err = refused(&d, &["merge", "a1.exr", "a2.exr", "-o", "a1.exr"], "none");
    assert!(err.contains("is an input"), "{err}");
    // Bad ranges and parts.
    for (args, says) in [
        (&["--part", "0/4"][..], "K must be from 1 to N"),
        (&["--part", "5/4"], "K must be from 1 to N"),
        (&["--samples", "5..3"], "is empty"),
        (
            &["--samples", "0..4294967295"],
            "not a whole number from 0 to",
        ),
        (&["--spp", "4", "--part", "5/8"], "has none"),
    ] {
        let mut all = vec!["render"];
        all.extend(SCENE);
        all.extend(args);
        all.extend(["-o", "x.exr"]);
        let err = refused(&d, &all, "x.exr");
        assert!(err.contains(says), "{args:?}: {err}");
    }
    let err = refused(
        &d,
        &["render", "cornell-area", "--samples", "0..2", "-o", "x.png"],
        "x.png",
    );
    assert!(err.contains("partial film"), "{err}");
    std::fs::remove_dir_all(d).unwrap();
}

#[test]
fn words_every_pixel_shares_are_stored_once() {
    let d = dir("shared");
    // One sample a pixel: the counts, the statistics of more samples and
    // the colour sums' top words are the same in every pixel.
    render(&d, &["--samples", "3..4"], "one.exr");
    render(&d, &["--samples", "0..16"], "block.exr");
    let per_pixel = |f: &str| bytes(&d, f).len() as f64 / (40.0 * 28.0);
    assert!(per_pixel("one.exr") < 80.0, "{}", per_pixel("one.exr"));
    assert!(per_pixel("block.exr") < 152.0, "{}", per_pixel("block.exr"));
    let text = String::from_utf8_lossy(&bytes(&d, "one.exr")).into_owned();
    for shared in ["n=1 ", "blocks=0 ", "m2.lo=0 ", "tail.n=0 "] {
        assert!(text.contains(shared), "{shared}");
    }
    render(&d, &["--samples", "0..3"], "a.exr");
    render(&d, &["--samples", "4..16"], "b.exr");
    render(&d, &["--spp", "16"], "whole.png");
    ok(&d, &["merge", "b.exr", "one.exr", "a.exr", "-o", "m.png"]);
    assert!(bytes(&d, "m.png") == bytes(&d, "whole.png"));
    std::fs::remove_dir_all(d).unwrap();
}

#[test]
fn damaged_parts_are_refused_naming_the_file() {
    let d = dir("damaged");
    render(&d, &["--samples", "0..4"], "a.exr");
    render(&d, &["--samples", "4..8"], "b.exr");
    render(&d, &["--spp", "8"], "image.exr");
    let whole = bytes(&d, "b.exr");
    std::fs::write(d.join("short.exr"), &whole[..whole.len() / 2]).unwrap();
    std::fs::write(d.join("header.exr"), &whole[..200]).unwrap();
    let mut flipped = whole.clone();
    let at = whole.len() * 3 / 4;
    for b in &mut flipped[at..at + 64] {
        *b ^= 0x5a;
    }
    std::fs::write(d.join("flipped.exr"), &flipped).unwrap();
    std::fs::write(d.join("empty.exr"), b"").unwrap();
    // A valid OpenEXR image that is not a partial film.
    for bad in [
        "short.exr",
        "header.exr",
        "flipped.exr",
        "empty.exr",
        "image.exr",
    ] {
        let err = refused(&d, &["merge", "a.exr", bad, "-o", "m.png"], "m.png");
        assert!(err.contains(bad), "{bad}: {err}");
        assert_eq!(err.trim().lines().count(), 1, "{bad}: {err}");
        let mut args = vec!["render"];
        args.extend(SCENE);
        args.extend(["--spp", "12", "--resume", bad, "-o", "r.png"]);
        let err = refused(&d, &args, "r.png");
        assert!(err.contains(bad), "{bad}: {err}");
    }
    // A header claiming more pixels than any render writes: refused for
    // that, the file named once.
    let mut huge = whole.clone();
    for name in ["dataWindow\0box2i\0", "displayWindow\0box2i\0"] {
        let at = whole
            .windows(name.len())
            .position(|w| w == name.as_bytes())
            .unwrap_or_else(|| panic!("{name:?} is not in the file"))
            + name.len()
            + 4;
        for (k, v) in [0i32, 0, 19999, 19999].into_iter().enumerate() {
            huge[at + 4 * k..at + 4 * k + 4].copy_from_slice(&v.to_le_bytes());
        }
    }
    std::fs::write(d.join("huge.exr"), &huge).unwrap();
    let err = refused(&d, &["merge", "a.exr", "huge.exr", "-o", "m.png"], "m.png");
    assert!(
        err.contains("huge.exr: 20000x20000 pixels") && err.matches("huge.exr").count() == 1,
        "{err}"
    );
    // An attribute changed in place, the file's structure kept: the count
    // every pixel shares, the seed.
    for (from, to) in [("n=4 ", "n=3 "), ("rayterm.seed", "rayterm.sees")] {
        let at = whole
            .windows(from.len())
            .position(|w| w == from.as_bytes())
            .unwrap_or_else(|| panic!("{from:?} is not in the file"));
        let mut edited = whole.clone();
        edited[at..at + to.len()].copy_from_slice(to.as_bytes());
        std::fs::write(d.join("edited.exr"), &edited).unwrap();
        let err = refused(
            &d,
            &["merge", "a.exr", "edited.exr", "-o", "m.png"],
            "m.png",
        );
        assert!(err.contains("edited.exr"), "{to}: {err}");
    }
    // A channel name turned into an escape sequence: the file is damaged,
    // and resealed, it is no partial film; the name never reaches the
    // terminal as it is.
    let name = b"block_mean.lo";
    let at = whole
        .windows(name.len())
        .position(|w| w == name)
        .expect("a block_mean.lo channel");
    let mut escaped = whole.clone();
    escaped[at..at + 4].copy_from_slice(b"\x1b[2J");
    std::fs::write(d.join("escaped.exr"), &escaped).unwrap();
    let err = refused(
        &d,
        &["merge", "a.exr", "escaped.exr", "-o", "m.png"],
        "m.png",
    );
    assert!(
        err.contains("escaped.exr: its data do not match their checksum"),
        "{err}"
    );
    let seal = b"rayterm.checksum\0string\0\x08\0\0\0";
    let at = escaped
        .windows(seal.len())
        .position(|w| w == seal)
        .expect("a checksum attribute")
        + seal.len();
    escaped[at..at + 8].copy_from_slice(b"00000000");
    let crc = format!("{:08x}", crc32fast::hash(&escaped));
    escaped[at..at + 8].copy_from_slice(crc.as_bytes());
    std::fs::write(d.join("escaped.exr"), &escaped).unwrap();
    let err = refused(
        &d,
        &["merge", "a.exr", "escaped.exr", "-o", "m.png"],
        "m.png",
    );
    assert!(
        err.contains("\u{fffd}[2Jk_mean.lo is no word of a pixel"),
        "{err}"
    );
    assert!(!err.contains('\x1b'), "{err:?}");
    // One flipped bit anywhere, in a sum, a count, a mean or an attribute.
    for i in 1..24 {
        let mut one = whole.clone();
        let at = whole.len() * i / 24;
        one[at] ^= 1 << (i % 8);
        std::fs::write(d.join("bit.exr"), &one).unwrap();
        let err = refused(&d, &["merge", "a.exr", "bit.exr", "-o", "m.png"], "m.png");
        assert!(err.contains("bit.exr"), "byte {at}: {err}");
    }
    std::fs::remove_dir_all(d).unwrap();
}

#[test]
fn a_checkpoint_resumes_into_the_uninterrupted_render() {
    let d = dir("resume");
    render(&d, &["--spp", "9", "--checkpoint", "c.exr"], "first.png");
    // Rerunning without --resume would throw the checkpoint's work away.
    let kept = bytes(&d, "c.exr");
    let mut again = vec!["render"];
    again.extend(SCENE);
    again.extend(["--spp", "30", "--checkpoint", "c.exr", "-o", "again.png"]);
    let err = refused(&d, &again, "again.png");
    assert!(
        err.contains("c.exr already exists") && err.contains("--resume c.exr"),
        "{err}"
    );
    assert!(bytes(&d, "c.exr") == kept);
    render(&d, &["--spp", "30", "--resume", "c.exr"], "resumed.png");
    render(&d, &["--spp", "30"], "whole.png");
    assert!(bytes(&d, "resumed.png") == bytes(&d, "whole.png"));
    // A part continues from its own checkpoint too.
    render(
        &d,
        &["--samples", "5..11", "--checkpoint", "pc.exr"],
        "p-early.exr",
    );
    render(&d, &["--samples", "5..20", "--resume", "pc.exr"], "p.exr");
    render(&d, &["--samples", "0..5"], "p0.exr");
    render(&d, &["--samples", "20..30"], "p2.exr");
    ok(&d, &["merge", "p0.exr", "p.exr", "p2.exr", "-o", "m.png"]);
    assert!(bytes(&d, "m.png") == bytes(&d, "whole.png"));
    // --time is the whole render's: resuming a finished one adds nothing.
    let spp_of = |line: &str| {
        let head = line.split(" spp").next().unwrap();
        head.rsplit(' ').next().unwrap().parse::<u32>().unwrap()
    };
    let timed = |extra: &[&str]| {
        let mut args = vec!["render"];
        args.extend(SCENE);
        args.extend(["--time", "0.5"]);
        args.extend(extra);
        args.extend(["-o", "timed.png"]);
        spp_of(&ok(&d, &args))
    };
    let first = timed(&["--checkpoint", "t.exr"]);
    assert_eq!(timed(&["--resume", "t.exr"]), first);
    // Another render's checkpoint, one past the requested samples, one
    // that starts elsewhere, and a checkpoint that is the output.
    for (args, out, says) in [
        (
            &["--size", "40x28", "--seed", "3", "--resume", "c.exr"][..],
            "x.png",
            "differ in seed",
        ),
        (
            &["--size", "40x28", "--spp", "4", "--resume", "c.exr"],
            "x.png",
            "more than the 4 this render takes",
        ),
        (
            &["--size", "40x28", "--samples", "3..9", "--resume", "c.exr"],
            "x.exr",
            "starts at sample 3",
        ),
        (
            &["--spp", "4", "--checkpoint", "same.png"],
            "same.png",
            "is the output",
        ),
    ] {
        let mut all = vec!["render", "cornell-area"];
        all.extend(args);
        all.extend(["-o", out]);
        let err = refused(&d, &all, out);
        assert!(err.contains(says), "{args:?}: {err}");
    }
    std::fs::remove_dir_all(d).unwrap();
}

/// The film resumed from is never the output written over, and a signal
/// before the first pass ends leaves no checkpoint of no samples (which
/// could not be resumed).
#[test]
fn a_checkpoint_is_never_lost_or_left_empty() {
    let d = dir("keep");
    render(&d, &["--spp", "4", "--checkpoint", "c.exr"], "a.png");
    let before = std::fs::read(d.join("c.exr")).unwrap();
    let mut args = vec!["render"];
    args.extend(SCENE);
    args.extend(["--spp", "8", "--resume", "c.exr", "-o", "c.exr"]);
    let err = refused(&d, &args, "never.png");
    assert!(err.contains("c.exr is an input of this render"), "{err}");
    assert_eq!(std::fs::read(d.join("c.exr")).unwrap(), before);

    let child = Command::new(BIN)
        .args([
            "render",
            "cornell-area",
            "--size",
            "1280x960",
            "--spp",
            "256",
        ])
        .args([
            "--light-samples",
            "256",
            "--checkpoint",
            "early.exr",
            "-o",
            "never.png",
        ])
        .current_dir(&d)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    // Within the first pass, of 315 million shadow rays.
    std::thread::sleep(Duration::from_millis(500));
    // SAFETY: signalling the child this test started.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGINT) }, 0);
    let res = child.wait_with_output().unwrap();
    let err = String::from_utf8_lossy(&res.stderr);
    assert_eq!(res.status.code(), Some(128 + libc::SIGINT), "{err}");
    assert!(err.contains("interrupted: nothing written"), "{err}");
    assert!(!d.join("early.exr").exists());
    std::fs::remove_dir_all(d).unwrap();
}

/// SIGTERM during a render with --checkpoint leaves a checkpoint of whole
/// passes, and resuming it gives the render never interrupted.
#[test]
fn a_signal_writes_the_checkpoint() {
    let d = dir("signal");
    let mut child = Command::new(BIN)
        .args([
            "render",
            "cornell-area",
            "--size",
            "40x28",
            "--spp",
            "1000000",
        ])
        .args(["--checkpoint", "c.exr", "-o", "never.png"])
        .current_dir(&d)
        .stdin(Stdio::null())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    std::thread::sleep(Duration::from_millis(1500));
    // SAFETY: signalling the child this test started.
    assert_eq!(unsafe { libc::kill(child.id() as i32, libc::SIGTERM) }, 0);
    let deadline = Instant::now() + Duration::from_secs(60);
    let status = loop {
        if let Some(s) = child.try_wait().unwrap() {
            break s;
        }
        assert!(Instant::now() < deadline, "the render did not stop");
        std::thread::sleep(Duration::from_millis(20));
    };
    let mut err = String::new();
    std::io::Read::read_to_string(&mut child.stderr.take().unwrap(), &mut err).unwrap();
    assert_eq!(status.code(), Some(128 + libc::SIGTERM), "{err}");
    assert!(!d.join("never.png").exists());
    // "interrupted: c.exr holds samples 0..N; continue with --resume c.exr"
    let held = err
        .split("interrupted: c.exr holds samples 0..")
        .nth(1)
        .and_then(|s| s.split(';').next())
        .and_then(|n| n.parse::<u32>().ok())
        .unwrap_or_else(|| panic!("{err}"));
    let spp = (held + 3).to_string();
    render(&d, &["--spp", &spp, "--resume", "c.exr"], "resumed.png");
    render(&d, &["--spp", &spp], "whole.png");
    assert!(bytes(&d, "resumed.png") == bytes(&d, "whole.png"));
    std::fs::remove_dir_all(d).unwrap();
}

/// Runs `script` with bash in `d`, the built rayterm first on PATH.
fn bash(d: &Path, script: &str, env: &[(&str, &str)]) -> Output {
    let bin_dir = Path::new(BIN).parent().unwrap();
    let path = format!(
        "{}:{}",
        bin_dir.display(),
        std::env::var("PATH").unwrap_or_default()
    );
    Command::new("bash")
        .args(["-c", script])
        .current_dir(d)
        .env("PATH", path)
        .envs(env.iter().copied())
        .stdin(Stdio::null())
        .output()
        .unwrap()
}

/// The runnable (`bash`) blocks of docs/split-renders.md.
fn doc_split_commands() -> (String, Vec<String>) {
    let section = std::fs::read_to_string(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("docs/split-renders.md"),
    )
    .unwrap();
    let mut lines = Vec::new();
    let mut inside = false;
    for line in section.lines() {
        if line.starts_with("```") {
            inside = !inside && line.trim() == "```bash";
        } else if inside && !line.trim().is_empty() {
            lines.push(line.to_string());
        }
    }
    (section, lines)
}

/// The commands of docs/split-renders.md, run as written in a directory like
/// a fresh clone's: the GNU parallel parts merge into the single render's
/// image, and the checkpointed render resumed into the uninterrupted one.
#[test]
fn the_split_render_doc_commands_run_as_written() {
    let (section, lines) = doc_split_commands();
    assert!(section.contains("--sshlogin") && section.contains("examples/slurm/submit.sh"));
    let d = dir("split-doc");
    std::os::unix::fs::symlink(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("data"),
        d.join("data"),
    )
    .unwrap();
    if !bash(&d, "command -v parallel", &[]).status.success() {
        eprintln!("skipping: GNU parallel is not installed (.ci/run installs it)");
        return;
    }
    for line in &lines {
        let out = bash(&d, line, &[]);
        assert!(
            out.status.success(),
            "{line}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    // parallel -j2 rayterm render ARGS --part {}/8 -o part-{}.exr ::: ...
    let split = lines
        .iter()
        .find(|l| l.starts_with("parallel -j2 rayterm render") && l.contains(":::"))
        .expect("the GNU parallel line");
    let args = &split["parallel -j2 ".len()..split.find(" --part").unwrap()];
    let merged = lines
        .iter()
        .find(|l| l.starts_with("rayterm merge part-*.exr -o "))
        .expect("the merge line");
    let out = merged.rsplit(' ').next().unwrap();
    bash(&d, &format!("{args} -o single-{out}"), &[]);
    assert!(bytes(&d, out) == bytes(&d, &format!("single-{out}")));
    // The resumed render equals one never stopped.
    let resumed = lines
        .iter()
        .find(|l| l.contains("--resume"))
        .expect("the resume line");
    let words: Vec<&str> = resumed.split_whitespace().collect();
    let mut whole = Vec::new();
    let mut i = 0;
    while i < words.len() {
        match words[i] {
            "--resume" | "--checkpoint" => i += 2,
            "-o" => {
                whole.extend(["-o", "whole.png"]);
                i += 2;
            }
            w => {
                whole.push(w);
                i += 1;
            }
        }
    }
    let out = bash(&d, &whole.join(" "), &[]);
    assert!(out.status.success(), "{whole:?}");
    let target = words[words.iter().position(|w| *w == "-o").unwrap() + 1];
    assert!(bytes(&d, target) == bytes(&d, "whole.png"));
    // The staged merge gives the merge's image.
    assert!(lines.iter().any(|l| l.contains("--partial")));
    assert!(bytes(&d, "staged.png") == bytes(&d, "out.png"));
    std::fs::remove_dir_all(d).unwrap();
}

/// The Slurm scripts: valid bash; submit.sh queues the array and a merge
/// that depends on it; the array's and the merge's command lines, run here
/// with the array variables set, make the single render's image.
#[test]
fn the_slurm_scripts_run_their_commands() {
    let d = dir("slurm");
    let ex = Path::new(env!("CARGO_MANIFEST_DIR")).join("examples/slurm");
    let script = |name: &str| ex.join(name).display().to_string();
    for s in ["render.sbatch", "merge.sbatch", "submit.sh"] {
        let out = bash(&d, &format!("bash -n {}", script(s)), &[]);
        assert!(
            out.status.success(),
            "{s}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    let text = std::fs::read_to_string(ex.join("render.sbatch")).unwrap();
    assert!(text.contains("#SBATCH --array=1-"));
    // sbatch stands in: records its arguments, answers a job id.
    std::fs::write(
        d.join("sbatch"),
        "#!/bin/sh\necho \"$@\" >> sbatch.log\necho 4242\n",
    )
    .unwrap();
    let out = bash(
        &d,
        &format!(
            "chmod +x sbatch && PATH=$PWD:$PATH {} 4",
            script("submit.sh")
        ),
        &[],
    );
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let log = std::fs::read_to_string(d.join("sbatch.log")).unwrap();
    assert!(
        log.contains("--array=1-4")
            && log.contains("--cpus-per-task=2")
            && log.contains("--dependency=afterany:4242"),
        "{log}"
    );
    // The memory asked for is the dry run's estimate of the default
    // 1920x1080 checkpointed part, and a quarter more: some 900 MB.
    let mem: u64 = log
        .split("--mem=")
        .nth(1)
        .and_then(|m| m.split('M').next())
        .and_then(|m| m.parse().ok())
        .unwrap_or_else(|| panic!("{log}"));
    assert!((600..2000).contains(&mem), "{log}");
    assert!(!d.join("estimate.exr").exists() && !d.join("estimate.ckpt.exr").exists());
    let env = [
        ("SCENE", "cornell-area"),
        ("SIZE", "40x28"),
        ("SPP", "12"),
        ("SLURM_ARRAY_TASK_COUNT", "4"),
        ("OUTPUT", "out.png"),
    ];
    for k in ["3", "1", "4", "2"] {
        let mut env = env.to_vec();
        env.push(("SLURM_ARRAY_TASK_ID", k));
        let out = bash(&d, &script("render.sbatch"), &env);
        assert!(
            out.status.success(),
            "task {k}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    }
    // Task 2 preempted and queued again on its own (`sbatch --array=2`,
    // an array of one; submit.sh's PARTS says how many there are): it
    // continues from its checkpoint (samples 3..5 of its 3..6).
    std::fs::remove_file(d.join("parts/part-2.exr")).unwrap();
    let mut ckpt = vec!["render", "cornell-area", "--size", "40x28"];
    ckpt.extend(["--samples", "3..5", "-o", "parts/part-2.ckpt.exr"]);
    ok(&d, &ckpt);
    let mut requeued: Vec<_> = env
        .iter()
        .map(|&(k, v)| {
            (
                k,
                if k == "SLURM_ARRAY_TASK_COUNT" {
                    "1"
                } else {
                    v
                },
            )
        })
        .collect();
    requeued.extend([("SLURM_ARRAY_TASK_ID", "2"), ("PARTS", "4")]);
    let out = bash(&d, &script("render.sbatch"), &requeued);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "requeued task: {err}");
    assert!(
        !d.join("parts/part-2.ckpt.exr").exists() && d.join("parts/part-2.exr").exists(),
        "{err}"
    );
    // A part that failed: the merge names it and the command that
    // renders it, writes a preview of the others, and fails.
    std::fs::rename(d.join("parts/part-3.exr"), d.join("part-3.away")).unwrap();
    let out = bash(&d, &script("merge.sbatch"), &env);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("part 3/4 is missing (samples 6..9 of 0..12)")
            && err.contains("--part 3/4 -o parts/part-3.exr"),
        "{err}"
    );
    assert!(d.join("out.preview.png").exists() && !d.join("out.png").exists());
    std::fs::rename(d.join("part-3.away"), d.join("parts/part-3.exr")).unwrap();
    let out = bash(&d, &script("merge.sbatch"), &env);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    render(&d, &["--spp", "12"], "single.png");
    assert!(bytes(&d, "out.png") == bytes(&d, "single.png"));
    std::fs::remove_dir_all(d).unwrap();
}

/// Two renders of one checkpoint would write over each other's every few
/// seconds: the second is refused at once, resuming or not; a render
/// killed outright leaves a claim nothing holds, which the next one takes,
/// and a render that ends leaves no lock file behind.
#[test]
fn a_checkpoint_is_claimed_by_one_render_at_a_time() {
    let d = dir("claim");
    let long = |signal: i32| {
        let mut child = Command::new(BIN)
            .args([
                "render",
                "cornell-area",
                "--size",
                "40x28",
                "--spp",
                "1000000",
            ])
            .args(["--checkpoint", "c.exr", "-o", "never.png"])
            .current_dir(&d)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        let start = Instant::now();
        while !d.join(".c.exr.lock").exists() {
            assert!(start.elapsed() < Duration::from_secs(30), "no claim");
            std::thread::sleep(Duration::from_millis(20));
        }
        let mut args = vec!["render"];
        args.extend(SCENE);
        for extra in [
            &["--checkpoint", "c.exr"][..],
            &["--resume", "c.exr", "--checkpoint", "c.exr"],
        ] {
            let mut args = args.clone();
            args.extend(["--spp", "2"]);
            args.extend(extra);
            args.extend(["-o", "second.png"]);
            let started = Instant::now();
            let err = refused(&d, &args, "second.png");
            assert!(started.elapsed() < Duration::from_secs(10), "{err}");
            assert!(
                err.contains("c.exr is being written by another render (it holds .c.exr.lock)"),
                "{err}"
            );
        }
        std::thread::sleep(Duration::from_millis(300));
        // SAFETY: signalling the child this test started.
        assert_eq!(unsafe { libc::kill(child.id() as i32, signal) }, 0);
        child.wait().unwrap();
    };
    long(libc::SIGTERM);
    assert!(!d.join(".c.exr.lock").exists());
    assert!(d.join("c.exr").exists());
    std::fs::remove_file(d.join("c.exr")).unwrap();
    // Killed outright: its first checkpoint, written after the first
    // pass, keeps its work.
    long(libc::SIGKILL);
    assert!(d.join(".c.exr.lock").exists());
    assert!(d.join("c.exr").exists());
    std::fs::remove_file(d.join("c.exr")).unwrap();
    render(&d, &["--spp", "2", "--checkpoint", "c.exr"], "after.png");
    let mut left: Vec<_> = std::fs::read_dir(&d)
        .unwrap()
        .map(|e| e.unwrap().file_name().into_string().unwrap())
        .collect();
    left.sort();
    assert_eq!(left, ["after.png", "c.exr"]);
    std::fs::remove_dir_all(d).unwrap();
}

/// A part that is missing, or not a file, is named as every other file a
/// command cannot read is.
#[test]
fn a_part_that_cannot_be_read_is_named() {
    let d = dir("unreadable");
    std::fs::create_dir(d.join("folder.exr")).unwrap();
    for (part, why) in [
        ("gone.exr", "cannot read gone.exr: not found"),
        ("folder.exr", "cannot read folder.exr: not a regular file"),
    ] {
        let err = refused(&d, &["merge", part, "-o", "m.png"], "m.png");
        assert!(err.contains(why), "{err}");
    }
    std::fs::remove_dir_all(d).unwrap();
}

/// What an older CPU's C library does for `powf`, `sincosf` and the rest:
/// glibc's plain variants in place of the FMA and AVX2 ones it picks here
/// (other C libraries ignore the variable).
const PLAIN_LIBM: (&str, &str) = (
    "GLIBC_TUNABLES",
    "glibc.cpu.hwcaps=-AVX2,-FMA,-FMA4,-AVX512F",
);

/// A farm of unlike x86-64 machines makes one image: every SIMD level this
/// CPU has renders every built-in scene to the same bytes, and parts
/// rendered each at another level, one with the plain C library maths,
/// merge into the single render byte for byte.
#[test]
fn parts_from_unlike_machines_merge_exactly() {
    use rayterm::bvh::Simd;
    let d = dir("machines");
    let levels = Simd::available();
    if !levels.contains(&Simd::Avx512) {
        eprintln!("note: this CPU has no AVX-512; the levels checked are {levels:?}");
    }
    let run = |args: &[&str], plain_libm: bool| {
        let mut c = Command::new(BIN);
        c.args(args).current_dir(&d).stdin(Stdio::null());
        if plain_libm {
            c.env(PLAIN_LIBM.0, PLAIN_LIBM.1);
        }
        let out = c.output().unwrap();
        assert!(
            out.status.success(),
            "{args:?}: {}",
            String::from_utf8_lossy(&out.stderr)
        );
    };
    for scene in [
        "cornell",
        "cornell-area",
        "cube-textured",
        "mirrors",
        "teapot",
        "env",
    ] {
        let base = [scene, "--size", "48x36", "--spp", "16"];
        let at = |extra: &[&str], out: &str, plain: bool| {
            run(
                &[&["render"], &base[..], extra, &["-o", out]].concat(),
                plain,
            )
        };
        at(&[], "single.exr", false);
        for l in &levels {
            at(&["--simd", l.name()], "level.exr", false);
            assert!(
                bytes(&d, "level.exr") == bytes(&d, "single.exr"),
                "{scene}: --simd {l} differs"
            );
        }
        // One part a level, and one more with the plain maths.
        let n = levels.len() + 1;
        let mut parts = Vec::new();
        for k in 1..=n {
            let (level, plain) = match levels.get(k - 1) {
                Some(l) => (*l, false),
                None => (Simd::Portable, true),
            };
            let part = format!("part-{k}.exr");
            let which = format!("{k}/{n}");
            at(&["--part", &which, "--simd", level.name()], &part, plain);
            parts.push(part);
        }
        let names: Vec<&str> = parts.iter().map(String::as_str).collect();
        run(
            &[&["merge"], &names[..], &["-o", "merged.exr"]].concat(),
            false,
        );
        assert!(
            bytes(&d, "merged.exr") == bytes(&d, "single.exr"),
            "{scene}: parts from unlike machines differ from the single render"
        );
    }
}
