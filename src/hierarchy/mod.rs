//! The bounding-volume hierarchy every culler traverses.
//!
//! A sloppy tree in the sense of paper 002 §3.1: objects are never split, so
//! sibling boxes may overlap. It is built top-down with a cost function, as
//! 002 §3.2 prescribes ("potential subdivision planes are evaluated using the
//! cost function"): here the binned surface-area heuristic with each object
//! weighted by its triangle count, since drawing cost is what culling saves.
//! A split is kept when `traversal_cost + Σ P(child)·triangles(child)` beats
//! drawing the node's triangles as a leaf, P being the surface-area ratio.
//!
//! Layout: flat arrays in depth-first order. The children of a node are
//! contiguous, and so are the objects of every subtree (`objects` is a
//! permutation of object ids), so a culler that accepts a whole subtree draws
//! one slice.
//!
//! The builder takes any [`Item`]: the cullers build over objects weighted
//! by triangles, the ray caster over a mesh's triangles weighted alike.

use serde::{Deserialize, Serialize};

use crate::bounds::Aabb;
use crate::scene::Object;

/// What a tree is built over: a box, and the cost of what it holds (the
/// work a test of the box can save).
pub trait Item {
    fn bounds(&self) -> Aabb;
    fn cost(&self) -> f64;
}

impl Item for Object {
    fn bounds(&self) -> Aabb {
        self.bounds
    }

    fn cost(&self) -> f64 {
        f64::from(self.triangles)
    }
}

#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct HierarchyParams {
    /// Nodes with more objects than this are always split.
    pub max_leaf_objects: u32,
    /// Cost of testing one node, in triangles drawn.
    pub traversal_cost: f64,
    /// Candidate split planes per axis.
    pub bins: usize,
}

impl Default for HierarchyParams {
    fn default() -> Self {
        HierarchyParams {
            max_leaf_objects: 4,
            traversal_cost: 64.0,
            bins: 16,
        }
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Node {
    pub bounds: Aabb,
    /// Children are `nodes[first_child..first_child + child_count]`.
    pub first_child: u32,
    /// 0 for a leaf.
    pub child_count: u32,
    /// The subtree's objects are `objects[first_object..first_object + object_count]`.
    pub first_object: u32,
    pub object_count: u32,
}

impl Node {
    pub fn is_leaf(&self) -> bool {
        self.child_count == 0
    }

    pub fn children(&self) -> std::ops::Range<usize> {
        self.first_child as usize..(self.first_child + self.child_count) as usize
    }
}

#[derive(Clone, Debug)]
pub struct Hierarchy {
    /// `nodes[0]` is the root.
    pub nodes: Vec<Node>,
    /// Object ids in subtree order.
    pub objects: Vec<u32>,
    pub params: HierarchyParams,
}

/// Summary figures for `occlu info` and the result files.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct HierarchyStats {
    pub nodes: usize,
    pub leaves: usize,
    pub depth: u32,
    pub max_leaf_objects: u32,
}

impl Hierarchy {
    /// Builds the tree over `objects` (at least one).
    pub fn build<T: Item>(objects: &[T], params: &HierarchyParams) -> Hierarchy {
        let mut b = Builder {
            objects,
            params,
            order: (0..objects.len() as u32).collect(),
            nodes: vec![placeholder()],
        };
        b.build(0, 0, objects.len());
        Hierarchy {
            nodes: b.nodes,
            objects: b.order,
            params: *params,
        }
    }

    /// Recomputes every box bottom-up from the objects' current bounds,
    /// keeping the topology: what moving objects cost a bounding-volume
    /// hierarchy each frame (children come after their parents, so one
    /// backward sweep suffices).
    pub fn refit(&mut self, objects: &[Object]) {
        for i in (0..self.nodes.len()).rev() {
            let node = self.nodes[i];
            self.nodes[i].bounds = if node.is_leaf() {
                self.subtree_objects(&node)
                    .iter()
                    .fold(Aabb::EMPTY, |b, &o| b.union(objects[o as usize].bounds))
            } else {
                self.nodes[node.children()]
                    .iter()
                    .fold(Aabb::EMPTY, |b, child| b.union(child.bounds))
            };
        }
    }

    pub fn root(&self) -> &Node {
        &self.nodes[0]
    }

    /// The object ids of a node's subtree.
    pub fn subtree_objects(&self, node: &Node) -> &[u32] {
        &self.objects[node.first_object as usize..(node.first_object + node.object_count) as usize]
    }

