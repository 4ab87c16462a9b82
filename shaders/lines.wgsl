// Coloured line lists for the overview picture: frustum edges and the boxes
// of culled objects, in eye-relative world coordinates of the viewing camera.

// CameraUniform in gpu/renderer.rs.
struct Camera {
    projection: mat4x4<f32>,
    // Projection times the world-to-camera rotation: for eye-relative
    // world positions.
    view_projection: mat4x4<f32>,
    // The world direction of the ray through pixel (x, y), at view depth 1,
    // is x * ray_x + y * ray_y + ray_c (gpu/conservative.rs).
    ray_x: vec4<f32>,
    ray_y: vec4<f32>,
    ray_c: vec4<f32>,
}

@group(0) @binding(0) var<uniform> camera: Camera;

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
