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

/// The extension's name, as files list it.
pub const MESHOPT: &str = "EXT_meshopt_compression";

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

    /// Its compressed bytes in `buffers`, where they must lie.
    pub fn stream<'a>(&self, buffers: &'a [Vec<u8>]) -> Result<&'a [u8], String> {
        buffers
            .get(self.source)
            .and_then(|b| b.get(self.source_offset..self.source_offset.checked_add(self.source_length)?))
            .ok_or_else(|| {
                format!(
                    "bufferView {}: EXT_meshopt_compression data lies outside its buffer",
                    self.view
                )
            })
    }
}

/// The fewest bytes a stream of `mode` can hold `count` elements of
/// `stride` bytes in: the parts every stream has, by the bitstream formats
/// of EXT_meshopt_compression (its Appendix A; meshoptimizer's decoders
/// refuse a shorter stream), each at its smallest; `None` past `usize`.
/// A view that claims more than its stream's length can hold is refused
/// before anything is allocated for it: without this, a few bytes could
/// claim gigabytes. It is exactly what meshoptimizer writes for the most
/// compressible data (zeros; a strip, each triangle adding the next
/// vertex), so no valid stream is refused.
fn shortest_stream(mode: Mode, count: usize, stride: usize) -> Option<usize> {
    match mode {
        // Version 0, the one the extension allows: a header byte; the
        // vertices in blocks of at most 256 (and 8 KiB); in each block,
        // for each byte of the stride, 2 header bits per group of 16
        // vertices, byte-aligned (a group of zero deltas needs nothing
        // more); a tail holding the baseline vertex, padded to 32 bytes.
        // At most 64 decoded bytes from one.
        Mode::Attributes => {
            let block = ((8192 / stride) & !15).min(256);
            let headers = |vertices: usize| vertices.div_ceil(16).div_ceil(4);
            let body = (count / block) * headers(block) + headers(count % block);
            body.checked_mul(stride)?.checked_add(stride.max(32))?.checked_add(1)
        }
        // A header byte, a code byte per triangle (three indices, at most
        // 12 bytes) and a 16-byte table.
        Mode::Triangles => Some(1 + count / 3 + 16),
        // A header byte, at least a byte per index (at most 4 bytes) and
        // 4 bytes of tail.
        Mode::Indices => count.checked_add(5),
    }
}

