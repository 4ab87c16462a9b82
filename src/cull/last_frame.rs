//! How a frame follows the last one a culler made something for: under
//! `auto` a culler does not run in every frame, and a bench's recording
//! starts its frames again after the warm-up, so what changed since (which
//! movers moved) is not always what `FrameInput::moved` names.

/// The last frame (`FrameInput::frame`) a culler made something for, to
/// tell what may have changed since: under `auto` a culler does not run
/// in every frame, and a bench's recording starts its frames again after
/// the warm-up.
#[derive(Clone, Copy, Debug, Default)]
pub struct LastFrame(Option<u32>);

/// How a frame follows the last one made for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Since {
    First,
    /// Frames were skipped (or the path started again): every mover may
    /// have moved, not only those `FrameInput::moved` names.
    Gap,
    Next,
    /// The same frame again (another walk of `auto`'s made for it).
    Same,
}

impl LastFrame {
    /// How `frame` follows the last; it becomes the last.
    pub fn advance(&mut self, frame: u32) -> Since {
        let since = match self.0 {
            None => Since::First,
            Some(f) if f.checked_add(1) == Some(frame) => Since::Next,
            Some(f) if f == frame => Since::Same,
            Some(_) => Since::Gap,
        };
        self.0 = Some(frame);
        since
    }
}
