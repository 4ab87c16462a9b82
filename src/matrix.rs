//! A benchmark matrix: one configuration file that lists several runs, and
//! `--shard K/N`, which gives a CI job its share of them.
//!
//! A file lists runs with `runs` (a list of run configurations) and with
//! `models` and `scenes` (scene sources) × `paths` (camera paths). Its other
//! fields are every run's defaults; a run's own fields win over them, and
//! flags win over both (`--out` names the folder the runs' folders go in).
//! The runs are in a fixed order: `runs` as listed, then each model, then
//! each built-in scene, each with every path in turn. Each run writes into
//! a folder of its own named from its place and content
//! (`03-town-street`: place, scene, path), so the same run has the
//! same folder on every machine and shards never collide. `--shard K/N`
//! runs the runs at places K, K + N, K + 2N, … (1-based): N jobs given
//! 1/N … N/N run every run exactly once between them.

use std::collections::BTreeSet;
use std::fmt;
use std::path::{Path, PathBuf};
use std::str::FromStr;

use crate::camera::path::{CameraPath, PathError};
use crate::config::{BenchConfig, BenchPlan, ConfigError, DEFAULT_OUT, DEFAULT_SCENE, from_json, read_json};
use crate::report::MatrixIdentity;
use crate::scene::{SceneError, SceneSpec};

/// The runs of one configuration file, before flags and planning.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Matrix {
    /// The configuration file, if any.
    file: Option<PathBuf>,
    /// The file's own fields: every run's defaults.
    defaults: BenchConfig,
    /// Each run's own fields, in the matrix's order; empty for a file that
    /// lists no runs (one run of its defaults).
    entries: Vec<BenchConfig>,
}

/// A run of a matrix: its folder's name and its validated plan (which
/// writes into that folder and records the name).
#[derive(Clone, Debug, PartialEq)]
pub struct MatrixRun {
    pub name: String,
    pub plan: BenchPlan,
}

#[derive(Debug, thiserror::Error)]
pub enum MatrixError {
    #[error(transparent)]
    Config(#[from] ConfigError),
    #[error("{path}: the matrix lists no runs (runs, models, scenes and paths are all empty)")]
    NoRuns { path: String },
    #[error("{path}: runs[{index}] sets out: each run of a matrix writes into its own folder under the matrix's --out")]
    OutInRun { path: String, index: usize },
    #[error(
        "--export-github-benchmark writes one run's file and a matrix has many runs: export from one run's summary.json instead"
    )]
    GithubExport,
    #[error("--trace writes one run's timeline and a matrix has many runs: trace one run at a time")]
    Trace,
    #[error("run {run}: {error}")]
    Plan { run: String, error: ConfigError },
    #[error("run {run}: {error}")]
    Path { run: String, error: PathError },
    #[error(
        "{path}: the matrix lists {runs} runs, more than the {max} one matrix may: split it into several files",
        max = MatrixIdentity::MAX_RUNS
    )]
    TooManyRuns { path: String, runs: usize },
    #[error("run {run}: {error}")]
    Scene { run: String, error: SceneError },
    #[error("run {run}: {}: {error}", model.display())]
    Model {
        run: String,
        model: PathBuf,
        error: std::io::Error,
    },
}

/// `json` where it is an object, as a run's configuration is; refused
/// otherwise (serde would read an array's elements as the fields in
/// order, past the check of their names).
fn object(
    file: &Path,
    at: &str,
    json: serde_json::Value,
) -> Result<serde_json::Map<String, serde_json::Value>, ConfigError> {
    use serde_json::Value;
    let kind = match json {
        Value::Object(fields) => return Ok(fields),
        Value::Array(_) => "an array",
        Value::String(_) => "a string",
        Value::Number(_) => "a number",
        Value::Bool(_) => "true or false",
        Value::Null => "null",
    };
    Err(ConfigError::Json {
        path: file.display().to_string(),
        message: format!("{at}a configuration is a JSON object of fields ({{\"frames\": 30, ...}}), not {kind}"),
    })
}

/// The keys of a configuration file that list runs rather than set one.
const LISTS: [&str; 4] = ["runs", "models", "scenes", "paths"];

