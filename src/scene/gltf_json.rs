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
use serde_json::value::RawValue;

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
/// the document's arrays: glTF 2.0's `glTFid` properties.
const INDEX_KEYS: [&str; 19] = [
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
];

/// Keys whose object's every member is an index, whatever its name: a
/// primitive's or a morph target's vertex attributes.
const ATTRIBUTE_KEYS: [&str; 2] = ["attributes", "targets"];

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

/// What a number or string in an array takes, at most, where the crate
/// keeps it as a [`Value`] (an accessor's `min` and `max`) and in the
/// document read as one: 32 bytes, in a vector growing to twice its length
/// while its old buffer is still held (40 million zeros in one `min`, 80 MB
/// of text, asked for a 2 GB buffer beside the 1 GB one).
const BYTES_PER_ARRAY_VALUE: u64 = 96;

/// What one takes in the crate's typed arrays, at most, worked out (not
/// measured): an index of `children` or `joints` (4 bytes, in a vector
/// growing as above), a number of a fixed array inside its struct (none
/// beyond the struct).
const BYTES_PER_TYPED_VALUE: u64 = 12;

/// What the document read as a [`Value`] takes per byte of the text the
/// crate keeps as text or skips (`extras`, `extensions`), at most, worked
/// out (not measured): a number of one digit and its comma become a
/// 32-byte value, in a vector growing as above.
const VALUE_BYTES_PER_SKIPPED_BYTE: u64 = 48;

/// The JSON of a glTF document, counted for its memory read, which is out
/// of proportion to its text: objects, as elements of its top-level arrays
/// or nested in them; numbers and strings in arrays, where the crate keeps
/// them as JSON (`min` and `max`) or not; the bytes it keeps as text or
/// skips.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct JsonCounts {
    items: u64,
    nested: u64,
    values_kept_as_json: u64,
    typed_values: u64,
    skipped_bytes: u64,
}

impl JsonCounts {
    /// Refused when reading the document as the gltf crate's structs would
    /// take more than `memory`, the bytes this process may still take
    /// (where known): each object becomes a struct of hundreds of bytes,
    /// where the text may spend two on it.
    pub fn check_as_structs(&self, memory: Option<u64>) -> Result<(), String> {
        let bytes = self.items.saturating_mul(BYTES_PER_ITEM)
            + self.nested.saturating_mul(BYTES_PER_NESTED)
            + self.values_kept_as_json.saturating_mul(BYTES_PER_ARRAY_VALUE)
            + self.typed_values.saturating_mul(BYTES_PER_TYPED_VALUE);
        self.check(bytes, memory, "")
    }

    /// Refused when reading the document as a [`Value`] too (done where
    /// it uses an extension occlu reads from its JSON) would take more
    /// than `memory`.
    pub fn check_as_value(&self, memory: Option<u64>) -> Result<(), String> {
        let bytes = (self.items + self.nested).saturating_mul(BYTES_PER_VALUE_OBJECT)
            + (self.values_kept_as_json + self.typed_values).saturating_mul(BYTES_PER_ARRAY_VALUE)
            + self.skipped_bytes.saturating_mul(VALUE_BYTES_PER_SKIPPED_BYTE);
        self.check(bytes, memory, " as written (for the extensions read from it)")
    }

    fn check(&self, bytes: u64, memory: Option<u64>, reading: &str) -> Result<(), String> {
        match memory {
            Some(memory) if bytes > memory => Err(format!(
                "its JSON holds {} and {} in arrays, which would take up to {} MB to read{reading}, and this process may take {} MB more",
                crate::text::count((self.items + self.nested) as usize, "object"),
                crate::text::count((self.values_kept_as_json + self.typed_values) as usize, "value"),
                bytes >> 20,
                memory >> 20
            )),
            _ => Ok(()),
        }
    }
}

