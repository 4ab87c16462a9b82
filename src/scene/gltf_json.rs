//! A glTF file's JSON as written, for what occlu reads that the gltf crate
//! does not keep: the extensions it decodes itself (Draco, meshopt,
//! instancing), whether a file uses one without declaring it, and the
//! asset version of a file the crate cannot parse.

use std::borrow::Cow;

use serde_json::Value;

/// The JSON text of a glTF file: a GLB's JSON chunk, or the whole file.
pub fn text(bytes: &[u8]) -> Result<Cow<'_, [u8]>, String> {
    match bytes.starts_with(b"glTF") {
        true => Ok(gltf::Glb::from_slice(bytes)
            .map_err(|e| format!("invalid GLB: {e}"))?
            .json),
        false => Ok(Cow::Borrowed(bytes)),
    }
}

/// The document of a glTF file, as written.
pub fn document(bytes: &[u8]) -> Result<Value, String> {
    serde_json::from_slice(&text(bytes)?).map_err(|e| format!("invalid glTF JSON: {e}"))
}

/// A JSON array's items; none where it is not one.
pub fn list(value: &Value) -> &[Value] {
    value.as_array().map_or(&[], Vec::as_slice)
}
