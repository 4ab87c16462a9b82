// Coloured line lists for the overview picture: frustum edges and the boxes
// of culled objects, in eye-relative world coordinates of the viewing camera.
// `camera` (binding 0) is camera.wgsl, written before this text.

struct LineVertex {
    @builtin(position) clip: vec4<f32>,
    @location(0) colour: vec3<f32>,
}

@vertex
fn vs_line(@location(0) position: vec3<f32>, @location(1) colour: vec3<f32>) -> LineVertex {
    return LineVertex(camera.view_projection * vec4<f32>(position, 1.0), colour);
}

@fragment
fn fs_line(in: LineVertex) -> @location(0) vec4<f32> {
    return vec4<f32>(in.colour, 1.0);
}
