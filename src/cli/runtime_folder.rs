//! A runtime folder for the Vulkan loader's Wayland probe, set before any
//! thread starts, so a headless machine prints no warning on every run.

/// On a headless Linux machine the Vulkan loader probes for a Wayland
/// display, and libwayland prints "XDG_RUNTIME_DIR is invalid or not set"
/// on every run when that variable is missing. occlu opens no window: where
/// the variable is unset it points it at a private folder of the user's
/// (created 0700 under the temporary folder, as the XDG specification asks
/// of a runtime folder), in which the probe finds no display and says
/// nothing. A folder that exists but is not the user's alone is left alone,
/// and so is the message.
pub fn give_wayland_a_runtime_folder() {
    #[cfg(target_os = "linux")]
    {
        use std::os::unix::fs::{DirBuilderExt, MetadataExt, PermissionsExt};
        if std::env::var_os("XDG_RUNTIME_DIR").is_some() {
            return;
        }
        let Ok(uid) = std::fs::metadata("/proc/self").map(|m| m.uid()) else {
            return;
        };
        let dir = std::env::temp_dir().join(format!("occlu-runtime-{uid}"));
        let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
        let private = std::fs::symlink_metadata(&dir)
            .is_ok_and(|m| m.is_dir() && m.uid() == uid && m.permissions().mode() & 0o777 == 0o700);
        if private {
            // SAFETY: main has started no thread yet, so nothing reads the
            // environment concurrently.
            unsafe { std::env::set_var("XDG_RUNTIME_DIR", &dir) };
        }
    }
}
