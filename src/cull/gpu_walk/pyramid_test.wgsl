// hiz's visibility test (hiz.rs), appended to boxes.wgsl: raster_mark.wgsl's
// counterpart, compute passes over the same GPU-built queue of tree nodes.
// Where raster_mark.wgsl draws each box against the depth drawn so far,
// cs_test compares each box's nearest depth with the farthest depth of the
// pyramid (pyramid.rs) over the box's screen rectangle, and marks the node
// visible unless the box lies behind all of it. Where it does not, and the
// rectangle holds at most MAX_PIXELS pixels, the node is queued instead,
// and cs_pixels compares its box with the depth itself at each of those
// pixels, as raster_mark.wgsl's fragments would be: one workgroup a box,
// its invocations sharing first the base texels under it, then the pixels
// of those that do not hide it on their own (cs_pixel_args sizes that
// dispatch).
// TO_TEST, VISIBLE, GROUP_SIZE and MAX_GROUPS are written before this text
// from layout.rs's constants, PLANE_ROUNDING and UNBOUNDED from
// gpu/conservative.rs's, MAX_TEXELS and MAX_PIXELS from hiz's parameters.
//
// Why this is conservative (gpu/conservative.rs gives the box its margins):
// every fragment of the object lies within the box's outline on screen and
// no nearer than the box's nearest corner, raised. The rectangle is every
// pixel the outline's bounding rectangle touches, and the pyramid texels
// read hold every one of those pixels in their footprint, so their least
// depth is at most the depth drawn at any pixel the object can reach. A box
// nearer than that at any point passes.
//
// Pixel by pixel (gpu/conservative.rs, BoxPlanes): at a pixel centre whose
// ray meets the box, a fragment of the object lies no nearer than the least
// of the box's entry planes there (nor than its nearest corner); where an
// entry plane lies behind another axis's exit plane, the ray misses the box
// and the object has no fragment at that pixel. box_planes makes the planes
// here from the tested box and the camera's pixel rays, each entry raised
// and each exit lowered by PLANE_ROUNDING of its terms' size, more than
// making and evaluating it in f32 may move it.

// pyramid.rs's ShapeUniform.
struct Pyramid {
    target_size: vec2<u32>,
    base_size: vec2<u32>,
    level_count: u32,
    // Per level: width, height, offset of its first texel; w pads.
    levels: array<vec4<u32>, 32>,
}

@group(1) @binding(0) var<storage, read> queue: array<u32>;
// Level as plain words (walk.wgsl): [1] is the number of entries.
@group(1) @binding(1) var<storage, read> level_in: array<u32>;
@group(1) @binding(2) var<storage, read_write> node_visible: array<u32>;
@group(1) @binding(3) var<storage, read> pyramid: array<f32>;
@group(1) @binding(4) var<uniform> shape: Pyramid;

// A box's planes (box_planes), per world axis: the entry and exit planes'
// per_x, per_y and constant (w pads), at pixel (x, y) worth
// dot(plane.xyz, vec3(x, y, 1.0)).
struct BoxPlanes {
    entries: array<vec4<f32>, 3>,
    exits: array<vec4<f32>, 3>,
}

// The boxes queued for cs_pixels: the indirect dispatch of cs_pixels first
// (x, y, z workgroups; level_test.rs resets it to 0, 1, 1 before each
// level), then how many were queued, then the queue.
struct PixelWork {
    groups: vec3<u32>,
    queued: atomic<u32>,
    nodes: array<u32>,
}

// cs_pixels reads the queue (binding 2: the same words) without the
// atomic, since its dispatch reads them as arguments too.
struct PixelQueue {
    groups: vec3<u32>,
    queued: u32,
    nodes: array<u32>,
}

@group(2) @binding(0) var depth: texture_2d<f32>;
@group(2) @binding(1) var<storage, read_write> pixel_work: PixelWork;
@group(2) @binding(2) var<storage, read> pixel_queue: PixelQueue;

@compute @workgroup_size(GROUP_SIZE)
fn cs_test(@builtin(global_invocation_id) id: vec3<u32>, @builtin(num_workgroups) grid: vec3<u32>) {
    let entries = level_in[1];
    for (var i = id.x; i < entries; i += grid.x * GROUP_SIZE) {
        let node = queue[i];
        // Nodes reaching the near plane are visible already (cs_prepare
        // marked them); every other queued node is TO_TEST.
        if node_visible[node] != TO_TEST {
            continue;
        }
        let on_screen = box_on_screen(boxes[node]);
        // Hidden only when the box lies strictly behind (raster_mark.wgsl's
        // boxes pass with GreaterEqual); a NaN counts as visible, and so
        // does a rectangle a NaN turned inside out.
        if all(on_screen.first <= on_screen.last) && on_screen.nearest < farthest_over(on_screen) {
            continue;
        }
        let extent = on_screen.last - on_screen.first + vec2<u32>(1u);
        if all(on_screen.first <= on_screen.last) && extent.x * extent.y <= MAX_PIXELS {
            let slot = atomicAdd(&pixel_work.queued, 1u);
            // Past the queue (one dispatch's workgroups at most), it is
            // simply visible.
            if slot < min(MAX_GROUPS, arrayLength(&pixel_work.nodes)) {
                pixel_work.nodes[slot] = node;
                continue;
            }
        }
        node_visible[node] = VISIBLE;
    }
}

