// The camera as every shader that reads it sees it, written before each
// such shader's text (gpu/renderer.rs's CAMERA_WGSL), so that the shaders
// share one definition; its layout is held against CameraUniform in
// gpu/renderer.rs by a test.

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
