//! `EXT_meshopt_compression`, the geometry compression gltfpack and
//! glTF-Transform write, and `KHR_meshopt_compression`, its Khronos
//! successor (gltfpack `-ce khr`): a buffer view's bytes are stored
//! compressed in another buffer (the extension's `buffer`, `byteOffset`,
//! `byteLength`), and the view's own buffer is a placeholder (`"fallback":
//! true`, usually without data). Each compressed view is decoded into its
//! place in that buffer before anything reads the file, so the rest of the
//! loader reads plain glTF. The KHR extension adds version 1 of the
//! attribute codec and the COLOR filter; the rest is the same.
//!
//! The codec is meshoptimizer-rs. `decode_buffer_view_into` checks mode,
//! filter, count and stride the way the EXT extension's specification
//! asks (version 0 alone); a KHR view of attributes is decoded by
//! `decode_vertex_buffer_into`, which reads either version, and its filter
//! applied after. Each decodes a malformed stream into an error, not a
//! crash.

use super::gltf_json::list;
use meshoptimizer_rs::codec::{
    Filter, Mode, decode_buffer_view_into, decode_filter_color, decode_filter_exp, decode_filter_oct,
    decode_filter_quat, decode_vertex_buffer_into,
};
use meshoptimizer_rs::{Limits, Workspace};
use serde_json::Value;

/// The extensions' names, as files list them.
pub const EXT_MESHOPT: &str = "EXT_meshopt_compression";
pub const KHR_MESHOPT: &str = "KHR_meshopt_compression";

/// A view's post-decompression filter: the codec's, and COLOR, which only
/// the KHR extension has.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewFilter {
    Codec(Filter),
    Color,
}

/// One compressed buffer view, as its extension object describes it.
#[derive(Clone, Debug, PartialEq)]
pub struct CompressedView {
    /// The view's index, for messages.
    pub view: usize,
    /// Which of the two extensions compressed it.
    pub extension: &'static str,
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
    pub filter: ViewFilter,
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
                    "bufferView {}: {} data lies outside its buffer",
                    self.view, self.extension
                )
            })
    }
}

/// The fewest bytes a stream of `mode` can hold `count` elements of
/// `stride` bytes in: the parts every stream has, by the bitstream formats
/// of the extensions (their Appendix A; meshoptimizer's decoders refuse a
/// shorter stream), each at its smallest, in the attribute codec's
/// `version`; `None` past `usize`.
/// A view that claims more than its stream's length can hold is refused
/// before anything is allocated for it: without this, a few bytes could
/// claim gigabytes. It is exactly what meshoptimizer writes for the most
/// compressible data (zeros; a strip, each triangle adding the next
/// vertex), so no valid stream is refused.
fn shortest_stream(mode: Mode, count: usize, stride: usize, version: u8) -> Option<usize> {
    match mode {
        // Version 0: a header byte; the vertices in blocks of at most 256
        // (and 8 KiB); in each block, for each byte of the stride, 2 header
        // bits per group of 16 vertices, byte-aligned (a group of zero
        // deltas needs nothing more); a tail holding the baseline vertex,
        // padded to 32 bytes. At most 64 decoded bytes from one.
        Mode::Attributes if version == 0 => {
            let block = ((8192 / stride) & !15).min(256);
            let headers = |vertices: usize| vertices.div_ceil(16).div_ceil(4);
            let body = (count / block) * headers(block) + headers(count % block);
            body.checked_mul(stride)?.checked_add(stride.max(32))?.checked_add(1)
        }
        // Version 1: a header byte; in each block, a control byte per 4
        // bytes of the stride (a byte of the stride that is zero through
        // the block needs nothing more); a tail holding the baseline
        // vertex and a byte per 4 of its bytes, padded to 24 bytes.
        Mode::Attributes => {
            let block = ((8192 / stride) & !15).min(256);
            let body = count.div_ceil(block).checked_mul(stride / 4)?;
            body.checked_add((stride + stride / 4).max(24))?.checked_add(1)
        }
        // A header byte, a code byte per triangle (three indices, at most
        // 12 bytes) and a 16-byte table.
        Mode::Triangles => Some(1 + count / 3 + 16),
        // A header byte, at least a byte per index (at most 4 bytes) and
        // 4 bytes of tail.
        Mode::Indices => count.checked_add(5),
    }
}

/// Whether buffer view `view` of a glTF document (its raw JSON) is
/// decoded through the exponential filter, whose encoder rounds each value
/// to a mantissa of the bits it chose: the values the file holds are not
/// the ones its exporter measured bounds on.
pub fn rounds_values(document: &Value, view: usize) -> bool {
    [EXT_MESHOPT, KHR_MESHOPT]
        .iter()
        .any(|name| document["bufferViews"][view]["extensions"][name]["filter"] == "EXPONENTIAL")
}

