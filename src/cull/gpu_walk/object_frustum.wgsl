// Every object's box and the frame's frustum (frustum.rs), bound as group 3
// by every pass that tests boxes against the frustum: walk.wgsl's
// cs_early_frustum and cs_compact, prepare_nodes.wgsl's cs_prepare.
// GPU_OUTSIDE_SLACK and GPU_ABSOLUTE_ERROR are written before this text.

// An object's box: its centre in two parts (high and low) and its half
// extent, rounded up.
struct ObjectBox {
    centre_high: vec4<f32>,
    centre_low: vec4<f32>,
    extent: vec4<f32>,
}

// The frame's eye in two parts, the frustum's planes (inward unit normal in
// xyz, offset in w, eye-centred), the view direction (xyz) with the near
// distance (w), and the box margins of prepare_nodes.wgsl: growth per
// reach, raise (absolute, per unit of depth) and the nearest view depth at
// which a box counts as reaching the near plane.
struct ObjectFrustum {
    eye_high: vec4<f32>,
    eye_low: vec4<f32>,
    planes: array<vec4<f32>, 5>,
    forward: vec4<f32>,
    margins: vec4<f32>,
}

@group(3) @binding(0) var<storage, read> object_boxes: array<ObjectBox>;
@group(3) @binding(1) var<uniform> frustum: ObjectFrustum;

fn max_abs(v: vec3<f32>) -> f32 {
    let a = abs(v);
    return max(max(a.x, a.y), a.z);
}

// The object's box centre relative to the eye, made part by part, so far
// from the origin the low parts still count.
fn eye_relative_centre(b: ObjectBox) -> vec3<f32> {
    return (b.centre_high.xyz - frustum.eye_high.xyz) + (b.centre_low.xyz - frustum.eye_low.xyz);
}

// What rounding may move a value of the box's by: GPU_OUTSIDE_SLACK of
// its reach, and GPU_ABSOLUTE_ERROR of the larger distance from the origin.
fn rounding(b: ObjectBox, reach: f32) -> f32 {
    let world = max(max_abs(frustum.eye_high.xyz), max_abs(b.centre_high.xyz));
    return GPU_OUTSIDE_SLACK * reach + GPU_ABSOLUTE_ERROR * world;
}

// Whether the object lies wholly behind one of the frustum's planes (see
// box_outside_frustum).
fn outside_frustum(object: u32) -> bool {
    return box_outside_frustum(object_boxes[object]);
}

// Whether box `b` lies wholly behind one of the frustum's planes, by more
// than the test's rounding could move it (frustum.rs: what vfc finds
// outside, this finds outside too).
fn box_outside_frustum(b: ObjectBox) -> bool {
    let centre = eye_relative_centre(b);
    let extent = b.extent.xyz;
    let slack = rounding(b, max_abs(abs(centre) + extent));
    for (var k = 0u; k < 5u; k++) {
        let plane = frustum.planes[k];
        if dot(plane.xyz, centre) + dot(abs(plane.xyz), extent) + plane.w < -slack {
            return true;
        }
    }
    return false;
}