impl Matrix {
    /// Reads a configuration file: a matrix when it has any of `runs`,
    /// `models`, `scenes` or `paths`, else one run. Relative paths are
    /// relative to the file.
    pub fn load(file: &Path) -> Result<Matrix, MatrixError> {
        let mut fields = object(file, "", read_json(file)?)?;
        refuse_unknown_fields(file, &fields)?;
        let [runs, models, scenes, paths] = LISTS.map(|key| fields.remove(key));
        let json = serde_json::Value::Object(fields);
        let listed = [&runs, &models, &scenes, &paths].iter().any(|l| l.is_some());
        let defaults = from_json::<BenchConfig>(file, "", json)?.relative_to(file, "")?;
        let mut entries = Vec::new();
        for (index, run) in list::<serde_json::Value>(file, "runs", runs)?.into_iter().enumerate() {
            let at = format!("runs[{index}]: ");
            let entry: BenchConfig = from_json(file, &at, serde_json::Value::Object(object(file, &at, run)?))?;
            if entry.out.is_some() {
                return Err(MatrixError::OutInRun {
                    path: file.display().to_string(),
                    index,
                });
            }
            entries.push(entry.relative_to(file, &at)?);
        }
        let models: Vec<PathBuf> = list(file, "models", models)?;
        let scenes: Vec<String> = list(file, "scenes", scenes)?;
        let paths: Vec<PathBuf> = list(file, "paths", paths)?;
        // Counted before the runs are made: a huge product is refused
        // before it takes the memory. A list left out takes the defaults'
        // scene or path; when all three are, they add no run.
        let crossed = (models.len() + scenes.len()).max(1) * paths.len().max(1);
        let listed_runs = entries.len()
            + if models.len() + scenes.len() + paths.len() > 0 {
                crossed
            } else {
                0
            };
        if listed_runs > MatrixIdentity::MAX_RUNS {
            return Err(MatrixError::TooManyRuns {
                path: file.display().to_string(),
                runs: listed_runs,
            });
        }
        let sources: Vec<BenchConfig> = models
            .into_iter()
            .map(|model| BenchConfig {
                model: Some(model),
                ..BenchConfig::default()
            })
            .chain(scenes.into_iter().map(|scene| BenchConfig {
                scene: Some(scene),
                ..BenchConfig::default()
            }))
            .collect();
        if !sources.is_empty() || !paths.is_empty() {
            // A list left out takes the defaults' scene or path.
            let sources = if sources.is_empty() {
                vec![BenchConfig::default()]
            } else {
                sources
            };
            let paths: Vec<Option<PathBuf>> = if paths.is_empty() {
                vec![None]
            } else {
                paths.into_iter().map(Some).collect()
            };
            for source in &sources {
                for path in &paths {
                    let entry = BenchConfig {
                        path: path.clone(),
                        ..source.clone()
                    };
                    entries.push(entry.relative_to(file, "models, scenes or paths: ")?);
                }
            }
        }
        if listed && entries.is_empty() {
            return Err(MatrixError::NoRuns {
                path: file.display().to_string(),
            });
        }
        Ok(Matrix {
            file: Some(file.to_path_buf()),
            defaults,
            entries,
        })
    }

    /// Whether the file lists runs (else it is one run, which writes into
    /// `--out` itself unless sharded).
    pub fn lists_runs(&self) -> bool {
        !self.entries.is_empty()
    }

    /// The one run of a file that lists none: `flags` over the file.
    pub fn single_run(&self, flags: &BenchConfig) -> Result<BenchPlan, ConfigError> {
        flags
            .clone()
            .or(self.defaults.clone())
            .plan()
            .map_err(|error| self.blamed(error, &self.defaults))
    }

    /// `error`, made planning `flags` over `fields` (the file's), as the
    /// file's when its fields make it on their own (planned alone, they
    /// fail the same way), so the message names the file; else as the
    /// flags' own.
    fn blamed(&self, error: ConfigError, fields: &BenchConfig) -> ConfigError {
        match &self.file {
            Some(file) if fields.clone().plan().is_err_and(|e| e.to_string() == error.to_string()) => {
                ConfigError::InFile {
                    path: file.display().to_string(),
                    error: Box::new(error),
                }
            }
            _ => error,
        }
    }