// One workgroup for each box cs_test queued.
@compute @workgroup_size(1)
fn cs_pixel_args() {
    pixel_work.groups.x = min(atomicLoad(&pixel_work.queued), min(MAX_GROUPS, arrayLength(&pixel_work.nodes)));
}

// Set by the first invocation to find the box shown, so the others stop.
var<workgroup> shown: atomic<u32>;

// The base texels of the box's rectangle that do not hide it on their own
// (cs_pixels' first step), each as y << 16 | x, for the second step.
const MAX_OPEN_TEXELS: u32 = 2048u;
var<workgroup> open_texels: array<u32, MAX_OPEN_TEXELS>;
var<workgroup> open_count: atomic<u32>;

@compute @workgroup_size(GROUP_SIZE)
fn cs_pixels(@builtin(workgroup_id) group: vec3<u32>, @builtin(local_invocation_index) lane: u32) {
    // Cleared here rather than trusted to start at zero: a flag left set
    // would skip the test and leave the box hidden.
    if lane == 0u {
        atomicStore(&shown, 0u);
        atomicStore(&open_count, 0u);
    }
    workgroupBarrier();
    let node = pixel_queue.nodes[group.x];
    let on_screen = box_on_screen(boxes[node]);
    let planes = box_planes(boxes[node]);
    // cs_test queued only rectangles the right way round; should this
    // one's rounding differ, the box is marked visible, after the barrier
    // below, which every invocation must reach.
    let upright = all(on_screen.first <= on_screen.last);
    // 1. Each base texel under the rectangle, by the box's entry planes at
    // their greatest (nearest) over the rectangle's pixels in the texel: a
    // texel farther than the least of them hides the box at each of those
    // pixels (its depth is the farthest over its footprint); and where an
    // entry plane at its greatest lies behind another axis's exit plane at
    // its least (farthest), every ray there misses the box. Either way its
    // pixels need no reading. Most of a large box far behind a wall goes
    // here, and most of the rectangle of a long box seen at a slant, which
    // its outline barely fills.
    let base_first = on_screen.first * shape.base_size / shape.target_size;
    let base_last = on_screen.last * shape.base_size / shape.target_size;
    let texels = base_last - base_first + vec2<u32>(1u);
    let base = shape.levels[0];
    for (var i = lane; upright && i < texels.x * texels.y; i += GROUP_SIZE) {
        let texel = base_first + vec2<u32>(i % texels.x, i / texels.x);
        let span = texel_pixels(texel, on_screen);
        if !span_hides_box(planes, span, on_screen.nearest, pyramid[base.z + texel.y * base.x + texel.x]) {
            let slot = atomicAdd(&open_count, 1u);
            if slot < MAX_OPEN_TEXELS {
                open_texels[slot] = texel.y << 16u | texel.x;
            }
        }
    }
    workgroupBarrier();
    if !upright {
        node_visible[node] = VISIBLE;
        return;
    }
    // 2. The pixels of those texels, shared out: a base texel holds at most
    // ⌈target / base⌉ pixels across (texel_pixels). Where more texels are
    // open than the list holds (a large box on a fine base, whose texels
    // hold a pixel or two, or one in front of most of what lies under it),
    // every pixel of the rectangle.
    let open = atomicLoad(&open_count);
    if open > MAX_OPEN_TEXELS {
        let extent = on_screen.last - on_screen.first + vec2<u32>(1u);
        for (var i = lane; i < extent.x * extent.y && atomicLoad(&shown) == 0u; i += GROUP_SIZE) {
            mark_if_shown(node, planes, on_screen.first + vec2<u32>(i % extent.x, i / extent.x), on_screen.nearest);
        }
        return;
    }
    let across = (shape.target_size + shape.base_size - vec2<u32>(1u)) / shape.base_size;
    let per_texel = across.x * across.y;
    for (var i = lane; i < open * per_texel && atomicLoad(&shown) == 0u; i += GROUP_SIZE) {
        let packed = open_texels[i / per_texel];
        let span = texel_pixels(vec2<u32>(packed & 0xffffu, packed >> 16u), on_screen);
        let offset = i % per_texel;
        let pixel = span.first + vec2<u32>(offset % across.x, offset / across.x);
        if all(pixel <= span.last) {
            mark_if_shown(node, planes, pixel, on_screen.nearest);
        }
    }
}

