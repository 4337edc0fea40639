//! Reading a glTF file: the JSON or GLB container, the extension checks, the buffers
//! (GLB `BIN` chunk, external files, `data:` URIs), and accessors checked against them
//! before the `gltf` crate's readers touch them (those assume a valid file and would
//! panic on a wrong type or stride).

use super::SUPPORTED_EXTENSIONS;
use crate::LoadError;
use base64::Engine;
use gltf::accessor::{DataType, Dimensions};
use gltf::Accessor;
use std::path::{Path, PathBuf};

/// A parsed, validated glTF document with its buffers loaded.
pub(crate) struct GltfFile {
    pub doc: gltf::Document,
    /// The bytes of each buffer, at least `byteLength` long.
    pub buffers: Vec<Vec<u8>>,
}

impl GltfFile {
    pub fn open(path: &Path) -> Result<Self, LoadError> {
        let err = |msg: String| LoadError::in_file(path, msg);
        let bytes = crate::read_regular_file(path)
            .map_err(|e| err(format!("cannot read the glTF file: {e}")))?;
        let is_glb = bytes.starts_with(b"glTF");
        let parsed = gltf::Gltf::from_slice_without_validation(&bytes).map_err(|e| {
            err(match (&e, is_glb) {
                (gltf::Error::Binary(b), _) => format!("not a valid GLB file: {b}"),
                (gltf::Error::Deserialize(j), true) => {
                    format!("invalid JSON in the GLB's JSON chunk: {j}")
                }
                (gltf::Error::Deserialize(j), false) => {
                    format!("not a valid glTF JSON file: {j}")
                }
                _ => format!("not a valid glTF file: {e}"),
            })
        })?;
        let gltf::Gltf { document, blob } = parsed;

        let asset = &document.as_json().asset;
        let major = |v: &str| v.split('.').next().map(str::to_string);
        if major(asset.min_version.as_deref().unwrap_or(&asset.version)).as_deref() != Some("2") {
            return Err(err(format!(
                "glTF version {} is not supported (radia reads glTF 2.x)",
                asset.min_version.as_deref().unwrap_or(&asset.version)
            )));
        }
        check_extensions(&document).map_err(err)?;
        check_position_references(&document).map_err(err)?;
        let doc = gltf::Document::from_json(document.into_json()).map_err(|e| {
            err(match e {
                gltf::Error::Validation(list) => {
                    let items: Vec<String> =
                        list.iter().map(|(p, e)| format!("{p}: {e}")).collect();
                    format!("invalid glTF: {}", items.join("; "))
                }
                e => format!("invalid glTF: {e}"),
            })
        })?;

        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let mut blob = blob;
        let mut buffers = Vec::new();
        for b in doc.buffers() {
            let what = match b.name() {
                Some(n) => format!("buffer {} (\"{n}\")", b.index()),
                None => format!("buffer {}", b.index()),
            };
            let data = match b.source() {
                gltf::buffer::Source::Bin => blob.take().ok_or_else(|| {
                    err(format!(
                        "{what} refers to the GLB binary chunk, but {}",
                        if is_glb {
                            "the file has none (or it was used by an earlier buffer)"
                        } else {
                            "this is not a GLB file"
                        }
                    ))
                })?,
                gltf::buffer::Source::Uri(uri) => read_uri(&dir, uri)
                    .map_err(|e| err(format!("{what} (uri \"{}\"): {e}", shorten(uri))))?,
            };
            if data.len() < b.length() {
                return Err(err(format!(
                    "{what} has {} bytes, fewer than its byteLength {}",
                    data.len(),
                    b.length()
                )));
            }
            buffers.push(data);
        }
        Ok(Self { doc, buffers })
    }

    /// The bytes of a buffer, for the `gltf` crate's readers.
    pub fn buffer(&self, b: gltf::Buffer<'_>) -> Option<&[u8]> {
        self.buffers.get(b.index()).map(Vec::as_slice)
    }
}

/// An unsupported extension that the file requires is an error; extensions it only uses
/// are named in one warning by the caller ([`unsupported_used`]).
fn check_extensions(doc: &gltf::Document) -> Result<(), String> {
    let missing: Vec<&str> = doc
        .extensions_required()
        .filter(|e| !SUPPORTED_EXTENSIONS.contains(e))
        .collect();
    match missing.as_slice() {
        [] => Ok(()),
        [one] => Err(format!(
            "the file requires the extension {one}, which radia does not support (radia reads: {})",
            SUPPORTED_EXTENSIONS.join(", ")
        )),
        many => Err(format!(
            "the file requires the extensions {}, which radia does not support (radia reads: {})",
            many.join(", "),
            SUPPORTED_EXTENSIONS.join(", ")
        )),
    }
}

