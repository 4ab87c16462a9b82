//! The GPU half of the walk: one mode's pipelines, per-node scratch and
//! tree on the GPU, the passes of one walk, and the audit after it (see the
//! module above for the frame they make).

use std::rc::Rc;

use super::frustum::{ObjectBox, ObjectFrustum, object_box};
use super::layout::{
    DISPATCH_OFFSET, DRAW_COMMAND_BYTES, DRAWN_EARLY, DRAWN_LATE, GROUP_SIZE, HIDDEN, LEVEL_BYTES, LEVEL_OUTSIDE,
    LEVEL_WORDS, MAX_GROUPS, shader_constants,
};
use super::level_test::{LevelTest, NodeTest};
use super::lists::VisibleLists;
#[cfg(test)]
use super::pyramid::PyramidLevel;
use super::tree::{CullTree, MAX_LEVELS};
use crate::bounds::Aabb;
use crate::camera::Camera;
use crate::cull::culler::FrameInput;
use crate::cull::last_frame::{LastFrame, Since};
#[cfg(test)]
use crate::gpu::QueryBox;
use crate::gpu::{
    BOX_INDEX_COUNT, BoxMargins, GpuAudit, GpuContext, GpuError, GpuSetup, GpuTimer, GpuWork, IndirectCount,
    IndirectDraws, Readback, bind_buffers, bind_group_layout, box_bind_group_layout, box_buffer, check_storage_binding,
    storage_buffer,
};
use crate::object_set::ObjectSet;
use crate::scene::Scene;

/// Which of a tree's two draw lists.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DrawList {
    /// The objects visible in the last walk: this frame's occluders.
    Visible,
    /// The objects visible in this walk and not in the last one.
    NewlyVisible,
}

/// A [`CullTree`] on the GPU, bound with the visible lists the walk keeps
/// between frames.
struct TreeOnGpu {
    nodes: u32,
    objects: u32,
    levels: u32,
    /// The nodes tested first (before the frustum is applied).
    seed: Vec<u32>,
    tree_group: wgpu::BindGroup,
    lists_group: wgpu::BindGroup,
    lists: Rc<VisibleLists>,
}

/// The walk recorded for the audit.
struct Walk {
    /// Seed nodes (those outside the frustum, never queued, are counted in
    /// the seed level's arguments).
    seed_len: u32,
    levels: u32,
}

/// A walk's boxes made on the GPU (prepare_nodes.wgsl): its pipelines,
/// what they read (each node's box in two f32 parts, and the seed nodes)
/// and write (the node scratch's boxes, words and first queue).
struct BoxesOnGpu {
    prepare: wgpu::ComputePipeline,
    seed: wgpu::ComputePipeline,
    group: wgpu::BindGroup,
    seeds: u32,
    /// The nodes' boxes where they are not the objects' (a flat tree's
    /// nodes are its objects, whose boxes [`ObjectFrustum`] keeps), with
    /// those staged for the next walk and the frame they were made for.
    node_boxes: Option<NodeSources>,
}

/// A tree's node boxes on the GPU, made again only when they may have
/// changed.
struct NodeSources {
    buffer: wgpu::Buffer,
    staged: Vec<ObjectBox>,
    frame: LastFrame,
}

/// Per-node scratch for a tree of `capacity` nodes.
struct NodeScratch {
    boxes: wgpu::Buffer,
    box_group: wgpu::BindGroup,
    /// The visibility buffer: one word per node, set by the level's test
    /// (and by `cs_prepare` for boxes that reach the near plane).
    node_visible: wgpu::Buffer,
    /// Two queues with their levels' arguments, used in turn: a level reads
    /// one and fills the other.
    queues: [wgpu::Buffer; 2],
    level_args: [wgpu::Buffer; 2],
    /// `step_groups[i]` reads queue `i` and fills the other.
    step_groups: [wgpu::BindGroup; 2],
}

