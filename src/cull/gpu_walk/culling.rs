//! The culler every GPU-walk mode is: what it walks ([`Walked`]: every
//! object, or the hierarchy cut at two depths), how a level tests boxes
//! ([`NodeTest`]), and the frame of the module above ([`cull_on_gpu`]).
//! roc, ioc and hiz differ only in those two choices and their parameters.

use std::rc::Rc;

use super::depths::DepthRange;
use super::level_test::NodeTest;
use super::lists::VisibleLists;
use super::{CullTree, DrawList, GpuWalk};
use crate::bounds::Aabb;
use crate::cull::culler::{Culler, FrameInput, TraversalStats};
use crate::cull::mode::ModeId;
use crate::gpu::{Frame, GpuAudit, GpuContext, GpuError, GpuSetup};
use crate::object_set::ObjectSet;

/// What a GPU walk tests.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Walked {
    /// Every object's box, in one level (a flat tree).
    Objects,
    /// The hierarchy's node boxes, level by level over the given depths.
    Nodes(DepthRange),
}

/// A mode that culls on the GPU by a [`GpuWalk`].
pub struct GpuCulling {
    mode: ModeId,
    walked: Walked,
    node_test: NodeTest,
    /// What summary.json records, before `prepare` adds the depths chosen.
    parameters: serde_json::Value,
    /// Over nodes: the start and bottom depths, chosen in `prepare`.
    chosen: Option<(u32, u32)>,
    /// Made in `prepare`.
    walk: Option<GpuWalk>,
    /// Over nodes: per tree node, the hierarchy node whose box it tests.
    source: Vec<u32>,
    /// Lists shared with other walks, given before `prepare`; without them
    /// `prepare` makes the walk lists of its own.
    shared_lists: Option<Rc<VisibleLists>>,
}

impl GpuCulling {
    pub fn new(mode: ModeId, walked: Walked, node_test: NodeTest, parameters: serde_json::Value) -> GpuCulling {
        GpuCulling {
            mode,
            walked,
            node_test,
            parameters,
            chosen: None,
            walk: None,
            source: Vec::new(),
            shared_lists: None,
        }
    }
}

#[cfg(test)]
impl GpuCulling {
    /// The walk, for the test that holds it against its CPU twin.
    pub(super) fn gpu_walk(&self) -> Option<&GpuWalk> {
        self.walk.as_ref()
    }
}

impl Culler for GpuCulling {
    fn name(&self) -> &str {
        self.mode.name()
    }

    fn parameters(&self) -> serde_json::Value {
        let mut p = self.parameters.clone();
        if let Some((start, bottom)) = self.chosen {
            p["start_depth"] = start.into();
            p["bottom_depth"] = bottom.into();
        }
        p
    }

    fn traverses_hierarchy(&self) -> bool {
        matches!(self.walked, Walked::Nodes(_))
    }

    fn prepare(&mut self, setup: &GpuSetup) -> Result<(), GpuError> {
        let tree = match self.walked {
            Walked::Objects => CullTree::flat(setup.scene.objects.len() as u32),
            Walked::Nodes(range) => {
                let (start, bottom) = range.choose(setup.hierarchy, &setup.scene.objects);
                self.chosen = Some((start, bottom));
                let (tree, source) = CullTree::cut(setup.hierarchy, start, bottom);
                self.source = source;
                tree
            }
        };
        let lists = match &self.shared_lists {
            Some(shared) => shared.clone(),
            None => Rc::new(VisibleLists::new(setup.gpu, setup.draws)?),
        };
        self.walk = Some(GpuWalk::new(setup, &tree, self.node_test, lists)?);
        Ok(())
    }

    fn share_visible_lists(&mut self, lists: &Rc<VisibleLists>) {
        self.shared_lists = Some(lists.clone());
    }

