//! What summary.json holds ([`Summary`]): the run's adapter, scene, path and
//! every mode's statistics, versioned by [`SCHEMA_VERSION`].

use std::collections::HashMap;

use serde::{Deserialize, Serialize};

use crate::camera::path::CameraPath;
use crate::cull::{ModeId, Unrunnable};
use crate::gpu::{AdapterReport, Resolution};
use crate::hierarchy::{Hierarchy, HierarchyParams, HierarchyStats};
use crate::measure::{Distribution, FrameStats, MissedObject, ModeSummary, PairedRatio};
use crate::scene::up::{Up, UpAxis};
use crate::scene::{LoadPhases, Scene};

/// Bumped whenever a field of summary.json changes meaning or disappears
/// (adding fields does not bump it).
pub const SCHEMA_VERSION: u32 = 1;

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Summary {
    pub schema_version: u32,
    pub tool: ToolInfo,
    /// The run's name in a matrix (`occlu bench --config` with `runs`, or
    /// `--shard`): the same on every machine that ran it, so `occlu merge`
    /// knows which folders are one run on several adapters. Absent for a
    /// single run.
    #[serde(default)]
    pub run: Option<String>,
    /// Which matrix the run is of: folders of one run name from two
    /// matrices (a run added in front renames every later one) are not
    /// merged as one. Absent for a single run and in older files.
    #[serde(default)]
    pub matrix: Option<MatrixIdentity>,
    pub adapter: AdapterReport,
    pub scene: SceneSummary,
    pub path: PathSummary,
    pub resolution: Resolution,
    pub frames: u32,
    pub warmup: u32,
    pub error_measured: bool,
    pub modes: Vec<ModeSummary>,
    /// Modes the adapter could not run, with why.
    pub skipped: Vec<SkippedMode>,
    /// The parameter sweep, if any: its mode summaries are labelled
    /// `MODE[KEY=VALUE]`, in the order of `values`.
    pub sweep: Option<SweepSummary>,
    /// What the modes got wrong; every row is in missed.csv.
    #[serde(default)]
    pub missed: MissedSummary,
    /// frames.csv's fingerprint, set when the results are written (absent
    /// in files from before it existed, which are read unchecked).
    #[serde(default)]
    pub frames_csv: Option<Fingerprint>,
    /// The run's answer in one line (absent where no conservative mode ran,
    /// and in older files).
    #[serde(default)]
    pub verdict: Option<Verdict>,
    /// The animated flythrough beside the charts (`bench --animate`), by
    /// its file name; absent without one.
    #[serde(default)]
    pub animation: Option<String>,
}

impl Summary {
    /// The first of what a user sets (frames, resolution, warmup, cluster
    /// size, the parameters of the modes both ran) that `other` set
    /// differently, if any: what it is and each run's value. Runs of one
    /// workload set them alike.
    pub(super) fn settings_differing_from(&self, other: &Summary) -> Option<(&'static str, String, String)> {
        // Where both files record it.
        let clusters = |s: &Summary, other: &Summary| match (s.scene.cluster_triangles, other.scene.cluster_triangles) {
            (Some(triangles), Some(_)) => triangles.to_string(),
            _ => String::new(),
        };
        // Each parameter of a mode both ran that the two set differently,
        // as MODE.KEY=VALUE (or "not recorded", in a file from an occlu
        // that had no such parameter).
        let parameters = |s: &Summary, other: &Summary| {
            let mut differing = Vec::new();
            for (mode, theirs) in s
                .modes
                .iter()
                .filter_map(|m| Some((m, other.modes.iter().find(|o| o.name == m.name)?)))
            {
                let keys = |p: &serde_json::Value| {
                    p.as_object()
                        .map(|o| o.keys().cloned().collect::<Vec<_>>())
                        .unwrap_or_default()
                };
                let mut all = keys(&mode.parameters);
                all.extend(keys(&theirs.parameters));
                all.sort();
                all.dedup();
                for key in all
                    .iter()
                    .filter(|k| mode.parameters.get(k) != theirs.parameters.get(k))
                {
                    // A string shown bare unless the other run's value is
                    // no string (4 against "4" must read differently).
                    let their_value = theirs.parameters.get(key);
                    differing.push(match mode.parameters.get(key) {
                        Some(serde_json::Value::String(text))
                            if their_value.is_none_or(serde_json::Value::is_string) =>
                        {
                            format!("{}.{key}={text}", mode.name)
                        }
                        Some(value) => format!("{}.{key}={value}", mode.name),
                        None => format!("{}.{key} not recorded", mode.name),
                    });
                }
                if all.is_empty() && mode.parameters != theirs.parameters {
                    differing.push(format!("{} {}", mode.name, mode.parameters));
                }
            }
            differing.join(", ")
        };
        [
            ("frame counts", self.frames.to_string(), other.frames.to_string()),
            ("resolutions", self.resolution.to_string(), other.resolution.to_string()),
            ("warmup frames", self.warmup.to_string(), other.warmup.to_string()),
            (
                "cluster sizes (--cluster-triangles)",
                clusters(self, other),
                clusters(other, self),
            ),
            ("mode parameters", parameters(self, other), parameters(other, self)),
        ]
        .into_iter()
        .find(|(_, x, y)| x != y)
    }
}