/// The compressed views of a glTF document (its raw JSON, since the gltf
/// crate drops extensions it does not know).
pub fn compressed_views(document: &Value) -> Result<Vec<CompressedView>, String> {
    let views = list(&document["bufferViews"]);
    let mut out = Vec::new();
    for (k, view) in views.iter().enumerate() {
        let extension = match [EXT_MESHOPT, KHR_MESHOPT].map(|name| !view["extensions"][name].is_null()) {
            [false, false] => continue,
            [true, false] => EXT_MESHOPT,
            [false, true] => KHR_MESHOPT,
            [true, true] => {
                return Err(format!(
                    "bufferView {k} uses both {EXT_MESHOPT} and {KHR_MESHOPT}, which the latter forbids"
                ));
            }
        };
        let ext = &view["extensions"][extension];
        let khr = extension == KHR_MESHOPT;
        let fail = |what: &str| format!("bufferView {k}: {extension} {what}");
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
            None | Some(Some("NONE")) => ViewFilter::Codec(Filter::None),
            Some(Some("OCTAHEDRAL")) => ViewFilter::Codec(Filter::Octahedral),
            Some(Some("QUATERNION")) => ViewFilter::Codec(Filter::Quaternion),
            Some(Some("EXPONENTIAL")) => ViewFilter::Codec(Filter::Exponential),
            Some(Some("COLOR")) if khr => ViewFilter::Color,
            Some(_) => return Err(fail("has an unknown 'filter'")),
        };
        if mode != Mode::Attributes && filter != ViewFilter::Codec(Filter::None) {
            return Err(fail("has a filter, which only ATTRIBUTES views may have"));
        }
        let count = number(ext, "count", None)?;
        let stride = number(ext, "byteStride", None)?;
        if count.checked_mul(stride) != Some(number(view, "byteLength", None)?) {
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
        // The KHR extension allows either version of the attribute codec;
        // a stream is held to the shorter bound before its bytes are read.
        let version = u8::from(khr);
        match shortest_stream(mode, count, stride, version) {
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
            extension,
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

/// Whether buffer `index` is a placeholder without data of its own: one
/// of the extensions says `"fallback": true` and it names no file.
pub fn is_placeholder(document: &Value, index: usize) -> bool {
    let buffer = &document["buffers"][index];
    let fallback = |extension: &str| buffer["extensions"][extension]["fallback"] == Value::Bool(true);
    (fallback(EXT_MESHOPT) || fallback(KHR_MESHOPT)) && buffer.get("uri").is_none()
}

/// Decodes every view of `views` into its place in `buffers`, using at most
/// `limit` bytes of scratch per view.
pub fn decode(buffers: &mut [Vec<u8>], views: &[CompressedView], limit: u64) -> Result<(), String> {
    let mut workspace = Workspace::new(Limits {
        max_bytes: usize::try_from(limit).unwrap_or(usize::MAX),
        ..Limits::default()
    });
    for v in views {
        let fail = |what: String| format!("bufferView {}: {} {what}", v.view, v.extension);
        let source = v.stream(buffers)?.to_vec();
        let length = v.decoded_length();
        let target = buffers
            .get_mut(v.target)
            .and_then(|b| b.get_mut(v.target_offset..v.target_offset.checked_add(length)?))
            .ok_or_else(|| fail(format!("decodes to {length} bytes, beyond its view's buffer")))?;
        let (count, stride, ws) = (v.count, v.stride, &mut workspace);
        let decoded = match (v.extension, v.mode, v.filter) {
            (KHR_MESHOPT, Mode::Attributes, filter) => decode_vertex_buffer_into(target, count, stride, &source, ws)
                .and_then(|()| match filter {
                    ViewFilter::Codec(Filter::None) => Ok(()),
                    ViewFilter::Codec(Filter::Octahedral) => decode_filter_oct(target, count, stride, ws),
                    ViewFilter::Codec(Filter::Quaternion) => decode_filter_quat(target, count, stride, ws),
                    ViewFilter::Codec(Filter::Exponential) => decode_filter_exp(target, count, stride, ws),
                    ViewFilter::Color => decode_filter_color(target, count, stride, ws),
                }),
            (_, mode, ViewFilter::Codec(filter)) => {
                decode_buffer_view_into(target, mode, filter, count, stride, &source, ws)
            }
            // Refused as the views were read (`compressed_views`); a view
            // made otherwise is refused here too.
            (_, _, ViewFilter::Color) => {
                return Err(fail(
                    "has the COLOR filter, which only ATTRIBUTES of KHR_meshopt_compression may".into(),
                ));
            }
        };
        decoded.map_err(|e| fail(format!("does not decode: {e}")))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use meshoptimizer_rs::codec::{
        IndexEncoding, VertexEncoding, encode_filter_color, encode_index_buffer, encode_index_sequence,
        encode_vertex_buffer,
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
        for version in [0, 1] {
            let encoding = VertexEncoding::new(version, 2).unwrap();
            for stride in [4, 8, 12, 16, 36, 64, 128, 256] {
                for count in [1, 15, 16, 17, 63, 64, 65, 255, 256, 257, 1000, 4099] {
                    let what = format!("{count} vertices of {stride} bytes, version {version}");
                    let shortest = shortest_stream(Mode::Attributes, count, stride, version).unwrap();
                    let zeros = encode_vertex_buffer(&vec![0; count * stride], count, stride, encoding, &mut workspace);
                    assert_eq!(zeros.unwrap().len(), shortest, "{what}: zeros");
                    let noisy = encode_vertex_buffer(&noise(count * stride), count, stride, encoding, &mut workspace);
                    assert!(noisy.unwrap().len() >= shortest, "{what}: noise");
                }
            }
        }
        for encoding in [IndexEncoding::new(0).unwrap(), IndexEncoding::DEFAULT] {
            for triangles in [1, 2, 10, 1000] {
                let what = format!("{triangles} triangles, {encoding:?}");
                let shortest = shortest_stream(Mode::Triangles, 3 * triangles, 4, 0).unwrap();
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
                let shortest = shortest_stream(Mode::Indices, count, 4, 0).unwrap();
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
        let shortest = shortest_stream(Mode::Attributes, 256, 16, 0).unwrap() as u64;
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

    /// A document of one view of `count` elements of `stride` bytes whose
    /// `compressed` bytes lie at the start of buffer 0, decoded into
    /// buffer 1, under `extensions` (each given `extension`).
    fn one_view(extensions: &[&str], extension: Value, count: usize, stride: usize) -> Value {
        let mut view = serde_json::json!({"buffer": 1, "byteLength": count * stride, "extensions": {}});
        for name in extensions {
            view["extensions"][*name] = extension.clone();
        }
        serde_json::json!({"bufferViews": [view]})
    }

    #[test]
    fn khr_views_decode_version_1_streams_and_the_color_filter() {
        let mut workspace = Workspace::new(Limits::default());
        let colors: Vec<f32> = (0..64)
            .flat_map(|k| [k as f32 / 63.0, 0.5, 1.0 - k as f32 / 63.0, 1.0])
            .collect();
        let filtered = encode_filter_color(64, 4, 8, &colors, &mut workspace).unwrap();
        let version_1 = VertexEncoding::new(1, 2).unwrap();
        let stream = encode_vertex_buffer(&filtered, 64, 4, version_1, &mut workspace).unwrap();
        assert_eq!(stream[0], 0xa1, "a version 1 stream");
        let extension = serde_json::json!({
            "buffer": 0, "byteLength": stream.len(), "mode": "ATTRIBUTES", "filter": "COLOR", "count": 64, "byteStride": 4
        });
        let views = compressed_views(&one_view(&[KHR_MESHOPT], extension.clone(), 64, 4)).unwrap();
        let mut buffers = vec![stream.clone(), vec![0; 256]];
        decode(&mut buffers, &views, 1 << 20).unwrap();
        // Each colour back within 8 bits' rounding (RGBA as unsigned bytes).
        for (k, rgba) in buffers[1].chunks(4).enumerate() {
            for (c, &byte) in rgba.iter().enumerate() {
                let error = (f32::from(byte) / 255.0 - colors[4 * k + c]).abs();
                assert!(error <= 2.0 / 255.0, "colour {k} channel {c}: {byte}");
            }
        }
        // The EXT extension has neither the filter nor version 1, and a view
        // may not use both extensions.
        let e = compressed_views(&one_view(&[EXT_MESHOPT], extension.clone(), 64, 4)).unwrap_err();
        assert!(e.contains("EXT_meshopt_compression has an unknown 'filter'"), "{e}");
        let plain = serde_json::json!({
            "buffer": 0, "byteLength": stream.len(), "mode": "ATTRIBUTES", "count": 64, "byteStride": 4
        });
        let views = compressed_views(&one_view(&[EXT_MESHOPT], plain, 64, 4)).unwrap();
        let e = decode(&mut buffers, &views, 1 << 20).unwrap_err();
        assert!(e.contains("EXT_meshopt_compression does not decode"), "{e}");
        let e = compressed_views(&one_view(&[EXT_MESHOPT, KHR_MESHOPT], extension, 64, 4)).unwrap_err();
        assert!(e.contains("uses both"), "{e}");
    }
}