    pub fn stats(&self) -> HierarchyStats {
        let mut depth = 0;
        let mut stack = vec![(0usize, 1u32)];
        while let Some((i, d)) = stack.pop() {
            depth = depth.max(d);
            stack.extend(self.nodes[i].children().map(|c| (c, d + 1)));
        }
        let leaves = self.nodes.iter().filter(|n| n.is_leaf());
        HierarchyStats {
            nodes: self.nodes.len(),
            leaves: leaves.clone().count(),
            depth,
            max_leaf_objects: leaves.map(|n| n.object_count).max().unwrap_or(0),
        }
    }
}

fn placeholder() -> Node {
    Node {
        bounds: Aabb::EMPTY,
        first_child: 0,
        child_count: 0,
        first_object: 0,
        object_count: 0,
    }
}

struct Builder<'a, T> {
    objects: &'a [T],
    params: &'a HierarchyParams,
    order: Vec<u32>,
    nodes: Vec<Node>,
}

#[derive(Clone, Copy)]
struct Bin {
    bounds: Aabb,
    cost: f64,
    count: usize,
}

const EMPTY_BIN: Bin = Bin {
    bounds: Aabb::EMPTY,
    cost: 0.0,
    count: 0,
};

impl<T: Item> Builder<'_, T> {
    fn object(&self, i: usize) -> &T {
        &self.objects[self.order[i] as usize]
    }

    /// Fills node `index` with the objects `order[start..end]`.
    fn build(&mut self, index: usize, start: usize, end: usize) {
        let (mut bounds, mut centroids, mut cost) = (Aabb::EMPTY, Aabb::EMPTY, 0.0);
        for i in start..end {
            let o = self.object(i);
            bounds = bounds.union(o.bounds());
            centroids = centroids.grown(o.bounds().center());
            cost += o.cost();
        }
        self.nodes[index] = Node {
            bounds,
            first_object: start as u32,
            object_count: (end - start) as u32,
            ..placeholder()
        };
        let count = end - start;
        if count == 1 {
            return;
        }
        let split = self.best_split(start, end, &bounds, &centroids);
        let must_split = count > self.params.max_leaf_objects as usize;
        let mid = match split {
            Some((split_cost, axis, plane)) if must_split || split_cost < cost => {
                self.partition(start, end, axis, plane)
            }
            None if must_split => start + count / 2, // identical centroids: any halving will do
            _ => return,
        };
        let first_child = self.nodes.len();
        self.nodes.extend([placeholder(), placeholder()]);
        self.nodes[index].first_child = first_child as u32;
        self.nodes[index].child_count = 2;
        self.build(first_child, start, mid);
        self.build(first_child + 1, mid, end);
    }

    /// The cheapest binned split as (cost, axis, centroid plane), or `None`
    /// when all centroids coincide.
    fn best_split(&self, start: usize, end: usize, bounds: &Aabb, centroids: &Aabb) -> Option<(f64, usize, f64)> {
        let bins = self.params.bins.max(2);
        let parent_area = bounds.surface_area().max(f64::MIN_POSITIVE);
        let mut best: Option<(f64, usize, f64)> = None;
        for axis in 0..3 {
            let (lo, hi) = (centroids.min[axis], centroids.max[axis]);
            if hi <= lo {
                continue;
            }
            let bin_of = |c: f64| (((c - lo) / (hi - lo) * bins as f64) as usize).min(bins - 1);
            let mut binned = vec![EMPTY_BIN; bins];
            for i in start..end {
                let o = self.object(i);
                let b = &mut binned[bin_of(o.bounds().center()[axis])];
                b.bounds = b.bounds.union(o.bounds());
                b.cost += o.cost();
                b.count += 1;
            }
            // Sweep from the right, then evaluate each plane from the left.
            let mut right = vec![EMPTY_BIN; bins];
            let mut acc = EMPTY_BIN;
            for k in (1..bins).rev() {
                acc = merge(acc, binned[k]);
                right[k] = acc;
            }
            let mut left = EMPTY_BIN;
            for k in 1..bins {
                left = merge(left, binned[k - 1]);
                let r = right[k];
                if left.count == 0 || r.count == 0 {
                    continue;
                }
                let cost = self.params.traversal_cost
                    + (left.bounds.surface_area() * left.cost + r.bounds.surface_area() * r.cost) / parent_area;
                if best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, axis, lo + (hi - lo) * k as f64 / bins as f64));
                }
            }
        }
        best
    }

    /// Moves objects with centroid below `plane` on `axis` to the front;
    /// returns the first index of the back half.
    fn partition(&mut self, start: usize, end: usize, axis: usize, plane: f64) -> usize {
        let objects = self.objects;
        let part = &mut self.order[start..end];
        let mut mid = 0;
        for i in 0..part.len() {
            if objects[part[i] as usize].bounds().center()[axis] < plane {
                part.swap(i, mid);
                mid += 1;
            }
        }
        // A plane from the binning always separates at least one object, but
        // floating-point ties could empty a side: fall back to halving.
        if mid == 0 || mid == part.len() {
            part.len() / 2 + start
        } else {
            start + mid
        }
    }
}

fn merge(a: Bin, b: Bin) -> Bin {
    Bin {
        bounds: a.bounds.union(b.bounds),
        cost: a.cost + b.cost,
        count: a.count + b.count,
    }
}