// Marks `node` visible, and tells the workgroup so, where a ray through
// `pixel` meets its box no farther than the depth drawn there.
fn mark_if_shown(node: u32, planes: BoxPlanes, pixel: vec2<u32>, nearest: f32) {
    if !span_hides_box(planes, PixelSpan(pixel, pixel), nearest, textureLoad(depth, pixel, 0).r) {
        atomicStore(&shown, 1u);
        node_visible[node] = VISIBLE;
    }
}

// The first and last pixels of the rectangle in base texel `texel`'s
// footprint: pixel p lies in texel ⌊p · base / target⌋ (farthest_over), so
// texel t holds pixels ⌈t · target / base⌉ up to the next texel's first,
// at most ⌈target / base⌉ of them across.
struct PixelSpan {
    first: vec2<u32>,
    last: vec2<u32>,
}

fn texel_pixels(texel: vec2<u32>, on_screen: OnScreen) -> PixelSpan {
    let target_size = shape.target_size;
    let base_size = shape.base_size;
    let first = (texel * target_size + base_size - vec2<u32>(1u)) / base_size;
    let next = ((texel + vec2<u32>(1u)) * target_size + base_size - vec2<u32>(1u)) / base_size;
    return PixelSpan(max(first, on_screen.first), min(next - vec2<u32>(1u), on_screen.last));
}

// Whether the box lies behind `farthest` at every pixel centre of a span,
// or the rays through them all miss it; over one pixel, against the depth
// drawn there, the pixel by pixel test itself. At each centre, the box's
// least entry plane (and its nearest corner) bounds its depth, and an entry
// plane behind another axis's exit plane means the ray misses it; over a
// span, each plane is taken at its greatest (entries) or least (exits),
// which lie at corners of it. The planes' f32 margins hold at any pixel
// centre, so at those corners too.
fn span_hides_box(planes: BoxPlanes, span: PixelSpan, nearest: f32, farthest: f32) -> bool {
    var entry = vec3<f32>();
    var exit = vec3<f32>();
    for (var a = 0u; a < 3u; a++) {
        entry[a] = at_corner(planes.entries[a], span, true);
        exit[a] = at_corner(planes.exits[a], span, false);
    }
    let missed = entry.x < exit.y || entry.x < exit.z || entry.y < exit.x || entry.y < exit.z || entry.z < exit.x || entry.z < exit.y;
    return missed || min(nearest, min(entry.x, min(entry.y, entry.z))) < farthest;
}

// The planes of the tested box `b` (gpu/conservative.rs's BoxPlanes): per
// world axis across which the eye lies outside the box, the plane of the
// face facing it, raised by the box's raise, and of the face opposite. The
// ray through pixel (x, y) meets the plane of the face at eye-relative
// coordinate `face` across axis a at view depth face / ray[a], so at depth
// near / that = (near / face) · (x · ray_x + y · ray_y + ray_c)[a].
// conservative.rs's ShaderBoxPlanes::as_the_shader_makes is this
// function's CPU twin.
fn box_planes(b: QueryBox) -> BoxPlanes {
    var planes = BoxPlanes(
        array<vec4<f32>, 3>(vec4<f32>(0.0, 0.0, UNBOUNDED, 0.0), vec4<f32>(0.0, 0.0, UNBOUNDED, 0.0), vec4<f32>(0.0, 0.0, UNBOUNDED, 0.0)),
        array<vec4<f32>, 3>(vec4<f32>(0.0, 0.0, -UNBOUNDED, 0.0), vec4<f32>(0.0, 0.0, -UNBOUNDED, 0.0), vec4<f32>(0.0, 0.0, -UNBOUNDED, 0.0)),
    );
    // camera.wgsl's projection puts the near distance at [3].z (reverse-Z).
    let near = camera.projection[3].z;
    for (var a = 0u; a < 3u; a++) {
        var facing = b.min[a];
        var opposite = b.max[a];
        if b.max[a] < 0.0 {
            facing = b.max[a];
            opposite = b.min[a];
        } else if b.min[a] <= 0.0 {
            // The eye lies within the box's extent along this axis.
            continue;
        }
        // A quotient by a subnormal face has no error bound (the division's
        // holds from f32's least normal number on): no bound from it.
        if abs(facing) < SMALLEST_NORMAL {
            continue;
        }
        let ray = vec3<f32>(camera.ray_x[a], camera.ray_y[a], camera.ray_c[a]);
        let entry = moved_plane((near / facing) * ray, b.min.w, 1.0);
        let exit = moved_plane((near / opposite) * ray, 0.0, -1.0);
        if plane_bounds(entry) && plane_bounds(exit) {
            planes.entries[a] = entry;
            planes.exits[a] = exit;
        }
    }
    return planes;
}