/// One GPU-driven mode's walk: its pipelines, per-node scratch, tree on
/// the GPU, and the record of its last walk for the audit.
pub struct GpuWalk {
    test: LevelTest,
    expand: wgpu::ComputePipeline,
    compact: wgpu::ComputePipeline,
    early_frustum: wgpu::ComputePipeline,
    /// Where the boxes are made, on the GPU.
    boxes_on_gpu: BoxesOnGpu,
    /// `compact`'s and `early_frustum`'s empty group 0.
    no_bindings: wgpu::BindGroup,
    scratch: NodeScratch,
    /// An empty level, copied over a level before its queue is filled.
    empty_level: wgpu::Buffer,
    objects: u32,
    triangles: Vec<u64>,
    /// One word per object: drawn this frame.
    drawn: wgpu::Buffer,
    /// Each level's arguments after it ran, for the audit.
    level_stats: wgpu::Buffer,
    /// Span [`WALK_SPAN`] around a walk and its compaction, and for a
    /// pyramid test [`PYRAMID_SPAN`] around the pyramid's build, where
    /// timestamps exist.
    timer: Option<GpuTimer>,
    audit_readback: Readback,
    counts_readback: Readback,
    walk: Option<Walk>,
    tree: TreeOnGpu,
    /// The objects' boxes and the frame's frustum, for the object-level
    /// frustum test of `early_frustum` and `compact`.
    object_frustum: ObjectFrustum,
    /// Scratch for the audit, reused so a frame allocates nothing once warm.
    words: Vec<u32>,
}

/// The timer's spans.
const WALK_SPAN: usize = 0;
const PYRAMID_SPAN: usize = 1;

/// Where the audit's parts sit in its read-back buffer (and, but for the
/// drawn words, in `level_stats`): each level's arguments after it ran, the
/// seed level's as it began, then a word per object drawn.
const SEED_LEVEL_OFFSET: u64 = MAX_LEVELS as u64 * LEVEL_BYTES;
const AUDIT_DRAWN_OFFSET: u64 = SEED_LEVEL_OFFSET + LEVEL_BYTES;

impl GpuWalk {
    /// Puts `tree` on the GPU, bound with `lists` (the visible set it starts
    /// from and keeps between frames), and makes what walking it with
    /// `node_test` takes. Needs [`GpuContext::gpu_driven`].
    pub fn new(
        setup: &GpuSetup,
        tree: &CullTree,
        node_test: NodeTest,
        lists: Rc<VisibleLists>,
    ) -> Result<GpuWalk, GpuError> {
        let GpuSetup { gpu, camera, draws, .. } = *setup;
        let cull_module = frustum_module(gpu, "walk.wgsl", include_str!("walk.wgsl"));
        let WalkLayouts {
            boxes: box_layout,
            step: step_layout,
            tree: tree_layout,
            lists: lists_layout,
        } = WalkLayouts::new(gpu);
        let nodes = tree.nodes.len() as u32;
        let scratch = NodeScratch::new(gpu, [&box_layout, &step_layout], camera, nodes);
        let s = &scratch;
        let test = LevelTest::new(
            setup,
            node_test,
            &box_layout,
            &s.queues,
            &s.level_args,
            &s.node_visible,
            nodes,
        )?;
        let expand = gpu.compute_pipeline(
            &cull_module,
            "cs_expand",
            Some(&[Some(&step_layout), Some(&tree_layout)]),
        );
        // cs_compact and cs_early_frustum share the module's groups 1 to 3
        // and bind nothing at 0: an empty group there keeps them within 8
        // storage buffers, the minimum an adapter guarantees.
        let no_bindings = bind_group_layout(gpu, "no bindings", &[]);
        let object_frustum = ObjectFrustum::new(gpu, lists.boxes.clone());
        let lists_pipeline = |entry: &str| {
            let layouts = [
                Some(&no_bindings),
                Some(&tree_layout),
                Some(&lists_layout),
                Some(&object_frustum.layout),
            ];
            gpu.compute_pipeline(&cull_module, entry, Some(&layouts))
        };
        let compact = lists_pipeline("cs_compact");
        let early_frustum = lists_pipeline("cs_early_frustum");
        let no_bindings = bind_buffers(gpu, &no_bindings, &[]);
        let objects = draws.len() as u32;
        let copy = wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        assert!(
            tree.order.len() == objects as usize && lists.objects() == objects,
            "a cull tree and its lists hold every object of the scene"
        );
        assert!((1..=MAX_LEVELS).contains(&tree.levels), "1..={MAX_LEVELS} levels");
        let drawn = storage_buffer(gpu, "drawn objects", u64::from(objects.max(1)) * 4, copy);
        let boxes_on_gpu = BoxesOnGpu::new(gpu, tree, &scratch, &object_frustum)?;
        let tree = TreeOnGpu::new(gpu, tree, &tree_layout, &lists_layout, lists, &drawn);
        let spans = match node_test {
            NodeTest::Raster => 1,
            NodeTest::Pyramid { .. } => 2,
        };
        Ok(GpuWalk {
            drawn,
            level_stats: storage_buffer(gpu, "level statistics", AUDIT_DRAWN_OFFSET, copy),
            empty_level: gpu.buffer_with(
                "empty level",
                bytemuck::cast_slice(&EMPTY_LEVEL),
                wgpu::BufferUsages::COPY_SRC,
            ),
            timer: GpuTimer::new(gpu, spans),
            audit_readback: Readback::new(gpu, "gpu culling audit", AUDIT_DRAWN_OFFSET + u64::from(objects) * 4),
            counts_readback: Readback::new(gpu, "draw list lengths", 8),
            objects,
            triangles: draws.iter().map(|d| u64::from(d.index_count / 3)).collect(),
            walk: None,
            tree,
            object_frustum,
            words: Vec::new(),
            scratch,
            test,
            expand,
            compact,
            early_frustum,
            boxes_on_gpu,
            no_bindings,
        })
    }

