// The visibility test of raster occlusion culling (paper 004 §1-2), appended
// to boxes.wgsl. One instance per entry of a GPU-built queue of tree nodes;
// the instance count comes from that queue's indirect arguments, so the CPU
// never learns how long the queue is. Early depth testing is forced, so a
// fragment reaches fs_mark only if it passes the depth test against the
// occluders drawn so far, and then marks its node visible in the visibility
// buffer. Every writer stores the same value, so plain stores suffice.
// VISIBLE is written before this text from layout.rs's constants.

@group(1) @binding(0) var<storage, read> queue: array<u32>;
@group(1) @binding(1) var<storage, read_write> node_visible: array<u32>;

@vertex
fn vs_queued(@builtin(vertex_index) corner: u32, @builtin(instance_index) entry: u32) -> BoxVertex {
    let node = queue[entry];
    return BoxVertex(box_clip(boxes[node], corner), node);
}

@fragment
@early_depth_test(force)
fn fs_mark(@location(0) @interpolate(flat) node: u32) {
    node_visible[node] = VISIBLE;
}