    /// # Panics
    /// Before `prepare`: a session prepares every mode first.
    fn frame(&mut self, ctx: &mut dyn Frame, input: &FrameInput) -> TraversalStats {
        let walk = self
            .walk
            .as_mut()
            .expect("the session prepared the mode, which made its walk");
        match self.walked {
            Walked::Objects => {
                let bounds = input.scene.objects.iter().map(|o| o.bounds);
                cull_on_gpu(ctx, input, walk, bounds)
            }
            Walked::Nodes(_) => {
                let nodes = &input.hierarchy.nodes;
                let bounds = self.source.iter().map(|&n| nodes[n as usize].bounds);
                cull_on_gpu(ctx, input, walk, bounds)
            }
        }
    }

    fn audit(&mut self, gpu: &GpuContext, _input: &FrameInput, drawn: &mut ObjectSet) -> Option<GpuAudit> {
        self.walk.as_mut()?.audit(gpu, drawn)
    }
}

/// One frame of GPU-driven culling over `walk`'s tree, whose nodes have the
/// boxes `bounds` this frame, every step through `GpuFrame`:
///
/// 1. Last frame's visible objects are drawn first: they are this frame's
///    occluders, and part of its image. Those that have left the frustum
///    are taken out first, each by its own box (frustum.rs).
/// 2. Per level: the queued nodes' boxes are tested against that depth.
///    [`NodeTest::Raster`] draws them with forced early depth testing, and
///    a fragment that passes marks its node visible (raster_mark.wgsl);
///    [`NodeTest::Pyramid`] builds the depth pyramid once, before the first
///    level, and a compute pass marks every queued box not behind the
///    pyramid, or for a small one not behind the depth at each of its pixels
///    (pyramid_test.wgsl). Then `cs_expand` queues the children of visible
///    inner nodes and marks the objects of visible leaves (walk.wgsl). The
///    queue's length stays on the GPU: it is the instance count of the next
///    level's indirect draw and dispatch. Boxes that reach the near plane
///    are marked visible before the walk (by `cs_prepare`, which makes the
///    boxes), since they cannot be rasterised, and boxes outside the
///    frustum are never queued.
/// 3. `cs_compact` turns the marks of objects inside the frustum (a
///    visible node's subtree may reach out of it) into next frame's visible
///    list and the list of objects visible now but not drawn in step 1.
/// 4. That list is drawn by indirect multi-draw (its length read back
///    first where indirect draws cannot take their count from a buffer).
///
/// The traversal figures are counted on the GPU and read back after the
/// frame, untimed (the mode's audit: objects drawn early and late, nodes
/// tested and hidden per level, the GPU time of steps 2-3): the ones
/// returned are empty.
///
/// # Panics
/// Without a GPU frame: a session runs GPU walks on the GPU.
fn cull_on_gpu(
    frame: &mut dyn Frame,
    input: &FrameInput,
    walk: &mut GpuWalk,
    bounds: impl ExactSizeIterator<Item = Aabb>,
) -> TraversalStats {
    let ctx = frame.on_gpu().expect("the session runs GPU walks on the GPU");
    let (camera, indirect_count) = (input.camera, ctx.gpu().indirect_count);
    // Staging the frustum and the boxes that changed is culling work on
    // the CPU, outside `record`.
    walk.prepare_frustum(camera, ctx.margins(), input.scene, input.moved, input.frame);
    ctx.record(&mut |work| walk.drop_what_left_the_frustum(work));
    ctx.draw_indirect(walk.list(DrawList::Visible, indirect_count));
    walk.stage_node_boxes(input, bounds);
    ctx.record(&mut |work| walk.begin(work));
    for _ in 0..walk.levels() {
        ctx.record(&mut |work| walk.walk_level(work));
    }
    ctx.record(&mut |work| walk.compact(work));
    if !indirect_count {
        ctx.round_trip(&mut |gpu, encoder| walk.read_counts(gpu, encoder));
    }
    ctx.draw_indirect(walk.list(DrawList::NewlyVisible, indirect_count));
    TraversalStats::default()
}
