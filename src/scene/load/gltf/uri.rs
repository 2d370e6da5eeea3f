//! A glTF file's URIs: `data:` URIs decoded, relative references resolved
//! beside the file, and refused where they leave its folder.

use std::path::{Path, PathBuf};

use base64::Engine;

use crate::scene::load::source::{resolve, Outside, Source};
use crate::words::{path as shown, quoted};

/// The bytes a URI holds itself (a `data:` URI's base64 payload), or why it
/// cannot be read; `None` for a relative reference, a file beside the glTF.
pub(super) fn inline_uri(uri: &str) -> Option<Result<Vec<u8>, String>> {
    if uri.trim().is_empty() {
        return Some(Err("its uri is empty".into()));
    }
    if let Some(rest) = uri.strip_prefix("data:") {
        return Some(match rest.split_once(";base64,") {
            Some((_, payload)) => base64::engine::general_purpose::STANDARD
                .decode(payload)
                .map_err(|e| format!("its base64 data is broken: {e}")),
            None => Err("only base64 data URIs are read".into()),
        });
    }
    // A scheme (two letters or more: `C:` is a drive) names something
    // elsewhere, which a renderer has no business fetching; a `file:` URI
    // is a file, outside the glTF's folder (see [`file`]).
    let scheme = uri.split_once(':').map(|(s, _)| s).filter(|s| {
        !s.eq_ignore_ascii_case("file")
            && s.len() > 1
            && s.starts_with(|c: char| c.is_ascii_alphabetic())
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || "+.-".contains(c))
    });
    scheme.map(|s| {
        Err(format!(
            "{}: URIs are not read; rayterm reads files beside the glTF and data: URIs",
            quoted(s)
        ))
    })
}

/// A relative URI as a path beside `base`, percent escapes decoded.
pub(super) fn uri_path(base: &Path, uri: &str) -> PathBuf {
    let bytes = uri.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        let hex = |b: u8| (b as char).to_digit(16);
        match (
            bytes[i],
            bytes.get(i + 1).and_then(|&b| hex(b)),
            bytes.get(i + 2).and_then(|&b| hex(b)),
        ) {
            (b'%', Some(h), Some(l)) => {
                out.push((h * 16 + l) as u8);
                i += 3;
            }
            (b, _, _) => {
                out.push(b);
                i += 1;
            }
        }
    }
    // Messages name the file: no control character reaches them.
    let path = crate::words::printable(&String::from_utf8_lossy(&out));
    resolve(base, &path)
}

/// The file a URI of the glTF at `base` names. glTF URIs are relative
/// references: one that leaves the glTF's folder (an absolute path, a
/// `file:` URI, a `..` too many, a symbolic link out) is refused, naming
/// it, unless the source allows it; it is then read at arm's length
/// ([`Outside`]).
pub(super) fn file(
    src: &dyn Source,
    base: &Path,
    uri: &str,
) -> Result<(PathBuf, Option<Outside>), String> {
    let local = uri
        .get(..5)
        .filter(|s| s.eq_ignore_ascii_case("file:"))
        .map(|_| &uri[5..]);
    let written = local.map_or(uri, |rest| {
        let rest = rest.strip_prefix("//localhost").unwrap_or(rest);
        rest.strip_prefix("//").unwrap_or(rest)
    });
    let path = uri_path(base, written);
    let outside = src.outside(base, &path);
    let absolute = local.is_some() || written.starts_with(['/', '\\']);
    if (outside.is_some() || absolute) && !src.outside_allowed() {
        let resolved = outside
            .as_ref()
            .map_or(path.clone(), |o| o.resolved.clone());
        return Err(format!(
            "its uri {} leaves the glTF's folder (it names {}): glTF URIs are relative \
             references to files beside it; move the file there, or allow files outside \
             with --allow-outside",
            quoted(uri),
            shown(&resolved)
        ));
    }
    Ok((path, outside))
}