/// A document's JSON `text` read before the gltf crate reads it, in one
/// pass with `extras` and `extensions` skipped (the crate keeps them as
/// text or JSON, or occlu reads their indices whole): what costs memory
/// counted, and an index past u32 refused, named with its line and column:
/// gltf-json keeps only its low 32 bits (`"mesh": 4294967296` would draw
/// mesh 0). Text this pass cannot read is refused too: a number beyond
/// f64, a lone surrogate, bytes that are not UTF-8 or arrays nested deeper
/// than 128, outside `extras` and `extensions`. The crate skips them in a
/// member it does not know (and refuses them elsewhere); read here, they
/// would end the pass before an index it must see.
pub fn census(text: &[u8]) -> Result<JsonCounts, String> {
    let mut counts = JsonCounts::default();
    Scan {
        key: Key::Other,
        depth: 0,
        in_array: false,
        counts: &mut counts,
    }
    .deserialize(&mut serde_json::Deserializer::from_slice(text))
    .map_err(|e| format!("invalid glTF: {e}"))?;
    Ok(counts)
}

/// What a value's key says of the numbers in it.
#[derive(Clone, Copy)]
enum Key {
    Index(&'static str),
    /// Its numbers are kept by the crate as JSON (`min`, `max`).
    KeptAsJson,
    /// Its object's members are indices.
    Attributes(&'static str),
    /// Kept by the crate as text or as JSON, or read by occlu from the
    /// JSON with its indices checked whole (Draco, meshopt, instancing),
    /// or bearing on no geometry (lights): skipped.
    Skipped,
    Other,
}

/// One JSON value of the document, under `key`, inside `depth` arrays and
/// objects, the innermost an array or not.
struct Scan<'c> {
    key: Key,
    depth: u32,
    in_array: bool,
    counts: &'c mut JsonCounts,
}

impl Scan<'_> {
    /// A number or string: counted where it lies in an array.
    fn scalar<E>(self) -> Result<(), E> {
        let count = u64::from(self.in_array);
        match self.key {
            Key::KeptAsJson => self.counts.values_kept_as_json += count,
            _ => self.counts.typed_values += count,
        }
        Ok(())
    }
}