    /// Levels a walk of the tree takes.
    pub fn levels(&self) -> u32 {
        self.tree.levels
    }

    /// On the CPU, before frame `frame`'s early draw: stages `camera`'s
    /// frustum and box `margins`, and the boxes of the objects of `scene`
    /// that moved (`moved`; every mover's where this walk did not run in the
    /// frame before, every object's in its first frame).
    pub fn prepare_frustum(&mut self, camera: &Camera, margins: BoxMargins, scene: &Scene, moved: &[u32], frame: u32) {
        self.object_frustum.prepare(camera, margins, scene, moved, frame);
    }

    /// Takes the objects that have left the frustum out of last frame's
    /// visible list, before it is drawn (`cs_early_frustum`).
    pub fn drop_what_left_the_frustum(&mut self, work: GpuWork) {
        let GpuWork { gpu, encoder, .. } = work;
        self.object_frustum.write(gpu);
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some("frustum test of the early list"),
            timestamp_writes: None,
        });
        pass.set_pipeline(&self.early_frustum);
        pass.set_bind_group(0, &self.no_bindings, &[]);
        pass.set_bind_group(1, &self.tree.tree_group, &[]);
        pass.set_bind_group(2, &self.tree.lists_group, &[]);
        pass.set_bind_group(3, &self.object_frustum.group, &[]);
        pass.dispatch_workgroups(groups_for(self.objects), 1, 1);
    }

    /// Stages the tree's node boxes (`bounds`, one per node, in node order,
    /// as `input`'s frame has them) for the GPU to make the frame's boxes
    /// from, where they may have changed: in the first frame, when objects
    /// moved, and after a gap in the frames this walk ran in a scene with
    /// movers. A flat tree's are the objects' own, staged with the frustum.
    pub fn stage_node_boxes(&mut self, input: &FrameInput, bounds: impl ExactSizeIterator<Item = Aabb>) {
        assert_eq!(bounds.len(), self.tree.nodes as usize, "one box per tree node");
        if let Some(sources) = &mut self.boxes_on_gpu.node_boxes {
            let changed = match sources.frame.advance(input.frame) {
                Since::First => true,
                Since::Gap => !input.scene.movers.is_empty(),
                Since::Next => !input.moved.is_empty(),
                Since::Same => false,
            };
            sources.staged.clear();
            if changed {
                sources.staged.extend(bounds.map(|b| object_box(&b)));
            }
        }
    }

    /// Starts a walk: makes the boxes on the GPU, marks those that reach
    /// the near plane visible and queues the seed nodes not outside the
    /// frustum, counting the others in the seed level's arguments (kept
    /// for the audit).
    pub fn begin(&mut self, work: GpuWork) {
        let GpuWork { gpu, encoder, .. } = work;
        let tree = &self.tree;
        let s = &self.scratch;
        if let Some(t) = &self.timer {
            t.begin(encoder, WALK_SPAN);
        }
        let on_gpu = &self.boxes_on_gpu;
        if let Some(sources) = on_gpu.node_boxes.as_ref().filter(|n| !n.staged.is_empty()) {
            gpu.queue
                .write_buffer(&sources.buffer, 0, bytemuck::cast_slice(&sources.staged));
        }
        encoder.copy_buffer_to_buffer(&self.empty_level, 0, &s.level_args[0], 0, LEVEL_BYTES);
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("prepare boxes"),
                timestamp_writes: None,
            });
            pass.set_bind_group(0, &on_gpu.group, &[]);
            pass.set_bind_group(3, &self.object_frustum.group, &[]);
            pass.set_pipeline(&on_gpu.prepare);
            pass.dispatch_workgroups(groups_for(tree.nodes), 1, 1);
            pass.set_pipeline(&on_gpu.seed);
            pass.dispatch_workgroups(groups_for(on_gpu.seeds), 1, 1);
        }
        encoder.copy_buffer_to_buffer(&s.level_args[0], 0, &self.level_stats, SEED_LEVEL_OFFSET, LEVEL_BYTES);
        self.test.begin(encoder, self.timer.as_ref().map(|t| (t, PYRAMID_SPAN)));
        self.walk = Some(Walk {
            seed_len: tree.seed.len() as u32,
            levels: 0,
        });
    }

    /// One level: tests the queued nodes' boxes against `depth` (drawn, or
    /// through its pyramid), marking the visible ones, then expands them
    /// into the next queue.
    ///
    /// # Panics
    /// Outside a walk, or past [`MAX_LEVELS`].
    pub fn walk_level(&mut self, work: GpuWork) {
        let GpuWork { encoder, depth, .. } = work;
        let walk = self.walk.as_mut().expect("walk_level follows begin");
        let tree = &self.tree;
        assert!(walk.levels < MAX_LEVELS, "at most {MAX_LEVELS} levels");
        let (input, output) = ((walk.levels % 2) as usize, ((walk.levels + 1) % 2) as usize);
        let s = &self.scratch;
        encoder.copy_buffer_to_buffer(&self.empty_level, 0, &s.level_args[output], 0, LEVEL_BYTES);
        self.test
            .encode(encoder, depth, &s.box_group, input, &s.level_args[input]);
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("expand a level"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.expand);
            pass.set_bind_group(0, &s.step_groups[input], &[]);
            pass.set_bind_group(1, &tree.tree_group, &[]);
            // The dispatch arguments follow the draw's five words.
            pass.dispatch_workgroups_indirect(&s.level_args[input], DISPATCH_OFFSET);
        }
        encoder.copy_buffer_to_buffer(
            &s.level_args[output],
            0,
            &self.level_stats,
            u64::from(walk.levels) * LEVEL_BYTES,
            LEVEL_BYTES,
        );
        walk.levels += 1;
    }

    /// Ends the walk: the marks become the tree's visible and newly visible
    /// lists.
    pub fn compact(&mut self, work: GpuWork) {
        let encoder = work.encoder;
        let tree = &self.tree;
        encoder.clear_buffer(&tree.lists.counts, 0, None);
        {
            let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
                label: Some("compact draw lists"),
                timestamp_writes: None,
            });
            pass.set_pipeline(&self.compact);
            pass.set_bind_group(0, &self.no_bindings, &[]);
            pass.set_bind_group(1, &tree.tree_group, &[]);
            pass.set_bind_group(2, &tree.lists_group, &[]);
            pass.set_bind_group(3, &self.object_frustum.group, &[]);
            pass.dispatch_workgroups(groups_for(self.objects), 1, 1);
        }
        if let Some(t) = &self.timer {
            t.end(encoder, WALK_SPAN);
        }
    }

    /// Submits `encoder` and reads the lengths of the tree's lists back,
    /// for adapters whose draws cannot take them from a buffer.
    pub fn read_counts(&mut self, gpu: &GpuContext, mut encoder: wgpu::CommandEncoder) {
        let lists = &self.tree.lists;
        self.counts_readback.copy(&mut encoder, &lists.counts, 0, 0, 8);
        gpu.queue.submit([encoder.finish()]);
        self.counts_readback.read(gpu, 8, &mut self.words);
        lists.set_known_counts([self.words[0], self.words[1]]);
    }

    /// The commands of one of the tree's lists; the count comes from the
    /// GPU when `indirect_count`, else from the last
    /// [`GpuWalk::read_counts`].
    pub fn list(&self, list: DrawList, indirect_count: bool) -> IndirectDraws<'_> {
        let tree = &self.tree;
        let (index, offset) = match list {
            DrawList::Visible => (0, 0),
            DrawList::NewlyVisible => (1, u64::from(tree.objects) * DRAW_COMMAND_BYTES),
        };
        IndirectDraws {
            commands: &tree.lists.commands,
            offset,
            count: if indirect_count {
                IndirectCount::InBuffer {
                    buffer: &tree.lists.counts,
                    offset: 4 * index as u64,
                    max: tree.objects,
                }
            } else {
                IndirectCount::Known(tree.lists.known_counts()[index])
            },
        }
    }

    /// After a frame with a walk, untimed: adds the objects drawn from the
    /// lists to `drawn` and returns the walk's figures; `None` when the frame
    /// had no walk.
    pub fn audit(&mut self, gpu: &GpuContext, drawn: &mut ObjectSet) -> Option<GpuAudit> {
        let walk = self.walk.take()?;
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        if let Some(t) = &self.timer {
            t.resolve(&mut encoder);
        }
        let level_bytes = u64::from(walk.levels) * LEVEL_BYTES;
        // The levels this walk ran, and the seed level.
        if level_bytes > 0 {
            self.audit_readback
                .copy(&mut encoder, &self.level_stats, 0, 0, level_bytes);
        }
        self.audit_readback.copy(
            &mut encoder,
            &self.level_stats,
            SEED_LEVEL_OFFSET,
            SEED_LEVEL_OFFSET,
            LEVEL_BYTES,
        );
        let drawn_bytes = u64::from(self.objects) * 4;
        if drawn_bytes > 0 {
            self.audit_readback
                .copy(&mut encoder, &self.drawn, 0, AUDIT_DRAWN_OFFSET, drawn_bytes);
        }
        gpu.queue.submit([encoder.finish()]);
        self.audit_readback
            .read(gpu, AUDIT_DRAWN_OFFSET + drawn_bytes, &mut self.words);

        let word = |offset: u64| (offset / 4) as usize;
        let levels = &self.words[..word(level_bytes)];
        let seed_outside = self.words[word(SEED_LEVEL_OFFSET) + LEVEL_OUTSIDE];
        let mut audit = GpuAudit {
            nodes_visited: u64::from(walk.seed_len),
            nodes_outside_frustum: u64::from(seed_outside),
            ..GpuAudit::default()
        };
        let mut reaching_near = 0;
        for (k, level) in levels.chunks_exact(word(LEVEL_BYTES)).enumerate() {
            // A level's arguments hold the next queue's length and the
            // counts of the level that filled it: its entries found hidden
            // or reaching the near plane, and the children it found outside
            // the frustum and did not queue (reached, so visited, too).
            if k + 1 < walk.levels as usize {
                audit.nodes_visited += u64::from(level[1]);
            }
            let [hidden, outside, near] = [level[HIDDEN], level[HIDDEN + 1], level[HIDDEN + 2]].map(u64::from);
            audit.nodes_visited += outside;
            audit.nodes_hidden += hidden;
            audit.nodes_outside_frustum += outside;
            reaching_near += near;
        }
        audit.nodes_tested = audit.nodes_visited - audit.nodes_outside_frustum - reaching_near;
        for (object, &flag) in self.words[word(AUDIT_DRAWN_OFFSET)..].iter().enumerate() {
            match flag {
                DRAWN_EARLY => audit.drawn_early += 1,
                DRAWN_LATE => audit.drawn_late += 1,
                _ => continue,
            }
            drawn.insert(object as u32);
            audit.triangles_drawn += self.triangles[object];
        }
        if let Some(t) = &mut self.timer {
            let spans = t.read_spans(gpu);
            audit.cull_gpu = spans.get(WALK_SPAN).copied();
            audit.pyramid_gpu = spans.get(PYRAMID_SPAN).copied();
        }
        Some(audit)
    }
}