/// Objects for unit tests of the structures built over them.
#[cfg(test)]
pub(crate) mod fixtures {
    use glam::{DAffine3, DVec3};

    use crate::bounds::Aabb;
    use crate::scene::Object;

    pub fn object(min: DVec3, size: f64, triangles: u32) -> Object {
        Object {
            name: String::new(),
            mesh: 0,
            transform: DAffine3::IDENTITY,
            bounds: Aabb::new(min, min + DVec3::splat(size)),
            triangles,
            part: 0,
        }
    }

    /// `n` unit cubes on a grid ten wide, 3 units apart.
    pub fn grid_objects(n: usize) -> Vec<Object> {
        (0..n)
            .map(|i| {
                object(
                    DVec3::new((i % 10) as f64 * 3.0, 0.0, (i / 10) as f64 * 3.0),
                    1.0,
                    100 + i as u32,
                )
            })
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::fixtures::{grid_objects, object};
    use super::*;
    use glam::DVec3;

    /// Every structural promise of the layout, checked from scratch.
    fn check_invariants(h: &Hierarchy, objects: &[Object]) {
        let mut seen = h.objects.clone();
        seen.sort();
        assert_eq!(
            seen,
            (0..objects.len() as u32).collect::<Vec<_>>(),
            "objects is a permutation"
        );
        for node in &h.nodes {
            let subtree = h.subtree_objects(node);
            let bounds = subtree
                .iter()
                .fold(Aabb::EMPTY, |b, &o| b.union(objects[o as usize].bounds));
            assert_eq!(node.bounds, bounds, "node bounds are the union of its objects");
            if !node.is_leaf() {
                let kids = &h.nodes[node.children()];
                assert_eq!(kids.iter().map(|k| k.object_count).sum::<u32>(), node.object_count);
                assert_eq!(kids[0].first_object, node.first_object);
                assert!(kids.iter().all(|k| k.object_count > 0));
            } else {
                assert!(node.object_count <= h.params.max_leaf_objects.max(1) || node.object_count == 1);
            }
        }
    }

    #[test]
    fn tree_over_a_grid_keeps_every_invariant() {
        let objects = grid_objects(100);
        let h = Hierarchy::build(&objects, &HierarchyParams::default());
        check_invariants(&h, &objects);
        let s = h.stats();
        assert_eq!(s.nodes, h.nodes.len());
        assert!(s.depth >= 6 && s.depth <= 20, "depth {}", s.depth);
    }

    #[test]
    fn refit_follows_moved_objects_and_keeps_the_topology() {
        let mut objects = grid_objects(40);
        let mut h = Hierarchy::build(&objects, &HierarchyParams::default());
        let before = h.clone();
        for (i, o) in objects.iter_mut().enumerate().filter(|(i, _)| i % 3 == 0) {
            let shift = DVec3::new(i as f64 * 7.0, -50.0, 3.0);
            o.bounds = Aabb::new(o.bounds.min + shift, o.bounds.max + shift * 2.0);
        }
        h.refit(&objects);
        check_invariants(&h, &objects);
        assert_eq!(h.objects, before.objects);
        for (a, b) in h.nodes.iter().zip(&before.nodes) {
            assert_eq!((a.first_child, a.child_count), (b.first_child, b.child_count));
        }
        assert_ne!(h.root().bounds, before.root().bounds);
    }

    #[test]
    fn single_object_is_a_leaf_root() {
        let objects = grid_objects(1);
        let h = Hierarchy::build(&objects, &HierarchyParams::default());
        assert_eq!(h.nodes.len(), 1);
        assert!(h.root().is_leaf());
        check_invariants(&h, &objects);
    }

    #[test]
    fn coincident_objects_are_split_to_the_leaf_limit() {
        let objects: Vec<Object> = (0..37).map(|_| object(DVec3::ZERO, 1.0, 10)).collect();
        let h = Hierarchy::build(&objects, &HierarchyParams::default());
        check_invariants(&h, &objects);
        assert!(h.nodes.iter().filter(|n| n.is_leaf()).all(|n| n.object_count <= 4));
    }

    #[test]
    fn separated_clusters_end_up_in_different_subtrees() {
        // Two far-apart groups: the root split must separate them.
        let mut objects: Vec<Object> = (0..8)
            .map(|i| object(DVec3::new(i as f64, 0.0, 0.0), 0.5, 500))
            .collect();
        objects.extend((0..8).map(|i| object(DVec3::new(1000.0 + i as f64, 0.0, 0.0), 0.5, 500)));
        let h = Hierarchy::build(&objects, &HierarchyParams::default());
        check_invariants(&h, &objects);
        for child in h.root().children() {
            let xs: Vec<f64> = h
                .subtree_objects(&h.nodes[child])
                .iter()
                .map(|&o| objects[o as usize].bounds.min.x)
                .collect();
            assert!(
                xs.iter().all(|&x| x < 100.0) || xs.iter().all(|&x| x >= 1000.0),
                "{xs:?}"
            );
        }
    }
}
