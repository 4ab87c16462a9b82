//! A glTF file's JSON as written, for what occlu reads that the gltf crate
//! does not keep: the extensions it decodes itself (Draco, meshopt,
//! instancing), whether a file uses one without declaring it
//! ([`ExtensionSites`]), and the asset version of a file the crate cannot
//! parse.

use std::borrow::Cow;

use serde::Deserialize;
use serde::de::{DeserializeOwned, DeserializeSeed, Deserializer, IgnoredAny, MapAccess, SeqAccess, Visitor};
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

/// Keys whose numbers (directly, or in an array) are indices into one of
/// the document's arrays: glTF 2.0's `glTFid` properties, and those of the
/// extensions occlu reads or the crate knows.
const INDEX_KEYS: [&str; 20] = [
    "scene",
    "nodes",
    "children",
    "mesh",
    "camera",
    "skin",
    "joints",
    "skeleton",
    "inverseBindMatrices",
    "indices",
    "material",
    "bufferView",
    "buffer",
    "sampler",
    "source",
    "index",
    "node",
    "input",
    "output",
    "light",
];

/// Keys whose object's every member is an index, whatever its name: a
/// primitive's, a morph target's or an extension's vertex attributes.
const ATTRIBUTE_KEYS: [&str; 2] = ["attributes", "targets"];

/// What one of gltf-json's structs takes per JSON object it is read from,
/// at most, the growth of the vector holding it included: three million
/// empty materials (`{}`, 3 bytes each) took 2.15 GB at the peak, 716
/// bytes each, the most of the kinds measured (three million empty nodes
/// 318 bytes each).
const BYTES_PER_OBJECT: u64 = 720;

/// Refuses, before the gltf crate reads it, a document's JSON `text` that
/// the crate would read wrong, or at a cost out of all proportion to the
/// text, in one pass with everything else skipped (`extras` too, which the
/// crate keeps as text):
/// - an index past u32: gltf-json keeps only its low 32 bits
///   (`"mesh": 4294967296` would draw mesh 0), so it is named with its
///   line and column;
/// - more JSON objects than `memory` (the bytes this process may still
///   take, where known) holds at [`BYTES_PER_OBJECT`]: each becomes a
///   struct of hundreds of bytes, where the text may spend two on it.
///
/// Text that is not JSON passes: the crate says what is wrong with it.
pub fn check_reading_cost(text: &[u8], memory: Option<u64>) -> Result<(), String> {
    let mut census = Census::default();
    let scanned = Scan {
        key: Key::Other,
        census: &mut census,
    }
    .deserialize(&mut serde_json::Deserializer::from_slice(text));
    match (scanned, census.wrapped_index) {
        (Err(e), true) => return Err(format!("invalid glTF: {e}")),
        (Err(_), false) | (Ok(()), _) => {}
    }
    let needed = census.objects.saturating_mul(BYTES_PER_OBJECT);
    match memory {
        Some(memory) if needed > memory => Err(format!(
            "its JSON holds {} objects, which would take about {} MB to read, and this process may take {} MB more",
            census.objects,
            needed >> 20,
            memory >> 20
        )),
        _ => Ok(()),
    }
}

#[derive(Default)]
struct Census {
    objects: u64,
    /// Whether the scan stopped at an index past u32.
    wrapped_index: bool,
}

/// What a value's key says of the numbers in it.
#[derive(Clone, Copy)]
enum Key {
    Index(&'static str),
    /// Its object's members are indices.
    Attributes(&'static str),
    /// Kept by the crate as text, and skipped.
    Extras,
    Other,
}

impl Key {
    fn named(name: &str) -> Key {
        let known = |keys: &[&'static str]| keys.iter().copied().find(|&k| k == name);
        match name {
            "extras" => Key::Extras,
            _ => known(&INDEX_KEYS)
                .map(Key::Index)
                .or_else(|| known(&ATTRIBUTE_KEYS).map(Key::Attributes))
                .unwrap_or(Key::Other),
        }
    }
}

/// One JSON value of the document, under `key`.
struct Scan<'c> {
    key: Key,
    census: &'c mut Census,
}

impl<'de> DeserializeSeed<'de> for Scan<'_> {
    type Value = ();
    fn deserialize<D: Deserializer<'de>>(self, deserializer: D) -> Result<(), D::Error> {
        match self.key {
            Key::Extras => IgnoredAny::deserialize(deserializer).map(drop),
            _ => deserializer.deserialize_any(self),
        }
    }
}

