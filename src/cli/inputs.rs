//! The scene and camera path that `render`, `flythrough` and `export` name,
//! loaded (the path planned as bench would when none is given), and the
//! outputs that would overwrite them refused.

use std::path::Path;

use occlu::camera::path::CameraPath;
use occlu::scene::{Scene, load};

use super::args::SceneAndPath;
use super::progress::Progress;
use super::signals::stop_listening;

impl SceneAndPath {
    /// Refuses an `output` that is one of the files this reads.
    pub fn refuse_as_output(&self, output: &Path) -> anyhow::Result<()> {
        let inputs: Vec<&Path> = [self.scene.model.as_deref(), self.path.as_deref()]
            .into_iter()
            .flatten()
            .collect();
        Ok(occlu::report::refuse_input_as_output(output, &inputs)?)
    }

    /// The scene and the path; an `output` that is one of the files the
    /// scene was read from (a glTF file's buffers) is refused.
    pub fn load(&self, output: &Path) -> anyhow::Result<(Scene, CameraPath)> {
        // Read first: a bad path file fails before a long scene load.
        let path_file = self.path.as_deref().map(CameraPath::load).transpose()?;
        let scene = load(&self.scene.spec()?, &self.scene.options())?;
        occlu::report::refuse_input_as_output(output, &scene.files)?;
        let path = match path_file {
            Some(p) => p,
            None => {
                let mut progress = Progress::new(false, 0, String::new());
                let planned =
                    occlu::camera::generate::default_path_heard(&scene, progress.listener("planning the path"))?.0;
                stop_listening()?;
                planned
            }
        };
        let path = match self.frames {
            Some(n) => path.with_frames(n)?,
            None => path,
        };
        Ok((scene, path))
    }
}
