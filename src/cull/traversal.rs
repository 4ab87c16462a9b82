//! Pieces the hierarchical modes share: front-to-back order and the
//! objects of a leaf.

use std::cmp::Ordering;
use std::collections::BinaryHeap;

use glam::DVec3;

use crate::bounds::Aabb;
use crate::camera::{Containment, Frustum};
use crate::hierarchy::{Hierarchy, Node};
use crate::scene::Scene;

/// Nodes ordered front to back by the distance from the eye to the nearest
/// corner of their box, as 003 §4.2 sorts ("the closest corner of the
/// node's BB to a given viewpoint is used for this sorting").
#[derive(Default)]
pub struct DepthQueue {
    heap: BinaryHeap<Entry>,
}

struct Entry {
    distance_squared: f64,
    node: u32,
}

// Reversed, so the max-heap yields the nearest node; ties by node id keep
// the order deterministic.
impl Ord for Entry {
    fn cmp(&self, other: &Self) -> Ordering {
        other
            .distance_squared
            .total_cmp(&self.distance_squared)
            .then_with(|| other.node.cmp(&self.node))
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

    pub fn push(&mut self, node: u32, bounds: &Aabb, eye: DVec3) {
        let distance_squared = bounds
            .corners()
            .iter()
            .map(|c| c.distance_squared(eye))
            .fold(f64::INFINITY, f64::min);
        self.heap.push(Entry { distance_squared, node });
    }

    pub fn pop(&mut self) -> Option<u32> {
        self.heap.pop().map(|e| e.node)
    }
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
        q.push(0, &at(10.0), eye);
        q.push(1, &at(2.0), eye);
        q.push(2, &at(5.0), eye);
        // A huge box whose nearest corner is far: the paper's rule, not the
        // nearest point of the box, decides.
        q.push(
            3,
            &Aabb::new(DVec3::new(-100.0, -100.0, 3.0), DVec3::new(100.0, 100.0, 4.0)),
            eye,
        );
        let order: Vec<u32> = std::iter::from_fn(|| q.pop()).collect();
        assert_eq!(order, [1, 2, 0, 3]);
    }
}
