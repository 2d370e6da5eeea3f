//! `--graphics` in a pseudo-terminal that never answers a query: auto
//! falls back to block symbols and says why; a protocol named on the
//! command line is used anyway, and the images go with the TUI on `q`.

use std::time::{Duration, Instant};

#[path = "common/pty.rs"]
mod pty;

const PATIENCE: Duration = Duration::from_secs(60);

fn run(args: &[&str], wait_for: &[u8]) -> (Option<std::process::ExitStatus>, Vec<u8>) {
    let dir = std::env::temp_dir();
    pty::run_tui(&dir, args, (120, 40), wait_for, b"q", PATIENCE)
}

fn contains(out: &[u8], needle: &[u8]) -> bool {
    out.windows(needle.len()).any(|w| w == needle)
}

#[test]
fn auto_falls_back_to_symbols_when_nothing_answers() {
    let start = Instant::now();
    let (status, out) = run(&["cornell"], b"the terminal answered no query");
    eprintln!("fallback seen after {:?}", start.elapsed());
    assert!(
        contains(&out, b"block symbols: the terminal answered no query"),
        "{}",
        String::from_utf8_lossy(&out)
    );
    // The queries went out, and no image followed them.
    assert!(contains(&out, b"\x1b_Gi=31,s=1,v=1,a=q"));
    assert!(!contains(&out, b"\x1bP0;1;0q") && !contains(&out, b"\x1b_Ga=T"));
    assert_eq!(status.map(|s| s.code()), Some(Some(0)));
    assert!(contains(&out, b"\x1b[?1049l"), "the screen is restored");
}

#[test]
fn a_protocol_named_is_used_and_its_images_go_on_quitting() {
    // Sixel: images of the bands, cells of an assumed size.
    let (status, out) = run(&["cornell", "--graphics", "sixel"], b"\x1bP0;1;0q");
    assert!(contains(&out, b"\x1bP0;1;0q\"1;1;"), "no sixel image");
    assert!(contains(&out, b"cells 8x16 px (assumed"));
    assert_eq!(status.map(|s| s.code()), Some(Some(0)));
    // Kitty: its images outlive the text, so they are deleted on leaving.
    let (status, out) = run(&["cornell", "--graphics", "kitty"], b"\x1b_Ga=T");
    assert!(contains(&out, b"\x1b_Ga=T,f=24,o=z"), "no kitty image");
    let leave = out
        .windows(8)
        .rposition(|w| w == b"\x1b[?1049l")
        .expect("the screen is restored");
    assert!(
        contains(&out[..leave], b"\x1b_Ga=d,d=I"),
        "the images are deleted before leaving"
    );
    assert_eq!(status.map(|s| s.code()), Some(Some(0)));
}
