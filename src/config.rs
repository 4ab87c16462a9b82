//! Run configuration: the options of `occlu bench`, from a JSON file
//! (`--config`, samples in configs/; read by `matrix::Matrix`,
//! since a file may list several runs) and from flags, which win. Relative
//! paths in a file are relative to the file.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::cull::{FULL_CALIBRATION_WARM_UPS, ModeError, ModeId, ModeParams, parse_modes};
use crate::gpu::{BackendChoice, Resolution};
use crate::input::ByteSize;
use crate::scene::builtin::with_movers;
use crate::scene::up::UpChoice;
use crate::scene::{LoadOptions, SceneSpec};

/// Every field optional: a file or the flags may give any subset.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BenchConfig {
    /// An OBJ, glTF or GLB file.
    pub model: Option<PathBuf>,
    /// A built-in scene, `NAME[:key=value,...]`.
    pub scene: Option<String>,
    /// Moving objects added to a built-in scene (its `movers` parameter).
    pub movers: Option<u32>,
    /// A camera path file; generated from the scene when absent.
    pub path: Option<PathBuf>,
    /// Mode names, or "all".
    pub modes: Option<Vec<String>>,
    /// Frames to record (resamples the path).
    pub frames: Option<u32>,
    /// Frames run before recording starts.
    pub warmup: Option<u32>,
    pub resolution: Option<Resolution>,
    pub backend: Option<BackendChoice>,
    /// Output directory.
    pub out: Option<PathBuf>,
    /// Measure image error against the reference (default true).
    pub error: Option<bool>,
    /// Meshes above this many triangles are split into clusters.
    pub cluster_triangles: Option<u32>,
    /// Largest model or glTF buffer file read ("8G", "512M").
    pub max_file_size: Option<ByteSize>,
    /// glTF buffers may lie outside the model's folder.
    pub external_buffers: Option<bool>,
    /// The scene's up axis ("z", "-y", "auto").
    pub up: Option<UpChoice>,
    /// Also write the run for github-action-benchmark here.
    pub export_github_benchmark: Option<PathBuf>,
    /// Also write the run's timeline here (Trace Event JSON).
    pub trace: Option<PathBuf>,
    /// Also write an animated flythrough of every mode beside the charts.
    pub animate: Option<bool>,
    /// Mode parameters, `MODE.KEY=VALUE`.
    pub params: Option<Vec<String>>,
    /// One mode at several values of one parameter, `MODE.KEY=V1,V2,...`.
    pub sweep: Option<String>,
}

/// Warm-up frames where none are set: as many as calibrate `auto` fully
/// ([`FULL_CALIBRATION_WARM_UPS`]: ten, eight of them calibrating), where
/// the default of five before calibrated it on three views:
/// each mode pays five frames more before recording, and `auto`, which
/// runs every candidate in a warm-up frame, a few times that.
pub const DEFAULT_WARMUP: u32 = FULL_CALIBRATION_WARM_UPS;
/// Warm-up frames beyond this are surely a mistake.
pub const MAX_WARMUP: u32 = 10_000;
pub const DEFAULT_OUT: &str = "occlu-out";
pub const DEFAULT_SCENE: &str = "city";

#[derive(Debug, thiserror::Error)]
pub enum ConfigError {
    #[error("{path}: {error}")]
    Io { path: String, error: std::io::Error },
    #[error("{path}: invalid run configuration: {message}")]
    Json { path: String, message: String },
    /// What the fields of the configuration file at `path` make wrong.
    #[error("{path}: {error}")]
    InFile { path: String, error: Box<ConfigError> },
    #[error("give a model file or --scene, not both")]
    ModelAndScene,
    #[error("--movers animates built-in scenes; a model file has no movers")]
    MoversOnModel,
    // Flags and a --config file's fields are merged before they are
    // checked, so these name both.
    #[error(
        "frames (--frames, or \"frames\" in a --config file) must be in 1..={}",
        crate::camera::path::MAX_FRAMES
    )]
    Frames,
    #[error("warmup (--warmup, or \"warmup\" in a --config file) must be at most {MAX_WARMUP}")]
    Warmup,
    #[error(transparent)]
    Mode(#[from] ModeError),
    #[error("--sweep '{0}' is not MODE.KEY=V1,V2,...")]
    Sweep(String),
    #[error("--sweep and --param both set {0}: the sweep sets it run by run, so give it in one of them")]
    SweptAndSet(String),
    #[error("--sweep names {key}={value} twice: each value runs once")]
    SweptTwice { key: String, value: String },
    #[error("--sweep gives {0} values, and at most {MAX_SWEEP_VALUES} run in one interleaved run: split it into runs")]
    SweepTooLong(usize),
}