    /// Every run, `flags` over its own fields over the defaults, each
    /// planned into its folder under `--out` and checked before any of
    /// them runs (its plan, its path file, its built-in scene's spec, that
    /// its model is a file), so a bad run fails the whole matrix on every
    /// shard. Each path file is read once, however many runs use it. A
    /// file that lists no runs is a matrix of one.
    pub fn plan(&self, flags: &BenchConfig) -> Result<Vec<MatrixRun>, MatrixError> {
        let entries = if self.entries.is_empty() {
            vec![BenchConfig::default()]
        } else {
            self.entries.clone()
        };
        let fields: Vec<BenchConfig> = entries
            .into_iter()
            .map(|entry| entry.or(self.defaults.clone()))
            .collect();
        let configs: Vec<BenchConfig> = fields.iter().map(|f| flags.clone().or(f.clone())).collect();
        if configs.iter().any(|c| c.export_github_benchmark.is_some()) {
            return Err(MatrixError::GithubExport);
        }
        if configs.iter().any(|c| c.trace.is_some()) {
            return Err(MatrixError::Trace);
        }
        let out = flags
            .out
            .clone()
            .or(self.defaults.out.clone())
            .unwrap_or_else(|| DEFAULT_OUT.into());
        let width = MatrixIdentity::place_width(configs.len());
        let names: Vec<String> = configs
            .iter()
            .enumerate()
            .map(|(place, config)| run_name(place, width, config))
            .collect();
        let matrix = MatrixIdentity::of(names.iter().map(String::as_str));
        let mut paths_read = BTreeSet::new();
        configs
            .into_iter()
            .zip(&fields)
            .zip(names)
            .map(|((config, fields), name)| {
                let mut plan = config.plan().map_err(|error| MatrixError::Plan {
                    run: name.clone(),
                    error: self.blamed(error, fields),
                })?;
                if let Some(path) = plan.path.as_ref().filter(|p| !paths_read.contains(*p)) {
                    CameraPath::load(path).map_err(|error| MatrixError::Path {
                        run: name.clone(),
                        error,
                    })?;
                    paths_read.insert(path.clone());
                }
                match &plan.scene {
                    SceneSpec::File(model) => {
                        let fault = match std::fs::metadata(model) {
                            Ok(m) if m.is_file() => None,
                            Ok(_) => Some(std::io::Error::other(
                                "not a file: a model is an .obj, .gltf or .glb file",
                            )),
                            Err(e) => Some(e),
                        };
                        if let Some(error) = fault {
                            return Err(MatrixError::Model {
                                run: name,
                                model: model.clone(),
                                error,
                            });
                        }
                    }
                    SceneSpec::Builtin(spec) => {
                        crate::scene::builtin::check(spec).map_err(|error| MatrixError::Scene {
                            run: name.clone(),
                            error,
                        })?
                    }
                }
                plan.out = out.join(&name);
                plan.run = Some(name.clone());
                plan.matrix = Some(matrix);
                Ok(MatrixRun { name, plan })
            })
            .collect()
    }
}

/// Refuses a field a configuration file cannot have, listing every one it
/// can: a run's ([`BenchConfig`]'s) and the [`LISTS`] (which the run's
/// own refusal would leave out, as they are taken off first).
fn refuse_unknown_fields(file: &Path, fields: &serde_json::Map<String, serde_json::Value>) -> Result<(), ConfigError> {
    // Every field of a run, as a default one serialises (None as null).
    let run = serde_json::to_value(BenchConfig::default()).expect("a configuration serialises");
    let known: Vec<&str> = run
        .as_object()
        .into_iter()
        .flat_map(|run| run.keys().map(String::as_str))
        .chain(LISTS)
        .collect();
    match fields.keys().find(|key| !known.contains(&key.as_str())) {
        Some(unknown) => {
            let expected: Vec<String> = known.iter().map(|k| format!("`{k}`")).collect();
            Err(ConfigError::Json {
                path: file.display().to_string(),
                message: format!("unknown field `{unknown}`, expected one of {}", expected.join(", ")),
            })
        }
        None => Ok(()),
    }
}

