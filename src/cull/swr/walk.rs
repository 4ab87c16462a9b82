//! Step 4 of `swr`'s frame: the hierarchy walked for the objects in the
//! frustum and not hidden, shared over threads. Once the buffer is built,
//! each node's verdict depends on the node alone, so subtrees can be walked
//! in any order and on any thread. The walk goes level by level from the
//! root until it holds [`SUBTREES`] nodes or more, then the threads take
//! those subtrees one at a time, each walking its own depth first. The
//! objects come out in one order whatever the thread count: those of the
//! levels walked first, then each subtree's, in the subtrees' order.

use std::ops::Range;
use std::sync::atomic::{AtomicUsize, Ordering};

use crate::bounds::Aabb;
use crate::camera::{Containment, Frustum};
use crate::hierarchy::Hierarchy;
use crate::parallel;
use crate::scene::Scene;

/// Subtrees the walk is cut into for its threads, whatever their count
/// (so the objects found come out in one order); enough to even out
/// subtrees of unlike cost over a few threads.
const SUBTREES: usize = 64;

/// A walk takes one thread more for each this many hierarchy nodes (a
/// job handed to the pool costs about 12 µs before it starts, a node's
/// test about one microsecond).
const NODES_PER_THREAD: usize = 1024;

/// The walk's threads' scratch, reused so a frame allocates nothing once
/// warm.
#[derive(Default)]
pub struct Walkers {
    walkers: Vec<Walker>,
    /// The nodes of the level being walked, and of the next (in the end,
    /// the subtrees shared).
    level: Vec<u32>,
    next: Vec<u32>,
    /// Per subtree walked: its place among the subtrees, its walker, and
    /// where its objects lie in that walker's `found`.
    walked: Vec<(usize, usize, Range<usize>)>,
}

/// One thread's share of the walk.
#[derive(Default)]
struct Walker {
    stack: Vec<u32>,
    /// The objects it found visible, subtree after subtree.
    found: Vec<u32>,
    /// Per subtree it walked: its place among the subtrees, and where its
    /// objects lie in `found`.
    walked: Vec<(usize, Range<usize>)>,
    tally: Walked,
}

impl Walker {
    fn clear(&mut self) {
        self.found.clear();
        self.walked.clear();
        self.tally = Walked::default();
    }
}

/// What a walk found besides the objects: the triangles of those it hid,
/// and its counts of nodes.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Walked {
    pub hidden_triangles: u64,
    pub nodes_visited: u64,
    pub nodes_culled_frustum: u64,
    pub nodes_culled_occlusion: u64,
}

impl Walked {
    fn add(&mut self, other: &Walked) {
        self.hidden_triangles += other.hidden_triangles;
        self.nodes_visited += other.nodes_visited;
        self.nodes_culled_frustum += other.nodes_culled_frustum;
        self.nodes_culled_occlusion += other.nodes_culled_occlusion;
    }
}

impl Walkers {
    /// Scratch for up to `threads` threads (one where that is none).
    pub fn new(threads: usize) -> Walkers {
        Walkers {
            walkers: (0..threads).map(|_| Walker::default()).collect(),
            ..Walkers::default()
        }
    }

    /// Walks the hierarchy as `walk` says, and puts the objects found
    /// visible in `found`.
    pub fn walk(&mut self, walk: &Walk, found: &mut Vec<u32>) -> Walked {
        // One walker at least (`Walkers::default()` has none).
        if self.walkers.is_empty() {
            self.walkers.push(Walker::default());
        }
        self.walkers.iter_mut().for_each(Walker::clear);
        let first = &mut self.walkers[0];
        // Level by level until there are subtrees enough to share.
        self.level.clear();
        self.level.push(0);
        while !self.level.is_empty() && self.level.len() < SUBTREES {
            self.next.clear();
            for &node in &self.level {
                walk.visit(node, first, &mut self.next);
            }
            std::mem::swap(&mut self.level, &mut self.next);
        }
        let head = first.found.len();
        let subtrees = &self.level[..];
        let threads = (1 + walk.hierarchy.nodes.len() / NODES_PER_THREAD)
            .min(self.walkers.len())
            .min(subtrees.len())
            .max(1);
        let taken = AtomicUsize::new(0);
        parallel::each(self.walkers[..threads].iter_mut(), |walker| {
            loop {
                let k = taken.fetch_add(1, Ordering::Relaxed);
                let Some(&root) = subtrees.get(k) else { break };
                let start = walker.found.len();
                walk.subtree(root, walker);
                walker.walked.push((k, start..walker.found.len()));
            }
        });
        // The objects in order: the levels', then subtree by subtree.
        let walkers = &self.walkers[..threads];
        found.clear();
        found.extend_from_slice(&walkers[0].found[..head]);
        self.walked.clear();
        for (w, walker) in walkers.iter().enumerate() {
            self.walked
                .extend(walker.walked.iter().map(|(k, range)| (*k, w, range.clone())));
        }
        self.walked.sort_unstable_by_key(|(k, _, _)| *k);
        for (_, w, range) in &self.walked {
            found.extend_from_slice(&walkers[*w].found[range.clone()]);
        }
        let mut totals = Walked::default();
        walkers.iter().for_each(|walker| totals.add(&walker.tally));
        totals
    }
}

/// What a walk tests nodes and objects with.
pub struct Walk<'a> {
    pub frustum: &'a Frustum,
    pub scene: &'a Scene,
    pub hierarchy: &'a Hierarchy,
    /// Whether the buffer hides a box (in the frustum).
    pub hides: &'a (dyn Fn(&Aabb) -> bool + Sync),
}