/// The run's answer in one line: the fastest conservative mode, against
/// `vfc` and the oracle, how far the next fastest and `auto` are from it,
/// and whether the run tells them apart.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct Verdict {
    pub fastest: String,
    /// Its mean frame time.
    pub frame_ms: f64,
    pub speedup_vs_vfc: Option<f64>,
    pub ratio_to_oracle: Option<f64>,
    /// The next fastest conservative mode and its time over the fastest's,
    /// where another ran over enough frames for an interval
    /// ([`PairedRatio`]; absent in older files).
    #[serde(default)]
    pub runner_up: Option<RunnerUp>,
    /// `auto`'s mean and p95 frame times over the fastest's, where it ran.
    pub auto_ratio: Option<f64>,
    pub auto_p95_ratio: Option<f64>,
    /// The 95 % interval of `auto_ratio`, from the frames paired by their
    /// place on the path ([`PairedRatio`]; absent under four frames and in
    /// older files).
    #[serde(default)]
    pub auto_interval: Option<[f64; 2]>,
}

/// The next fastest conservative mode, its mean frame time over the
/// fastest's, and the 95 % interval of that ratio from the frames paired
/// by their place on the path: where it holds 1, the run does not tell the
/// two apart.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct RunnerUp {
    pub name: String,
    pub ratio: f64,
    pub interval: [f64; 2],
}

impl Verdict {
    /// From `modes`, each run as the mode of `ids` beside it, over the
    /// frames `rows`: the fastest by mean frame time of the conservative
    /// ones, leaving out the oracle (it knows the answer) and `auto` (it
    /// runs the others). The fastest of several modes is picked by the same
    /// frames that measure it, so among near equals the intervals against
    /// it lean a little its way.
    pub fn of(modes: &[ModeSummary], ids: &[ModeId], rows: &[FrameStats]) -> Option<Verdict> {
        let frame = |m: &ModeSummary| m.stats.get("frame_ms").copied();
        let mut ranked: Vec<(&ModeSummary, Distribution)> = modes
            .iter()
            .zip(ids)
            .filter(|(m, id)| m.conservative && !matches!(id, ModeId::Oracle | ModeId::Auto))
            .filter_map(|(m, _)| frame(m).map(|f| (m, f)))
            .collect();
        ranked.sort_by(|a, b| a.1.mean.total_cmp(&b.1.mean));
        let &(m, f) = ranked.first()?;
        let auto = modes
            .iter()
            .zip(ids)
            .find(|(_, id)| **id == ModeId::Auto)
            .map(|(a, _)| a);
        let against_fastest =
            |other: &ModeSummary| PairedRatio::of(&paired_frame_ms((rows, &other.name), (rows, &m.name)));
        let auto_frame = auto.and_then(frame);
        Some(Verdict {
            fastest: m.name.clone(),
            frame_ms: f.mean,
            speedup_vs_vfc: m.speedup_vs_vfc,
            ratio_to_oracle: m.ratio_to_oracle,
            runner_up: ranked.get(1).and_then(|(next, _)| {
                against_fastest(next).map(|r| RunnerUp {
                    name: next.name.clone(),
                    ratio: r.ratio,
                    interval: r.interval,
                })
            }),
            auto_ratio: auto_frame.map(|a| a.mean / f.mean),
            auto_p95_ratio: auto_frame.map(|a| a.p95 / f.p95),
            auto_interval: auto.and_then(against_fastest).map(|r| r.interval),
        })
    }
}

