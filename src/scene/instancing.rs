//! `EXT_mesh_gpu_instancing`, as gltfpack (`-mi`) and glTF-Transform
//! (`instance`) write it for forests, crowds and repeated buildings: a node
//! with a mesh draws it once per instance, each placed by the node's world
//! transform times the instance's own (translation × rotation × scale,
//! read from the accessors the extension's `attributes` name), and never
//! where the node itself stands. occlu makes an object of each instance,
//! as of any node: culling tests objects, and a batch of instances drawn
//! as one would hide nothing from the modes that cull.
//!
//! Departure from the extension: a rotation off unit length is
//! normalised, with one warning, as node rotations are (gltf.rs); custom
//! attributes (`_ID`, `_COLOR`) are not read.

use glam::{DAffine3, DQuat, DVec3};
use gltf::accessor::{DataType, Dimensions};
use serde_json::Value;

/// The extension's name, as files list it.
pub const INSTANCING: &str = "EXT_mesh_gpu_instancing";

/// Reads an accessor (by index) as elements of up to four components,
/// those it lacks 0, after checking it is of `dimensions` components of one
/// of `types` (what it is for named in errors).
pub type ReadAccessor<'a> = dyn Fn(usize, &str, &[DataType], Dimensions) -> Result<Vec<[f64; 4]>, String> + 'a;

/// How far from unit length an instance's rotation may be before its
/// normalising is warned of: beyond the rounding of a unit quaternion in
/// normalized 8-bit integers (4 components each within 1/254).
const UNIT_ROTATION_TOLERANCE: f64 = 0.01;