/// A configuration file's JSON, read within [`crate::input::TEXT_LIMIT`];
/// an object that names a key twice is refused (a JSON value keeps the
/// last, so a second `"frames"` would silently win over the first).
pub fn read_json(path: &Path) -> Result<serde_json::Value, ConfigError> {
    let text = crate::input::read_text(path, crate::input::TEXT_LIMIT).map_err(|error| ConfigError::Io {
        path: path.display().to_string(),
        error,
    })?;
    serde_json::from_str::<Unique>(&text)
        .map(|json| json.0)
        .map_err(|e| invalid(path, "", &e))
}

/// A JSON value whose objects name each key once.
struct Unique(serde_json::Value);

impl<'de> Deserialize<'de> for Unique {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Unique, D::Error> {
        d.deserialize_any(UniqueVisitor).map(Unique)
    }
}

struct UniqueVisitor;

impl<'de> serde::de::Visitor<'de> for UniqueVisitor {
    type Value = serde_json::Value;

    fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        f.write_str("a JSON value")
    }

    fn visit_bool<E>(self, v: bool) -> Result<serde_json::Value, E> {
        Ok(v.into())
    }

    fn visit_i64<E>(self, v: i64) -> Result<serde_json::Value, E> {
        Ok(v.into())
    }

    fn visit_u64<E>(self, v: u64) -> Result<serde_json::Value, E> {
        Ok(v.into())
    }

    fn visit_f64<E>(self, v: f64) -> Result<serde_json::Value, E> {
        Ok(v.into())
    }

    fn visit_str<E>(self, v: &str) -> Result<serde_json::Value, E> {
        Ok(v.into())
    }

    fn visit_unit<E>(self) -> Result<serde_json::Value, E> {
        Ok(serde_json::Value::Null)
    }

    fn visit_seq<A: serde::de::SeqAccess<'de>>(self, mut seq: A) -> Result<serde_json::Value, A::Error> {
        let mut items = Vec::new();
        while let Some(Unique(item)) = seq.next_element()? {
            items.push(item);
        }
        Ok(items.into())
    }

    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<serde_json::Value, A::Error> {
        let mut fields = serde_json::Map::new();
        while let Some(key) = map.next_key::<String>()? {
            if fields.contains_key(&key) {
                return Err(serde::de::Error::custom(format_args!("duplicate field `{key}`")));
            }
            let Unique(value) = map.next_value()?;
            fields.insert(key, value);
        }
        Ok(fields.into())
    }
}

/// `json` (a whole file, or the part `at` names, such as `runs[2]: `) as
/// the type it should be, or the one-line error that names where it fails.
pub fn from_json<T: serde::de::DeserializeOwned>(
    path: &Path,
    at: &str,
    json: serde_json::Value,
) -> Result<T, ConfigError> {
    serde_path_to_error::deserialize(json).map_err(|e| {
        // The field whose value is wrong (`frames`, `runs[1].modes`), up to
        // the field a message names itself ("unknown field `runs`, ...");
        // `.` is the whole.
        let whole = e.path().to_string();
        let named = e.path().iter().next_back().map(ToString::to_string);
        let field = match named {
            Some(last) if e.inner().to_string().contains(&format!("`{last}`")) => {
                whole.strip_suffix(&last).unwrap_or(&whole).trim_end_matches('.')
            }
            _ => whole.as_str(),
        };
        let at = match field {
            "" | "." => at.to_string(),
            field => format!("{at}{field}: "),
        };
        invalid(path, &at, e.inner())
    })
}

