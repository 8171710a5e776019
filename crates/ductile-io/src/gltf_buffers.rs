//! The buffers of a glTF file, read without trusting the file (`docs/reliability.md`).
//!
//! A buffer is the GLB binary chunk, a `data:` URI (base64), or a relative URI reference
//! resolved inside the glTF file's folder. The rules:
//!
//! * no URI scheme other than `data:` (so no `file:`, `http:`, …), no absolute path, no `..`
//!   component: a buffer cannot name a file outside the folder;
//! * the resolved file must still be inside the folder once symbolic links are followed, and
//!   must be a regular file (not a FIFO, a device such as `/dev/zero`, or a directory);
//! * at most the buffer's declared `byteLength` is read, and a source shorter than that is an
//!   error (the accessor checks rely on it);
//! * a buffer may not declare more than [`MAX_BUFFER_BYTES`].

use std::io::Read as _;
use std::path::{Component, Path, PathBuf};

use base64::Engine as _;

use crate::error::{IoError, Result};

/// The largest buffer the importer reads (4 GiB): ten million vertices with positions,
/// normals, texture coordinates and indices take about 0.5 GB.
pub const MAX_BUFFER_BYTES: usize = 4 << 30;

/// The data of every buffer of `document`, in order, each exactly `byteLength` bytes long.
/// `base` is the folder of the glTF file (`None`: only the binary chunk and `data:` URIs may
/// be used); `path` names the file in errors.
pub(crate) fn load_buffers(
    document: &gltf::Document,
    base: Option<&Path>,
    mut blob: Option<Vec<u8>>,
    path: &Path,
) -> Result<Vec<Vec<u8>>> {
    let bad = |index: usize, problem: String| IoError::GltfStructure {
        path: path.to_owned(),
        problem: format!("buffer {index}: {problem}"),
    };
    let mut out = Vec::new();
    for buffer in document.buffers() {
        let (index, length) = (buffer.index(), buffer.length());
        if length > MAX_BUFFER_BYTES {
            return Err(bad(
                index,
                format!("declares {length} bytes, more than the limit of {MAX_BUFFER_BYTES}"),
            ));
        }
        let mut data = match buffer.source() {
            gltf::buffer::Source::Bin => blob
                .take()
                .ok_or_else(|| bad(index, "refers to a binary chunk the file lacks".into()))?,
            gltf::buffer::Source::Uri(uri) => match uri.strip_prefix("data:") {
                Some(rest) => decode_data_uri(rest).map_err(|p| bad(index, p))?,
                None => read_relative(uri, base, length).map_err(|p| bad(index, p))?,
            },
        };
        if data.len() < length {
            return Err(bad(
                index,
                format!(
                    "declares {length} bytes but its source holds only {}",
                    data.len()
                ),
            ));
        }
        data.truncate(length);
        out.push(data);
    }
    Ok(out)
}

/// The bytes of a `data:[<media type>];base64,<data>` URI (the part after `data:`).
fn decode_data_uri(rest: &str) -> std::result::Result<Vec<u8>, String> {
    let Some((header, payload)) = rest.split_once(',') else {
        return Err("the data URI has no ','".into());
    };
    if !header.ends_with(";base64") {
        return Err("only base64 data URIs are supported".into());
    }
    base64::engine::general_purpose::STANDARD
        .decode(payload)
        .map_err(|e| format!("the data URI is not valid base64: {e}"))
}

