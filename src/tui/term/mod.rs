//! The terminal itself: what it sends (`input`: keys, mouse, answers),
//! what we send it (`screen`, a ratatui backend that writes only what
//! changed; `output`, which writes it as fast as the link absorbs, paced by
//! `pace`) and what it can do (`terminfo`).

pub mod detect;
pub mod input;
pub mod output;
pub mod pace;
pub mod screen;
pub mod terminfo;

use super::color::ColorMode;

/// Said in the status line when the colours may be fewer than the
/// terminal has: ssh does not pass `COLORTERM` on.
pub const SSH_HINT: &str =
    "256 colours: over SSH COLORTERM is not passed on; if your terminal has 24-bit colour, start with --color truecolor";

/// The colour mode the environment (`var` reads a variable) suggests:
/// `COLORTERM`, then the terminfo entry of `TERM` (`RGB`, `Tc`, or a
/// `-direct` name); with a hint when over SSH nothing said truecolor.
pub fn detect_colour(var: impl Fn(&str) -> Option<String>) -> (ColorMode, Option<&'static str>) {
    let colorterm = var("COLORTERM");
    let rgb = var("TERM")
        .is_some_and(|t| t.ends_with("-direct") || terminfo::truecolor(&t).unwrap_or(false));
    let mode = ColorMode::detect(colorterm.as_deref(), rgb);
    let ssh = ["SSH_CONNECTION", "SSH_CLIENT", "SSH_TTY"]
        .iter()
        .any(|v| var(v).is_some());
    let hint = (ssh && colorterm.is_none() && mode != ColorMode::Truecolor).then_some(SSH_HINT);
    (mode, hint)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env<'a>(pairs: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |k| {
            pairs
                .iter()
                .find(|(n, _)| *n == k)
                .map(|(_, v)| v.to_string())
        }
    }

    #[test]
    fn ssh_without_colorterm_gets_a_hint() {
        let ssh = [
            ("SSH_CONNECTION", "1.2.3.4 5 6.7.8.9 22"),
            ("TERM", "dumb-nowhere"),
        ];
        assert_eq!(
            detect_colour(env(&ssh)),
            (ColorMode::Palette256, Some(SSH_HINT))
        );
        let local = [("TERM", "dumb-nowhere")];
        assert_eq!(detect_colour(env(&local)), (ColorMode::Palette256, None));
        let told = [("SSH_TTY", "/dev/pts/1"), ("COLORTERM", "truecolor")];
        assert_eq!(detect_colour(env(&told)), (ColorMode::Truecolor, None));
        let direct = [("SSH_TTY", "/dev/pts/1"), ("TERM", "xterm-direct")];
        assert_eq!(detect_colour(env(&direct)), (ColorMode::Truecolor, None));
    }
}