fn invalid(path: &Path, at: &str, e: &serde_json::Error) -> ConfigError {
    ConfigError::Json {
        path: path.display().to_string(),
        message: format!("{at}{e}"),
    }
}

/// The scene a model file, a built-in scene (the city when neither is
/// given) and a mover count name together.
pub fn scene_spec(
    model: Option<PathBuf>,
    scene: Option<String>,
    movers: Option<u32>,
) -> Result<SceneSpec, ConfigError> {
    match (model, scene) {
        (Some(_), Some(_)) => Err(ConfigError::ModelAndScene),
        (Some(_), None) if movers.is_some() => Err(ConfigError::MoversOnModel),
        (Some(model), None) => Ok(SceneSpec::File(model)),
        (None, scene) => {
            let spec = scene.unwrap_or_else(|| DEFAULT_SCENE.into());
            Ok(SceneSpec::Builtin(match movers {
                Some(n) => with_movers(&spec, n),
                None => spec,
            }))
        }
    }
}

/// A complete, validated plan for one bench run.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchPlan {
    pub scene: SceneSpec,
    pub path: Option<PathBuf>,
    pub modes: Vec<ModeId>,
    pub params: ModeParams,
    pub sweep: Option<Sweep>,
    pub frames: Option<u32>,
    pub warmup: u32,
    pub resolution: Resolution,
    pub backend: BackendChoice,
    pub out: PathBuf,
    pub measure_error: bool,
    pub load: LoadOptions,
    /// Also write the run in github-action-benchmark's format here.
    pub export_github_benchmark: Option<PathBuf>,
    /// Also write the run's timeline here, in the Trace Event format.
    pub trace: Option<PathBuf>,
    /// Also write an animated flythrough of every mode beside the charts.
    pub animate: bool,
    /// The run's name in a matrix (summary.json's `run`); `None` for a
    /// single run.
    pub run: Option<String>,
    /// The matrix the run is of (summary.json's `matrix`).
    pub matrix: Option<crate::report::MatrixIdentity>,
}

impl BenchConfig {
    /// `self` with its relative paths taken as relative to the folder of
    /// the configuration file `file`; an empty one, which would name that
    /// folder, is refused (the flags take none), naming the field after
    /// `at`.
    pub fn relative_to(mut self, file: &Path, at: &str) -> Result<BenchConfig, ConfigError> {
        let base = file.parent().unwrap_or(Path::new(""));
        for (name, p) in [
            ("model", &mut self.model),
            ("path", &mut self.path),
            ("out", &mut self.out),
            ("trace", &mut self.trace),
            ("export_github_benchmark", &mut self.export_github_benchmark),
        ] {
            let Some(p) = p else { continue };
            if p.as_os_str().is_empty() {
                return Err(ConfigError::Json {
                    path: file.display().to_string(),
                    message: format!("{at}{name}: an empty path names no file"),
                });
            }
            if p.is_relative() {
                *p = base.join(&*p);
            }
        }
        Ok(self)
    }

