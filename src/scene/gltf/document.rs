//! The file: a GLB container or JSON text, its validation, the extensions it
//! requires, and its buffers (the GLB's binary chunk, base64 data URIs, or
//! files beside the model).

use super::{json_pointer, GltfOptions, IMPLEMENTED_EXTENSIONS};
use crate::io::LoadLimits;
use crate::scene::load::SceneError;
use base64::Engine;
use std::io::Read;
use std::ops::Range;
use std::path::{Path, PathBuf};

/// A read and validated model with its buffers.
pub(super) struct File {
    pub document: gltf::Document,
    /// Each buffer's bytes, `byteLength` of them.
    pub buffers: Vec<Vec<u8>>,
    pub warnings: Vec<String>,
}

/// The GLB magic, `glTF` (glTF 2.0 §4.4.2).
const GLB_MAGIC: &[u8; 4] = b"glTF";
/// Chunk types (glTF 2.0 §4.4.3).
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

fn error(path: &Path, pointer: impl Into<String>, message: impl Into<String>) -> SceneError {
    SceneError::Gltf {
        path: path.to_path_buf(),
        pointer: pointer.into(),
        message: message.into(),
    }
}

/// Reads at most `limit` bytes of `file`, refusing a larger file.
fn read_bounded(path: &Path, limit: u64) -> Result<Vec<u8>, std::io::Error> {
    let file = std::fs::File::open(path)?;
    let len = file.metadata()?.len();
    if len > limit {
        return Err(std::io::Error::other(format!(
            "{len} bytes, more than the limit of {limit}"
        )));
    }
    let mut bytes = Vec::with_capacity(len as usize);
    file.take(limit).read_to_end(&mut bytes)?;
    Ok(bytes)
}

/// Reads and validates the model at `path` and loads its buffers.
pub(super) fn read(path: &Path, options: &GltfOptions) -> Result<File, SceneError> {
    if path.is_dir() {
        return Err(SceneError::Directory { path: path.into() });
    }
    let limits = LoadLimits::default();
    let bytes = read_bounded(path, limits.max_input_bytes).map_err(|error| SceneError::Read {
        path: path.into(),
        error,
    })?;
    let (json, blob) = if bytes.starts_with(GLB_MAGIC) {
        let (json, bin) = split_glb(path, &bytes)?;
        let json = bytes[json].to_vec();
        // The binary chunk keeps the file's allocation (no copy of the
        // largest part of the file).
        let blob = bin.map(|r| {
            let mut bytes = bytes;
            bytes.truncate(r.end);
            bytes.drain(..r.start);
            bytes
        });
        (json, blob)
    } else {
        (bytes, None)
    };
    let root: gltf::json::Root = gltf::json::deserialize::from_slice(&json)
        .map_err(|e| error(path, "", format!("not a valid glTF 2.0 JSON document: {e}")))?;
    let mut warnings = Vec::new();
    for (i, name) in root.extensions_required.iter().enumerate() {
        if !IMPLEMENTED_EXTENSIONS.contains(&name.as_str()) {
            return Err(error(
                path,
                format!("/extensionsRequired/{i}"),
                format!(
                    "the model requires the extension `{name}`, which caustic does not implement (it reads {})",
                    IMPLEMENTED_EXTENSIONS.join(", ")
                ),
            ));
        }
    }
    for (i, name) in root.extensions_used.iter().enumerate() {
        if !IMPLEMENTED_EXTENSIONS.contains(&name.as_str()) {
            warnings.push(format!(
                "{}: /extensionsUsed/{i}: the extension `{name}` is used but not required; caustic ignores it",
                path.display()
            ));
        }
    }
    if !root.asset.version.starts_with("2.") {
        return Err(error(
            path,
            "/asset/version",
            format!("glTF version {}: caustic reads glTF 2.x", root.asset.version),
        ));
    }
    validate(path, &root)?;
    let document = gltf::Document::from_json_without_validation(root);
    let buffers = buffers(path, &document, blob, options, &limits)?;
    Ok(File {
        document,
        buffers,
        warnings,
    })
}

