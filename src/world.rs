//! The scene as one frame sees it. A scene's movers are put where the frame
//! has them, so everything a culler reads (object bounds, the hierarchy once
//! refit) is current. Static scenes skip all of it.

use std::time::{Duration, Instant};

use crate::hierarchy::Hierarchy;
use crate::scene::Scene;

pub struct World {
    pub scene: Scene,
    /// Built over the frame-0 poses; refit by each mode that traverses it,
    /// inside that mode's timed frame ([`World::refit`]).
    pub hierarchy: Hierarchy,
    moved: Vec<u32>,
}

impl World {
    pub fn new(scene: Scene, hierarchy: Hierarchy) -> World {
        World {
            scene,
            hierarchy,
            moved: Vec::new(),
        }
    }

    /// Puts every mover where `frame` has it.
    pub fn advance(&mut self, frame: u32) {
        self.moved.clear();
        self.scene.pose(frame, &mut self.moved);
    }

    /// Objects whose pose changed in the last [`World::advance`].
    pub fn moved(&self) -> &[u32] {
        &self.moved
    }

    /// Refits the hierarchy around the objects' current bounds when any
    /// moved, and returns the time it took. Repeating it leaves the same
    /// boxes, so every mode that traverses the hierarchy can pay for it in
    /// its own frame, as it would if it ran alone.
    pub fn refit(&mut self) -> Duration {
        if self.moved.is_empty() {
            return Duration::ZERO;
        }
        let start = Instant::now();
        self.hierarchy.refit(&self.scene.objects);
        start.elapsed()
    }
}