    /// `self` with every unset field taken from `fallback`. A model or scene
    /// given here replaces both of the fallback's, so a flag can switch a
    /// configured scene to a model; a model drops the fallback's movers
    /// too (a model has none), while a scene keeps them (a matrix's
    /// top-level movers are every scene's).
    pub fn or(self, fallback: BenchConfig) -> BenchConfig {
        let (source_given, model_given) = (self.model.is_some() || self.scene.is_some(), self.model.is_some());
        BenchConfig {
            model: if source_given { self.model } else { fallback.model },
            scene: if source_given { self.scene } else { fallback.scene },
            movers: if model_given {
                self.movers
            } else {
                self.movers.or(fallback.movers)
            },
            path: self.path.or(fallback.path),
            modes: self.modes.or(fallback.modes),
            frames: self.frames.or(fallback.frames),
            warmup: self.warmup.or(fallback.warmup),
            resolution: self.resolution.or(fallback.resolution),
            backend: self.backend.or(fallback.backend),
            out: self.out.or(fallback.out),
            error: self.error.or(fallback.error),
            cluster_triangles: self.cluster_triangles.or(fallback.cluster_triangles),
            max_file_size: self.max_file_size.or(fallback.max_file_size),
            external_buffers: self.external_buffers.or(fallback.external_buffers),
            up: self.up.or(fallback.up),
            export_github_benchmark: self.export_github_benchmark.or(fallback.export_github_benchmark),
            trace: self.trace.or(fallback.trace),
            animate: self.animate.or(fallback.animate),
            sweep: self.sweep.or(fallback.sweep),
            // Per key, a flag wins over the file; a key given twice in one
            // of them is refused when the parameters are parsed (so the
            // file's entries of a key it repeats are kept).
            params: match (fallback.params, self.params) {
                (Some(file), Some(flags)) => {
                    let key = |item: &String| item.split_once('=').map(|(k, _)| k.trim().to_string());
                    let set: Vec<Option<String>> = flags.iter().map(key).collect();
                    let in_file: Vec<Option<String>> = file.iter().map(key).collect();
                    let overridden =
                        |k: &Option<String>| set.contains(k) && in_file.iter().filter(|f| *f == k).count() == 1;
                    let mut kept: Vec<String> = file.into_iter().filter(|item| !overridden(&key(item))).collect();
                    kept.extend(flags);
                    Some(kept)
                }
                (file, flags) => flags.or(file),
            },
        }
    }

    /// Fills defaults and validates.
    pub fn plan(self) -> Result<BenchPlan, ConfigError> {
        let scene = scene_spec(self.model, self.scene, self.movers)?;
        if self
            .frames
            .is_some_and(|n| n == 0 || n > crate::camera::path::MAX_FRAMES)
        {
            return Err(ConfigError::Frames);
        }
        if self.warmup.is_some_and(|n| n > MAX_WARMUP) {
            return Err(ConfigError::Warmup);
        }
        let mut modes = parse_modes(&self.modes.unwrap_or_else(|| vec!["all".into()]))?;
        let sweep = self.sweep.as_deref().map(Sweep::parse).transpose()?;
        if let Some(s) = &sweep
            && !modes.contains(&s.mode)
        {
            modes.push(s.mode);
        }
        let items = self.params.unwrap_or_default();
        let params = ModeParams::parse(&items, &modes)?;
        if let Some(s) = &sweep {
            let key = format!("{}.{}", s.mode, s.key);
            if params.is_set(&key) {
                return Err(ConfigError::SweptAndSet(key));
            }
            for (i, value) in s.values.iter().enumerate() {
                // Each value with the other parameters, as it will run: a
                // mode's check may weigh one parameter against another
                // (ioc's start depth must lie above its bottom depth).
                let with: Vec<String> = items.iter().cloned().chain([format!("{key}={value}")]).collect();
                ModeParams::parse(&with, &modes)?;
                if s.values[..i].iter().any(|earlier| same_value(earlier, value)) {
                    return Err(ConfigError::SweptTwice {
                        key,
                        value: value.clone(),
                    });
                }
            }
        }
        Ok(BenchPlan {
            scene,
            path: self.path,
            params,
            sweep,
            modes,
            frames: self.frames,
            warmup: self.warmup.unwrap_or(DEFAULT_WARMUP),
            resolution: self.resolution.unwrap_or(Resolution::DEFAULT),
            backend: self.backend.unwrap_or_default(),
            out: self.out.unwrap_or_else(|| DEFAULT_OUT.into()),
            measure_error: self.error.unwrap_or(true),
            load: load_options(
                self.cluster_triangles,
                self.max_file_size,
                self.external_buffers,
                self.up,
            ),
            export_github_benchmark: self.export_github_benchmark,
            trace: self.trace,
            animate: self.animate.unwrap_or(false),
            run: None,
            matrix: None,
        })
    }
}

