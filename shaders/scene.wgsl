// Scene rendering: one vertex stage, two fragment stages.
//
// fs_shaded is what every culling mode draws (timed); fs_object_id is the
// reference pass (untimed) that records which object owns each pixel. Error
// is measured by comparing depth between the two, so the vertex position is
// @invariant: both pipelines must compute bit-identical depth for the same
// triangle, whatever each program's other outputs are.

struct Camera {
    projection: mat4x4<f32>,
    // Projection times the world-to-camera rotation (used by boxes.wgsl).
    view_projection: mat4x4<f32>,
}

struct Object {
    // Object-to-camera transform, built camera-relative in f64 on the CPU.
    model_view: mat4x4<f32>,
}

@group(0) @binding(0) var<uniform> camera: Camera;
@group(0) @binding(1) var<storage, read> objects: array<Object>;

struct VertexOut {
    @invariant @builtin(position) clip: vec4<f32>,
    @location(0) view_position: vec3<f32>,
    @location(1) @interpolate(flat) object: u32,
}

// The draw's first instance is the object id.
@vertex
fn vs_main(@location(0) position: vec3<f32>, @builtin(instance_index) object: u32) -> VertexOut {
    let view = objects[object].model_view * vec4<f32>(position, 1.0);
    var out: VertexOut;
    out.clip = camera.projection * view;
    out.view_position = view.xyz;
    out.object = object;
    return out;
}

// A stable, well-spread colour per object.
fn palette(object: u32) -> vec3<f32> {
    var h = object * 747796405u + 2891336453u;
    h = ((h >> ((h >> 28u) + 4u)) ^ h) * 277803737u;
    h = (h >> 22u) ^ h;
    let rgb = vec3<f32>(f32(h & 255u), f32((h >> 8u) & 255u), f32((h >> 16u) & 255u)) / 255.0;
    return 0.35 + 0.6 * rgb;
}

// Flat shading from screen-space derivatives (no normals are stored), lit
// by a headlight.
@fragment
fn fs_shaded(in: VertexOut) -> @location(0) vec4<f32> {
    let normal = normalize(cross(dpdx(in.view_position), dpdy(in.view_position)));
    let facing = abs(dot(normal, normalize(-in.view_position)));
    return vec4<f32>(palette(in.object) * (0.25 + 0.75 * facing), 1.0);
}

// 0 is the clear value: "no object".
@fragment
fn fs_object_id(in: VertexOut) -> @location(0) u32 {
    return in.object + 1u;
}

// Depth complexity: every fragment adds 1/255 to an additively blended
// 8-bit target, so a pixel's value × 255 counts the surfaces drawn over it
// (no depth test), saturating at 255.
@fragment
fn fs_heat(in: VertexOut) -> @location(0) vec4<f32> {
    return vec4<f32>(1.0 / 255.0, 0.0, 0.0, 1.0);
}
