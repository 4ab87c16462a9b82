// Bounding boxes for occlusion tests: depth test only, no colour, no depth
// writes. One instance per box, drawn indexed: the vertex index is one of
// the box's 8 corners, and the 36 indices (BOX_INDICES in gpu/queries.rs)
// are its 12 triangles, wound counter-clockwise seen from outside so back
// faces can be culled (the eye is never inside a tested box: such boxes are
// visible without a test). Indexing shades 8 vertices a box instead of 36.
// pixel_count.wgsl holds the fragment stage that counts visible pixels per
// box; raster_mark.wgsl, appended to this file, draws boxes named by a
// GPU-built queue. `camera` (binding 0) is camera.wgsl, written before this
// text.

struct QueryBox {
    // Eye-relative world coordinates, already grown (gpu/conservative.rs);
    // min.w is how much the box is raised in depth.
    min: vec4<f32>,
    max: vec4<f32>,
}

@group(0) @binding(1) var<storage, read> boxes: array<QueryBox>;

struct BoxVertex {
    @builtin(position) clip: vec4<f32>,
    // Which box: the pixel counter to add to.
    @location(0) @interpolate(flat) index: u32,
}

// Clip position of `corner` (0..8) of box `b`: bit 0 picks max x, bit 1
// max y, bit 2 max z.
fn box_clip(b: QueryBox, corner: u32) -> vec4<f32> {
    let p = vec3<f32>(
        select(b.min.x, b.max.x, (corner & 1u) != 0u),
        select(b.min.y, b.max.y, (corner & 2u) != 0u),
        select(b.min.z, b.max.z, (corner & 4u) != 0u),
    );
    let clip = camera.view_projection * vec4<f32>(p, 1.0);
    // Raised in depth by min.w (gpu/conservative.rs, rule 1): z / w grows by
    // it, x and y stay.
    return vec4<f32>(clip.xy, clip.z + b.min.w * clip.w, clip.w);
}

@vertex
fn vs_box(@builtin(vertex_index) corner: u32, @builtin(instance_index) index: u32) -> BoxVertex {
    return BoxVertex(box_clip(boxes[index], corner), index);
}