#[cfg(test)]
impl GpuWalk {
    /// The pyramid the last walk tested against, for a walk with a
    /// pyramid test: its levels, and their texels read back.
    pub(super) fn pyramid(&self, gpu: &GpuContext) -> Option<(Vec<PyramidLevel>, Vec<Vec<f32>>)> {
        let pyramid = self.test.pyramid()?;
        Some((pyramid.levels().to_vec(), pyramid.read(gpu)))
    }

    /// Every node's word of the visibility buffer as the last walk left it
    /// (before it: `TO_TEST`, `OUTSIDE_FRUSTUM` or `REACHES_NEAR`;
    /// the level test turned the boxes it found visible into
    /// [`VISIBLE`](super::layout::VISIBLE)),
    /// for the CPU twin of the walk.
    pub(super) fn node_states(&self, gpu: &GpuContext) -> Vec<u32> {
        self.read_words(gpu, &self.scratch.node_visible, 1)
    }

    /// The boxes the last walk tested, as the GPU made them, one per node.
    pub(super) fn tested_boxes(&self, gpu: &GpuContext) -> Vec<QueryBox> {
        let words = self.read_words(gpu, &self.scratch.boxes, 8);
        let floats: Vec<f32> = words.into_iter().map(f32::from_bits).collect();
        floats
            .chunks_exact(8)
            .map(|b| QueryBox {
                min: glam::Vec4::from_slice(&b[..4]),
                max: glam::Vec4::from_slice(&b[4..]),
            })
            .collect()
    }