/// Reads at most `length` bytes of the file a relative URI reference names inside `base`.
fn read_relative(
    uri: &str,
    base: Option<&Path>,
    length: usize,
) -> std::result::Result<Vec<u8>, String> {
    let shown: String = uri.chars().take(120).collect();
    let relative = relative_path(uri).map_err(|p| format!("URI '{shown}' {p}"))?;
    let base = base.ok_or_else(|| {
        format!("URI '{shown}' names an external file, but the glTF data has no folder")
    })?;
    let folder = base
        .canonicalize()
        .map_err(|e| format!("the folder {} cannot be read: {e}", base.display()))?;
    let file = folder
        .join(&relative)
        .canonicalize()
        .map_err(|e| format!("URI '{shown}': {e}"))?;
    if !file.starts_with(&folder) {
        return Err(format!(
            "URI '{shown}' leads outside the glTF file's folder (through a symbolic link)"
        ));
    }
    let meta = std::fs::metadata(&file).map_err(|e| format!("URI '{shown}': {e}"))?;
    if !meta.is_file() {
        return Err(format!("URI '{shown}' is not a regular file"));
    }
    let f = std::fs::File::open(&file).map_err(|e| format!("URI '{shown}': {e}"))?;
    let mut data = Vec::with_capacity(length.min(meta.len() as usize));
    f.take(length as u64)
        .read_to_end(&mut data)
        .map_err(|e| format!("URI '{shown}': {e}"))?;
    Ok(data)
}

/// The relative path a URI reference names: percent-decoded, with no scheme, no root and no
/// `..` component. The error completes "URI '…' ".
fn relative_path(uri: &str) -> std::result::Result<PathBuf, String> {
    // A scheme is letters, digits, '+', '-', '.' before the first ':' (RFC 3986 §3.1); a
    // ':' after a '/' is part of a path.
    if let Some(colon) = uri.find(':')
        && !uri[..colon].contains('/')
    {
        return Err(format!(
            "has the scheme '{}:'; only data: URIs and relative file names are read",
            &uri[..colon]
        ));
    }
    let decoded = percent_decode(uri).ok_or("has an invalid percent escape or is not UTF-8")?;
    if decoded.contains('\0') || decoded.contains('\\') {
        return Err("contains a NUL or a backslash".into());
    }
    let path = PathBuf::from(&decoded);
    let mut clean = PathBuf::new();
    for c in path.components() {
        match c {
            Component::Normal(part) => clean.push(part),
            Component::CurDir => {}
            Component::ParentDir => {
                return Err(
                    "contains '..': only files inside the glTF file's folder are read".into(),
                );
            }
            Component::RootDir | Component::Prefix(_) => {
                return Err(
                    "is an absolute path: only files inside the glTF file's folder are read".into(),
                );
            }
        }
    }
    if clean.as_os_str().is_empty() {
        return Err("names no file".into());
    }
    Ok(clean)
}

/// `%XX` escapes decoded (RFC 3986 §2.1); `None` for a bad escape or bytes that are not UTF-8.
fn percent_decode(s: &str) -> Option<String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut k = 0;
    while k < bytes.len() {
        if bytes[k] == b'%' {
            let hex = std::str::from_utf8(bytes.get(k + 1..k + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            k += 3;
        } else {
            out.push(bytes[k]);
            k += 1;
        }
    }
    String::from_utf8(out).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn relative_names_pass_and_escapes_are_refused() {
        assert_eq!(
            relative_path("mesh.bin").unwrap(),
            PathBuf::from("mesh.bin")
        );
        assert_eq!(
            relative_path("./data/a%20b.bin").unwrap(),
            PathBuf::from("data/a b.bin")
        );
        for bad in [
            "../../../../etc/passwd",
            "data/../../x.bin",
            "%2e%2e/secret.bin",
            "/etc/passwd",
            "/proc/self/environ",
            "file:///etc/passwd",
            "http://example.com/a.bin",
            "C:/Windows/win.ini",
            "a%zz.bin",
            "",
            "a\\..\\b",
        ] {
            assert!(relative_path(bad).is_err(), "{bad} was accepted");
        }
    }

    #[test]
    fn data_uris_decode_and_others_are_refused() {
        assert_eq!(
            decode_data_uri("application/octet-stream;base64,AAEC").unwrap(),
            vec![0, 1, 2]
        );
        assert!(decode_data_uri("text/plain,hello").is_err());
        assert!(decode_data_uri(";base64,@@@").is_err());
    }
}
