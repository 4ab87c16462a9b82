// Visible pixels per box: the "virtual occlusion buffer" of paper 002 §4.2
// on today's hardware. Early depth testing is forced, so only fragments that
// pass the depth test run this shader, and each adds one to its box's
// counter. Without forced early depth, hidden fragments would be counted too.
//
// Progressive sampling (002 §4.2, Figure 2): the screen is cut into
// horizontal spans of `span` pixels; only every `step`-th row of spans is
// counted, and in every second column of spans the rows are offset by
// step / 2. step = 1 counts every pixel.

struct Sampling {
    step: u32,
    span: u32,
}

@group(1) @binding(0) var<storage, read_write> counts: array<atomic<u32>>;
@group(1) @binding(1) var<uniform> sampling: Sampling;

@fragment
@early_depth_test(force)
fn fs_count(@builtin(position) position: vec4<f32>, @location(0) @interpolate(flat) index: u32) {
    let x = u32(position.x);
    let y = u32(position.y);
    let column = x / sampling.span;
    let offset = (column % 2u) * (sampling.step / 2u);
    if ((y + offset) % sampling.step == 0u) {
        atomicAdd(&counts[index], 1u);
    }
}
