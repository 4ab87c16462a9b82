// Error measurement against the reference frame (untimed).
//
// count_depth_differences: one invocation per pixel; a pixel is wrong when
// the mode's depth differs from the reference depth in any bit. Depth, not
// colour or id, is compared because it does not depend on draw order. The
// largest |difference| is kept too: non-negative f32 values order like
// their bits, so an integer atomicMax on the bits finds it.
//
// mark_visible_objects: sets bit (id - 1) of a bitset for every object id in
// the reference id target, i.e. the objects that own at least one pixel.
//
// attribute_wrong_pixels: for one mode, charges each wrong pixel to the
// object that owns it in the reference, and keeps the first such pixel of
// each object (row-major), so the results can name what a mode missed.

@group(0) @binding(0) var reference_depth: texture_2d<f32>;
@group(0) @binding(1) var mode_depth: texture_2d<f32>;
struct DepthError {
    wrong_pixels: atomic<u32>,
    max_difference_bits: atomic<u32>,
}

@group(0) @binding(2) var<storage, read_write> error: DepthError;

@compute @workgroup_size(8, 8)
fn count_depth_differences(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(reference_depth);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let p = vec2<i32>(id.xy);
    let reference = textureLoad(reference_depth, p, 0).r;
    let mode = textureLoad(mode_depth, p, 0).r;
    if (bitcast<u32>(reference) != bitcast<u32>(mode)) {
        atomicAdd(&error.wrong_pixels, 1u);
        atomicMax(&error.max_difference_bits, bitcast<u32>(abs(reference - mode)));
    }
}

@group(0) @binding(0) var reference_ids: texture_2d<u32>;
@group(0) @binding(1) var<storage, read_write> visible: array<atomic<u32>>;

@compute @workgroup_size(8, 8)
fn mark_visible_objects(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(reference_ids);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let object = textureLoad(reference_ids, vec2<i32>(id.xy), 0).r;
    if (object != 0u) {
        let i = object - 1u;
        atomicOr(&visible[i / 32u], 1u << (i % 32u));
    }
}

@group(0) @binding(0) var depth_in: texture_2d<f32>;
@group(0) @binding(1) var<storage, read_write> depth_out: array<f32>;

// copy_depth: a depth target (the reference's or a mode's) as a row-major
// array, read the same way as the error count reads it (no depth-format
// texture copy is needed).
@compute @workgroup_size(8, 8)
fn copy_depth(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(depth_in);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    depth_out[id.y * size.x + id.x] = textureLoad(depth_in, vec2<i32>(id.xy), 0).r;
}

@group(0) @binding(2) var owners: texture_2d<u32>;
// Two words per object: wrong pixels, and the complement of the row-major
// index of its first wrong pixel (a buffer cleared to 0 then needs no fill:
// the largest complement is the smallest index).
@group(0) @binding(3) var<storage, read_write> per_object: array<atomic<u32>>;

@compute @workgroup_size(8, 8)
fn attribute_wrong_pixels(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = textureDimensions(reference_depth);
    if (id.x >= size.x || id.y >= size.y) {
        return;
    }
    let p = vec2<i32>(id.xy);
    let object = textureLoad(owners, p, 0).r;
    let reference = textureLoad(reference_depth, p, 0).r;
    let mode = textureLoad(mode_depth, p, 0).r;
    if (object == 0u || bitcast<u32>(reference) == bitcast<u32>(mode)) {
        return;
    }
    let slot = 2u * (object - 1u);
    atomicAdd(&per_object[slot], 1u);
    atomicMax(&per_object[slot + 1u], ~(id.y * size.x + id.x));
}
