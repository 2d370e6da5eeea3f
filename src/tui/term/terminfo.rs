//! Whether the terminal's terminfo entry declares 24-bit colour: the
//! extended boolean or number `RGB` (ncurses' `*-direct` entries) or `Tc`
//! (tmux's), read from the compiled entry without linking ncurses.

use std::path::{Path, PathBuf};

/// The directories ncurses searches, in its order.
fn search_path() -> Vec<PathBuf> {
    let mut dirs = Vec::new();
    if let Some(d) = std::env::var_os("TERMINFO") {
        dirs.push(PathBuf::from(d));
    }
    if let Some(home) = std::env::var_os("HOME") {
        dirs.push(Path::new(&home).join(".terminfo"));
    }
    let defaults = ["/etc/terminfo", "/lib/terminfo", "/usr/share/terminfo"];
    match std::env::var("TERMINFO_DIRS") {
        Ok(list) => {
            for d in list.split(':') {
                if d.is_empty() {
                    dirs.extend(defaults.iter().map(PathBuf::from));
                } else {
                    dirs.push(PathBuf::from(d));
                }
            }
        }
        Err(_) => dirs.extend(defaults.iter().map(PathBuf::from)),
    }
    dirs.push(PathBuf::from("/usr/lib/terminfo"));
    dirs
}

/// The compiled entry for `term`: `DIR/t/term`, or `DIR/74/term` (macOS).
fn find(term: &str, dirs: &[PathBuf]) -> Option<Vec<u8>> {
    let first = term.chars().next()?;
    if term.contains('/') || term.starts_with('.') {
        return None;
    }
    dirs.iter().find_map(|d| {
        [first.to_string(), format!("{:x}", first as u32)]
            .iter()
            .find_map(|sub| std::fs::read(d.join(sub).join(term)).ok())
    })
}

/// Whether the entry for `term` declares direct (24-bit) colour; `None`
/// when no entry is found or it cannot be read.
pub(crate) fn truecolor(term: &str) -> Option<bool> {
    parse_truecolor(&find(term, &search_path())?)
}

fn u16_at(b: &[u8], i: usize) -> Option<usize> {
    Some(u16::from_le_bytes([*b.get(i)?, *b.get(i + 1)?]) as usize)
}

/// Reads the extended capabilities of a compiled entry (term(5)): after
/// the standard sections, a header of five counts, the booleans, numbers
/// and string offsets, and a string table that ends with every extended
/// capability's name (booleans first, then numbers, then strings).
pub(crate) fn parse_truecolor(b: &[u8]) -> Option<bool> {
    let magic = u16_at(b, 0)?;
    let number_size = match magic {
        0o432 => 2,
        0o1036 => 4,
        _ => return None,
    };
    let h = |i: usize| u16_at(b, 2 * i);
    let (names, bools, nums, strs, table) = (h(1)?, h(2)?, h(3)?, h(4)?, h(5)?);
    let mut at = 12 + names + bools;
    at += at % 2;
    at += nums * number_size + strs * 2 + table;
    at += at % 2;
    if at + 10 > b.len() {
        // No extended section.
        return Some(false);
    }
    let e = |i: usize| u16_at(b, at + 2 * i);
    let (ebools, enums, estrs, items, etable) = (e(0)?, e(1)?, e(2)?, e(3)?, e(4)?);
    let bool_at = at + 10;
    let mut num_at = bool_at + ebools;
    num_at += num_at % 2;
    let offsets_at = num_at + enums * number_size;
    let table_at = offsets_at + 2 * items;
    let table = b.get(table_at..table_at + etable)?;
    let mut words: Vec<&[u8]> = table.split(|&c| c == 0).collect();
    // The table ends with a NUL, which leaves one empty piece.
    if words.last().is_some_and(|w| w.is_empty()) {
        words.pop();
    }
    let count = ebools + enums + estrs;
    let names = words.get(words.len().checked_sub(count)?..)?;
    let number = |i: usize| -> Option<i64> {
        let p = num_at + i * number_size;
        let v = b.get(p..p + number_size)?;
        Some(if number_size == 2 {
            i16::from_le_bytes([v[0], v[1]]) as i64
        } else {
            i32::from_le_bytes([v[0], v[1], v[2], v[3]]) as i64
        })
    };
    for (i, name) in names.iter().enumerate() {
        let set = if i < ebools {
            b.get(bool_at + i).is_some_and(|&v| v == 1)
        } else if i < ebools + enums {
            number(i - ebools).is_some_and(|v| v > 0)
        } else {
            // A string capability `RGB` also declares it.
            true
        };
        if set && (*name == b"RGB" || *name == b"Tc") {
            return Some(true);
        }
    }
    Some(false)
}

#[cfg(test)]
mod tests {
    use super::*;

    const DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/terminfo");

    #[test]
    fn extended_capabilities_are_read() {
        let dirs = [PathBuf::from(DIR)];
        // Compiled with `tic -x`: one entry with `RGB`, one with `Tc`, one
        // with neither, and one with 32-bit numbers and `RGB#24`.
        let read = |t: &str| parse_truecolor(&find(t, &dirs).expect(t));
        assert_eq!(read("rayterm-rgb"), Some(true));
        assert_eq!(read("rayterm-tc"), Some(true));
        assert_eq!(read("rayterm-plain"), Some(false));
        assert_eq!(read("rayterm-rgbnum"), Some(true));
        assert!(find("missing", &dirs).is_none());
        assert!(find("../x", &dirs).is_none());
    }

    #[test]
    fn damaged_entries_are_not_read() {
        let dirs = [PathBuf::from(DIR)];
        let good = find("rayterm-rgb", &dirs).unwrap();
        assert_eq!(parse_truecolor(b""), None);
        assert_eq!(parse_truecolor(&[0x1a, 0x01, 0xff]), None);
        for n in 0..good.len() {
            // Truncated anywhere: no panic.
            let _ = parse_truecolor(&good[..n]);
        }
    }
}