/// The specification's checks (every index in range, required fields,
/// enumerations), except the required extensions, which [`read`] checks
/// against what caustic implements.
fn validate(path: &Path, root: &gltf::json::Root) -> Result<(), SceneError> {
    use gltf::json::validation::Validate;
    // gltf-json's check of POSITION's bounds indexes the accessors with the
    // attribute's index unchecked: every POSITION index is checked first.
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            let position = gltf::json::validation::Checked::Valid(gltf::json::mesh::Semantic::Positions);
            if let Some(i) = prim.attributes.get(&position) {
                if i.value() >= root.accessors.len() {
                    return Err(error(
                        path,
                        format!("/meshes/{m}/primitives/{p}/attributes/POSITION"),
                        format!(
                            "accessor {} out of range ({} accessors)",
                            i.value(),
                            root.accessors.len()
                        ),
                    ));
                }
            }
        }
    }
    // An image's source, which gltf-json leaves unchecked (and the gltf
    // crate unwraps): a `uri` or a `bufferView`, the latter with its
    // `mimeType` (glTF 2.0 §5.18).
    for (i, image) in root.images.iter().enumerate() {
        match (&image.uri, &image.buffer_view, &image.mime_type) {
            (None, None, _) => {
                return Err(error(
                    path,
                    format!("/images/{i}"),
                    "an image needs a `uri` or a `bufferView`",
                ));
            }
            (_, Some(_), None) => {
                return Err(error(
                    path,
                    format!("/images/{i}/mimeType"),
                    "required with a `bufferView`",
                ));
            }
            _ => {}
        }
    }
    let mut errors = Vec::new();
    root.validate(root, gltf::json::Path::new, &mut |p, e| errors.push((p(), e)));
    // POSITION's `min` and `max` are required by the specification but
    // unused here (caustic computes bounds); files without them render.
    let first = errors.into_iter().find(|(p, _)| {
        let p = p.as_str();
        !p.starts_with("extensionsRequired")
            && !(p.contains("attributes[\"POSITION\"]") && (p.ends_with(".min") || p.ends_with(".max")))
    });
    match first {
        None => Ok(()),
        Some((p, e)) => {
            let what = match e {
                gltf::json::validation::Error::IndexOutOfBounds => "index out of range".to_string(),
                gltf::json::validation::Error::Invalid => "invalid value".to_string(),
                gltf::json::validation::Error::Missing => "required value missing".to_string(),
                other => other.to_string(),
            };
            Err(error(path, json_pointer(p.as_str()), what))
        }
    }
}

/// The byte ranges of the JSON chunk and the optional binary chunk of a
/// GLB file (glTF 2.0 §4.4), every length checked against the file.
fn split_glb(path: &Path, bytes: &[u8]) -> Result<(Range<usize>, Option<Range<usize>>), SceneError> {
    let word = |at: usize| -> Option<u32> {
        bytes
            .get(at..at + 4)
            .map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    };
    let truncated = |what: &str| error(path, "", format!("truncated GLB file: {what}"));
    let version = word(4).ok_or_else(|| truncated("no header"))?;
    if version != 2 {
        return Err(error(
            path,
            "",
            format!("GLB version {version}: caustic reads version 2"),
        ));
    }
    let length = word(8).ok_or_else(|| truncated("no header"))? as usize;
    if length > bytes.len() {
        return Err(truncated(&format!(
            "the header announces {length} bytes, the file has {}",
            bytes.len()
        )));
    }
    let bytes = &bytes[..length];
    let mut at = 12;
    let mut json = None;
    let mut bin = None;
    while at < bytes.len() {
        let chunk_length = word(at).ok_or_else(|| truncated("a chunk header is cut"))? as usize;
        let chunk_type = word(at + 4).ok_or_else(|| truncated("a chunk header is cut"))?;
        let start = at + 8;
        let end = start
            .checked_add(chunk_length)
            .filter(|&e| e <= bytes.len())
            .ok_or_else(|| {
                truncated(&format!(
                    "the chunk at byte {at} announces {chunk_length} bytes, {} remain",
                    bytes.len().saturating_sub(start)
                ))
            })?;
        match chunk_type {
            CHUNK_JSON if json.is_none() && at == 12 => json = Some(start..end),
            CHUNK_BIN if json.is_some() && bin.is_none() => bin = Some(start..end),
            CHUNK_JSON | CHUNK_BIN => {
                return Err(error(
                    path,
                    "",
                    format!("GLB chunk at byte {at}: the JSON chunk must come first and each chunk appear once"),
                ))
            }
            // Unknown chunks are skipped (glTF 2.0 §4.4.3.1).
            _ => {}
        }
        // Chunks are padded to 4 bytes.
        at = end.div_ceil(4) * 4;
    }
    let json = json.ok_or_else(|| error(path, "", "GLB file without a JSON chunk"))?;
    Ok((json, bin))
}

/// Where a URI leads: decoded bytes (a data URI) or a file.
pub(super) enum UriTarget {
    Data(Vec<u8>),
    File(PathBuf),
}

/// Resolves `uri` (at `pointer`): a base64 data URI is decoded; a relative
/// reference is percent-decoded and resolved against the model's folder,
/// which it may not leave unless the options allow it.
pub(super) fn resolve_uri(
    path: &Path,
    dir: &Path,
    uri: &str,
    pointer: &str,
    options: &GltfOptions,
) -> Result<UriTarget, SceneError> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (header, data) = rest
            .split_once(',')
            .ok_or_else(|| error(path, pointer, "a data URI without a comma"))?;
        if !header.ends_with(";base64") {
            return Err(error(
                path,
                pointer,
                "a data URI that is not base64 (`;base64,` expected)",
            ));
        }
        let bytes = base64::engine::general_purpose::STANDARD
            .decode(data.trim_end())
            .map_err(|e| error(path, pointer, format!("the data URI does not decode as base64: {e}")))?;
        return Ok(UriTarget::Data(bytes));
    }
    if uri.contains("://") || uri.starts_with('/') || uri.starts_with('\\') {
        return Err(error(
            path,
            pointer,
            format!("`{uri}`: only relative references and data URIs are read"),
        ));
    }
    let decoded = percent_decode(uri).ok_or_else(|| error(path, pointer, format!("`{uri}`: bad percent-encoding")))?;
    let file = dir.join(&decoded);
    if !options.allow_outside_files {
        let folder = std::fs::canonicalize(dir).unwrap_or_else(|_| dir.to_path_buf());
        if let Ok(target) = std::fs::canonicalize(&file) {
            if !target.starts_with(&folder) {
                return Err(error(
                    path,
                    pointer,
                    format!(
                        "`{uri}` leads outside the model's folder ({}); refused unless --allow-outside-files is given",
                        folder.display()
                    ),
                ));
            }
        }
    }
    Ok(UriTarget::File(file))
}