/// The compressed views of a glTF document (its raw JSON, since the gltf
/// crate drops extensions it does not know).
pub fn compressed_views(document: &Value) -> Result<Vec<CompressedView>, String> {
    let views = document["bufferViews"].as_array().map_or(&[][..], Vec::as_slice);
    let mut out = Vec::new();
    for (k, view) in views.iter().enumerate() {
        let ext = &view["extensions"][MESHOPT];
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
        let stride_fits = match mode {
            Mode::Attributes => stride % 4 == 0 && (4..=256).contains(&stride),
            Mode::Triangles | Mode::Indices => stride == 2 || stride == 4,
        };
        if !stride_fits {
            return Err(fail(&format!("'byteStride' {stride} is not one its mode takes")));
        }
        let source_length = number(ext, "byteLength", None)?;
        match shortest_stream(mode, count, stride) {
            Some(shortest) if shortest <= source_length => {}
            shortest => {
                return Err(fail(&format!(
                    "claims {count} elements of {stride} bytes, more than its {source_length} compressed bytes can hold (they need {})",
                    shortest.map_or("more bytes than memory has".into(), |n| format!("at least {n}"))
                )));
            }
        }
        out.push(CompressedView {
            view: k,
            target: number(view, "buffer", None)?,
            target_offset: number(view, "byteOffset", Some(0))?,
            source: number(ext, "buffer", None)?,
            source_offset: number(ext, "byteOffset", Some(0))?,
            source_length,
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
    buffer["extensions"][MESHOPT]["fallback"] == Value::Bool(true) && buffer.get("uri").is_none()
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
        let source = v.stream(buffers)?.to_vec();
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

#[cfg(test)]
mod tests {
    use super::*;
    use meshoptimizer_rs::codec::{
        IndexEncoding, VertexEncoding, encode_index_buffer, encode_index_sequence, encode_vertex_buffer,
    };

    /// Bytes of a cheap generator, for data that does not compress.
    fn noise(n: usize) -> Vec<u8> {
        let mut state = 0x2545_f491_4f6c_dd1du64;
        (0..n)
            .map(|_| {
                state = state.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1);
                (state >> 56) as u8
            })
            .collect()
    }

    #[test]
    fn the_shortest_streams_are_what_meshoptimizer_writes_for_the_most_compressible_data() {
        let mut workspace = Workspace::new(Limits::default());
        let version_0 = VertexEncoding::new(0, 2).unwrap();
        for stride in [4, 8, 12, 16, 36, 64, 128, 256] {
            for count in [1, 15, 16, 17, 63, 64, 65, 255, 256, 257, 1000, 4099] {
                let what = format!("{count} vertices of {stride} bytes");
                let shortest = shortest_stream(Mode::Attributes, count, stride).unwrap();
                let zeros = encode_vertex_buffer(&vec![0; count * stride], count, stride, version_0, &mut workspace);
                assert_eq!(zeros.unwrap().len(), shortest, "{what}: zeros");
                let noisy = encode_vertex_buffer(&noise(count * stride), count, stride, version_0, &mut workspace);
                assert!(noisy.unwrap().len() >= shortest, "{what}: noise");
            }
        }
        for encoding in [IndexEncoding::new(0).unwrap(), IndexEncoding::DEFAULT] {
            for triangles in [1, 2, 10, 1000] {
                let what = format!("{triangles} triangles, {encoding:?}");
                let shortest = shortest_stream(Mode::Triangles, 3 * triangles, 4).unwrap();
                // A strip: each triangle shares an edge with the one
                // before and adds the next vertex, a code byte alone.
                let strip: Vec<u32> = (0..triangles as u32)
                    .flat_map(|t| {
                        if t % 2 == 0 {
                            [t, t + 1, t + 2]
                        } else {
                            [t + 1, t, t + 2]
                        }
                    })
                    .collect();
                let stream = encode_index_buffer(&strip, encoding, &mut workspace).unwrap();
                assert_eq!(stream.len(), shortest, "{what}: a strip");
                let spread: Vec<u32> = (0..3 * triangles as u32).map(|i| i * 7919 % 65_521).collect();
                let stream = encode_index_buffer(&spread, encoding, &mut workspace).unwrap();
                assert!(stream.len() >= shortest, "{what}: spread");
            }
            for count in [1, 5, 1000] {
                let shortest = shortest_stream(Mode::Indices, count, 4).unwrap();
                let stream = encode_index_sequence(&vec![0; count], encoding, &mut workspace).unwrap();
                assert_eq!(stream.len(), shortest, "{count} indices, {encoding:?}");
            }
        }
    }

    #[test]
    fn a_view_claiming_more_than_its_stream_can_hold_is_refused_before_decoding() {
        let document = |mode: &str, count: u64, stride: u64, compressed: u64| {
            serde_json::json!({"bufferViews": [{
                "buffer": 1, "byteLength": count * stride,
                "extensions": {"EXT_meshopt_compression": {
                    "buffer": 0, "byteLength": compressed, "mode": mode, "count": count, "byteStride": stride
                }}
            }]})
        };
        // 4 KiB of vertices from the shortest stream that holds them, and
        // from one byte less; 2^31 triangle indices from 201 bytes.
        let shortest = shortest_stream(Mode::Attributes, 256, 16).unwrap() as u64;
        assert!(compressed_views(&document("ATTRIBUTES", 256, 16, shortest)).is_ok());
        for (mode, count, stride, compressed) in [
            ("ATTRIBUTES", 256, 16, shortest - 1),
            ("TRIANGLES", 3 << 29, 4, 201),
            ("INDICES", 1000, 2, 1000),
        ] {
            let e = compressed_views(&document(mode, count, stride, compressed)).unwrap_err();
            assert!(
                e.contains(&format!("claims {count} elements of {stride} bytes"))
                    && e.contains(&format!("its {compressed} compressed bytes")),
                "{mode}: {e}"
            );
        }
        let e = compressed_views(&document("ATTRIBUTES", 8, 6, 100)).unwrap_err();
        assert!(e.contains("'byteStride' 6"), "{e}");
    }
}
