//! Choices that stick: the TUI's colours, symbols and graphics from
//! `$XDG_CONFIG_HOME/rayterm/config.toml` (else `~/.config/rayterm/`), then
//! from `RAYTERM_COLOR`, `RAYTERM_SYMBOLS` and `RAYTERM_GRAPHICS`, each
//! overriding the one before; command-line options override both.

use std::path::{Path, PathBuf};

use anyhow::{anyhow, Context, Result};
use serde::Deserialize;

use super::color::ColorMode;
use super::graphics::symbols::SymbolsArg;
use super::graphics::GraphicsArg;
use crate::choice::{self, Choice};
use crate::words::{clip_quotes, quoted};

/// The defaults found; `None` where nothing was said.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub(crate) struct Defaults {
    pub(crate) color: Option<ColorMode>,
    pub(crate) symbols: Option<SymbolsArg>,
    pub(crate) graphics: Option<GraphicsArg>,
}

/// The file as written: values are checked as the command line checks them.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct File {
    color: Option<toml::Spanned<String>>,
    symbols: Option<toml::Spanned<String>>,
    graphics: Option<toml::Spanned<String>>,
}

/// The configuration file's path (which need not exist).
pub(crate) fn path(var: impl Fn(&str) -> Option<String>) -> Option<PathBuf> {
    let base = var("XDG_CONFIG_HOME")
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
        .or_else(|| var("HOME").map(|h| PathBuf::from(h).join(".config")))?;
    Some(base.join("rayterm").join("config.toml"))
}

/// The defaults from the file at `path` (if there is one) and the
/// environment (`var`); a bad file or variable is an error that names it
/// (and the file's line).
pub(crate) fn load(file: Option<&Path>, var: impl Fn(&str) -> Option<String>) -> Result<Defaults> {
    let mut d = match file {
        Some(path) => match std::fs::read_to_string(path) {
            Ok(text) => parse(path, &text)?,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Defaults::default(),
            Err(e) => return Err(e).with_context(|| format!("cannot read {}", path.display())),
        },
        None => Defaults::default(),
    };
    let from_env = |name: &str| var(name).filter(|v| !v.is_empty());
    if let Some(v) = from_env("RAYTERM_COLOR") {
        d.color = Some(value(&v).map_err(|e| anyhow!("RAYTERM_COLOR: {e}"))?);
    }
    if let Some(v) = from_env("RAYTERM_SYMBOLS") {
        d.symbols = Some(value(&v).map_err(|e| anyhow!("RAYTERM_SYMBOLS: {e}"))?);
    }
    if let Some(v) = from_env("RAYTERM_GRAPHICS") {
        d.graphics = Some(value(&v).map_err(|e| anyhow!("RAYTERM_GRAPHICS: {e}"))?);
    }
    Ok(d)
}

fn parse(path: &Path, text: &str) -> Result<Defaults> {
    let at = |offset: usize| {
        let line = text[..offset.min(text.len())].matches('\n').count() + 1;
        format!("{}:{line}", path.display())
    };
    let file: File = toml::from_str(text).map_err(|e| {
        let msg = clip_quotes(e.message().trim());
        match e.span() {
            Some(span) => anyhow!("{}: {msg}", at(span.start)),
            None => anyhow!("{}: {msg}", path.display()),
        }
    })?;
    fn field<T: Choice>(
        v: Option<toml::Spanned<String>>,
        at: impl Fn(usize) -> String,
    ) -> Result<Option<T>> {
        v.map(|v| value(v.get_ref()).map_err(|e| anyhow!("{}: {e}", at(v.span().start))))
            .transpose()
    }
    Ok(Defaults {
        color: field(file.color, at)?,
        symbols: field(file.symbols, at)?,
        graphics: field(file.graphics, at)?,
    })
}

/// A value as the command line takes it, or what the choices are.
fn value<T: Choice>(v: &str) -> Result<T, String> {
    choice::parse(v).ok_or_else(|| {
        format!(
            "\"{}\" is not one of {}",
            quoted(v),
            choice::names::<T>().join(", ")
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::tui::graphics::symbols::Symbols;

    fn env<'a>(pairs: &'a [(&'a str, &'a str)]) -> impl Fn(&str) -> Option<String> + 'a {
        move |k| {
            pairs
                .iter()
                .find(|(n, _)| *n == k)
                .map(|(_, v)| v.to_string())
        }
    }

    #[test]
    fn the_file_then_the_environment() {
        let dir = std::env::temp_dir().join(format!("rayterm-config-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let file = dir.join("config.toml");
        std::fs::write(&file, "# mine\ncolor = \"256\"\nsymbols = \"sextant\"\n").unwrap();
        let d = load(Some(&file), env(&[])).unwrap();
        assert_eq!(
            d,
            Defaults {
                color: Some(ColorMode::Palette256),
                symbols: Some(SymbolsArg::Set(Symbols::Sextant)),
                graphics: None,
            }
        );
        let d = load(
            Some(&file),
            env(&[
                ("RAYTERM_COLOR", "truecolor"),
                ("RAYTERM_GRAPHICS", "symbols"),
            ]),
        )
        .unwrap();
        assert_eq!(d.color, Some(ColorMode::Truecolor));
        assert_eq!(d.symbols, Some(SymbolsArg::Set(Symbols::Sextant)));
        assert_eq!(d.graphics, Some(GraphicsArg::Symbols));
        // A bad value: the file and its line, and the choices.
        std::fs::write(&file, "color = \"256\"\n\nsymbols = \"braille\"\n").unwrap();
        let e = load(Some(&file), env(&[])).unwrap_err().to_string();
        assert!(e.starts_with(&format!("{}:3: ", file.display())), "{e}");
        assert!(e.contains("auto, half, quad, sextant, octant"), "{e}");
        let d = load(None, env(&[("RAYTERM_SYMBOLS", "Auto")])).unwrap();
        assert_eq!(d.symbols, Some(SymbolsArg::Auto));
        // Bad TOML and an unknown key: named too.
        std::fs::write(&file, "color = 256 colours\n").unwrap();
        let e = load(Some(&file), env(&[])).unwrap_err().to_string();
        assert!(e.starts_with(&format!("{}:1: ", file.display())), "{e}");
        std::fs::write(&file, "\ncolour = \"16\"\n").unwrap();
        let e = load(Some(&file), env(&[])).unwrap_err().to_string();
        assert!(e.starts_with(&format!("{}:2: ", file.display())), "{e}");
        // A bad variable is named; no file is no error.
        let e = load(None, env(&[("RAYTERM_COLOR", "millions")]))
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("RAYTERM_COLOR: "), "{e}");
        assert_eq!(
            load(Some(&dir.join("none.toml")), env(&[])).unwrap(),
            Defaults::default()
        );
        std::fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn the_file_is_under_xdg_config_home_else_home() {
        assert_eq!(
            path(env(&[("XDG_CONFIG_HOME", "/x"), ("HOME", "/h")])),
            Some(PathBuf::from("/x/rayterm/config.toml"))
        );
        assert_eq!(
            path(env(&[("XDG_CONFIG_HOME", ""), ("HOME", "/h")])),
            Some(PathBuf::from("/h/.config/rayterm/config.toml"))
        );
    }
}