/// `%XX` escapes decoded (RFC 3986 §2.1); `None` for a bad escape or
/// bytes that are not UTF-8.
fn percent_decode(s: &str) -> Option<String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

/// Every buffer's bytes, checked against its `byteLength`.
fn buffers(
    path: &Path,
    doc: &gltf::Document,
    mut blob: Option<Vec<u8>>,
    options: &GltfOptions,
    limits: &LoadLimits,
) -> Result<Vec<Vec<u8>>, SceneError> {
    let dir = path.parent().map_or_else(|| PathBuf::from("."), Path::to_path_buf);
    let mut out = Vec::new();
    for buffer in doc.buffers() {
        let pointer = format!("/buffers/{}", buffer.index());
        let length = buffer.length();
        if length as u64 > limits.max_input_bytes {
            return Err(error(
                path,
                format!("{pointer}/byteLength"),
                format!("{length} bytes: more than the limit of {}", limits.max_input_bytes),
            ));
        }
        let mut data = match buffer.source() {
            gltf::buffer::Source::Bin => {
                let data = blob.take().ok_or_else(|| {
                    error(
                        path,
                        &pointer,
                        "the buffer has no URI, but the file has no GLB binary chunk for it",
                    )
                })?;
                if data.len() < length {
                    return Err(error(
                        path,
                        format!("{pointer}/byteLength"),
                        format!(
                            "{length} bytes, but the GLB binary chunk has only {}: truncated",
                            data.len()
                        ),
                    ));
                }
                data
            }
            gltf::buffer::Source::Uri(uri) => {
                let at = format!("{pointer}/uri");
                match resolve_uri(path, &dir, uri, &at, options)? {
                    UriTarget::Data(data) => data,
                    UriTarget::File(file) => {
                        let size = std::fs::metadata(&file)
                            .map_err(|e| error(path, &at, format!("{}: {e}", file.display())))?
                            .len();
                        if size < length as u64 {
                            return Err(error(
                                path,
                                format!("{pointer}/byteLength"),
                                format!("{length} bytes, but {} has only {size}: truncated", file.display()),
                            ));
                        }
                        let mut data = Vec::with_capacity(length);
                        std::fs::File::open(&file)
                            .and_then(|f| f.take(length as u64).read_to_end(&mut data))
                            .map_err(|e| error(path, &at, format!("{}: {e}", file.display())))?;
                        data
                    }
                }
            }
        };
        if data.len() < length {
            return Err(error(
                path,
                format!("{pointer}/byteLength"),
                format!("{length} bytes, but its data has only {}: truncated", data.len()),
            ));
        }
        data.truncate(length);
        out.push(data);
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percent_escapes_decode() {
        assert_eq!(percent_decode("a%20b.bin").as_deref(), Some("a b.bin"));
        assert_eq!(percent_decode("plain.png").as_deref(), Some("plain.png"));
        assert_eq!(percent_decode("bad%2"), None);
        assert_eq!(percent_decode("bad%zz"), None);
    }

    #[test]
    fn glb_lengths_are_checked() {
        let p = Path::new("m.glb");
        let json = b"{\"asset\":{\"version\":\"2.0\"}}";
        let mut glb = Vec::new();
        glb.extend_from_slice(b"glTF");
        glb.extend_from_slice(&2u32.to_le_bytes());
        let total = 12 + 8 + json.len().div_ceil(4) * 4;
        glb.extend_from_slice(&(total as u32).to_le_bytes());
        glb.extend_from_slice(&(json.len() as u32).to_le_bytes());
        glb.extend_from_slice(&CHUNK_JSON.to_le_bytes());
        glb.extend_from_slice(json);
        while glb.len() < total {
            glb.push(b' ');
        }
        let (j, b) = split_glb(p, &glb).unwrap();
        assert_eq!(&glb[j], json);
        assert!(b.is_none());
        let cut = &glb[..glb.len() - 3];
        let e = split_glb(p, cut).unwrap_err().to_string();
        assert!(e.contains("truncated"), "{e}");
        // A chunk announcing more than the file holds.
        let mut lying = glb.clone();
        lying[12..16].copy_from_slice(&1000u32.to_le_bytes());
        let e = split_glb(p, &lying).unwrap_err().to_string();
        assert!(e.contains("announces 1000 bytes"), "{e}");
        assert!(split_glb(p, b"glTF").is_err());
    }
}
