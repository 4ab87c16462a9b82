//! A glTF file's JSON as written, for what occlu reads that the gltf crate
//! does not keep: the extensions it decodes itself (Draco, meshopt,
//! instancing), whether a file uses one without declaring it
//! ([`ExtensionSites`]), and the asset version of a file the crate cannot
//! parse.

use std::borrow::Cow;

use serde::Deserialize;
use serde::de::{DeserializeOwned, Deserializer, IgnoredAny, MapAccess, SeqAccess, Visitor};
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

/// A glTF file's JSON text ([`text`]) read as `T`: the whole document as
/// written (a [`Value`]), or its [`ExtensionSites`].
pub fn parsed<T: DeserializeOwned>(text: &[u8]) -> Result<T, String> {
    serde_json::from_slice(text).map_err(|e| format!("invalid glTF JSON: {e}"))
}

/// A JSON array's items; none where it is not one.
pub fn list(value: &Value) -> &[Value] {
    value.as_array().map_or(&[], Vec::as_slice)
}

/// The objects of a glTF document that may carry an extension occlu reads
/// from the JSON (primitives, nodes, buffer views and buffers), each with
/// the names of its extensions: read from the text with the rest of the
/// document skipped, as the gltf crate skips what it does not know (deep
/// `extras`, numbers beyond f64), so that any file the crate reads reads
/// here, and names are compared as JSON decodes them (escapes included).
#[derive(Debug, Default, Deserialize)]
#[serde(default)]
pub struct ExtensionSites {
    pub meshes: Vec<MeshSites>,
    pub nodes: Vec<Site>,
    #[serde(rename = "bufferViews")]
    pub buffer_views: Vec<Site>,
    pub buffers: Vec<Site>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(default)]
pub struct MeshSites {
    pub primitives: Vec<Site>,
}

#[derive(Debug, Default, Deserialize)]
#[serde(default)]
pub struct Site {
    pub extensions: ExtensionNames,
}

/// The keys of an `extensions` object; none where it is anything else.
#[derive(Debug, Default)]
pub struct ExtensionNames(pub Vec<String>);

impl<'de> Deserialize<'de> for ExtensionNames {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        struct Names;
        impl<'de> Visitor<'de> for Names {
            type Value = ExtensionNames;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("any JSON value")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<ExtensionNames, A::Error> {
                let mut names = Vec::new();
                while let Some((name, IgnoredAny)) = map.next_entry::<String, IgnoredAny>()? {
                    names.push(name);
                }
                Ok(ExtensionNames(names))
            }
            fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<ExtensionNames, A::Error> {
                while seq.next_element::<IgnoredAny>()?.is_some() {}
                Ok(ExtensionNames::default())
            }
            fn visit_bool<E>(self, _: bool) -> Result<ExtensionNames, E> {
                Ok(ExtensionNames::default())
            }
            fn visit_i64<E>(self, _: i64) -> Result<ExtensionNames, E> {
                Ok(ExtensionNames::default())
            }
            fn visit_u64<E>(self, _: u64) -> Result<ExtensionNames, E> {
                Ok(ExtensionNames::default())
            }
            fn visit_f64<E>(self, _: f64) -> Result<ExtensionNames, E> {
                Ok(ExtensionNames::default())
            }
            fn visit_str<E>(self, _: &str) -> Result<ExtensionNames, E> {
                Ok(ExtensionNames::default())
            }
            fn visit_unit<E>(self) -> Result<ExtensionNames, E> {
                Ok(ExtensionNames::default())
            }
        }
        deserializer.deserialize_any(Names)
    }
}
