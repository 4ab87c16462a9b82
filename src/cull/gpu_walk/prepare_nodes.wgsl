// The boxes of every walk (roc, ioc, hiz) made on the GPU, from each tree
// node's box in two f32 parts (object_frustum.wgsl's ObjectBox: the
// objects' own for a flat tree, the hierarchy's nodes for a cut one), so
// the CPU hands over only the camera: what gpu/conservative.rs's
// eye_relative_box makes on the CPU in f64 (twin.rs's NodeBoxes), with
// margins for f32 (frustum.rs, BoxMargins::for_shader).
// cs_prepare, per node: its word of the visibility buffer (OUTSIDE_FRUSTUM,
// REACHES_NEAR or TO_TEST) and its QueryBox (boxes.wgsl: min with the raise
// in w, then max; empty unless tested). cs_seed then queues the seed nodes
// not outside the frustum in the seed level, and counts the others.
// GROUP_SIZE, MAX_GROUPS, the node words and the LEVEL_* word indices are
// written before this text from layout.rs's constants.

@group(0) @binding(0) var<storage, read_write> boxes: array<vec4<f32>>;
@group(0) @binding(1) var<storage, read_write> node_visible: array<u32>;
@group(0) @binding(2) var<storage, read_write> queue: array<u32>;
// The seed level's arguments as words (walk.wgsl's Level).
@group(0) @binding(3) var<storage, read_write> level: array<atomic<u32>>;
@group(0) @binding(4) var<storage, read> node_boxes: array<ObjectBox>;
@group(0) @binding(5) var<storage, read> seeds: array<u32>;

@compute @workgroup_size(GROUP_SIZE)
fn cs_prepare(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) grid: vec3<u32>) {
    let n = arrayLength(&node_boxes);
    for (var node = id.x; node < n; node += grid.x * GROUP_SIZE) {
        let b = node_boxes[node];
        var state = OUTSIDE_FRUSTUM;
        var low = vec4<f32>(0.0);
        var high = vec4<f32>(0.0);
        // The frustum test first: the near-plane rule must not take a box
        // beside the camera for one that holds it.
        if !box_outside_frustum(b) {
            let centre = eye_relative_centre(b);
            let reach = max_abs(abs(centre) + b.extent.xyz);
            // Grown as on the CPU, and by the rounding of this arithmetic
            // besides, so the box holds the one the CPU would make.
            let grow = vec3<f32>(frustum.margins.x * reach + rounding(b, reach));
            let lo = centre - b.extent.xyz - grow;
            let hi = centre + b.extent.xyz + grow;
            let f = frustum.forward.xyz;
            let nearest = dot(min(f * lo, f * hi), vec3<f32>(1.0));
            if nearest <= frustum.margins.w {
                state = REACHES_NEAR;
            } else {
                state = TO_TEST;
                let raise = frustum.margins.y + frustum.margins.z * frustum.forward.w / nearest;
                low = vec4<f32>(lo, raise);
                high = vec4<f32>(hi, 0.0);
            }
        }
        node_visible[node] = state;
        boxes[2u * node] = low;
        boxes[2u * node + 1u] = high;
    }
}

@compute @workgroup_size(GROUP_SIZE)
fn cs_seed(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) grid: vec3<u32>) {
    let n = arrayLength(&seeds);
    for (var i = id.x; i < n; i += grid.x * GROUP_SIZE) {
        let node = seeds[i];
        if node_visible[node] == OUTSIDE_FRUSTUM {
            atomicAdd(&level[LEVEL_OUTSIDE], 1u);
        } else {
            let slot = atomicAdd(&level[LEVEL_ENTRIES], 1u);
            queue[slot] = node;
            atomicMax(&level[LEVEL_GROUPS_X], min(slot / GROUP_SIZE + 1u, MAX_GROUPS));
        }
    }
}
