// The depth pyramid of two-phase hierarchical-depth culling (see
// pyramid.rs). Reverse-Z: a smaller depth is farther, so every texel keeps
// the smallest depth below it: the farthest surface over its footprint. A
// box whose nearest depth is smaller than that is hidden.
//
// Every level lives in one f32 array; a dispatch fills one level.

struct Level {
    // The level read (the depth target itself for the base).
    source_offset: u32,
    source_width: u32,
    source_height: u32,
    // The level written.
    offset: u32,
    width: u32,
    height: u32,
}

@group(0) @binding(0) var<uniform> level: Level;
@group(0) @binding(1) var<storage, read_write> pyramid: array<f32>;
@group(0) @binding(2) var depth: texture_2d<f32>;

// The base: a power-of-two size at most the target's over a divisor d, so
// each base texel covers source_width / width ∈ [d, 2d) target texels
// across (the whole side where the target is narrower than d). Target
// texel p belongs to base texel ⌊p · width / source_width⌋, as the test
// maps a box's pixels to base texels (pyramid_test.wgsl), so base texel t
// takes the least depth over target texels ⌈t · source / width⌉ up to the
// next one's first: every target texel in exactly one base texel, which is
// what keeps the base conservative at any target size, and each read once.
@compute @workgroup_size(8, 8)
fn cs_base(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= level.width || id.y >= level.height {
        return;
    }
    let x0 = (id.x * level.source_width + level.width - 1u) / level.width;
    let x1 = ((id.x + 1u) * level.source_width + level.width - 1u) / level.width;
    let y0 = (id.y * level.source_height + level.height - 1u) / level.height;
    let y1 = ((id.y + 1u) * level.source_height + level.height - 1u) / level.height;
    var farthest = 1.0;
    for (var y = y0; y < y1; y++) {
        for (var x = x0; x < x1; x++) {
            farthest = min(farthest, textureLoad(depth, vec2<u32>(x, y), 0).r);
        }
    }
    pyramid[level.offset + id.y * level.width + id.x] = farthest;
}

// Every further level halves a power-of-two size (a side already 1 stays
// 1): its texel takes the least of the 2×2 (or 2×1) texels below it.
@compute @workgroup_size(8, 8)
fn cs_reduce(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= level.width || id.y >= level.height {
        return;
    }
    let x1 = min(2u * id.x + 1u, level.source_width - 1u);
    let y1 = min(2u * id.y + 1u, level.source_height - 1u);
    var farthest = 1.0;
    for (var y = 2u * id.y; y <= y1; y++) {
        for (var x = 2u * id.x; x <= x1; x++) {
            farthest = min(farthest, pyramid[level.source_offset + y * level.source_width + x]);
        }
    }
    pyramid[level.offset + id.y * level.width + id.x] = farthest;
}
