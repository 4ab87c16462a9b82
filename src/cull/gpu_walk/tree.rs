//! [`CullTree`]: a tree as GPU-driven culling walks it, built on the CPU
//! once per mode. Nodes' children are contiguous, the objects of each
//! subtree are contiguous in `order`, and the walk starts from `seed`.

use crate::hierarchy::Hierarchy;

/// The most levels one walk may take (the size of the per-level statistics).
pub const MAX_LEVELS: u32 = 64;

/// A node as walk.wgsl reads it.
#[repr(C)]
#[derive(Clone, Copy, Debug, PartialEq, Eq, bytemuck::Pod, bytemuck::Zeroable)]
pub struct TreeNode {
    pub first_child: u32,
    /// 0 where the walk stops: a leaf, or a node at the bottom depth.
    pub child_count: u32,
    pub first_object: u32,
    pub object_count: u32,
}

/// A tree for GPU-driven culling, built on the CPU.
#[derive(Clone, Debug, PartialEq)]
pub struct CullTree {
    pub nodes: Vec<TreeNode>,
    /// Object ids; a node's objects are `order[first_object..][..object_count]`.
    pub order: Vec<u32>,
    /// The nodes tested in the first level.
    pub seed: Vec<u32>,
    /// Levels a walk takes: one more than the depth of the deepest node
    /// below the seed.
    pub levels: u32,
}

impl CullTree {
    /// Every object a leaf of its own, all tested in one level (roc).
    pub fn flat(objects: u32) -> CullTree {
        CullTree {
            nodes: (0..objects)
                .map(|o| TreeNode {
                    first_child: 0,
                    child_count: 0,
                    first_object: o,
                    object_count: 1,
                })
                .collect(),
            order: (0..objects).collect(),
            seed: (0..objects).collect(),
            levels: 1,
        }
    }

    /// Whether it is [`CullTree::flat`]'s: node k is object k, seeded.
    pub fn is_flat(&self) -> bool {
        self.levels == 1
            && self.seed.len() == self.nodes.len()
            && self.order.iter().enumerate().all(|(k, &o)| o as usize == k)
            && self
                .nodes
                .iter()
                .enumerate()
                .all(|(k, n)| (n.first_object as usize, n.object_count, n.child_count) == (k, 1, 0))
            && self.seed.iter().enumerate().all(|(k, &n)| n as usize == k)
    }

    /// `hierarchy` cut at depth `bottom` (its nodes there become leaves) and
    /// walked from its nodes at depth `start` (or leaves above it); the root
    /// is at depth 0. Also returns, per tree node, the hierarchy node it
    /// stands for. `start` is at most `bottom`, and `bottom - start` less
    /// than [`MAX_LEVELS`].
    pub fn cut(hierarchy: &Hierarchy, start: u32, bottom: u32) -> (CullTree, Vec<u32>) {
        assert!(
            start <= bottom && bottom - start < MAX_LEVELS,
            "levels {start}..={bottom}"
        );
        // Breadth first, so every node's children get consecutive numbers.
        let mut source = vec![0u32];
        let mut depth = vec![0u32];
        let mut nodes = Vec::new();
        let mut next = 0;
        while next < source.len() {
            let h = &hierarchy.nodes[source[next] as usize];
            let d = depth[next];
            let expand = !h.is_leaf() && d < bottom;
            nodes.push(TreeNode {
                first_child: if expand { source.len() as u32 } else { 0 },
                child_count: if expand { h.child_count } else { 0 },
                first_object: h.first_object,
                object_count: h.object_count,
            });
            if expand {
                source.extend(h.children().map(|c| c as u32));
                depth.extend(h.children().map(|_| d + 1));
            }
            next += 1;
        }
        let seed: Vec<u32> = (0..nodes.len() as u32)
            .filter(|&i| {
                let d = depth[i as usize];
                d == start || (d < start && nodes[i as usize].child_count == 0)
            })
            .collect();
        let deepest = depth.iter().copied().max().unwrap_or(0);
        let tree = CullTree {
            nodes,
            order: hierarchy.objects.clone(),
            seed,
            levels: deepest.max(start) - start + 1,
        };
        (tree, source)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::hierarchy::HierarchyParams;
    use crate::hierarchy::fixtures::grid_objects;

    /// Walks `tree` as the GPU does when every node is visible, returning
    /// the objects marked and the number of levels taken.
    fn walk_all_visible(tree: &CullTree) -> (Vec<u32>, u32) {
        let (mut queue, mut marked, mut levels) = (tree.seed.clone(), Vec::new(), 0);
        while !queue.is_empty() {
            levels += 1;
            let mut next = Vec::new();
            for &i in &queue {
                let n = tree.nodes[i as usize];
                if n.child_count == 0 {
                    marked.extend_from_slice(&tree.order[n.first_object as usize..][..n.object_count as usize]);
                } else {
                    next.extend(n.first_child..n.first_child + n.child_count);
                }
            }
            queue = next;
        }
        marked.sort_unstable();
        (marked, levels)
    }

    #[test]
    fn every_cut_reaches_every_object_once_in_its_levels() {
        let objects = grid_objects(100);
        let h = Hierarchy::build(&objects, &HierarchyParams::default());
        let deepest = h.stats().depth - 1;
        let all: Vec<u32> = (0..100).collect();
        for bottom in 0..=deepest + 1 {
            for start in 0..=bottom {
                let (tree, source) = CullTree::cut(&h, start, bottom);
                let (marked, levels) = walk_all_visible(&tree);
                assert_eq!(marked, all, "start {start}, bottom {bottom}");
                assert_eq!(levels, tree.levels, "start {start}, bottom {bottom}");
                assert_eq!(tree.levels, bottom.min(deepest).max(start) - start + 1);
                // Tree nodes stand for hierarchy nodes with the same objects;
                // every node below the bottom depth is left out.
                assert_eq!(source.len(), tree.nodes.len());
                for (node, &s) in tree.nodes.iter().zip(&source) {
                    let hn = &h.nodes[s as usize];
                    assert_eq!(
                        (node.first_object, node.object_count),
                        (hn.first_object, hn.object_count)
                    );
                    assert!(node.child_count == 0 || node.child_count == hn.child_count);
                }
            }
        }
        let (root_only, _) = CullTree::cut(&h, 0, 0);
        assert_eq!(root_only.nodes.len(), 1, "a bottom of 0 keeps the root alone");
        let (full, _) = CullTree::cut(&h, 0, deepest);
        assert_eq!(full.nodes.len(), h.nodes.len(), "the deepest bottom keeps every node");
    }

    #[test]
    fn a_flat_tree_tests_every_object_in_one_level() {
        let tree = CullTree::flat(5);
        assert_eq!(walk_all_visible(&tree), ((0..5).collect(), 1));
        assert_eq!(tree.seed, (0..5).collect::<Vec<u32>>());
        assert!(tree.nodes.iter().all(|n| n.child_count == 0 && n.object_count == 1));
    }
}