    /// `words_per_node` words a node of `buffer`, read back.
    fn read_words(&self, gpu: &GpuContext, buffer: &wgpu::Buffer, words_per_node: u64) -> Vec<u32> {
        let bytes = u64::from(self.tree.nodes) * 4 * words_per_node;
        let readback = Readback::new(gpu, "node words", bytes);
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        readback.copy(&mut encoder, buffer, 0, 0, bytes);
        gpu.queue.submit([encoder.finish()]);
        let mut words = Vec::new();
        readback.read(gpu, bytes, &mut words);
        words
    }
}

impl TreeOnGpu {
    /// `tree` on the GPU, bound with `lists` and `drawn` (a word per object
    /// drawn).
    fn new(
        gpu: &GpuContext,
        tree: &CullTree,
        tree_layout: &wgpu::BindGroupLayout,
        lists_layout: &wgpu::BindGroupLayout,
        lists: Rc<VisibleLists>,
        drawn: &wgpu::Buffer,
    ) -> TreeOnGpu {
        let storage = wgpu::BufferUsages::STORAGE;
        let node_buffer = gpu.buffer_with("tree nodes", bytemuck::cast_slice(&tree.nodes), storage);
        let order = gpu.buffer_with("tree order", bytemuck::cast_slice(&tree.order), storage);
        TreeOnGpu {
            nodes: tree.nodes.len() as u32,
            objects: tree.order.len() as u32,
            levels: tree.levels,
            seed: tree.seed.clone(),
            tree_group: bind_buffers(gpu, tree_layout, &[&node_buffer, &order, &lists.object_state]),
            lists_group: bind_buffers(
                gpu,
                lists_layout,
                &[&lists.all_commands, &lists.commands, &lists.counts, drawn],
            ),
            lists,
        }
    }
}