/// The frame times of mode `a` in rows `a_rows` and of mode `b` in rows
/// `b_rows` (two modes of one run, or one mode in two runs of one path),
/// in the frames both ran, paired by frame.
pub(super) fn paired_frame_ms(
    (a_rows, a): (&[FrameStats], &str),
    (b_rows, b): (&[FrameStats], &str),
) -> Vec<(f64, f64)> {
    let of_b: HashMap<u32, f64> = b_rows
        .iter()
        .filter(|r| r.mode == b)
        .map(|r| (r.frame, r.frame_ms))
        .collect();
    a_rows
        .iter()
        .filter(|r| r.mode == a)
        .filter_map(|r| of_b.get(&r.frame).map(|&y| (r.frame_ms, y)))
        .collect()
}

/// The head of missed.csv, for report.md and machines.
#[derive(Clone, Debug, Default, Serialize, Deserialize, PartialEq)]
pub struct MissedSummary {
    /// Rows in missed.csv (0: no mode got anything wrong, and no file).
    pub rows: usize,
    /// The first [`MissedSummary::SHOWN`] of them.
    pub first: Vec<MissedObject>,
}

impl MissedSummary {
    /// Rows report.md lists.
    pub const SHOWN: usize = 10;

    pub fn of(missed: &[MissedObject]) -> MissedSummary {
        MissedSummary {
            rows: missed.len(),
            first: missed.iter().take(Self::SHOWN).cloned().collect(),
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct SkippedMode {
    pub mode: String,
    pub reason: String,
}

impl From<Unrunnable> for SkippedMode {
    fn from(skipped: Unrunnable) -> SkippedMode {
        SkippedMode {
            mode: skipped.mode.to_string(),
            reason: skipped.reason,
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct SweepSummary {
    pub mode: String,
    pub key: String,
    pub values: Vec<String>,
}

impl SweepSummary {
    pub fn label(&self, value: &str) -> String {
        format!("{}[{}={value}]", self.mode, self.key)
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct ToolInfo {
    pub name: String,
    pub version: String,
}

impl ToolInfo {
    pub fn current() -> ToolInfo {
        ToolInfo {
            name: env!("CARGO_PKG_NAME").into(),
            version: env!("CARGO_PKG_VERSION").into(),
        }
    }
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct SceneSummary {
    #[serde(flatten)]
    pub facts: SceneFacts,
    pub hierarchy_params: HierarchyParams,
    pub upload_ms: f64,
    /// The most triangles of a mesh's cluster (`--cluster-triangles`): it
    /// sets the objects the modes cull (absent in files from before it was
    /// recorded).
    #[serde(default)]
    pub cluster_triangles: Option<u32>,
}

/// What `occlu info` says of a scene, and summary.json records.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct SceneFacts {
    pub source: String,
    pub objects: usize,
    pub meshes: usize,
    pub triangles: u64,
    pub vertices: usize,
    pub bounds_min: [f64; 3],
    pub bounds_max: [f64; 3],
    pub hierarchy: HierarchyStats,
    /// Objects that move from frame to frame.
    #[serde(default)]
    pub movers: usize,
    /// The geometry as loaded ([`Fingerprint::of_scene`]): what makes two
    /// runs' scenes the same wherever their files lay (absent in files from
    /// before it was recorded).
    #[serde(default)]
    pub geometry: Option<Fingerprint>,
    /// The up axis generated paths and the overview use, and why.
    #[serde(default)]
    pub up: Up,
    /// The file's own cameras (glTF).
    #[serde(default)]
    pub cameras: Vec<CameraFact>,
    /// The file's animations (glTF).
    #[serde(default)]
    pub animations: Vec<AnimationFact>,
    pub warnings: Vec<String>,
    pub load_ms: f64,
    pub build_ms: f64,
    /// Where `load_ms` went (absent in files from before it was recorded).
    #[serde(default)]
    pub load_phases: LoadPhases,
}

impl SceneFacts {
    pub fn of(scene: &Scene, hierarchy: &Hierarchy, load_ms: f64, build_ms: f64) -> SceneFacts {
        SceneFacts {
            source: scene.source.clone(),
            objects: scene.objects.len(),
            meshes: scene.meshes.len(),
            triangles: scene.triangles(),
            vertices: scene.vertices.len(),
            bounds_min: scene.bounds.min.to_array(),
            bounds_max: scene.bounds.max.to_array(),
            hierarchy: hierarchy.stats(),
            movers: scene.movers.len(),
            geometry: Some(Fingerprint::of_scene(scene)),
            up: scene.up.clone(),
            cameras: scene
                .cameras
                .iter()
                .map(|c| CameraFact {
                    name: c.name.clone(),
                    node: c.node,
                    projection: c.projection.to_string(),
                    fov_y_deg: c.pose.fov_y_deg,
                    near: c.pose.near,
                })
                .collect(),
            animations: scene
                .animations
                .iter()
                .map(|a| AnimationFact {
                    name: a.name.clone(),
                    channels: a.channels,
                    duration: a.duration,
                    camera: a.camera.as_ref().map(|c| c.name.clone()),
                })
                .collect(),
            warnings: scene.warnings.clone(),
            load_ms,
            build_ms,
            load_phases: scene.phases,
        }
    }
}

/// A camera of the model file, as `info` lists it.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct CameraFact {
    pub name: String,
    pub node: usize,
    pub projection: String,
    pub fov_y_deg: Option<f64>,
    pub near: Option<f64>,
}

/// An animation of the model file, as `info` lists it.
#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct AnimationFact {
    pub name: String,
    pub channels: usize,
    /// Seconds.
    pub duration: f64,
    /// The camera it moves, if any.
    pub camera: Option<String>,
}

#[derive(Clone, Debug, Serialize, Deserialize, PartialEq)]
pub struct PathSummary {
    pub source: String,
    pub keyframes: usize,
    pub near: f64,
    /// For a generated path: why it is the kind it is, and what a walk
    /// rests on.
    #[serde(default)]
    pub generated: Option<String>,
    /// Frames with a surface closer to the eye than the near plane's
    /// corners (clipped geometry shows what lies behind it; the generated
    /// paths aim for 0).
    #[serde(default)]
    pub frames_with_geometry_within_near: Option<u32>,
    /// The cameras the run replayed ([`Fingerprint::of_path`]), which the
    /// source's name alone does not pin down (absent in older files).
    #[serde(default)]
    pub cameras: Option<Fingerprint>,
}

/// A matrix: how many runs it has and the FNV-1a hash of their names in
/// order, one a line. The names hold each run's place, scene and path, and
/// are the same on every machine, so every shard records the same identity.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
pub struct MatrixIdentity {
    pub runs: usize,
    #[serde(with = "hex64")]
    pub names: u64,
}

impl MatrixIdentity {
    /// The most runs one matrix may list: past it, two long lists
    /// multiplied by mistake are likelier than a plan, and checking them
    /// would take long.
    pub const MAX_RUNS: usize = 10_000;

    /// The digits of a run's place in its folder's name (`02`): as many as
    /// a matrix of `runs` runs needs, and at least two.
    pub fn place_width(runs: usize) -> usize {
        runs.to_string().len().max(2)
    }

    pub fn of<'a>(names: impl IntoIterator<Item = &'a str>) -> MatrixIdentity {
        let mut h = Fnv1a::new();
        let mut runs = 0;
        for name in names {
            h.write(name.as_bytes());
            h.write(b"\n");
            runs += 1;
        }
        MatrixIdentity {
            runs,
            names: h.finish().fnv1a,
        }
    }
}

impl std::fmt::Display for MatrixIdentity {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        write!(
            f,
            "a matrix of {} #{:016x}",
            crate::text::count(self.runs, "run"),
            self.names
        )
    }
}

/// What identifies a frames.csv: its length and FNV-1a hash. Not a defence
/// against forgery, only against a file from another run or cut short.
#[derive(Clone, Copy, Debug, Serialize, Deserialize, PartialEq, Eq)]
pub struct Fingerprint {
    pub bytes: u64,
    /// FNV-1a (64 bits) of the file, in hex.
    #[serde(with = "hex64")]
    pub fnv1a: u64,
}

impl Fingerprint {
    pub fn of(bytes: &[u8]) -> Fingerprint {
        let mut hasher = Fnv1a::new();
        hasher.write(bytes);
        hasher.finish()
    }

    /// A scene's geometry as loaded: vertices, indices, each mesh's range
    /// and each object's mesh and transform, and how many objects move.
    /// Names, warnings and where the file lay do not count: the same model
    /// read on two machines gives the same fingerprint (parsing and placing
    /// a file's geometry is exact arithmetic, the same on every platform).
    ///
    /// A built-in scene is made with sin/cos, whose last bits the
    /// platform's maths library decides, so its floats would tell a macOS
    /// or Windows run from a Linux one: for it, its canonical spec (its
    /// `source`) and occlu's version stand in for the floats; its integers
    /// (indices, ranges, meshes) still count.
    pub fn of_scene(scene: &Scene) -> Fingerprint {
        let mut h = Fnv1a::new();
        let made_with_trigonometry = scene.source.starts_with("builtin:");
        h.write(&(scene.vertices.len() as u64).to_le_bytes());
        if made_with_trigonometry {
            h.write(scene.source.as_bytes());
            h.write(env!("CARGO_PKG_VERSION").as_bytes());
        } else {
            for v in &scene.vertices {
                for c in v {
                    h.write(&c.to_le_bytes());
                }
            }
        }
        h.write(&(scene.indices.len() as u64).to_le_bytes());
        for i in &scene.indices {
            h.write(&i.to_le_bytes());
        }
        for m in &scene.meshes {
            h.write(&m.first_index.to_le_bytes());
            h.write(&m.index_count.to_le_bytes());
        }
        for o in &scene.objects {
            h.write(&o.mesh.to_le_bytes());
            if !made_with_trigonometry {
                for c in o.transform.to_cols_array() {
                    h.write(&c.to_le_bytes());
                }
            }
        }
        h.write(&(scene.movers.len() as u64).to_le_bytes());
        h.finish()
    }

    /// A camera path as replayed: its keyframes, near plane, interpolation
    /// and frame count (a resampled path is another path). A generated path
    /// (`generated:KIND`) is made with sin/cos from its scene: for it, its
    /// kind, its keyframe count and occlu's version stand in for the
    /// keyframes' and near plane's floats (its scene is compared on its
    /// own, and generation is the same arithmetic everywhere), with the
    /// scene's `up`, which generation follows and the scene's fingerprint
    /// does not hold.
    pub fn of_path(path: &CameraPath, up: UpAxis) -> Fingerprint {
        let mut h = Fnv1a::new();
        if path.source.starts_with("generated:") {
            h.write(path.source.as_bytes());
            h.write(up.to_string().as_bytes());
            h.write(env!("CARGO_PKG_VERSION").as_bytes());
            h.write(&(path.keyframes.len() as u64).to_le_bytes());
        } else {
            for k in &path.keyframes {
                let numbers = [k.time, k.fov_y]
                    .into_iter()
                    .chain(k.position.to_array())
                    .chain(k.rotation.to_array());
                for n in numbers {
                    h.write(&n.to_le_bytes());
                }
            }
            h.write(&path.near.to_le_bytes());
        }
        h.write(format!("{:?}", path.interpolation).as_bytes());
        h.write(&path.frames.to_le_bytes());
        h.finish()
    }
}

/// Whether `other` is `base` where both are means of a deterministic
/// counter (sums of integers over the same frame count n): equal but for
/// the rounding of the division, a few steps of f64 of `base` (or of 1,
/// below it). Sums that differ give means at least 1/n apart, far more
/// wherever the sums are below 2^50 (a looser tolerance, 1e-9, took one
/// triangle more in 3 000 frames of 417 000 for the same count).
pub(super) fn same_count(base: f64, other: f64) -> bool {
    (other - base).abs() <= 4.0 * f64::EPSILON * base.abs().max(1.0)
}

/// FNV-1a (64 bits), fed piece by piece, counting the bytes it was fed.
struct Fnv1a {
    hash: u64,
    bytes: u64,
}

impl Fnv1a {
    fn new() -> Fnv1a {
        Fnv1a {
            hash: 0xcbf2_9ce4_8422_2325,
            bytes: 0,
        }
    }

    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.hash = (self.hash ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
        }
        self.bytes += bytes.len() as u64;
    }

    fn finish(&self) -> Fingerprint {
        Fingerprint {
            bytes: self.bytes,
            fnv1a: self.hash,
        }
    }
}

/// A u64 as a hex string, which JSON readers that hold numbers in doubles
/// keep whole.
mod hex64 {
    use serde::{Deserialize, Deserializer, Serializer};

    pub fn serialize<S: Serializer>(v: &u64, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&format!("{v:016x}"))
    }

    pub fn deserialize<'de, D: Deserializer<'de>>(d: D) -> Result<u64, D::Error> {
        let text = String::deserialize(d)?;
        u64::from_str_radix(&text, 16).map_err(serde::de::Error::custom)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::generate::default_path;
    use crate::scene::{LoadOptions, SceneSpec, load, load_bytes};

    /// Moves the last bit of the first vertex and of the first object's
    /// transform, as another platform's sin/cos may.
    fn nudged(scene: &Scene) -> Scene {
        let mut other = scene.clone();
        other.vertices[0][0] = other.vertices[0][0].next_up();
        other.objects[0].transform.translation.x = other.objects[0].transform.translation.x.next_up();
        other
    }

    /// A review's finding: one triangle more in one of 3 000 frames that
    /// draw 417 000 each was the same count to a tolerance of 1e-9 of the
    /// mean; a count of one more over the run is another count, and the
    /// same sum over the same frames is the same.
    #[test]
    fn one_more_in_a_long_run_is_another_count() {
        let (sum, frames) = (1_251_037_000u64, 3_000u64);
        let mean = |sum: u64| sum as f64 / frames as f64;
        assert!(same_count(mean(sum), mean(sum)));
        assert!(!same_count(mean(sum), mean(sum + 1)));
        assert!(!same_count(mean(sum + 1), mean(sum)));
        // A billion a frame over 8 frames, and below 1.
        assert!(!same_count(1e9, 1e9 + 1.0 / 8.0));
        assert!(!same_count(0.0, 1.0 / 3000.0));
    }

    #[test]
    fn built_in_scenes_and_generated_paths_fingerprint_by_what_made_them_files_by_their_numbers() {
        let city = load(&SceneSpec::Builtin("city:blocks=1".into()), &LoadOptions::default()).unwrap();
        assert_eq!(Fingerprint::of_scene(&nudged(&city)), Fingerprint::of_scene(&city));
        let other_city = load(
            &SceneSpec::Builtin("city:blocks=1,seed=2".into()),
            &LoadOptions::default(),
        )
        .unwrap();
        assert_ne!(Fingerprint::of_scene(&other_city), Fingerprint::of_scene(&city));

        let obj = "o a\nv 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n";
        let model = load_bytes(std::path::Path::new("tri.obj"), obj.as_bytes(), &LoadOptions::default()).unwrap();
        assert_ne!(Fingerprint::of_scene(&nudged(&model)), Fingerprint::of_scene(&model));

        let (generated, _) = default_path(&city).unwrap();
        let mut moved = generated.clone();
        moved.keyframes[0].position.x = moved.keyframes[0].position.x.next_up();
        moved.near = moved.near.next_up();
        let of_path = |path: &CameraPath| Fingerprint::of_path(path, UpAxis::Y);
        assert_eq!(of_path(&moved), of_path(&generated));
        assert_ne!(of_path(&generated.clone().with_frames(7).unwrap()), of_path(&generated));
        // Generated for a scene Z up (`--up z`), the same kind of path is
        // another path.
        assert_ne!(Fingerprint::of_path(&generated, UpAxis::Z), of_path(&generated));
        let file = CameraPath {
            source: "fly.json".into(),
            ..generated.clone()
        };
        let mut moved_file = file.clone();
        moved_file.keyframes[0].position.x = moved_file.keyframes[0].position.x.next_up();
        assert_ne!(of_path(&moved_file), of_path(&file));
        // A file keeps its own up, which its keyframes' rotations hold.
        assert_eq!(Fingerprint::of_path(&file, UpAxis::Z), of_path(&file));
    }

    /// summary.json's numbers read back as written: merge and compare
    /// recompute from files read back (serde_json's float_roundtrip).
    #[test]
    fn numbers_written_to_json_read_back_to_the_last_bit() {
        let drifted = (1..20_000u32)
            .map(|k| f64::from(k) / 3.0e4 + 2.0)
            .filter(|&x| serde_json::from_str::<f64>(&serde_json::to_string(&x).unwrap()).unwrap() != x)
            .count();
        assert_eq!(drifted, 0);
    }

    #[test]
    fn the_verdict_names_the_next_fastest_and_whether_the_run_tells_it_and_auto_from_the_fastest() {
        // Along a path whose views vary by ±40 %: roc, ioc as dear, and
        // auto 10 % dearer, each in ±4 % noise; vfc twice roc. Which of roc
        // and ioc is faster is the noise's draw.
        let mut rng = crate::rng::Rng::new(5);
        let modes = [("vfc", 2.0), ("roc", 1.0), ("ioc", 1.0), ("auto", 1.1)];
        let rows: Vec<FrameStats> = (0..120u32)
            .flat_map(|frame| {
                let view = 20.0 * (1.0 + 0.4 * (f64::from(frame) / 9.0).sin());
                modes
                    .map(|(mode, cost)| FrameStats {
                        frame,
                        frame_ms: cost * view * rng.range(0.96, 1.04),
                        ..FrameStats::blank(mode)
                    })
                    .to_vec()
            })
            .collect();
        let descriptions: Vec<crate::measure::ModeDescription> = modes
            .iter()
            .map(|(name, _)| crate::measure::ModeDescription {
                name: (*name).into(),
                conservative: true,
                parameters: serde_json::json!({}),
            })
            .collect();
        let summaries = crate::measure::summarize(&rows, &descriptions, 100);
        let ids = [ModeId::Vfc, ModeId::Roc, ModeId::Ioc, ModeId::Auto];
        let v = Verdict::of(&summaries, &ids, &rows).unwrap();
        let mean = |k: usize| summaries[k].stats["frame_ms"].mean;
        let (fastest, next_fastest) = if mean(1) <= mean(2) { (1, 2) } else { (2, 1) };
        assert_eq!(v.fastest, modes[fastest].0);
        let next = v.runner_up.as_ref().unwrap();
        assert_eq!(next.name, modes[next_fastest].0);
        assert!(
            (next.ratio - mean(next_fastest) / mean(fastest)).abs() < 1e-12,
            "{next:?}"
        );
        assert!(next.interval[0] <= 1.0 && 1.0 <= next.interval[1], "{next:?}");
        let [low, high] = v.auto_interval.unwrap();
        assert!(1.0 < low && low < 1.1 && 1.1 < high, "{low}–{high}");
        let line = crate::report::markdown::verdict_line(&v);
        let runner_up = format!("{} takes {:.2}× its time (95 % interval", next.name, next.ratio);
        assert!(line.contains(&runner_up), "{line}");
        assert!(line.contains("not told apart in this run"), "{line}");
        assert!(
            line.contains(&format!("auto takes 1.10× its time (95 % interval {low:.2}–{high:.2}")),
            "{line}"
        );
    }
}
