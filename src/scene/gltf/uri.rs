//! A glTF file's URIs: `data:` URIs decoded, relative references resolved
//! beside the file.

use std::path::{Path, PathBuf};

use base64::Engine;

use crate::scene::source::resolve;

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
    // elsewhere, which a renderer has no business fetching.
    let scheme = uri.split_once(':').map(|(s, _)| s).filter(|s| {
        s.len() > 1
            && s.starts_with(|c: char| c.is_ascii_alphabetic())
            && s.chars()
                .all(|c| c.is_ascii_alphanumeric() || "+.-".contains(c))
    });
    scheme.map(|s| {
        Err(format!(
            "{}: URIs are not read; rayterm reads files beside the glTF and data: URIs",
            crate::words::printable(s)
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