/// What the passes that test boxes against the frustum share (frustum.rs),
/// written before their own text.
const OBJECT_FRUSTUM_WGSL: &str = include_str!("object_frustum.wgsl");

/// A module of the shared constants, object_frustum.wgsl and `source`.
fn frustum_module(gpu: &GpuContext, label: &str, source: &str) -> wgpu::ShaderModule {
    gpu.device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some(label),
        source: wgpu::ShaderSource::Wgsl([&shader_constants(), OBJECT_FRUSTUM_WGSL, source].concat().into()),
    })
}

/// The bind group layouts of a walk's passes: the boxes a level tests
/// (boxes.wgsl's group 0), a level's step (queues, arguments and node
/// words), the tree with the objects' state, and the draw lists.
struct WalkLayouts {
    boxes: wgpu::BindGroupLayout,
    step: wgpu::BindGroupLayout,
    tree: wgpu::BindGroupLayout,
    lists: wgpu::BindGroupLayout,
}

impl WalkLayouts {
    fn new(gpu: &GpuContext) -> WalkLayouts {
        use wgpu::BufferBindingType::Storage;
        let read = (wgpu::ShaderStages::COMPUTE, Storage { read_only: true });
        let write = (wgpu::ShaderStages::COMPUTE, Storage { read_only: false });
        WalkLayouts {
            boxes: box_bind_group_layout(gpu),
            step: bind_group_layout(gpu, "level step", &[read, read, read, write, write]),
            tree: bind_group_layout(gpu, "tree", &[read, read, write]),
            lists: bind_group_layout(gpu, "lists", &[read, write, write, write]),
        }
    }
}

