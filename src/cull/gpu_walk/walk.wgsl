// The compute stages of a GPU walk (paper 004 §2) that every level test
// shares: walking the tree one level at a time, and building the draw lists.
// The test that marks a level's visible nodes comes before each expansion:
// raster_mark.wgsl (roc, ioc) or pyramid_test.wgsl (hiz).
//
// Every pass strides over its work by the size of its grid, so a queue or an
// object count beyond what one dispatch can launch is still covered.

struct TreeNode {
    // Children are nodes[first_child .. first_child + child_count]; a node
    // with none is where the walk stops (a leaf, or the bottom depth).
    first_child: u32,
    child_count: u32,
    // The subtree's objects are order[first_object .. first_object + object_count].
    first_object: u32,
    object_count: u32,
}

// The arguments of one level: an indexed indirect draw of a box (36
// indices) per queue entry, an indirect dispatch over the queue, and what
// became of the previous level's nodes that were not found visible by a
// test.
struct Level {
    index_count: u32,
    entries: atomic<u32>,
    first_index: u32,
    base_vertex: i32,
    first_instance: u32,
    groups_x: atomic<u32>,
    groups_y: u32,
    groups_z: u32,
    // Tested, and not found visible.
    hidden: atomic<u32>,
    // Children outside the frustum: hidden untested, and not queued.
    outside: atomic<u32>,
    // Reaching the near plane: visible untested.
    near: atomic<u32>,
}

// wgpu's DrawIndexedIndirectArgs.
struct DrawCommand {
    index_count: u32,
    instance_count: u32,
    first_index: u32,
    base_vertex: i32,
    first_instance: u32,
}

struct Counts {
    visible: atomic<u32>,
    newly_visible: atomic<u32>,
}

// node_visible words (TO_TEST, VISIBLE, OUTSIDE_FRUSTUM, REACHES_NEAR),
// object_state bits (VISIBLE_LAST_FRAME persists from frame to frame;
// MARKED lives from the level walk to compaction), drawn words
// (DRAWN_EARLY, DRAWN_LATE), GROUP_SIZE and MAX_GROUPS are written before
// this text from layout.rs's constants.

@group(0) @binding(0) var<storage, read> queue_in: array<u32>;
// Level as plain words: [1] is the number of entries in queue_in.
@group(0) @binding(1) var<storage, read> level_in: array<u32>;
@group(0) @binding(2) var<storage, read> node_visible: array<u32>;
@group(0) @binding(3) var<storage, read_write> queue_out: array<u32>;
@group(0) @binding(4) var<storage, read_write> level_out: Level;

@group(1) @binding(0) var<storage, read> nodes: array<TreeNode>;
@group(1) @binding(1) var<storage, read> order: array<u32>;
@group(1) @binding(2) var<storage, read_write> object_state: array<u32>;

@group(2) @binding(0) var<storage, read> draws: array<DrawCommand>;
// The visible list at [0, n), the newly visible list at [n, 2n), n objects.
@group(2) @binding(1) var<storage, read_write> commands: array<DrawCommand>;
@group(2) @binding(2) var<storage, read_write> counts: Counts;
// DRAWN_EARLY for every object drawn first this frame (last frame's
// visible list), DRAWN_LATE for every one drawn after the walk (read back
// for the statistics).
@group(2) @binding(3) var<storage, read_write> drawn: array<u32>;

// 004 §2: "If the node is culled, we stop the traversal for the node [...].
// If the node is a leaf, we directly mark it as a potentially visible
// occludee in the VB. Otherwise, we tightly pack and enqueue them for the
// next occlusion test." Bottom-depth nodes arrive here as leaves, so marking
// a leaf's objects also marks "all the children in the subtrees of the
// visible nodes" at the bottom level.
@compute @workgroup_size(GROUP_SIZE)
fn cs_expand(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) grid: vec3<u32>) {
    let entries = level_in[1];
    for (var i = id.x; i < entries; i += grid.x * GROUP_SIZE) {
        let index = queue_in[i];
        switch node_visible[index] {
            case TO_TEST: {
                atomicAdd(&level_out.hidden, 1u);
                continue;
            }
            case REACHES_NEAR: {
                atomicAdd(&level_out.near, 1u);
            }
            default: {}
        }
        let node = nodes[index];
        if node.child_count == 0u {
            // Subtrees reached in one walk are disjoint: no other
            // invocation touches these objects' state.
            for (var k = 0u; k < node.object_count; k++) {
                let object = order[node.first_object + k];
                object_state[object] |= MARKED;
            }
        } else {
            // A child outside the frustum cannot be visible: it is counted
            // and not queued, which spares its test.
            var inside = 0u;
            for (var k = 0u; k < node.child_count; k++) {
                inside += u32(node_visible[node.first_child + k] != OUTSIDE_FRUSTUM);
            }
            atomicAdd(&level_out.outside, node.child_count - inside);
            let slot = atomicAdd(&level_out.entries, inside);
            var next = slot;
            for (var k = 0u; k < node.child_count; k++) {
                let child = node.first_child + k;
                if node_visible[child] != OUTSIDE_FRUSTUM {
                    queue_out[next] = child;
                    next += 1u;
                }
            }
            let groups = (slot + inside + GROUP_SIZE - 1u) / GROUP_SIZE;
            atomicMax(&level_out.groups_x, min(groups, MAX_GROUPS));
        }
    }
}

// Before last frame's visible list is drawn as this frame's occluders: an
// object of it that has left the frustum is drawn with no instance, and no
// longer counts as visible last frame (marked again, it is drawn late).
@compute @workgroup_size(GROUP_SIZE)
fn cs_early_frustum(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) grid: vec3<u32>) {
    let listed = atomicLoad(&counts.visible);
    for (var i = id.x; i < listed; i += grid.x * GROUP_SIZE) {
        let object = commands[i].first_instance;
        if outside_frustum(object) {
            commands[i].instance_count = 0u;
            object_state[object] &= ~VISIBLE_LAST_FRAME;
        }
    }
}

// The objects marked this frame and inside the frustum (a visible node's
// subtree may reach out of it) become the visible list (next frame's
// occluders); those not drawn as occluders this frame also go to the newly
// visible list, drawn now.
@compute @workgroup_size(GROUP_SIZE)
fn cs_compact(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) grid: vec3<u32>) {
    let n = arrayLength(&draws);
    for (var object = id.x; object < n; object += grid.x * GROUP_SIZE) {
        let state = object_state[object];
        let was_visible = (state & VISIBLE_LAST_FRAME) != 0u;
        let marked = (state & MARKED) != 0u && !outside_frustum(object);
        object_state[object] = select(0u, VISIBLE_LAST_FRAME, marked);
        drawn[object] = select(select(0u, DRAWN_LATE, marked), DRAWN_EARLY, was_visible);
        if marked {
            commands[atomicAdd(&counts.visible, 1u)] = draws[object];
            if !was_visible {
                commands[n + atomicAdd(&counts.newly_visible, 1u)] = draws[object];
            }
        }
    }
}
