// hiz's visibility test (hiz.rs), appended to boxes.wgsl: raster_mark.wgsl's
// counterpart, a compute pass over the same GPU-built queue of tree nodes.
// Where raster_mark.wgsl draws each box against the depth drawn so far, this
// compares each box's nearest depth with the farthest depth of the pyramid
// (pyramid.rs) over the box's screen rectangle, and marks the node visible
// unless the box lies behind all of it. Where it does not, and the
// rectangle holds at most MAX_PIXELS pixels, the box is compared with the
// depth itself at each of them, as raster_mark.wgsl's fragments would be.
// TO_TEST, VISIBLE and GROUP_SIZE are written before this text from
// pool.rs's constants, MAX_TEXELS and MAX_PIXELS from hiz's parameters.
//
// Why this is conservative (gpu/conservative.rs gives the box its margins):
// every fragment of the object lies within the box's outline on screen and
// no nearer than the box's nearest corner, raised. The rectangle is every
// pixel the outline's bounding rectangle touches, and the pyramid texels
// read hold every one of those pixels in their footprint, so their least
// depth is at most the depth drawn at any pixel the object can reach. A box
// nearer than that at any point passes.
//
// Pixel by pixel (gpu/conservative.rs, BoxPlanes): at a pixel centre whose
// ray meets the box, a fragment of the object lies no nearer than the least
// of the box's entry planes there (nor than its nearest corner); where an
// entry plane lies behind another axis's exit plane, the ray misses the box
// and the object has no fragment at that pixel. The planes come from the
// CPU in f64, each entry raised and each exit lowered by what their f32
// evaluation here may move them.

// pyramid.rs's ShapeUniform.
struct Pyramid {
    target_size: vec2<u32>,
    base_size: vec2<u32>,
    level_count: u32,
    // Per level: width, height, offset of its first texel; w pads.
    levels: array<vec4<u32>, 32>,
}

@group(1) @binding(0) var<storage, read> queue: array<u32>;
// Level as plain words (walk.wgsl): [1] is the number of entries.
@group(1) @binding(1) var<storage, read> level_in: array<u32>;
@group(1) @binding(2) var<storage, read_write> node_visible: array<u32>;
@group(1) @binding(3) var<storage, read> pyramid: array<f32>;
@group(1) @binding(4) var<uniform> shape: Pyramid;

// gpu/conservative.rs's ShaderBoxPlanes: per plane (per_x, per_y, constant).
struct BoxPlanes {
    entries: array<vec4<f32>, 3>,
    exits: array<vec4<f32>, 3>,
}

@group(2) @binding(0) var<storage, read> box_planes: array<BoxPlanes>;
@group(2) @binding(1) var depth: texture_2d<f32>;

@compute @workgroup_size(GROUP_SIZE)
fn cs_test(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) grid: vec3<u32>) {
    let entries = level_in[1];
    for (var i = id.x; i < entries; i += grid.x * GROUP_SIZE) {
        let node = queue[i];
        // Nodes reaching the near plane are visible already (the CPU marked
        // them); every other queued node is TO_TEST.
        if node_visible[node] == TO_TEST && box_may_be_visible(node) {
            node_visible[node] = VISIBLE;
        }
    }
}

fn box_may_be_visible(node: u32) -> bool {
    let b = boxes[node];
    // Every corner lies beyond the near plane (boxes reaching it are never
    // queued as TO_TEST), so w > 0 and the corners bound the projection.
    var low = vec2<f32>(3.4e38);
    var high = vec2<f32>(-3.4e38);
    var nearest = 0.0;
    for (var corner = 0u; corner < 8u; corner++) {
        let clip = box_clip(b, corner);
        let ndc = clip.xyz / clip.w;
        low = min(low, ndc.xy);
        high = max(high, ndc.xy);
        // Reverse-Z: the nearest corner has the greatest depth; box_clip
        // already raised it.
        nearest = max(nearest, ndc.z);
    }
    // Framebuffer pixels (rows top down) the rectangle touches, clamped to
    // the target: the object has no pixel beyond it.
    let size = vec2<f32>(shape.target_size);
    let top_left = (vec2<f32>(low.x, -high.y) * 0.5 + 0.5) * size;
    let bottom_right = (vec2<f32>(high.x, -low.y) * 0.5 + 0.5) * size;
    let first = vec2<u32>(clamp(floor(top_left), vec2<f32>(0.0), size - 1.0));
    let last = vec2<u32>(clamp(floor(bottom_right), vec2<f32>(0.0), size - 1.0));
    // Base texel t's footprint spans target pixels [t, t + 1) · target /
    // base, so it touches pixel p when t = ⌊p · base / target⌋; pixels in
    // order map to base texels in order.
    let base_first = first * shape.base_size / shape.target_size;
    let base_last = last * shape.base_size / shape.target_size;
    // The finest level where the rectangle spans at most MAX_TEXELS texels
    // across: a level-k texel holds base texels [t · 2^k, (t + 1) · 2^k).
    var k = 0u;
    while k + 1u < shape.level_count && any((base_last >> vec2<u32>(k)) - (base_first >> vec2<u32>(k)) >= vec2<u32>(MAX_TEXELS)) {
        k++;
    }
    let level = shape.levels[k];
    let first_texel = base_first >> vec2<u32>(k);
    let last_texel = base_last >> vec2<u32>(k);
    var farthest = 1.0;
    for (var y = first_texel.y; y <= last_texel.y; y++) {
        for (var x = first_texel.x; x <= last_texel.x; x++) {
            farthest = min(farthest, pyramid[level.z + y * level.x + x]);
        }
    }
    // Hidden only when the box lies strictly behind (raster_mark.wgsl's
    // boxes pass with GreaterEqual); a NaN counts as visible.
    if nearest < farthest {
        return false;
    }
    let extent = last - first + vec2<u32>(1u);
    if extent.x * extent.y > MAX_PIXELS {
        return true;
    }
    return pixel_may_show_box(node, first, last, nearest);
}

// Whether, at some pixel of first..last (inclusive), a ray through its
// centre meets the box no farther than the depth drawn there.
fn pixel_may_show_box(node: u32, first: vec2<u32>, last: vec2<u32>, nearest: f32) -> bool {
    let p = box_planes[node];
    for (var y = first.y; y <= last.y; y++) {
        for (var x = first.x; x <= last.x; x++) {
            let centre = vec3<f32>(f32(x) + 0.5, f32(y) + 0.5, 1.0);
            let entry = vec3<f32>(dot(p.entries[0].xyz, centre), dot(p.entries[1].xyz, centre), dot(p.entries[2].xyz, centre));
            let exit = vec3<f32>(dot(p.exits[0].xyz, centre), dot(p.exits[1].xyz, centre), dot(p.exits[2].xyz, centre));
            let missed = entry.x < exit.y || entry.x < exit.z || entry.y < exit.x || entry.y < exit.z || entry.z < exit.x || entry.z < exit.y;
            if missed {
                continue;
            }
            let bound = min(nearest, min(entry.x, min(entry.y, entry.z)));
            if !(bound < textureLoad(depth, vec2<u32>(x, y), 0).r) {
                return true;
            }
        }
    }
    return false;
}