impl BoxesOnGpu {
    /// The passes that make `tree`'s boxes, words and seed queue in
    /// `scratch`, from its nodes' boxes: the objects' own in `objects` for a
    /// flat tree, else a buffer of their own, staged each frame they may
    /// have changed.
    /// Fails where the adapter cannot bind a box for each node.
    fn new(
        gpu: &GpuContext,
        tree: &CullTree,
        scratch: &NodeScratch,
        objects: &ObjectFrustum,
    ) -> Result<BoxesOnGpu, GpuError> {
        let module = frustum_module(gpu, "prepare_nodes.wgsl", include_str!("prepare_nodes.wgsl"));
        use wgpu::BufferBindingType::Storage;
        let (read, write) = (Storage { read_only: true }, Storage { read_only: false });
        let layout = bind_group_layout(
            gpu,
            "prepare boxes",
            &[write, write, write, write, read, read].map(|t| (wgpu::ShaderStages::COMPUTE, t)),
        );
        let pipeline = |entry: &str| {
            gpu.compute_pipeline(
                &module,
                entry,
                Some(&[Some(&layout), None, None, Some(&objects.layout)]),
            )
        };
        let bytes = tree.nodes.len().max(1) as u64 * size_of::<ObjectBox>() as u64;
        let node_boxes = if tree.is_flat() {
            None
        } else {
            check_storage_binding(gpu, "storage binding for the walk's node boxes (bytes)", bytes)?;
            Some(NodeSources {
                buffer: storage_buffer(gpu, "node boxes", bytes, wgpu::BufferUsages::COPY_DST),
                staged: Vec::new(),
                frame: LastFrame::default(),
            })
        };
        let seeds = gpu.buffer_with(
            "seed nodes",
            bytemuck::cast_slice(&tree.seed),
            wgpu::BufferUsages::STORAGE,
        );
        let sources = node_boxes.as_ref().map_or(objects.boxes(), |n| &n.buffer);
        Ok(BoxesOnGpu {
            prepare: pipeline("cs_prepare"),
            seed: pipeline("cs_seed"),
            group: bind_buffers(
                gpu,
                &layout,
                &[
                    &scratch.boxes,
                    &scratch.node_visible,
                    &scratch.queues[0],
                    &scratch.level_args[0],
                    sources,
                    &seeds,
                ],
            ),
            seeds: tree.seed.len() as u32,
            node_boxes,
        })
    }
}