// f32's least normal number.
const SMALLEST_NORMAL: f32 = 1.17549435e-38;

// `plane` raised by `raise` and moved by `sign` times PLANE_ROUNDING of its
// terms' size over the target (the raise counted apart, since it may
// cancel part of the constant whose rounding the margin covers).
fn moved_plane(plane: vec3<f32>, raise: f32, sign: f32) -> vec4<f32> {
    let size = vec2<f32>(shape.target_size);
    let terms = abs(plane.z) + raise + abs(plane.x) * size.x + abs(plane.y) * size.y;
    return vec4<f32>(plane.xy, plane.z + raise + sign * PLANE_ROUNDING * terms, 0.0);
}

// Whether f32 holds the plane well enough for it to bound anything: not
// for a face within f32's smallest distances of the eye (a NaN bounds
// nothing either).
fn plane_bounds(plane: vec4<f32>) -> bool {
    return all(abs(plane) < vec4<f32>(UNBOUNDED / 10.0));
}

// A plane's greatest (or least) over a span's pixel centres.
fn at_corner(plane: vec4<f32>, span: PixelSpan, greatest: bool) -> f32 {
    let rising = vec2<bool>(plane.x > 0.0, plane.y > 0.0) == vec2<bool>(greatest);
    let corner = vec2<f32>(select(span.first, span.last, rising));
    return dot(plane.xyz, vec3<f32>(corner + 0.5, 1.0));
}

// A box on the target: the framebuffer pixels (rows top down) its outline's
// bounding rectangle touches, clamped to the target (the object has no
// pixel beyond it), and its nearest depth, raised.
struct OnScreen {
    first: vec2<u32>,
    last: vec2<u32>,
    nearest: f32,
}

fn box_on_screen(b: QueryBox) -> OnScreen {
    // Every corner lies beyond the near plane (boxes reaching it are never
    // queued as TO_TEST), so w > 0 and the corners bound the projection.
    var low = vec2<f32>(3.4e38);
    var high = vec2<f32>(-3.4e38);
    var nearest = 0.0;
    for (var corner = 0u; corner < 8u; corner++) {
        let clip = box_clip(b, corner);
        let ndc = clip.xyz / clip.w;
        low = min(low, ndc.xy);
        high = max(high, ndc.xy);
        // Reverse-Z: the nearest corner has the greatest depth; box_clip
        // already raised it.
        nearest = max(nearest, ndc.z);
    }
    let size = vec2<f32>(shape.target_size);
    let top_left = (vec2<f32>(low.x, -high.y) * 0.5 + 0.5) * size;
    let bottom_right = (vec2<f32>(high.x, -low.y) * 0.5 + 0.5) * size;
    return OnScreen(
        vec2<u32>(clamp(floor(top_left), vec2<f32>(0.0), size - 1.0)),
        vec2<u32>(clamp(floor(bottom_right), vec2<f32>(0.0), size - 1.0)),
        nearest,
    );
}

// The farthest depth of the pyramid over the rectangle's pixels.
fn farthest_over(on_screen: OnScreen) -> f32 {
    // Pixel p lies in base texel ⌊p · base / target⌋ (pyramid.wgsl's
    // cs_base takes it there); pixels in order map to base texels in order.
    let base_first = on_screen.first * shape.base_size / shape.target_size;
    let base_last = on_screen.last * shape.base_size / shape.target_size;
    // The finest level where the rectangle spans at most MAX_TEXELS texels
    // across: a level-k texel holds base texels [t · 2^k, (t + 1) · 2^k).
    var k = 0u;
    while k + 1u < shape.level_count && any((base_last >> vec2<u32>(k)) - (base_first >> vec2<u32>(k)) >= vec2<u32>(MAX_TEXELS)) {
        k++;
    }
    let level = shape.levels[k];
    let first_texel = base_first >> vec2<u32>(k);
    let last_texel = base_last >> vec2<u32>(k);
    var farthest = 1.0;
    for (var y = first_texel.y; y <= last_texel.y; y++) {
        for (var x = first_texel.x; x <= last_texel.x; x++) {
            farthest = min(farthest, pyramid[level.z + y * level.x + x]);
        }
    }
    return farthest;
}
