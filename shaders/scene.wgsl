// Scene rendering: one vertex stage, two fragment stages.
//
// fs_shaded is what every culling mode draws (timed); fs_object_id is the
// reference pass (untimed) that records which object owns each pixel. Error
// is measured by comparing depth between the two, so the vertex position is
// @invariant: both pipelines must compute bit-identical depth for the same
// triangle, whatever each program's other outputs are. `camera` (binding 0)
// is camera.wgsl, written before this text.

struct Object {
    // Object-to-camera transform, built camera-relative in f64 on the CPU.
    model_view: mat4x4<f32>,
    // FragmentLimit in gpu/conservative.rs: per world axis, near / (the
    // eye-relative coordinate of the box face facing the eye), or 0 where
    // the eye lies within the box's extent; w is the raise.
    limit: vec4<f32>,
}

@group(0) @binding(1) var<storage, read> objects: array<Object>;

struct VertexOut {
    @invariant @builtin(position) clip: vec4<f32>,
    @location(0) view_position: vec3<f32>,
    @location(1) @interpolate(flat) object: u32,
    // The object's fragment limit, handed on unchanged: on llvmpipe a flat
    // varying costs the fragment stage far less than a storage read.
    @location(2) @interpolate(flat) limit: vec4<f32>,
}

// The draw's first instance is the object id.
@vertex
fn vs_main(@location(0) position: vec3<f32>, @builtin(instance_index) object: u32) -> VertexOut {
    let view = objects[object].model_view * vec4<f32>(position, 1.0);
    var out: VertexOut;
    out.clip = camera.projection * view;
    out.view_position = view.xyz;
    out.object = object;
    out.limit = objects[object].limit;
    return out;
}

// Whether a fragment lies in front of its object's bounding box: depth
// extrapolated by the rasteriser on a triangle seen edge-on (rule 2 of
// gpu/conservative.rs). Every fragment stage discards such fragments, so
// that no box test can miss a fragment that direct rendering shows.
//
// The pixel's ray meets the plane of the box face facing the eye across
// axis i at depth limit[i] * ray[i]; the nearest of those is where it
// enters the box. The comparison is on the bits: non-negative floats order
// like their bits, and a fragment's depth may be NaN or infinite where the
// rasteriser extrapolated wildly (seen on llvmpipe: such a fragment stored
// depth 1). Any float comparison with NaN is false, and shader compilers
// may assume there is none; as bits, NaN, infinity and negative depths all
// lie beyond any limit. A negative limit (the ray leaves the face behind)
// clamps to 0, beyond which every fragment lies.
fn in_front_of_box(in: VertexOut) -> bool {
    let p = in.clip;
    let ray = p.x * camera.ray_x.xyz + p.y * camera.ray_y.xyz + camera.ray_c.xyz;
    let faces = select(vec3<f32>(2.0), in.limit.xyz * ray, in.limit.xyz != vec3<f32>(0.0));
    let nearest = max(min(faces.x, min(faces.y, faces.z)) + in.limit.w, 0.0);
    return bitcast<u32>(p.z) > bitcast<u32>(nearest);
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
    // Derivatives first: they need the whole quad, in uniform control flow.
    let normal = normalize(cross(dpdx(in.view_position), dpdy(in.view_position)));
    let facing = abs(dot(normal, normalize(-in.view_position)));
    if (in_front_of_box(in)) {
        discard;
    }
    return vec4<f32>(palette(in.object) * (0.25 + 0.75 * facing), 1.0);
}

// 0 is the clear value: "no object".
@fragment
fn fs_object_id(in: VertexOut) -> @location(0) u32 {
    if (in_front_of_box(in)) {
        discard;
    }
    return in.object + 1u;
}

// Depth complexity: every fragment adds 1/255 to an additively blended
// 8-bit target, so a pixel's value × 255 counts the surfaces drawn over it
// (no depth test), saturating at 255.
@fragment
fn fs_heat(in: VertexOut) -> @location(0) vec4<f32> {
    if (in_front_of_box(in)) {
        discard;
    }
    return vec4<f32>(1.0 / 255.0, 0.0, 0.0, 1.0);
}
