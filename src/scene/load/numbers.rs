//! Numbers in text files (OBJ, MTL): read in f64, and accepted only where
//! the f32 the renderer stores can hold them. Huge but representable values
//! load with one warning per file.

use crate::words::quoted;
use std::path::Path;

/// Coordinates beyond this are legal but almost certainly a mistake.
pub const ABSURD: f64 = 1e18;

/// Why a value cannot be used, or `None` when it can: NaN, infinite, or
/// beyond the range of f32.
pub(crate) fn unusable(x: f64) -> Option<&'static str> {
    if !x.is_finite() {
        Some("is not a finite number")
    } else if x.abs() > f32::MAX as f64 {
        Some("is too large: 32-bit floats are finite only up to 3.4e38")
    } else {
        None
    }
}

/// Whether `word` is how the C runtimes of Windows print a number that is
/// not finite (`1.#INF`, `-1.#IND`, `1.#QNAN`, `-nan(ind)`), which Rust
/// does not read as a number.
pub(crate) fn spelled_not_finite(word: &str) -> bool {
    let w = word.trim_start_matches(['-', '+']).to_ascii_lowercase();
    match w.strip_prefix("1.#") {
        Some(kind) => ["inf", "ind", "qnan", "snan"]
            .iter()
            .any(|k| kind.starts_with(k) && kind[k.len()..].bytes().all(|b| b.is_ascii_digit())),
        None => w.starts_with("nan(") && w.ends_with(')'),
    }
}

/// Parses one number: an error message (without the location) when it is
/// not a number or [`unusable`].
pub(crate) fn parse(word: &str) -> Result<f64, String> {
    let x: f64 = word
        .parse()
        .map_err(|_| format!("'{}' is not a number", quoted(word)))?;
    match unusable(x) {
        Some(why) => Err(format!("'{}' {why}", quoted(word))),
        None => Ok(x),
    }
}

/// Counts absurd values ([`ABSURD`]) in one file and says so once.
#[derive(Default)]
pub(crate) struct Absurd {
    first: Option<(usize, String)>,
    more: usize,
}

impl Absurd {
    pub(crate) fn check(&mut self, line: usize, x: f64, shown: impl FnOnce() -> String) {
        if x.abs() > ABSURD {
            match self.first {
                None => self.first = Some((line, shown())),
                Some(_) => self.more += 1,
            }
        }
    }

    /// Both counts, `self` first (from earlier in the file).
    pub(crate) fn then(mut self, later: Absurd) -> Absurd {
        match self.first {
            None => self.first = later.first,
            Some(_) => self.more += later.first.is_some() as usize,
        }
        self.more += later.more;
        self
    }

    /// The warning, if any value was absurd.
    pub(crate) fn warning(self, path: &Path) -> Option<String> {
        let (line, shown) = self.first?;
        let more = match self.more {
            0 => String::new(),
            n => format!(" (and {n} more)"),
        };
        Some(format!(
            "{}:{line}: absurd value {shown}{more}: beyond {ABSURD:e} nothing computed \
             from it keeps any precision",
            path.display()
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn only_numbers_f32_can_hold() {
        assert_eq!(parse("1.5"), Ok(1.5));
        assert_eq!(parse("-1e-45"), Ok(-1e-45));
        assert_eq!(parse("3e38"), Ok(3e38));
        for bad in [
            "nan",
            "inf",
            "-infinity",
            "1e39",
            "1e400",
            "1,5",
            "",
            "0x10",
        ] {
            assert!(parse(bad).is_err(), "{bad}");
        }
        assert!(parse("1e39")
            .unwrap_err()
            .contains("32-bit floats are finite only"));
    }

    #[test]
    fn windows_spellings_of_infinity_and_nan_are_known() {
        for w in [
            "1.#INF",
            "-1.#INF",
            "1.#IND",
            "-1.#IND",
            "1.#QNAN",
            "1.#QNAN0",
            "-nan(ind)",
            "nan(snan)",
        ] {
            assert!(spelled_not_finite(w), "{w}");
        }
        for w in ["1.#", "1.#INFX", "2.#INF", "nan(", "1.5", "#IND", "x"] {
            assert!(!spelled_not_finite(w), "{w}");
        }
    }

    #[test]
    fn absurd_values_warn_once() {
        let mut a = Absurd::default();
        a.check(2, 1.0, || "1".into());
        assert!(Absurd::default().warning(Path::new("f")).is_none());
        a.check(3, 1e30, || "1e30".into());
        a.check(4, -1e20, || "-1e20".into());
        let w = a.warning(Path::new("m.obj")).unwrap();
        assert!(
            w.starts_with("m.obj:3: absurd value 1e30 (and 1 more)"),
            "{w}"
        );
    }
}