/// The items of a list field of the file (`key`), each deserialised.
fn list<T: serde::de::DeserializeOwned>(
    file: &Path,
    key: &str,
    json: Option<serde_json::Value>,
) -> Result<Vec<T>, ConfigError> {
    let items: Vec<serde_json::Value> =
        json.map_or(Ok(Vec::new()), |json| from_json(file, &format!("{key}: "), json))?;
    items
        .into_iter()
        .map(|item| from_json(file, &format!("{key}: "), item))
        .collect()
}

/// A run's folder name: its place (1-based, zero-padded to `width` so
/// folders sort in the matrix's order), its scene's and its path's names.
/// The place alone makes it unique; the rest says what it holds.
fn run_name(place: usize, width: usize, config: &BenchConfig) -> String {
    let stem = |p: &Path| {
        p.file_stem()
            .map_or(String::new(), |s| s.to_string_lossy().into_owned())
    };
    let scene = match (&config.model, &config.scene) {
        (Some(model), _) => stem(model),
        (None, Some(scene)) => scene.clone(),
        (None, None) => DEFAULT_SCENE.into(),
    };
    let path = config.path.as_deref().map_or("generated".into(), stem);
    format!(
        "{:0width$}-{}-{}",
        place + 1,
        crate::text::slug(&scene),
        crate::text::slug(&path)
    )
}

/// `--shard K/N`: the K-th of N jobs that split a matrix (1 ≤ K ≤ N).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    index: u32,
    count: u32,
}

impl Shard {
    /// The whole matrix: what a run without `--shard` runs.
    pub const WHOLE: Shard = Shard { index: 1, count: 1 };

    /// Whether the run at `place` (0-based, in the matrix's order) is this
    /// shard's: places K−1, K−1+N, K−1+2N, …
    pub fn takes(&self, place: usize) -> bool {
        place % self.count as usize == (self.index - 1) as usize
    }
}

impl FromStr for Shard {
    type Err = String;

    fn from_str(text: &str) -> Result<Shard, String> {
        let refuse = || format!("'{text}' is not K/N, shard K of N with 1 <= K <= N (e.g. 2/3)");
        let (k, n) = text.split_once('/').ok_or_else(refuse)?;
        // Digits only: u32's parser would take "+1".
        let number = |s: &str| {
            s.bytes()
                .all(|b| b.is_ascii_digit())
                .then(|| s.parse::<u32>().ok())
                .flatten()
                .ok_or_else(refuse)
        };
        let (index, count) = (number(k)?, number(n)?);
        if index == 0 || index > count {
            return Err(refuse());
        }
        Ok(Shard { index, count })
    }
}

