//! Pieces the hierarchical modes share: front-to-back order and the
//! objects of a leaf.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use glam::DVec3;

use crate::bounds::Aabb;
use crate::camera::{Camera, Containment, Frustum, nearest_view_depth};
use crate::cull::culler::TraversalStats;
use crate::gpu::Frame;
use crate::hierarchy::{Hierarchy, Node};
use crate::scene::Scene;

/// Nodes ordered front to back by a key, nearest first: see
/// [`nearest_corner`] (003) and [`view_depth`] (002).
#[derive(Default)]
pub struct DepthQueue {
    heap: BinaryHeap<Entry>,
}

struct Entry {
    key: f64,
    node: u32,
}

/// 003 §4.2's order: "the closest corner of the node's BB to a given
/// viewpoint is used for this sorting" (squared distance).
pub fn nearest_corner(bounds: &Aabb, eye: DVec3) -> f64 {
    bounds
        .corners()
        .iter()
        .map(|c| c.distance_squared(eye))
        .fold(f64::INFINITY, f64::min)
}

/// 002 §4.4's order: z_min, the depth of the box's nearest corner along the
/// view direction.
pub fn view_depth(bounds: &Aabb, camera: &Camera) -> f64 {
    nearest_view_depth(
        &camera.view_rotation(),
        bounds.min - camera.eye,
        bounds.max - camera.eye,
    )
}

// Reversed, so the max-heap yields the nearest node; ties by node id keep
// the order deterministic.
impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        other.key.total_cmp(&self.key).then_with(|| other.node.cmp(&self.node))
    }
}

impl PartialOrd for Entry {
    fn partial_cmp(&self, other: &Self) -> Option<Ordering> {
        Some(self.cmp(other))
    }
}

impl PartialEq for Entry {
    fn eq(&self, other: &Self) -> bool {
        self.cmp(other) == Ordering::Equal
    }
}

impl Eq for Entry {}

impl DepthQueue {
    pub fn clear(&mut self) {
        self.heap.clear();
    }

    pub fn push(&mut self, node: u32, key: f64) {
        self.heap.push(Entry { key, node });
    }

    pub fn pop(&mut self) -> Option<u32> {
        self.heap.pop().map(|e| e.node)
    }
}

/// How many times the triangles of a frustum where occlusion culling
/// found nothing worth its cost another must hold to be tried again at
/// once ([`outgrew`]).
pub const OUTGROWN: f64 = 4.0;

/// Whether a frustum holding `now` triangles outgrew one that held `then`:
/// more than [`OUTGROWN`] times as many. What occlusion culling hid or
/// cost in the smaller says nothing of the larger: a camera that faced a
/// wall in a doorway, or looked out over an empty edge, turning into a
/// room or a city.
pub fn outgrew(now: u64, then: u64) -> bool {
    now as f64 > OUTGROWN * then.max(1) as f64
}

/// View-frustum culling of the subtree under `node` (002 §4.1): appends
/// the objects it does not exclude, accepting a fully-inside node's whole
/// subtree without further tests.
pub fn frustum_cull_subtree(
    scene: &Scene,
    hierarchy: &Hierarchy,
    node: u32,
    frustum: &Frustum,
    stack: &mut Vec<u32>,
    out: &mut Vec<u32>,
    stats: &mut TraversalStats,
) {
    stack.clear();
    stack.push(node);
    while let Some(index) = stack.pop() {
        let node = &hierarchy.nodes[index as usize];
        stats.nodes_visited += 1;
        match frustum.classify(&node.bounds) {
            Containment::Outside => stats.nodes_culled_frustum += 1,
            Containment::Inside => out.extend_from_slice(hierarchy.subtree_objects(node)),
            Containment::Intersecting if node.is_leaf() => {
                leaf_objects_in_frustum(scene, hierarchy, node, frustum, out)
            }
            Containment::Intersecting => stack.extend(node.children().map(|c| c as u32)),
        }
    }
}

/// The nodes of `candidates` the frustum does not exclude; each counts as
/// visited, and those excluded as frustum-culled.
pub fn in_frustum<'a>(
    hierarchy: &'a Hierarchy,
    candidates: impl Iterator<Item = u32> + 'a,
    frustum: &'a Frustum,
    stats: &'a mut TraversalStats,
) -> impl Iterator<Item = u32> + 'a {
    candidates.filter(move |&n| {
        stats.nodes_visited += 1;
        let outside = frustum.classify(&hierarchy.nodes[n as usize].bounds) == Containment::Outside;
        stats.nodes_culled_frustum += u64::from(outside);
        !outside
    })
}

/// The children of `node`, as node ids.
pub fn children(node: &Node) -> impl Iterator<Item = u32> + use<> {
    node.children().map(|c| c as u32)
}

/// Draws the objects of leaf `node` that the frustum does not exclude;
/// `scratch` is reused between calls.
pub fn draw_leaf(
    ctx: &mut dyn Frame,
    scene: &Scene,
    hierarchy: &Hierarchy,
    node: &Node,
    frustum: &Frustum,
    scratch: &mut Vec<u32>,
) {
    scratch.clear();
    leaf_objects_in_frustum(scene, hierarchy, node, frustum, scratch);
    ctx.draw(scratch);
}

/// Appends the objects of leaf `node` that the frustum does not exclude.
pub fn leaf_objects_in_frustum(
    scene: &Scene,
    hierarchy: &Hierarchy,
    node: &Node,
    frustum: &Frustum,
    out: &mut Vec<u32>,
) {
    out.extend(
        hierarchy
            .subtree_objects(node)
            .iter()
            .filter(|&&o| frustum.classify(&scene.objects[o as usize].bounds) != Containment::Outside),
    );
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nearest_corner_comes_first() {
        let eye = DVec3::ZERO;
        let mut q = DepthQueue::default();
        let at = |x: f64| Aabb::new(DVec3::new(x, 0.0, 0.0), DVec3::new(x + 1.0, 1.0, 1.0));
        let mut push = |node, b: &Aabb| q.push(node, nearest_corner(b, eye));
        push(0, &at(10.0));
        push(1, &at(2.0));
        push(2, &at(5.0));
        // A huge box whose nearest corner is far: the paper's rule, not the
        // nearest point of the box, decides.
        push(
            3,
            &Aabb::new(DVec3::new(-100.0, -100.0, 3.0), DVec3::new(100.0, 100.0, 4.0)),
        );
        let order: Vec<u32> = std::iter::from_fn(|| q.pop()).collect();
        assert_eq!(order, [1, 2, 0, 3]);
    }
}
