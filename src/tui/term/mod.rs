//! The terminal itself: what it sends (`input`: keys, mouse, answers),
//! what we send it (`screen`, a ratatui backend that writes only what
//! changed; `output`, which writes it as fast as the link absorbs, paced by
//! `pace`) and what it can do (`terminfo`).

pub(crate) mod detect;
pub(crate) mod glyphs;
pub(crate) mod input;
pub(crate) mod output;
pub(crate) mod pace;
pub(crate) mod screen;
pub(crate) mod terminfo;

use super::color::ColorMode;

/// The colour mode: what the terminal said (`answer`: XTGETTCAP or
/// DECRQSS), else what tmux knows of the terminal it runs in (`tmux_rgb`),
/// else the environment (`var` reads a variable): `COLORTERM`, then the
/// terminfo entry of `TERM` (`RGB`, `Tc`, or a `-direct` name). With fewer
/// than 24 bits, why, and how to ask for more, for the status line.
pub(crate) fn choose_colour(
    answer: Option<bool>,
    tmux_rgb: Option<bool>,
    var: impl Fn(&str) -> Option<String>,
) -> (ColorMode, Option<String>) {
    let said = answer.or(tmux_rgb);
    let colorterm = var("COLORTERM");
    let rgb = var("TERM")
        .is_some_and(|t| t.ends_with("-direct") || terminfo::truecolor(&t).unwrap_or(false));
    let mode = match said {
        Some(true) => ColorMode::Truecolor,
        Some(false) => ColorMode::Palette256,
        None => ColorMode::detect(colorterm.as_deref(), rgb),
    };
    if mode == ColorMode::Truecolor {
        return (mode, None);
    }
    let why = match (answer, tmux_rgb) {
        (Some(false), _) => "the terminal says it keeps no 24-bit colour",
        (None, Some(false)) => "tmux says its terminal has no RGB",
        _ if ["SSH_CONNECTION", "SSH_CLIENT", "SSH_TTY"]
            .iter()
            .any(|v| var(v).is_some()) =>
        {
            "no answer on 24-bit colour, and ssh does not pass COLORTERM on"
        }
        _ => "no answer on 24-bit colour, nor COLORTERM",
    };
    let hint = format!(
        "{}: {why}; for 24-bit: --color truecolor or RAYTERM_COLOR=truecolor",
        mode.name()
    );
    (mode, Some(hint))
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
    fn the_terminal_is_believed_before_the_environment() {
        let ssh = [
            ("SSH_CONNECTION", "1.2.3.4 5 6.7.8.9 22"),
            ("TERM", "dumb-nowhere"),
        ];
        // Asked over ssh, the terminal says it has 24-bit colour.
        assert_eq!(
            choose_colour(Some(true), None, env(&ssh)),
            (ColorMode::Truecolor, None)
        );
        // No answer: the environment decides, and the hint says why.
        let (mode, hint) = choose_colour(None, None, env(&ssh));
        assert_eq!(mode, ColorMode::Palette256);
        assert!(hint.unwrap().contains("ssh does not pass COLORTERM"));
        let local = [("TERM", "dumb-nowhere")];
        let (mode, hint) = choose_colour(None, None, env(&local));
        assert_eq!(mode, ColorMode::Palette256);
        assert!(hint.unwrap().contains("nor COLORTERM"));
        let told = [("SSH_TTY", "/dev/pts/1"), ("COLORTERM", "truecolor")];
        assert_eq!(
            choose_colour(None, None, env(&told)),
            (ColorMode::Truecolor, None)
        );
        let direct = [("SSH_TTY", "/dev/pts/1"), ("TERM", "xterm-direct")];
        assert_eq!(
            choose_colour(None, None, env(&direct)).0,
            ColorMode::Truecolor
        );
        // A terminal that answers no wins over COLORTERM; inside tmux, tmux
        // knows its terminal.
        let (mode, hint) = choose_colour(Some(false), Some(true), env(&told));
        assert_eq!(mode, ColorMode::Palette256);
        assert!(hint.unwrap().contains("the terminal says"));
        assert_eq!(
            choose_colour(None, Some(true), env(&local)).0,
            ColorMode::Truecolor
        );
        assert_eq!(
            choose_colour(None, Some(false), env(&told)).0,
            ColorMode::Palette256
        );
    }
}