impl fmt::Display for Shard {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "{}/{}", self.index, self.count)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn matrix(dir: &Path, json: &str) -> Result<Matrix, MatrixError> {
        let file = dir.join("m.json");
        std::fs::write(&file, json).unwrap();
        Matrix::load(&file)
    }

    #[test]
    fn shards_split_the_runs_once_each_and_refuse_what_is_not_k_of_n() {
        let shards: Vec<Shard> = ["1/3", "2/3", "3/3"].iter().map(|s| s.parse().unwrap()).collect();
        let taken: Vec<Vec<usize>> = shards
            .iter()
            .map(|s| (0..7).filter(|&p| s.takes(p)).collect())
            .collect();
        assert_eq!(taken, [vec![0, 3, 6], vec![1, 4], vec![2, 5]]);
        assert!("1/1".parse::<Shard>().unwrap().takes(5));
        for bad in [
            "0/3", "4/3", "a/b", "1/0", "3", "-1/3", "1/3/5", "", "+1/3", "1/+3", " 1/3",
        ] {
            let e = bad.parse::<Shard>().unwrap_err();
            assert!(e.contains("not K/N"), "{bad}: {e}");
        }
        assert_eq!("2/3".parse::<Shard>().unwrap().to_string(), "2/3");
    }

    #[test]
    fn a_matrixs_top_level_movers_are_every_scenes() {
        let dir = tempfile::tempdir().unwrap();
        let m = matrix(
            dir.path(),
            r#"{"movers": 3, "scenes": ["city:blocks=1"], "runs": [{"scene": "city:blocks=2"}]}"#,
        );
        let runs = m.unwrap().plan(&BenchConfig::default()).unwrap();
        let scenes: Vec<SceneSpec> = runs.into_iter().map(|r| r.plan.scene).collect();
        assert_eq!(
            scenes,
            [
                SceneSpec::Builtin("city:blocks=2,movers=3".into()),
                SceneSpec::Builtin("city:blocks=1,movers=3".into())
            ]
        );
    }

    #[test]
    fn runs_then_models_and_scenes_by_paths_in_order_with_names_and_defaults() {
        let dir = tempfile::tempdir().unwrap();
        for p in ["a.json", "b.json"] {
            std::fs::write(
                dir.path().join(p),
                r#"{"frames": 2, "keyframes": [{"time": 0, "position": [0, 2, 0], "target": [1, 2, 0]}]}"#,
            )
            .unwrap();
        }
        std::fs::write(dir.path().join("town.obj"), "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n").unwrap();
        let m = matrix(
            dir.path(),
            r#"{"frames": 4, "modes": ["vfc"], "out": "res",
                "runs": [{"scene": "forest", "frames": 2}],
                "models": ["town.obj"], "scenes": ["city:blocks=1"], "paths": ["a.json", "b.json"]}"#,
        )
        .unwrap();
        assert!(m.lists_runs());
        let flags = BenchConfig {
            modes: Some(vec!["dr".into()]),
            ..BenchConfig::default()
        };
        let runs = m.plan(&flags).unwrap();
        let names: Vec<&str> = runs.iter().map(|r| r.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "01-forest-generated",
                "02-town-a",
                "03-town-b",
                "04-city-blocks-1-a",
                "05-city-blocks-1-b"
            ]
        );
        let first = &runs[0].plan;
        assert_eq!(first.frames, Some(2), "the run's own field wins");
        assert_eq!(runs[1].plan.frames, Some(4), "the file's field is the default");
        assert!(
            runs.iter().all(|r| r.plan.modes == [crate::cull::ModeId::Dr]),
            "flags win"
        );
        assert_eq!(first.out, dir.path().join("res").join("01-forest-generated"));
        assert_eq!(first.run.as_deref(), Some("01-forest-generated"));
        assert_eq!(runs[2].plan.scene, SceneSpec::File(dir.path().join("town.obj")));
        assert_eq!(runs[2].plan.path, Some(dir.path().join("b.json")));
        // --out names the matrix's folder.
        let out = BenchConfig {
            out: Some("elsewhere".into()),
            ..BenchConfig::default()
        };
        assert_eq!(
            m.plan(&out).unwrap()[4].plan.out,
            Path::new("elsewhere/05-city-blocks-1-b")
        );
    }

    #[test]
    fn a_file_without_lists_is_one_run_and_a_matrix_of_one_when_sharded() {
        let dir = tempfile::tempdir().unwrap();
        let m = matrix(dir.path(), r#"{"scene": "city:blocks=1", "frames": 3}"#).unwrap();
        assert!(!m.lists_runs());
        let flags = BenchConfig::default();
        assert_eq!(m.single_run(&flags).unwrap().out, Path::new(DEFAULT_OUT));
        let runs = m.plan(&flags).unwrap();
        assert_eq!(runs.len(), 1);
        assert_eq!(
            runs[0].plan.out,
            Path::new(DEFAULT_OUT).join("01-city-blocks-1-generated")
        );
        assert!(!Matrix::default().lists_runs());
    }

    #[test]
    fn a_bad_run_fails_the_whole_matrix_naming_it() {
        let dir = tempfile::tempdir().unwrap();
        let plan = |json: &str| matrix(dir.path(), json).and_then(|m| m.plan(&BenchConfig::default()));
        let e = plan(r#"{"scenes": ["city", "forest"], "runs": [{"frames": 0}]}"#).unwrap_err();
        assert!(
            matches!(&e, MatrixError::Plan { run, .. } if run == "01-city-generated"),
            "{e}"
        );
        let e = plan(r#"{"scenes": ["city"], "paths": ["missing.json"]}"#).unwrap_err();
        assert!(
            matches!(&e, MatrixError::Path { run, .. } if run == "01-city-missing"),
            "{e}"
        );
        let e = plan(r#"{"scenes": ["city", "city:blocks=x"]}"#).unwrap_err();
        assert!(
            matches!(&e, MatrixError::Scene { run, .. } if run == "02-city-blocks-x-generated"),
            "{e}"
        );
        std::fs::create_dir(dir.path().join("adir")).unwrap();
        let e = plan(r#"{"models": ["adir"]}"#).unwrap_err();
        assert!(e.to_string().contains("adir: not a file"), "{e}");
        let e = plan(r#"{"models": ["gone.obj"]}"#).unwrap_err();
        assert!(e.to_string().contains("run 01-gone-generated") && e.to_string().contains("gone.obj"));
        let e = plan(r#"{"runs": [{"modes": ["vfc"]}, {"runs": []}]}"#).unwrap_err();
        assert!(e.to_string().contains("runs[1]: unknown field `runs`"), "{e}");
        let e = plan(r#"{"runs": [{"out": "x"}]}"#).unwrap_err();
        assert!(matches!(e, MatrixError::OutInRun { index: 0, .. }));
        let e = plan(r#"{"runs": []}"#).unwrap_err();
        assert!(matches!(e, MatrixError::NoRuns { .. }));
        let e = plan(r#"{"scenes": "city"}"#).unwrap_err();
        assert!(e.to_string().contains("scenes: invalid type"), "{e}");
        let e = plan(r#"{"scenes": ["city"], "export_github_benchmark": "g.json"}"#).unwrap_err();
        assert!(matches!(e, MatrixError::GithubExport));
        let e = plan(r#"{"scenes": ["city"], "trace": "t.json"}"#).unwrap_err();
        assert!(matches!(e, MatrixError::Trace));
    }

    #[test]
    fn a_matrix_of_exactly_the_most_runs_is_taken_and_one_more_refused() {
        let dir = tempfile::tempdir().unwrap();
        let runs = |n: usize| format!(r#"{{"runs": [{}]}}"#, vec!["{}"; n].join(","));
        let m = matrix(dir.path(), &runs(MatrixIdentity::MAX_RUNS)).unwrap();
        assert_eq!(m.entries.len(), MatrixIdentity::MAX_RUNS);
        let e = matrix(dir.path(), &runs(MatrixIdentity::MAX_RUNS + 1)).unwrap_err();
        assert!(e.to_string().contains("lists 10001 runs"), "{e}");
        let listed = format!(
            r#"{{"runs": [{}], "scenes": ["city", "forest"]}}"#,
            vec!["{}"; MatrixIdentity::MAX_RUNS - 2].join(",")
        );
        assert_eq!(
            matrix(dir.path(), &listed).unwrap().entries.len(),
            MatrixIdentity::MAX_RUNS
        );
    }

    #[test]
    fn the_sample_matrix_plans_the_workflows_runs() {
        let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("configs/matrix.json");
        let runs = Matrix::load(&file).unwrap().plan(&BenchConfig::default()).unwrap();
        let names: Vec<&str> = runs.iter().map(|r| r.name.as_str()).collect();
        assert_eq!(
            names,
            [
                "01-forest-generated",
                "02-city-city-corner",
                "03-city-city-walk",
                "04-city-movers-20-city-corner",
                "05-city-movers-20-city-walk"
            ]
        );
    }

    #[test]
    fn files_are_strict_and_resolve_paths_relative_to_themselves() {
        let dir = tempfile::tempdir().unwrap();
        let m = matrix(
            dir.path(),
            r#"{"path": "walk.json", "resolution": "320x240", "modes": ["vfc"], "trace": "t.json", "export_github_benchmark": "g.json"}"#,
        )
        .unwrap();
        let plan = m.single_run(&BenchConfig::default()).unwrap();
        assert_eq!(plan.path, Some(dir.path().join("walk.json")));
        assert_eq!(plan.trace, Some(dir.path().join("t.json")));
        assert_eq!(plan.export_github_benchmark, Some(dir.path().join("g.json")));
        assert_eq!(plan.resolution, "320x240".parse().unwrap());
        let error = |json: &str| matrix(dir.path(), json).unwrap_err().to_string();
        assert!(error(r#"{"resolutoin": "320x240"}"#).contains("unknown field `resolutoin`"));
        assert!(error(r#"{"resolution": "320"}"#).contains("WIDTHxHEIGHT"));
        assert!(
            error("[1, 2]")
                .contains("a configuration is a JSON object of fields ({\"frames\": 30, ...}), not an array")
        );
        assert!(error("{ not json").contains("m.json"));
    }
}