/// A member's key, as what it says of its value's numbers.
struct KeySeed;

impl<'de> DeserializeSeed<'de> for KeySeed {
    type Value = Key;
    fn deserialize<D: Deserializer<'de>>(self, deserializer: D) -> Result<Key, D::Error> {
        deserializer.deserialize_str(self)
    }
}

impl<'de> Visitor<'de> for KeySeed {
    type Value = Key;
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a key")
    }
    fn visit_str<E>(self, name: &str) -> Result<Key, E> {
        Ok(Key::named(name))
    }
}

impl<'de> Visitor<'de> for Scan<'_> {
    type Value = ();
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("any JSON value")
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        self.census.objects += 1;
        while let Some(key) = map.next_key_seed(KeySeed)? {
            let key = match self.key {
                Key::Attributes(name) => Key::Index(name),
                _ => key,
            };
            map.next_value_seed(Scan {
                key,
                census: &mut *self.census,
            })?;
        }
        Ok(())
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        while seq
            .next_element_seed(Scan {
                key: self.key,
                census: &mut *self.census,
            })?
            .is_some()
        {}
        Ok(())
    }
    fn visit_u64<E: serde::de::Error>(self, value: u64) -> Result<(), E> {
        match self.key {
            Key::Index(name) if value > u64::from(u32::MAX) => {
                self.census.wrapped_index = true;
                Err(E::custom(format_args!(
                    "`{name}` holds the index {value}, past the largest a glTF reader keeps ({})",
                    u32::MAX
                )))
            }
            _ => Ok(()),
        }
    }
    fn visit_bool<E>(self, _: bool) -> Result<(), E> {
        Ok(())
    }
    fn visit_i64<E>(self, _: i64) -> Result<(), E> {
        Ok(())
    }
    fn visit_f64<E>(self, _: f64) -> Result<(), E> {
        Ok(())
    }
    fn visit_str<E>(self, _: &str) -> Result<(), E> {
        Ok(())
    }
    fn visit_unit<E>(self) -> Result<(), E> {
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const CUBE_NODE: &str = r#"{"asset": {"version": "2.0"}, "nodes": [{"mesh": MESH}], "meshes": [{"primitives": [{"attributes": {"POSITION": POSITION}, "extras": {"mesh": 4294967296}}]}]}"#;

    fn document(mesh: &str, position: &str) -> String {
        CUBE_NODE.replace("MESH", mesh).replace("POSITION", position)
    }

    #[test]
    fn an_index_past_u32_is_refused_by_its_key_and_place_and_extras_are_left_alone() {
        assert_eq!(check_reading_cost(document("0", "1").as_bytes(), None), Ok(()));
        assert_eq!(check_reading_cost(document("4294967295", "1").as_bytes(), None), Ok(()));
        let wrapped = check_reading_cost(document("4294967296", "1").as_bytes(), None).unwrap_err();
        assert!(
            wrapped.contains("`mesh` holds the index 4294967296") && wrapped.contains("line 1 column"),
            "{wrapped}"
        );
        let attribute = check_reading_cost(document("0", "8589934592").as_bytes(), None).unwrap_err();
        assert!(
            attribute.contains("`attributes` holds the index 8589934592"),
            "{attribute}"
        );
        // Not an index, and not JSON: left to the crate.
        let count = r#"{"asset": {"version": "2.0"}, "buffers": [{"byteLength": 8589934592}]}"#;
        assert_eq!(check_reading_cost(count.as_bytes(), None), Ok(()));
        assert_eq!(check_reading_cost(b"{\"nodes\": [", None), Ok(()));
    }

    #[test]
    fn a_document_of_more_objects_than_memory_holds_is_refused_by_their_count() {
        let nodes = format!(
            r#"{{"asset": {{"version": "2.0"}}, "nodes": [{}]}}"#,
            vec!["{}"; 999].join(",")
        );
        // The document, the asset and 999 nodes.
        let needed = 1001 * BYTES_PER_OBJECT;
        assert_eq!(check_reading_cost(nodes.as_bytes(), Some(needed)), Ok(()));
        let refused = check_reading_cost(nodes.as_bytes(), Some(needed - 1)).unwrap_err();
        assert!(refused.starts_with("its JSON holds 1001 objects"), "{refused}");
    }
}