/// How a scene is loaded, from what the command line or a config file set
/// (the defaults for the rest).
pub fn load_options(
    cluster_triangles: Option<u32>,
    max_file_size: Option<ByteSize>,
    external_buffers: Option<bool>,
    up: Option<UpChoice>,
) -> LoadOptions {
    let defaults = LoadOptions::default();
    LoadOptions {
        cluster_triangles: cluster_triangles.unwrap_or(defaults.cluster_triangles),
        max_file_size: max_file_size.map_or(defaults.max_file_size, |size| size.0),
        external_buffers: external_buffers.unwrap_or(defaults.external_buffers),
        up: up.unwrap_or(defaults.up),
    }
}

/// Whether two values of a parameter are one: written alike, or numbers
/// alike (`0` and `0.0`, `1` and `01`), whole ones compared whole (beyond
/// 2^53, f64 would take two for one).
fn same_value(a: &str, b: &str) -> bool {
    match (a.parse::<i128>(), b.parse::<i128>()) {
        (Ok(x), Ok(y)) => x == y,
        _ => a == b || matches!((a.parse::<f64>(), b.parse::<f64>()), (Ok(x), Ok(y)) if x == y),
    }
}

/// The most values a sweep may run, in one interleaved run: each is a
/// culler of its own, measured every frame (a GPU's timestamp queries for
/// 2 048 of them passed what wgpu allows in one set).
const MAX_SWEEP_VALUES: usize = 256;

/// One mode run at several values of one of its parameters, in the same
/// interleaved run.
#[derive(Clone, Debug, PartialEq)]
pub struct Sweep {
    pub mode: ModeId,
    pub key: String,
    pub values: Vec<String>,
}

impl Sweep {
    fn parse(spec: &str) -> Result<Sweep, ConfigError> {
        let malformed = || ConfigError::Sweep(spec.to_string());
        let (key, values) = spec.split_once('=').ok_or_else(malformed)?;
        let (mode, param) = key.split_once('.').ok_or_else(malformed)?;
        let mode = parse_modes(&[mode.to_string()])?
            .into_iter()
            .next()
            .filter(|_| mode != "all")
            .ok_or_else(malformed)?;
        let values: Vec<String> = values.split(',').map(|v| v.trim().to_string()).collect();
        if values.iter().any(String::is_empty) {
            return Err(malformed());
        }
        if values.len() > MAX_SWEEP_VALUES {
            return Err(ConfigError::SweepTooLong(values.len()));
        }
        Ok(Sweep {
            mode,
            key: param.to_string(),
            values,
        })
    }
}

/// One culler of a plan: a mode, its label in the results, its parameters.
pub struct ModeRun {
    pub label: String,
    pub mode: ModeId,
    pub params: ModeParams,
}