impl NodeScratch {
    fn new(
        gpu: &GpuContext,
        [box_layout, step_layout]: [&wgpu::BindGroupLayout; 2],
        camera: &wgpu::Buffer,
        capacity: u32,
    ) -> NodeScratch {
        let capacity = capacity.max(1);
        let words = u64::from(capacity) * 4;
        let copy_dst = wgpu::BufferUsages::COPY_DST;
        let (boxes, box_group) = box_buffer(gpu, box_layout, camera, capacity);
        let node_visible = storage_buffer(gpu, "visibility buffer", words, copy_dst | wgpu::BufferUsages::COPY_SRC);
        let queues = [0, 1].map(|_| storage_buffer(gpu, "node queue", words, copy_dst));
        let level_args = [0, 1].map(|_| {
            storage_buffer(
                gpu,
                "level arguments",
                LEVEL_BYTES,
                wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_SRC | copy_dst,
            )
        });
        let step_groups = [0, 1].map(|i| {
            let o = 1 - i;
            bind_buffers(
                gpu,
                step_layout,
                &[&queues[i], &level_args[i], &node_visible, &queues[o], &level_args[o]],
            )
        });
        NodeScratch {
            boxes,
            box_group,
            node_visible,
            queues,
            level_args,
            step_groups,
        }
    }
}

/// An empty level's arguments (`Level` in walk.wgsl): an indexed indirect
/// draw of one box per entry and an indirect dispatch over the entries,
/// none yet, and no nodes counted.
const EMPTY_LEVEL: [u32; LEVEL_WORDS] = [BOX_INDEX_COUNT, 0, 0, 0, 0, 0, 1, 1, 0, 0, 0];

/// Workgroups that cover `n` items, within the grid limit (the shaders
/// stride over the rest).
fn groups_for(n: u32) -> u32 {
    n.div_ceil(GROUP_SIZE).min(MAX_GROUPS)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cull::gpu_walk::TreeNode;
    use crate::cull::gpu_walk::frustum::{ObjectBox, ShaderFrustum};
    use crate::gpu::wgsl::{parse, struct_layout as layout};
    use crate::gpu::{BOXES_WGSL, CAMERA_WGSL};

    #[test]
    fn the_shaders_lay_out_what_this_file_writes_and_reads() {
        let module = parse(&[&shader_constants(), OBJECT_FRUSTUM_WGSL, include_str!("walk.wgsl")].concat());
        let (members, size) = layout(&module, "Level");
        assert_eq!(
            u64::from(size),
            LEVEL_BYTES,
            "EMPTY_LEVEL and Level are LEVEL_WORDS words"
        );
        let offset = |name: &str| members.iter().find(|(n, _)| n == name).map(|&(_, o)| u64::from(o));
        assert_eq!(offset("groups_x"), Some(DISPATCH_OFFSET));
        assert_eq!(
            offset("hidden"),
            Some(HIDDEN as u64 * 4),
            "the audit reads hidden, outside, near"
        );
        assert_eq!(offset("outside"), Some(HIDDEN as u64 * 4 + 4));
        assert_eq!(offset("near"), Some(HIDDEN as u64 * 4 + 8));
        let (members, size) = layout(&module, "TreeNode");
        assert_eq!(size as usize, std::mem::size_of::<TreeNode>());
        let names: Vec<&str> = members.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["first_child", "child_count", "first_object", "object_count"]);
        assert_eq!(u64::from(layout(&module, "DrawCommand").1), DRAW_COMMAND_BYTES);
        let (members, size) = layout(&module, "ObjectBox");
        assert_eq!(size as usize, std::mem::size_of::<ObjectBox>());
        let names: Vec<&str> = members.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["centre_high", "centre_low", "extent"]);
        let (members, size) = layout(&module, "ObjectFrustum");
        assert_eq!(size as usize, std::mem::size_of::<ShaderFrustum>());
        let names: Vec<&str> = members.iter().map(|(n, _)| n.as_str()).collect();
        assert_eq!(names, ["eye_high", "eye_low", "planes", "forward", "margins"]);
        parse(
            &[
                CAMERA_WGSL,
                BOXES_WGSL,
                &shader_constants(),
                include_str!("raster_mark.wgsl"),
            ]
            .concat(),
        );
    }
}
