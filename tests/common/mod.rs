//! Helpers shared by the integration tests.
#![allow(dead_code)] // each test binary uses its own subset

pub mod gltf_writer;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use occlu::gpu::{BackendChoice, GpuContext};

/// Runs the `occlu` binary built for these tests.
pub fn occlu(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_occlu"))
        .args(args)
        .output()
        .expect("occlu binary runs")
}

pub fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

pub fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

/// stderr without the loader noise of headless Vulkan (libwayland prints
/// "XDG_RUNTIME_DIR is invalid" when the Vulkan loader probes for Wayland).
pub fn own_stderr(o: &Output) -> Vec<String> {
    stderr(o)
        .lines()
        .filter(|l| !l.contains("XDG_RUNTIME_DIR"))
        .map(str::to_string)
        .collect()
}

pub fn write(dir: &Path, name: &str, contents: impl AsRef<[u8]>) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, contents).expect("fixture written");
    p
}

/// Two objects (a quad and a tetrahedron) and a 'g' group: 2 + 4 + 1 = 7 triangles.
pub const THREE_OBJECTS_OBJ: &str = "\
# three objects
o quad
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
f 1 2 3 4
o tetra
v 2 0 0
v 3 0 0
v 2 1 0
v 2 0 1
f 5 6 7
f 5 6 8
f 5 7 8
f 6 7 8
g lone
v 4 0 0
v 5 0 0
v 4 1 0
f 9 10 11
";

/// Every backend that has an adapter here (Vulkan and GL on the reference
/// machine). Fails when there is none at all: the tests need a GPU or a
/// software rasteriser.
pub fn gpus() -> Vec<GpuContext> {
    let found: Vec<GpuContext> = [BackendChoice::Vulkan, BackendChoice::Gl]
        .into_iter()
        .filter_map(|b| GpuContext::new(b).ok())
        .collect();
    assert!(
        !found.is_empty(),
        "no Vulkan or GL adapter: install Mesa (scripts/install-deps) to run the GPU tests"
    );
    found
}