impl<'de> DeserializeSeed<'de> for Scan<'_> {
    type Value = ();
    fn deserialize<D: Deserializer<'de>>(self, deserializer: D) -> Result<(), D::Error> {
        match self.key {
            Key::Skipped => {
                let skipped = <&RawValue>::deserialize(deserializer)?;
                self.counts.skipped_bytes += skipped.get().len() as u64;
                Ok(())
            }
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
            _ if name == "extras" || name == "extensions" => Key::Skipped,
            _ if name == "min" || name == "max" => Key::KeptAsJson,
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
            0..=2 => self.counts.items += 1,
            _ => self.counts.nested += 1,
        }
        while let Some(key) = map.next_key_seed(KeySeed { parent: self.key })? {
            map.next_value_seed(Scan {
                key,
                depth: self.depth + 1,
                in_array: false,
                counts: &mut *self.counts,
            })?;
        }
        Ok(())
    }
    fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<(), A::Error> {
        while seq
            .next_element_seed(Scan {
                key: self.key,
                depth: self.depth + 1,
                in_array: true,
                counts: &mut *self.counts,
            })?
            .is_some()
        {}
        Ok(())
    }
    fn visit_u64<E: serde::de::Error>(self, value: u64) -> Result<(), E> {
        match self.key {
            Key::Index(name) if value > u64::from(u32::MAX) => Err(E::custom(format_args!(
                "`{name}` holds the index {value}, past the largest a glTF reader keeps ({}), in its JSON",
                u32::MAX
            ))),
            _ => self.scalar(),
        }
    }
    fn visit_bool<E>(self, _: bool) -> Result<(), E> {
        self.scalar()
    }
    fn visit_i64<E>(self, _: i64) -> Result<(), E> {
        self.scalar()
    }
    fn visit_f64<E>(self, _: f64) -> Result<(), E> {
        self.scalar()
    }
    fn visit_str<E>(self, _: &str) -> Result<(), E> {
        self.scalar()
    }
    fn visit_unit<E>(self) -> Result<(), E> {
        self.scalar()
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
        // Escaped keys, morph targets and arrays of indices.
        let escaped = document("0", "1").replace(r#""mesh": 0"#, r#""\u006desh": 4294967296"#);
        assert!(refused(&escaped).contains("`mesh` holds"), "{escaped}");
        let targets = r#"{"meshes": [{"primitives": [{"targets": [{"NORMAL": 4294967300}]}]}]}"#;
        assert!(refused(targets).contains("`targets` holds"));
        assert!(refused(r#"{"nodes": [{"children": [1, 4294967296]}]}"#).contains("`children` holds"));
        // Not indices: a count; extras and extensions (where anything goes,
        // or occlu reads the indices whole).
        let light = r#"{"nodes": [{"extensions": {"KHR_lights_punctual": {"light": 4294967296}}}]}"#;
        for kept in [
            r#"{"asset": {"version": "2.0"}, "buffers": [{"byteLength": 8589934592}]}"#,
            r#"{"nodes": [{"extras": {"big": 1e400}, "extensions": {"ACME_ids": {"index": 8589934592, "at": 1e400}}}]}"#,
            light,
        ] {
            assert!(census(kept.as_bytes()).is_ok(), "{kept}");
        }
        // What the pass cannot read ahead of an index is refused (it would
        // end the pass before the index), and so is text that is not JSON.
        for unreadable in [
            r#"{"zzz": 1e400, "nodes": [{"mesh": 4294967296}]}"#,
            r#"{"zzz": "\ud800", "nodes": [{"mesh": 4294967296}]}"#,
            "{\"nodes\": [",
        ] {
            assert!(
                census(unreadable.as_bytes()).unwrap_err().starts_with("invalid glTF: "),
                "{unreadable}"
            );
        }
    }

    #[test]
    fn a_document_of_more_objects_and_array_values_than_memory_holds_is_refused_by_their_count() {
        let nodes = format!(
            r#"{{"asset": {{"version": "2.0"}}, "nodes": [{}], "accessors": [{{"min": [0, 0, 0], "extras": [1, 2]}}]}}"#,
            vec![r#"{"x": {"y": {}}, "children": [1, 2]}"#; 999].join(",")
        );
        let counts = census(nodes.as_bytes()).unwrap();
        // The document, the asset, 999 nodes and an accessor, two objects
        // nested in each node; two children a node, three minimums kept
        // as JSON, and the six bytes of `[1, 2]` skipped.
        let expected = JsonCounts {
            items: 1002,
            nested: 1998,
            values_kept_as_json: 3,
            typed_values: 1998,
            skipped_bytes: 6,
        };
        assert_eq!(counts, expected);
        let as_structs =
            1002 * BYTES_PER_ITEM + 1998 * BYTES_PER_NESTED + 3 * BYTES_PER_ARRAY_VALUE + 1998 * BYTES_PER_TYPED_VALUE;
        assert!(counts.check_as_structs(Some(as_structs)).is_ok());
        let refused = counts.check_as_structs(Some(as_structs - 1)).unwrap_err();
        assert!(
            refused.starts_with("its JSON holds 3000 objects and 2001 values in arrays"),
            "{refused}"
        );
        let as_value = 3000 * BYTES_PER_VALUE_OBJECT + 2001 * BYTES_PER_ARRAY_VALUE + 6 * VALUE_BYTES_PER_SKIPPED_BYTE;
        assert!(counts.check_as_value(Some(as_value)).is_ok());
        assert!(counts.check_as_value(Some(as_value - 1)).is_err());
        assert!(counts.check_as_structs(None).is_ok());
    }
}