/// The `gltf` crate's validation (gltf-json 1.4.1, `primitive_validate_hook`) indexes the
/// accessors with a primitive's POSITION before checking that it exists, and panics on a
/// file where it does not: check that reference first.
fn check_position_references(doc: &gltf::Document) -> Result<(), String> {
    let json = doc.as_json();
    for (i, mesh) in json.meshes.iter().enumerate() {
        for (j, prim) in mesh.primitives.iter().enumerate() {
            let position = prim.attributes.get(&gltf::json::validation::Checked::Valid(
                gltf::Semantic::Positions,
            ));
            if let Some(a) = position {
                if a.value() >= json.accessors.len() {
                    return Err(format!(
                        "mesh {i} primitive {j}: POSITION refers to accessor {}, but the file has {} accessor(s)",
                        a.value(),
                        json.accessors.len()
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Extensions in `extensionsUsed` that radia ignores.
pub(crate) fn unsupported_used(doc: &gltf::Document) -> Vec<String> {
    doc.extensions_used()
        .filter(|e| !SUPPORTED_EXTENSIONS.contains(e))
        .map(str::to_string)
        .collect()
}

/// A URI as it can be quoted in a message (data URIs are long).
pub(crate) fn shorten(uri: &str) -> String {
    if uri.len() > 60 {
        format!(
            "{}...",
            &uri[..uri.char_indices().nth(40).map_or(uri.len(), |c| c.0)]
        )
    } else {
        uri.to_string()
    }
}

/// The bytes a buffer URI names: a base64 `data:` URI, or a file relative to `dir`.
pub(crate) fn read_uri(dir: &Path, uri: &str) -> Result<Vec<u8>, String> {
    if let Some(rest) = uri.strip_prefix("data:") {
        let (header, payload) = rest
            .split_once(',')
            .ok_or("a data URI needs a ',' before its data")?;
        if !header.ends_with(";base64") {
            return Err("only base64 data URIs are supported".into());
        }
        return base64::engine::general_purpose::STANDARD
            .decode(payload)
            .map_err(|e| format!("invalid base64 in the data URI: {e}"));
    }
    if let Some((scheme, _)) = uri.split_once(':') {
        // A Windows drive letter is not a scheme; anything else (http:, file:) is.
        if scheme.len() > 1
            && scheme
                .chars()
                .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
        {
            return Err(format!("the URI scheme \"{scheme}:\" is not supported (only relative paths and data: URIs)"));
        }
    }
    let file: PathBuf = dir.join(percent_decode(uri)?);
    crate::read_regular_file(&file).map_err(|e| format!("cannot read \"{}\": {e}", file.display()))
}

/// URIs in glTF are percent-encoded (RFC 3986): "my%20mesh.bin" is "my mesh.bin".
fn percent_decode(s: &str) -> Result<String, String> {
    let bytes = s.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = s
                .get(i + 1..i + 3)
                .and_then(|h| u8::from_str_radix(h, 16).ok())
                .ok_or_else(|| format!("bad percent escape in the URI \"{s}\""))?;
            out.push(hex);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).map_err(|_| format!("the URI \"{s}\" is not UTF-8 once decoded"))
}

/// How an accessor is read, for the checks.
pub(crate) struct AccessorSpec<'a> {
    /// What it is, for messages ("POSITION", "indices", ...).
    pub what: &'a str,
    pub dimensions: &'a [Dimensions],
    /// Component types allowed, each with whether it must be `normalized` (integer
    /// texture coordinates are; indices are not).
    pub types: &'a [(DataType, bool)],
}

fn dims_name(d: Dimensions) -> &'static str {
    match d {
        Dimensions::Scalar => "SCALAR",
        Dimensions::Vec2 => "VEC2",
        Dimensions::Vec3 => "VEC3",
        Dimensions::Vec4 => "VEC4",
        Dimensions::Mat2 => "MAT2",
        Dimensions::Mat3 => "MAT3",
        Dimensions::Mat4 => "MAT4",
    }
}

fn type_name(t: DataType) -> &'static str {
    match t {
        DataType::I8 => "BYTE",
        DataType::U8 => "UNSIGNED_BYTE",
        DataType::I16 => "SHORT",
        DataType::U16 => "UNSIGNED_SHORT",
        DataType::U32 => "UNSIGNED_INT",
        DataType::F32 => "FLOAT",
    }
}

/// Checks that `acc` has a type the reader expects and that every byte it reads lies in
/// its buffer view and buffer, so that reading it cannot fail or panic.
pub(crate) fn check_accessor(
    file: &GltfFile,
    acc: &Accessor<'_>,
    spec: &AccessorSpec<'_>,
) -> Result<(), String> {
    let name = format!("{} accessor {}", spec.what, acc.index());
    if !spec.dimensions.contains(&acc.dimensions()) {
        let allowed: Vec<&str> = spec.dimensions.iter().map(|d| dims_name(*d)).collect();
        return Err(format!(
            "{name} has type {}, expected {}",
            dims_name(acc.dimensions()),
            allowed.join(" or ")
        ));
    }
    if !spec
        .types
        .iter()
        .any(|(t, norm)| *t == acc.data_type() && *norm == acc.normalized())
    {
        let allowed: Vec<String> = spec
            .types
            .iter()
            .map(|(t, n)| format!("{}{}", if *n { "normalized " } else { "" }, type_name(*t)))
            .collect();
        return Err(format!(
            "{name} has componentType {}{}, expected {}",
            if acc.normalized() { "normalized " } else { "" },
            type_name(acc.data_type()),
            allowed.join(" or ")
        ));
    }
    if acc.count() == 0 {
        return Err(format!("{name} has count 0 (must be at least 1)"));
    }
    let elem = acc.size();
    match acc.view() {
        Some(view) => check_range(file, &name, &view, acc.offset(), acc.count(), elem)?,
        None if acc.sparse().is_none() => {
            return Err(format!(
                "{name} has no bufferView (an all-zero accessor; radia does not read those)"
            ))
        }
        None => {}
    }
    if let Some(sparse) = acc.sparse() {
        let n = sparse.count();
        if n == 0 || n > acc.count() {
            return Err(format!(
                "{name}: sparse count {n} must be between 1 and the accessor's count {}",
                acc.count()
            ));
        }
        let idx = sparse.indices();
        let size = match idx.index_type() {
            gltf::accessor::sparse::IndexType::U8 => 1,
            gltf::accessor::sparse::IndexType::U16 => 2,
            gltf::accessor::sparse::IndexType::U32 => 4,
        };
        check_range(
            file,
            &format!("{name} sparse indices"),
            &idx.view(),
            idx.offset(),
            n,
            size,
        )?;
        let values = sparse.values();
        check_range(
            file,
            &format!("{name} sparse values"),
            &values.view(),
            values.offset(),
            n,
            elem,
        )?;
    }
    Ok(())
}

/// `count` elements of `elem` bytes from `offset` in `view` (with its stride) must lie in
/// the view, and the view in its buffer.
fn check_range(
    file: &GltfFile,
    name: &str,
    view: &gltf::buffer::View<'_>,
    offset: usize,
    count: usize,
    elem: usize,
) -> Result<(), String> {
    let buffer_len = file.buffers[view.buffer().index()].len();
    let view_end = view.offset().checked_add(view.length());
    if view_end.is_none_or(|e| e > buffer_len) {
        return Err(format!(
            "{name}: its bufferView {} (bytes {}..{}) reaches past the end of buffer {} ({} bytes)",
            view.index(),
            view.offset(),
            view.offset().saturating_add(view.length()),
            view.buffer().index(),
            buffer_len
        ));
    }
    let stride = view.stride().unwrap_or(elem);
    if stride < elem {
        return Err(format!(
            "{name}: bufferView {} has byteStride {stride}, smaller than an element ({elem} bytes)",
            view.index()
        ));
    }
    let end = stride
        .checked_mul(count - 1)
        .and_then(|x| x.checked_add(elem))
        .and_then(|x| x.checked_add(offset));
    if end.is_none_or(|e| e > view.length()) {
        return Err(format!(
            "{name}: {count} elements of {elem} bytes (stride {stride}) from byte {offset} do not fit in bufferView {} ({} bytes)",
            view.index(),
            view.length()
        ));
    }
    Ok(())
}
