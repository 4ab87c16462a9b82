//! `EXT_meshopt_compression`, the geometry compression gltfpack and
//! glTF-Transform write: a buffer view's bytes are stored compressed in
//! another buffer (the extension's `buffer`, `byteOffset`, `byteLength`),
//! and the view's own buffer is a placeholder (`"fallback": true`, usually
//! without data). Each compressed view is decoded into its place in that
//! buffer before anything reads the file, so the rest of the loader reads
//! plain glTF.
//!
//! The codec is meshoptimizer-rs (`decode_buffer_view_into`), which checks
//! mode, filter, count and stride the way the extension's specification
//! asks, and decodes a malformed stream into an error, not a crash.

use meshoptimizer_rs::codec::{Filter, Mode, decode_buffer_view_into};
use meshoptimizer_rs::{Limits, Workspace};
use serde_json::Value;

/// One compressed buffer view, as its extension object describes it.
#[derive(Clone, Debug, PartialEq)]
pub struct CompressedView {
    /// The view's index, for messages.
    pub view: usize,
    /// Where the decoded bytes go: the view's own buffer and range.
    pub target: usize,
    pub target_offset: usize,
    /// Where the compressed bytes are.
    pub source: usize,
    pub source_offset: usize,
    pub source_length: usize,
    pub count: usize,
    pub stride: usize,
    pub mode: Mode,
    pub filter: Filter,
}

impl CompressedView {
    /// Bytes it decodes to.
    pub fn decoded_length(&self) -> usize {
        self.count.saturating_mul(self.stride)
    }
}

/// The compressed views of a glTF document (its raw JSON, since the gltf
/// crate drops extensions it does not know).
pub fn compressed_views(document: &Value) -> Result<Vec<CompressedView>, String> {
    let views = document["bufferViews"].as_array().map_or(&[][..], Vec::as_slice);
    let mut out = Vec::new();
    for (k, view) in views.iter().enumerate() {
        let ext = &view["extensions"]["EXT_meshopt_compression"];
        if ext.is_null() {
            continue;
        }
        let fail = |what: &str| format!("bufferView {k}: EXT_meshopt_compression {what}");
        let number = |value: &Value, key: &str, default: Option<usize>| match value.get(key) {
            Some(v) => v
                .as_u64()
                .and_then(|n| usize::try_from(n).ok())
                .ok_or_else(|| fail(&format!("'{key}' is not a whole number"))),
            None => default.ok_or_else(|| fail(&format!("lacks '{key}'"))),
        };
        let mode = match ext["mode"].as_str() {
            Some("ATTRIBUTES") => Mode::Attributes,
            Some("TRIANGLES") => Mode::Triangles,
            Some("INDICES") => Mode::Indices,
            _ => return Err(fail("has no known 'mode' (ATTRIBUTES, TRIANGLES or INDICES)")),
        };
        let filter = match ext.get("filter").map(Value::as_str) {
            None | Some(Some("NONE")) => Filter::None,
            Some(Some("OCTAHEDRAL")) => Filter::Octahedral,
            Some(Some("QUATERNION")) => Filter::Quaternion,
            Some(Some("EXPONENTIAL")) => Filter::Exponential,
            Some(_) => return Err(fail("has an unknown 'filter'")),
        };
        let count = number(ext, "count", None)?;
        let stride = number(ext, "byteStride", None)?;
        if number(view, "byteLength", None)? != count.saturating_mul(stride) {
            return Err(fail("decodes to a length other than its view's byteLength"));
        }
        out.push(CompressedView {
            view: k,
            target: number(view, "buffer", None)?,
            target_offset: number(view, "byteOffset", Some(0))?,
            source: number(ext, "buffer", None)?,
            source_offset: number(ext, "byteOffset", Some(0))?,
            source_length: number(ext, "byteLength", None)?,
            count,
            stride,
            mode,
            filter,
        });
    }
    Ok(out)
}

/// Whether buffer `index` is a placeholder without data of its own: its
/// extension says `"fallback": true` and it names no file.
pub fn is_placeholder(document: &Value, index: usize) -> bool {
    let buffer = &document["buffers"][index];
    buffer["extensions"]["EXT_meshopt_compression"]["fallback"] == Value::Bool(true) && buffer.get("uri").is_none()
}

/// Decodes every view of `views` into its place in `buffers`, using at most
/// `limit` bytes of scratch per view.
pub fn decode(buffers: &mut [Vec<u8>], views: &[CompressedView], limit: u64) -> Result<(), String> {
    let mut workspace = Workspace::new(Limits {
        max_bytes: usize::try_from(limit).unwrap_or(usize::MAX),
        ..Limits::default()
    });
    for v in views {
        let fail = |what: String| format!("bufferView {}: EXT_meshopt_compression {what}", v.view);
        let source = buffers
            .get(v.source)
            .and_then(|b| b.get(v.source_offset..v.source_offset.checked_add(v.source_length)?))
            .ok_or_else(|| fail("data lies outside its buffer".into()))?
            .to_vec();
        let length = v.decoded_length();
        let target = buffers
            .get_mut(v.target)
            .and_then(|b| b.get_mut(v.target_offset..v.target_offset.checked_add(length)?))
            .ok_or_else(|| fail(format!("decodes to {length} bytes, beyond its view's buffer")))?;
        decode_buffer_view_into(target, v.mode, v.filter, v.count, v.stride, &source, &mut workspace)
            .map_err(|e| fail(format!("does not decode: {e}")))?;
    }
    Ok(())
}
