//! A glTF file's JSON as written, for what occlu reads that the gltf crate
//! does not keep: the extensions it decodes itself (Draco, meshopt,
//! instancing), whether a file uses one without declaring it
//! ([`ExtensionSites`]), and the asset version of a file the crate cannot
//! parse; and, before the crate reads it, what the crate would read wrong
//! or at a cost out of proportion to the text ([`census`]).

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

/// Extensions whose members are scanned for indices, by the prefix of
/// their names: Khronos' and the multi-vendor ones, which the crate or
/// occlu read with their indices. Another vendor's extension is kept by
/// the crate as JSON, where a number under a key such as `index` may be
/// anything, so it is skipped.
const SCANNED_EXTENSIONS: [&str; 2] = ["KHR_", "EXT_"];

/// What one of gltf-json's structs takes per element of the document's
/// top-level arrays (a node, a material), at most, the growth of the
/// vector holding it included: three million empty materials (`{}`, 3
/// bytes each) took 2.15 GB at the peak, 716 bytes each, the most of the
/// kinds measured (empty nodes 318–417 bytes).
const BYTES_PER_ITEM: u64 = 720;

/// What the crate takes per object nested in an element, at most: a
/// million materials each with a texture (`pbrMetallicRoughness` and
/// `baseColorTexture` nested) took 105 bytes per nested object beyond
/// the empty material's, meshes of one primitive with its attributes 57.
const BYTES_PER_NESTED: u64 = 128;

/// What an object takes read as a [`Value`] (a map holding a few members
/// allocates a node of room for eleven), at most: a million nodes each
/// with a name took 720 bytes more read as one too.
const BYTES_PER_VALUE_OBJECT: u64 = 720;

/// The JSON objects of a glTF document, counted where their memory is
/// decided: elements of its top-level arrays, and objects nested in them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JsonObjects {
    items: u64,
    nested: u64,
}

impl JsonObjects {
    /// Refused when reading the document as the gltf crate's structs would
    /// take more than `memory`, the bytes this process may still take
    /// (where known): each object becomes a struct of hundreds of bytes,
    /// where the text may spend two on it.
    pub fn check_as_structs(&self, memory: Option<u64>) -> Result<(), String> {
        let bytes = self.items.saturating_mul(BYTES_PER_ITEM) + self.nested.saturating_mul(BYTES_PER_NESTED);
        self.check(bytes, memory, "")
    }

    /// Refused when reading the document as a [`Value`] too (done where
    /// it uses an extension occlu reads from its JSON) would take more
    /// than `memory`.
    pub fn check_as_value(&self, memory: Option<u64>) -> Result<(), String> {
        let bytes = (self.items + self.nested).saturating_mul(BYTES_PER_VALUE_OBJECT);
        self.check(bytes, memory, " as written (for the extensions read from it)")
    }

    fn check(&self, bytes: u64, memory: Option<u64>, reading: &str) -> Result<(), String> {
        match memory {
            Some(memory) if bytes > memory => Err(format!(
                "its JSON holds {} objects, which would take up to {} MB to read{reading}, and this process may take {} MB more",
                self.items + self.nested,
                bytes >> 20,
                memory >> 20
            )),
            _ => Ok(()),
        }
    }
}

/// A document's JSON `text` read before the gltf crate reads it, in one
/// pass with everything but what it looks for skipped (`extras` too,
/// which the crate keeps as text): its objects counted, and an index past
/// u32 refused, named with its line and column: gltf-json keeps only its
/// low 32 bits (`"mesh": 4294967296` would draw mesh 0). Text that is not
/// JSON passes: the crate says what is wrong with it.
pub fn census(text: &[u8]) -> Result<JsonObjects, String> {
    let mut census = Census::default();
    let scanned = Scan {
        key: Key::Other,
        depth: 0,
        census: &mut census,
    }
    .deserialize(&mut serde_json::Deserializer::from_slice(text));
    match (scanned, census.wrapped_index) {
        (Err(e), true) => Err(format!("invalid glTF: {e}")),
        (Err(_), false) | (Ok(()), _) => Ok(census.objects),
    }
}

#[derive(Default)]
struct Census {
    objects: JsonObjects,
    /// Whether the scan stopped at an index past u32.
    wrapped_index: bool,
}

/// What a value's key says of the numbers in it.
#[derive(Clone, Copy)]
enum Key {
    Index(&'static str),
    /// Its object's members are indices.
    Attributes(&'static str),
    /// Its object's members are extensions.
    Extensions,
    /// Kept by the crate as text or as JSON, and skipped.
    Skipped,
    Other,
}

/// One JSON value of the document, under `key`, inside `depth` arrays and
/// objects.
struct Scan<'c> {
    key: Key,
    depth: u32,
    census: &'c mut Census,
}

impl<'de> DeserializeSeed<'de> for Scan<'_> {
    type Value = ();
    fn deserialize<D: Deserializer<'de>>(self, deserializer: D) -> Result<(), D::Error> {
        match self.key {
            Key::Skipped => IgnoredAny::deserialize(deserializer).map(drop),
            _ => deserializer.deserialize_any(self),
        }
    }
}