/// The instances of node `n` of the document `raw` (its JSON), where it has
/// a mesh and the extension: each instance's transform relative to the
/// node, and how many of their rotations were normalised from off unit
/// length.
pub fn of_node(raw: &Value, n: usize, read_accessor: &ReadAccessor) -> Result<Option<(Vec<DAffine3>, usize)>, String> {
    let node = &raw["nodes"][n];
    // No behaviour is defined for the extension on a node without a mesh.
    let Some(extension) = node["extensions"].get(INSTANCING).filter(|_| !node["mesh"].is_null()) else {
        return Ok(None);
    };
    let fail = |what: String| format!("node {n}: {INSTANCING} {what}");
    let attribute = |name: &str, types: &[DataType], dimensions| match &extension["attributes"][name] {
        Value::Null => Ok(None),
        index => {
            let index = index
                .as_u64()
                .and_then(|i| usize::try_from(i).ok())
                .ok_or_else(|| fail(format!("{name} is not an accessor index")))?;
            read_accessor(index, name, types, dimensions).map(Some).map_err(&fail)
        }
    };
    let float = [DataType::F32];
    let translations = attribute("TRANSLATION", &float, Dimensions::Vec3)?;
    let rotations = attribute(
        "ROTATION",
        &[DataType::F32, DataType::I8, DataType::I16],
        Dimensions::Vec4,
    )?;
    let scales = attribute("SCALE", &float, Dimensions::Vec3)?;
    let present = [&translations, &rotations, &scales].map(|a| a.as_ref().map(Vec::len));
    let mut counts = present.iter().flatten();
    let Some(&count) = counts.next() else {
        return Err(fail("names none of TRANSLATION, ROTATION and SCALE".into()));
    };
    if counts.any(|&c| c != count) {
        let [t, r, s] = present.map(|c| c.map_or("none".into(), |c| c.to_string()));
        return Err(fail(format!(
            "attributes differ in count (TRANSLATION {t}, ROTATION {r}, SCALE {s}); they must agree"
        )));
    }
    let mut normalised = 0;
    let mut transforms = Vec::with_capacity(count);
    for k in 0..count {
        let vector = |values: &Option<Vec<[f64; 4]>>, default: DVec3| {
            values
                .as_ref()
                .map_or(default, |v| DVec3::new(v[k][0], v[k][1], v[k][2]))
        };
        let translation = vector(&translations, DVec3::ZERO);
        let scale = vector(&scales, DVec3::ONE);
        let [x, y, z, w] = rotations.as_ref().map_or([0.0, 0.0, 0.0, 1.0], |r| r[k]);
        let rotation = DQuat::from_xyzw(x, y, z, w);
        if !(translation.is_finite() && scale.is_finite() && rotation.is_finite()) {
            return Err(fail(format!("instance {k}: its transform is not finite")));
        }
        let length = rotation.length();
        if length == 0.0 {
            return Err(fail(format!("instance {k}: rotation [0, 0, 0, 0] is not a rotation")));
        }
        normalised += usize::from((length - 1.0).abs() > UNIT_ROTATION_TOLERANCE);
        transforms.push(DAffine3::from_scale_rotation_translation(
            scale,
            rotation / length,
            translation,
        ));
    }
    Ok(Some((transforms, normalised)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use serde_json::json;

    /// Reads accessor k of `accessors` as given, refusing none.
    fn reading(
        accessors: Vec<Vec<[f64; 4]>>,
    ) -> impl Fn(usize, &str, &[DataType], Dimensions) -> Result<Vec<[f64; 4]>, String> {
        move |k, _, _, _| {
            accessors
                .get(k)
                .cloned()
                .ok_or_else(|| format!("accessor {k} does not exist"))
        }
    }

    fn node(attributes: serde_json::Value) -> Value {
        json!({"nodes": [{"mesh": 0, "extensions": {INSTANCING: {"attributes": attributes}}}, {"mesh": 0}]})
    }

    #[test]
    fn an_instance_is_placed_by_translation_times_rotation_times_scale() {
        let half = std::f64::consts::FRAC_1_SQRT_2;
        // Two instances: a quarter turn about y, scaled 2 along x then moved;
        // and one only moved.
        let read = reading(vec![
            vec![[10.0, 0.0, 0.0, 0.0], [0.0, 5.0, 0.0, 0.0]],
            vec![[0.0, half, 0.0, half], [0.0, 0.0, 0.0, 1.0]],
            vec![[2.0, 1.0, 1.0, 0.0], [1.0, 1.0, 1.0, 0.0]],
        ]);
        let raw = node(json!({"TRANSLATION": 0, "ROTATION": 1, "SCALE": 2}));
        assert!(of_node(&raw, 1, &read).unwrap().is_none(), "node 1 is not instanced");
        let (instances, normalised) = of_node(&raw, 0, &read).unwrap().unwrap();
        assert_eq!(normalised, 0);
        let [a, b] = instances[..] else { panic!("two instances") };
        // (1, 0, 0) scaled to (2, 0, 0), turned a quarter about y to
        // (0, 0, -2), moved by (10, 0, 0).
        assert!(
            a.transform_point3(DVec3::X)
                .abs_diff_eq(DVec3::new(10.0, 0.0, -2.0), 1e-12)
        );
        assert!(
            b.transform_point3(DVec3::X)
                .abs_diff_eq(DVec3::new(1.0, 5.0, 0.0), 1e-12)
        );
    }

    #[test]
    fn rotations_are_normalised_and_counted() {
        let read = reading(vec![vec![[0.0, 0.0, 0.0, 2.0], [0.0, 0.0, 0.0, 1.003]]]);
        let (instances, normalised) = of_node(&node(json!({"ROTATION": 0})), 0, &read).unwrap().unwrap();
        assert_eq!(normalised, 1, "only the rotation far off unit length is counted");
        for instance in &instances {
            assert!(
                instance.transform_point3(DVec3::X).abs_diff_eq(DVec3::X, 1e-12),
                "{instance}"
            );
        }
    }

    #[test]
    fn malformed_instances_are_refused_with_the_node_named() {
        let one = vec![[0.0, 0.0, 0.0, 1.0]];
        let refused = [
            (json!({}), vec![], "names none of TRANSLATION, ROTATION and SCALE"),
            (
                json!({"TRANSLATION": 0, "SCALE": 1}),
                vec![one.clone(), vec![one[0]; 2]],
                "TRANSLATION 1, ROTATION none, SCALE 2",
            ),
            (
                json!({"ROTATION": 0}),
                vec![vec![[0.0; 4]]],
                "instance 0: rotation [0, 0, 0, 0] is not a rotation",
            ),
            (
                json!({"SCALE": 0}),
                vec![vec![[f64::NAN, 1.0, 1.0, 0.0]]],
                "instance 0: its transform is not finite",
            ),
            (
                json!({"SCALE": "0"}),
                vec![one.clone()],
                "SCALE is not an accessor index",
            ),
            (json!({"SCALE": 3}), vec![one], "accessor 3 does not exist"),
        ];
        for (attributes, accessors, why) in refused {
            let e = of_node(&node(attributes), 0, &reading(accessors)).unwrap_err();
            assert!(
                e.starts_with("node 0: EXT_mesh_gpu_instancing") && e.contains(why),
                "{why}: {e}"
            );
        }
    }
}