impl BenchPlan {
    /// Every culler to run: one per mode, or one per value for the swept
    /// mode.
    pub fn runs(&self) -> Vec<ModeRun> {
        self.modes
            .iter()
            .flat_map(|&mode| match &self.sweep {
                Some(s) if s.mode == mode => s
                    .values
                    .iter()
                    .map(|v| ModeRun {
                        label: format!("{mode}[{}={v}]", s.key),
                        mode,
                        params: self.params.with(&format!("{mode}.{}", s.key), v),
                    })
                    .collect(),
                _ => vec![ModeRun {
                    label: mode.to_string(),
                    mode,
                    params: self.params.clone(),
                }],
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_give_the_built_in_city_with_every_mode() {
        let p = BenchConfig::default().plan().unwrap();
        assert_eq!(p.scene, SceneSpec::Builtin("city".into()));
        assert_eq!(p.modes, ModeId::ALL.to_vec());
        assert_eq!(p.resolution, Resolution::DEFAULT);
        assert!(p.measure_error);
    }

    #[test]
    fn flags_override_the_file_and_a_model_replaces_a_scene() {
        let file = BenchConfig {
            scene: Some("city:blocks=2".into()),
            frames: Some(10),
            warmup: Some(1),
            ..Default::default()
        };
        let flags = BenchConfig {
            model: Some("m.obj".into()),
            frames: Some(20),
            params: Some(vec!["omq.factor=0.5".into()]),
            ..Default::default()
        };
        let file = BenchConfig {
            params: Some(vec!["omq.factor=0.9".into(), "omq.om=32x24".into()]),
            ..file
        };
        let file = BenchConfig {
            movers: Some(3),
            ..file
        };
        // The file's movers go with its scene when a model replaces it (a
        // model has none); another scene takes them.
        assert_eq!(flags.clone().or(file.clone()).movers, None);
        let scene_flag = BenchConfig {
            scene: Some("city:blocks=1".into()),
            ..Default::default()
        };
        assert_eq!(scene_flag.or(file.clone()).movers, Some(3));
        let p = flags.or(file).plan().unwrap();
        assert_eq!(p.scene, SceneSpec::File("m.obj".into()));
        assert_eq!((p.frames, p.warmup), (Some(20), 1));
        assert_eq!(
            p.params
                .get::<f64>(ModeId::Omq, ModeId::Omq.info().param("factor").unwrap()),
            Ok(0.5),
            "the flag wins"
        );
        assert_eq!(
            p.params
                .get::<String>(ModeId::Omq, ModeId::Omq.info().param("om").unwrap()),
            Ok("32x24".into()),
            "the file still counts"
        );
        // A key given twice in one source is refused (the review of hostile
        // input found the last one silently kept).
        let twice = BenchConfig {
            params: Some(vec!["omq.factor=0.5".into(), "omq.factor=0.6".into()]),
            ..Default::default()
        };
        let error = twice.clone().plan().unwrap_err().to_string();
        assert!(error.contains("parameter 'omq.factor' is given twice"), "{error}");
        // Also where a flag sets the key the file repeats.
        let flag = BenchConfig {
            params: Some(vec!["omq.factor=0.7".into()]),
            ..Default::default()
        };
        let error = flag.or(twice).plan().unwrap_err().to_string();
        assert!(error.contains("parameter 'omq.factor' is given twice"), "{error}");
    }

    #[test]
    fn file_size_limits_read_as_numbers_or_sizes_and_flags_win() {
        let file: BenchConfig =
            serde_json::from_str(r#"{"max_file_size": 1000000, "external_buffers": true}"#).unwrap();
        assert_eq!(file.clone().plan().unwrap().load.max_file_size, 1_000_000);
        let sized: BenchConfig = serde_json::from_str(r#"{"max_file_size": "8G"}"#).unwrap();
        assert_eq!(sized.plan().unwrap().load.max_file_size, 8 << 30);
        let flags = BenchConfig {
            external_buffers: Some(false),
            ..BenchConfig::default()
        };
        assert!(!flags.or(file).plan().unwrap().load.external_buffers);
        assert!(serde_json::from_str::<BenchConfig>(r#"{"max_file_size": "lots"}"#).is_err());
        // A fraction or a negative number says what a size may be.
        for written in ["1.5", "-3"] {
            let text = format!(r#"{{"max_file_size": {written}}}"#);
            let error = serde_json::from_str::<BenchConfig>(&text).unwrap_err().to_string();
            assert!(error.contains("expected a whole number of bytes"), "{error}");
        }
    }

    #[test]
    fn a_sweep_refuses_a_param_of_its_key_and_a_value_twice() {
        let plan = |sweep: &str, params: &[&str]| {
            BenchConfig {
                sweep: Some(sweep.into()),
                params: Some(params.iter().map(|p| p.to_string()).collect()),
                ..BenchConfig::default()
            }
            .plan()
        };
        assert!(matches!(
            plan("omq.factor=0.5,0.7", &["omq.factor=0.1"]),
            Err(ConfigError::SweptAndSet(k)) if k == "omq.factor"
        ));
        assert!(matches!(
            plan("omq.factor=0.5,0.7,0.5", &[]),
            Err(ConfigError::SweptTwice { value, .. }) if value == "0.5"
        ));
        // Numbers alike are one value however written.
        assert!(matches!(
            plan("omq.factor=0.5,0.50", &[]),
            Err(ConfigError::SweptTwice { value, .. }) if value == "0.50"
        ));
        assert!(same_value("1", "01") && same_value("1e3", "1000") && !same_value("400x300", "400x301"));
        assert!(
            !same_value("9007199254740993", "9007199254740992"),
            "whole numbers compared whole"
        );
        let many: Vec<String> = (1..=257).map(|k| format!("{}", f64::from(k) / 1000.0)).collect();
        assert!(matches!(
            plan(&format!("omq.factor={}", many.join(",")), &[]),
            Err(ConfigError::SweepTooLong(257))
        ));
        assert!(plan("omq.factor=0.5,0.7", &["omq.om=32x24"]).is_ok());
        // Each value is checked with the other parameters.
        assert!(plan("ioc.start=0,5", &["ioc.bottom=6"]).is_ok());
        assert!(matches!(
            plan("ioc.start=0,5", &["ioc.bottom=2"]),
            Err(ConfigError::Mode(e)) if e.to_string().contains("below the bottom depth")
        ));
    }

    #[test]
    fn a_sweep_runs_its_mode_once_per_value() {
        let plan = BenchConfig {
            modes: Some(vec!["vfc".into()]),
            sweep: Some("ac.threshold=0, 50,auto".into()),
            ..Default::default()
        }
        .plan()
        .unwrap();
        let labels: Vec<String> = plan.runs().iter().map(|r| r.label.clone()).collect();
        assert_eq!(
            labels,
            ["vfc", "ac[threshold=0]", "ac[threshold=50]", "ac[threshold=auto]"]
        );
        assert_eq!(
            plan.runs()[2]
                .params
                .get::<String>(ModeId::Ac, ModeId::Ac.info().param("threshold").unwrap()),
            Ok("50".into())
        );
        let bad = |s: &str| {
            BenchConfig {
                sweep: Some(s.into()),
                ..Default::default()
            }
            .plan()
            .unwrap_err()
            .to_string()
        };
        assert!(bad("ac.threshold").contains("not MODE.KEY=V1,V2"));
        assert!(bad("ac.threshold=1,,2").contains("not MODE.KEY=V1,V2"));
        assert!(bad("ac.threshold=1,-5").contains("parameter 'ac.threshold'"));
        assert!(bad("ac.bogus=1").contains("unknown parameter 'ac.bogus'"));
        assert!(bad("warp.x=1").contains("unknown mode 'warp'"));
    }

    #[test]
    fn bad_plans_are_rejected() {
        let both = BenchConfig {
            model: Some("m.obj".into()),
            scene: Some("city".into()),
            ..Default::default()
        };
        assert!(matches!(both.plan(), Err(ConfigError::ModelAndScene)));
        let zero = BenchConfig {
            frames: Some(0),
            ..Default::default()
        };
        assert!(matches!(zero.plan(), Err(ConfigError::Frames)));
        let long = BenchConfig {
            warmup: Some(u32::MAX),
            ..Default::default()
        };
        assert!(matches!(long.plan(), Err(ConfigError::Warmup)));
        let moving_model = BenchConfig {
            model: Some("m.obj".into()),
            movers: Some(3),
            ..Default::default()
        };
        assert!(matches!(moving_model.plan(), Err(ConfigError::MoversOnModel)));
    }

    #[test]
    fn movers_join_the_built_in_scene_spec() {
        let plan = |scene: Option<&str>| {
            BenchConfig {
                scene: scene.map(str::to_string),
                movers: Some(30),
                ..Default::default()
            }
            .plan()
            .unwrap()
            .scene
        };
        assert_eq!(plan(None), SceneSpec::Builtin("city:movers=30".into()));
        assert_eq!(
            plan(Some("city:blocks=2")),
            SceneSpec::Builtin("city:blocks=2,movers=30".into())
        );
    }
}