/// The key of a member of an object under `parent`, as what it says of
/// its value's numbers.
struct KeySeed {
    parent: Key,
}

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
        let known = |keys: &[&'static str]| keys.iter().copied().find(|&k| k == name);
        Ok(match self.parent {
            Key::Attributes(attributes) => Key::Index(attributes),
            Key::Extensions if SCANNED_EXTENSIONS.iter().any(|p| name.starts_with(p)) => Key::Other,
            Key::Extensions => Key::Skipped,
            _ if name == "extras" => Key::Skipped,
            _ if name == "extensions" => Key::Extensions,
            _ => known(&INDEX_KEYS)
                .map(Key::Index)
                .or_else(|| known(&ATTRIBUTE_KEYS).map(Key::Attributes))
                .unwrap_or(Key::Other),
        })
    }
}

impl<'de> Visitor<'de> for Scan<'_> {
    type Value = ();
    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("any JSON value")
    }
    fn visit_map<A: MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
        // The document, its members and their arrays' elements are items.
        match self.depth {
            0..=2 => self.census.objects.items += 1,
            _ => self.census.objects.nested += 1,
        }
        while let Some(key) = map.next_key_seed(KeySeed { parent: self.key })? {
            map.next_value_seed(Scan {
                key,
                depth: self.depth + 1,
                census: &mut *self.census,
            })?;
        }
        Ok(())
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        while seq
            .next_element_seed(Scan {
                key: self.key,
                depth: self.depth + 1,
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
                    "`{name}` holds the index {value}, past the largest a glTF reader keeps ({}), in its JSON",
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

    fn refused(text: &str) -> String {
        census(text.as_bytes()).expect_err("an index past u32")
    }

    #[test]
    fn an_index_past_u32_is_refused_by_its_key_and_place_and_what_the_crate_keeps_as_json_is_left_alone() {
        assert!(census(document("0", "1").as_bytes()).is_ok());
        assert!(census(document("4294967295", "1").as_bytes()).is_ok());
        let wrapped = refused(&document("4294967296", "1"));
        assert!(
            wrapped.contains("`mesh` holds the index 4294967296") && wrapped.contains("in its JSON at line 1 column"),
            "{wrapped}"
        );
        assert!(refused(&document("0", "8589934592")).contains("`attributes` holds the index 8589934592"));
        // Escaped keys, morph targets, arrays of indices, and extensions
        // the crate or occlu read.
        let escaped = document("0", "1").replace(r#""mesh": 0"#, r#""\u006desh": 4294967296"#);
        assert!(refused(&escaped).contains("`mesh` holds"), "{escaped}");
        let targets = r#"{"meshes": [{"primitives": [{"targets": [{"NORMAL": 4294967300}]}]}]}"#;
        assert!(refused(targets).contains("`targets` holds"));
        assert!(refused(r#"{"nodes": [{"children": [1, 4294967296]}]}"#).contains("`children` holds"));
        let light = r#"{"nodes": [{"extensions": {"KHR_lights_punctual": {"light": 4294967296}}}]}"#;
        assert!(refused(light).contains("`light` holds"));
        // Not indices: a count, extras, a vendor's extension, and text that
        // is not JSON (left to the crate).
        for kept in [
            r#"{"asset": {"version": "2.0"}, "buffers": [{"byteLength": 8589934592}]}"#,
            r#"{"nodes": [{"extensions": {"ACME_ids": {"index": 8589934592}}}]}"#,
            "{\"nodes\": [",
        ] {
            assert!(census(kept.as_bytes()).is_ok(), "{kept}");
        }
    }

    #[test]
    fn a_document_of_more_objects_than_memory_holds_is_refused_by_their_count() {
        let nodes = format!(
            r#"{{"asset": {{"version": "2.0"}}, "nodes": [{}]}}"#,
            vec![r#"{"extensions": {"EXT_x": {}}}"#; 999].join(",")
        );
        let objects = census(nodes.as_bytes()).unwrap();
        // The document, the asset and 999 nodes; two objects nested in each.
        assert_eq!(
            objects,
            JsonObjects {
                items: 1001,
                nested: 1998
            }
        );
        let as_structs = 1001 * BYTES_PER_ITEM + 1998 * BYTES_PER_NESTED;
        assert!(objects.check_as_structs(Some(as_structs)).is_ok());
        let refused = objects.check_as_structs(Some(as_structs - 1)).unwrap_err();
        assert!(refused.starts_with("its JSON holds 2999 objects"), "{refused}");
        let as_value = 2999 * BYTES_PER_VALUE_OBJECT;
        assert!(objects.check_as_value(Some(as_value)).is_ok());
        assert!(objects.check_as_value(Some(as_value - 1)).is_err());
        assert!(objects.check_as_structs(None).is_ok());
    }
}
