//! Run configuration: the options of `occlu bench`, from a JSON file
//! (`--config`, samples in configs/) and from flags, which win. Relative
//! paths in a file are relative to the file.

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};

use crate::cull::{ModeError, ModeParams, parse_modes};
use crate::gpu::{BackendChoice, Resolution};
use crate::scene::{DEFAULT_CLUSTER_TRIANGLES, SceneSpec};

/// Every field optional: a file or the flags may give any subset.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BenchConfig {
    /// An OBJ, glTF or GLB file.
    pub model: Option<PathBuf>,
    /// A built-in scene, `NAME[:key=value,...]`.
    pub scene: Option<String>,
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
    /// Mode parameters, `MODE.KEY=VALUE`.
    pub params: Option<Vec<String>>,
}

pub const DEFAULT_WARMUP: u32 = 3;
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
    #[error("give a model file or --scene, not both")]
    ModelAndScene,
    #[error("--frames must be in 1..={}", crate::camera::path::MAX_FRAMES)]
    Frames,
    #[error("--warmup must be at most {MAX_WARMUP}")]
    Warmup,
    #[error(transparent)]
    Mode(#[from] ModeError),
}

/// A complete, validated plan for one bench run.
#[derive(Clone, Debug, PartialEq)]
pub struct BenchPlan {
    pub scene: SceneSpec,
    pub path: Option<PathBuf>,
    pub modes: Vec<&'static str>,
    pub params: ModeParams,
    pub frames: Option<u32>,
    pub warmup: u32,
    pub resolution: Resolution,
    pub backend: BackendChoice,
    pub out: PathBuf,
    pub measure_error: bool,
    pub cluster_triangles: u32,
}

impl BenchConfig {
    pub fn load(path: &Path) -> Result<BenchConfig, ConfigError> {
        let name = path.display().to_string();
        let text = std::fs::read_to_string(path).map_err(|error| ConfigError::Io {
            path: name.clone(),
            error,
        })?;
        let mut config: BenchConfig = serde_json::from_str(&text).map_err(|e| ConfigError::Json {
            path: name,
            message: e.to_string(),
        })?;
        let base = path.parent().unwrap_or(Path::new(""));
        for p in [&mut config.model, &mut config.path, &mut config.out]
            .into_iter()
            .flatten()
        {
            if p.is_relative() {
                *p = base.join(&*p);
            }
        }
        Ok(config)
    }

    /// `self` with every unset field taken from `fallback`. A model or scene
    /// given here replaces both of the fallback's, so a flag can switch a
    /// configured scene to a model.
    pub fn or(self, fallback: BenchConfig) -> BenchConfig {
        let source_given = self.model.is_some() || self.scene.is_some();
        BenchConfig {
            model: if source_given { self.model } else { fallback.model },
            scene: if source_given { self.scene } else { fallback.scene },
            path: self.path.or(fallback.path),
            modes: self.modes.or(fallback.modes),
            frames: self.frames.or(fallback.frames),
            warmup: self.warmup.or(fallback.warmup),
            resolution: self.resolution.or(fallback.resolution),
            backend: self.backend.or(fallback.backend),
            out: self.out.or(fallback.out),
            error: self.error.or(fallback.error),
            cluster_triangles: self.cluster_triangles.or(fallback.cluster_triangles),
            // Per key, a flag wins over the file: later entries override.
            params: match (fallback.params, self.params) {
                (Some(mut file), Some(flags)) => {
                    file.extend(flags);
                    Some(file)
                }
                (file, flags) => flags.or(file),
            },
        }
    }

    /// Fills defaults and validates.
    pub fn plan(self) -> Result<BenchPlan, ConfigError> {
        let scene = match (self.model, self.scene) {
            (Some(_), Some(_)) => return Err(ConfigError::ModelAndScene),
            (Some(model), None) => SceneSpec::File(model),
            (None, scene) => SceneSpec::Builtin(scene.unwrap_or_else(|| DEFAULT_SCENE.into())),
        };
        if self
            .frames
            .is_some_and(|n| n == 0 || n > crate::camera::path::MAX_FRAMES)
        {
            return Err(ConfigError::Frames);
        }
        if self.warmup.is_some_and(|n| n > MAX_WARMUP) {
            return Err(ConfigError::Warmup);
        }
        let modes = parse_modes(&self.modes.unwrap_or_else(|| vec!["all".into()]))?;
        Ok(BenchPlan {
            scene,
            path: self.path,
            params: ModeParams::parse(&self.params.unwrap_or_default(), &modes)?,
            modes,
            frames: self.frames,
            warmup: self.warmup.unwrap_or(DEFAULT_WARMUP),
            resolution: self.resolution.unwrap_or(Resolution::DEFAULT),
            backend: self.backend.unwrap_or_default(),
            out: self.out.unwrap_or_else(|| DEFAULT_OUT.into()),
            measure_error: self.error.unwrap_or(true),
            cluster_triangles: self.cluster_triangles.unwrap_or(DEFAULT_CLUSTER_TRIANGLES),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_give_the_built_in_city_with_every_mode() {
        let p = BenchConfig::default().plan().unwrap();
        assert_eq!(p.scene, SceneSpec::Builtin("city".into()));
        assert_eq!(p.modes, crate::cull::mode_names());
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
        let p = flags.or(file).plan().unwrap();
        assert_eq!(p.scene, SceneSpec::File("m.obj".into()));
        assert_eq!((p.frames, p.warmup), (Some(20), 1));
        assert_eq!(p.params.get::<f64>("omq", "factor"), Ok(0.5), "the flag wins");
        assert_eq!(
            p.params.get::<String>("omq", "om"),
            Ok("32x24".into()),
            "the file still counts"
        );
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
    }

    #[test]
    fn files_are_strict_and_resolve_paths_relative_to_themselves() {
        let dir = tempfile::tempdir().unwrap();
        let f = dir.path().join("c.json");
        std::fs::write(
            &f,
            r#"{"path": "walk.json", "resolution": "320x240", "modes": ["vfc"]}"#,
        )
        .unwrap();
        let c = BenchConfig::load(&f).unwrap();
        assert_eq!(c.path, Some(dir.path().join("walk.json")));
        assert_eq!(c.resolution, Some("320x240".parse().unwrap()));
        std::fs::write(&f, r#"{"resolutoin": "320x240"}"#).unwrap();
        assert!(
            BenchConfig::load(&f)
                .unwrap_err()
                .to_string()
                .contains("unknown field `resolutoin`")
        );
        std::fs::write(&f, r#"{"resolution": "320"}"#).unwrap();
        assert!(BenchConfig::load(&f).unwrap_err().to_string().contains("WIDTHxHEIGHT"));
    }
}