impl Walk<'_> {
    /// Walks the subtree of node `root`, depth first.
    fn subtree(&self, root: u32, walker: &mut Walker) {
        let mut stack = std::mem::take(&mut walker.stack);
        stack.clear();
        stack.push(root);
        while let Some(node) = stack.pop() {
            self.visit(node, walker, &mut stack);
        }
        walker.stack = stack;
    }

    /// Visits node `index`: culled outside the frustum or hidden, its
    /// objects found or hidden (a leaf), or its children put on `next`.
    fn visit(&self, index: u32, walker: &mut Walker, next: &mut Vec<u32>) {
        let node = &self.hierarchy.nodes[index as usize];
        walker.tally.nodes_visited += 1;
        if self.frustum.classify(&node.bounds) == Containment::Outside {
            walker.tally.nodes_culled_frustum += 1;
            return;
        }
        let hidden = self.hides;
        let triangles = |o: u32| u64::from(self.scene.objects[o as usize].triangles);
        if hidden(&node.bounds) {
            walker.tally.nodes_culled_occlusion += 1;
            walker.tally.hidden_triangles += self
                .hierarchy
                .subtree_objects(node)
                .iter()
                .map(|&o| triangles(o))
                .sum::<u64>();
            return;
        }
        if !node.is_leaf() {
            next.extend(node.children().map(|c| c as u32));
            return;
        }
        for &o in self.hierarchy.subtree_objects(node) {
            let bounds = &self.scene.objects[o as usize].bounds;
            if self.frustum.classify(bounds) == Containment::Outside {
                continue;
            }
            if hidden(bounds) {
                walker.tally.hidden_triangles += triangles(o);
            } else {
                walker.found.push(o);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::generate::default_path;
    use crate::gpu::Resolution;
    use crate::hierarchy::HierarchyParams;
    use crate::scene::{LoadOptions, SceneSpec, load};

    /// What a plain depth-first walk of the whole hierarchy finds, node
    /// by node as the walk's rules say: the objects found (sorted), the
    /// triangles hidden, and the nodes visited, outside the frustum and
    /// hidden.
    fn walked_one_by_one(walk: &Walk) -> (Vec<u32>, u64, [u64; 3]) {
        let (mut found, mut hidden_triangles, mut counts) = (Vec::new(), 0, [0; 3]);
        let hides = walk.hides;
        let triangles = |o: &u32| u64::from(walk.scene.objects[*o as usize].triangles);
        let mut stack = vec![0];
        while let Some(index) = stack.pop() {
            let node = &walk.hierarchy.nodes[index];
            counts[0] += 1;
            if walk.frustum.classify(&node.bounds) == Containment::Outside {
                counts[1] += 1;
            } else if hides(&node.bounds) {
                counts[2] += 1;
                hidden_triangles += walk.hierarchy.subtree_objects(node).iter().map(triangles).sum::<u64>();
            } else if !node.is_leaf() {
                stack.extend(node.children());
            } else {
                for o in walk.hierarchy.subtree_objects(node) {
                    let bounds = &walk.scene.objects[*o as usize].bounds;
                    if walk.frustum.classify(bounds) == Containment::Outside {
                        continue;
                    }
                    if hides(bounds) {
                        hidden_triangles += triangles(o);
                    } else {
                        found.push(*o);
                    }
                }
            }
        }
        found.sort_unstable();
        (found, hidden_triangles, counts)
    }

    #[test]
    fn threads_find_what_a_plain_walk_finds_in_one_order_whatever_their_count() {
        let scene = load(&SceneSpec::Builtin("city:blocks=8".into()), &LoadOptions::default()).unwrap();
        let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
        assert!(
            hierarchy.nodes.len() >= 4 * NODES_PER_THREAD,
            "{} nodes",
            hierarchy.nodes.len()
        );
        let path = default_path(&scene).and_then(|(p, _)| p.with_frames(6)).unwrap();
        // Boxes hidden by a rule of their own, at every level of the tree.
        let hides = |bounds: &Aabb| (bounds.min.x * 0.37 + bounds.min.z * 0.21 + bounds.max.y).sin() > 0.2;
        let nothing = |_: &Aabb| false;
        let mut walkers = [1, 2, 5].map(Walkers::new);
        let mut threads_found_hidden = 0;
        for frame in 0..6 {
            let frustum = path.camera(frame, Resolution::DEFAULT.aspect()).frustum();
            for (hiding, hides) in [(false, &nothing as &(dyn Fn(&Aabb) -> bool + Sync)), (true, &hides)] {
                let walk = Walk {
                    frustum: &frustum,
                    scene: &scene,
                    hierarchy: &hierarchy,
                    hides,
                };
                let (expected, hidden_triangles, counts) = walked_one_by_one(&walk);
                let mut orders = Vec::new();
                for walkers in &mut walkers {
                    let mut found = Vec::new();
                    let walked = walkers.walk(&walk, &mut found);
                    let got = [
                        walked.nodes_visited,
                        walked.nodes_culled_frustum,
                        walked.nodes_culled_occlusion,
                    ];
                    assert_eq!(
                        (got, walked.hidden_triangles),
                        (counts, hidden_triangles),
                        "frame {frame}"
                    );
                    orders.push(found.clone());
                    found.sort_unstable();
                    assert_eq!(found, expected, "frame {frame}: each object found once");
                }
                assert!(orders.iter().all(|o| *o == orders[0]), "frame {frame}: one order");
                threads_found_hidden += usize::from(hiding && hidden_triangles > 0 && !expected.is_empty());
            }
        }
        assert!(
            threads_found_hidden >= 3,
            "{threads_found_hidden} frames both hid and found objects"
        );
    }
}
