//! The ternary tree of paper 001 §3.1–3.4: the structure the `chc` mode
//! culls with, kept current as objects move and as the view changes.
//!
//! A node stands for a box of space, its cell. An inner node is cut in two
//! by an axis-aligned plane and has exactly three children: the two halves,
//! and a third, *straddle* child holding the objects that lie in neither
//! half (001: "the additional child contain objects, which was previously in
//! the parent node (i.e. objects intersecting the splitting plane.) We don't
//! split this node any further"). Objects live in leaves only, each in the
//! deepest node whose cell holds it, and move between nodes as they move.
//!
//! Departure: a straddle child may be split on another axis. The paper's
//! scenes were cut into a uniform grid; in a city, objects nest (the floors
//! of a building lie inside its shell), so a plane through a building puts
//! the shell and every floor in one straddle child, which would then draw
//! all floors whenever the shell shows. A horizontal cut separates them.
//!
//! What a query tests (001 §3.2): the cell of a node, which holds every
//! object below it, unless nothing below has changed for `tight_after`
//! frames; then the TightBox, the union of the objects' boxes, computed once
//! and reused until something below changes. A straddle child always uses
//! its objects' union, since its cell is its parent's. The root's cell grows
//! to hold objects that leave it; objects outside a child's cell go to the
//! straddle child, so every box a query tests holds all geometry below it.
//!
//! Split and merge (001 §3.4) work from the visible and total pixels of
//! each leaf's last query: [`split_wanted`] and [`merge_wanted`] hold the
//! paper's criteria; the axis of a split faces the camera.

use std::time::{Duration, Instant};

use glam::DVec3;
use serde::Serialize;

use crate::bounds::Aabb;

/// No node: the root's parent.
pub const NO_NODE: u32 = u32::MAX;

/// Nodes deeper than this are never split: halving a cell 48 times leaves
/// nothing to separate.
const MAX_DEPTH: u32 = 48;

/// The constants of 001 §3.4 and §3.2.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct TreeParams {
    /// A leaf whose visible/total pixel ratio is at least this …
    pub r_split: f64,
    /// … and which holds at least this many objects is split.
    pub o_split: u32,
    /// Sibling leaves that all have a ratio at most this …
    pub r_merge: f64,
    /// … and at most this many objects each are merged into their parent.
    pub o_merge: u32,
    /// Frames without change before a node's TightBox replaces its cell.
    pub tight_after: u32,
}

impl Default for TreeParams {
    /// 001 §3.4: "Rsplit = 0.25, Osplit = 12, Rmerge = 0.75 and Omerge = 5";
    /// 001 §3.2 says only "a few frames" for TightBoxes.
    fn default() -> Self {
        TreeParams {
            r_split: 0.25,
            o_split: 12,
            r_merge: 0.75,
            o_merge: 5,
            tight_after: 3,
        }
    }
}

/// Visible and total pixels of a node's box, from its last query (001 §3.3).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Pixels {
    pub frame: u32,
    pub visible: u64,
    pub total: u64,
}

impl Pixels {
    /// Visible over total; `None` for a box that covered no pixel.
    pub fn ratio(&self) -> Option<f64> {
        (self.total > 0).then(|| self.visible as f64 / self.total as f64)
    }
}

/// 001 §3.4: split when visible/total ≥ R_split and objects ≥ O_split.
pub fn split_wanted(params: &TreeParams, pixels: Pixels, objects: usize) -> bool {
    pixels.ratio().is_some_and(|r| r >= params.r_split) && objects >= params.o_split as usize
}

/// 001 §3.4, for one of the sibling leaves (all three must agree): merge
/// when visible/total ≤ R_merge and objects ≤ O_merge.
pub fn merge_wanted(params: &TreeParams, pixels: Pixels, objects: usize) -> bool {
    pixels.ratio().is_some_and(|r| r <= params.r_merge) && objects <= params.o_merge as usize
}

/// The split axis of 001 §3.4: the one whose faces look most directly at
/// the camera, so the halves lie one behind the other as seen from it.
pub fn facing_axis(view_direction: DVec3) -> usize {
    let d = view_direction.abs();
    if d.x >= d.y && d.x >= d.z {
        0
    } else if d.y >= d.z {
        1
    } else {
        2
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Split {
    pub axis: usize,
    pub position: f64,
    /// Low half, high half, straddle child.
    pub children: [u32; 3],
}

#[derive(Clone, Debug)]
pub struct TernaryNode {
    pub cell: Aabb,
    pub parent: u32,
    pub split: Option<Split>,
    /// A third child: boxed by its objects, since its cell is its parent's.
    pub straddle: bool,
    pub depth: u32,
    /// The objects of a leaf (empty for inner nodes).
    pub objects: Vec<u32>,
    /// Objects anywhere below.
    pub count: u32,
    /// Frame of the last change below: an object moved, entered or left.
    pub changed: u32,
    /// The union of the objects below, while nothing has changed.
    tight: Option<Aabb>,
    /// Coherence state of `chc` (001 §3, after [KS05]/CHC): whether the
    /// node was found visible, and in which frame it was last visited.
    pub visible: bool,
    pub last_visited: Option<u32>,
    /// The last pixel counts of the node's box.
    pub pixels: Option<Pixels>,
}

/// How many leaves one pass of split and merge changed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Reshaped {
    pub splits: u32,
    pub merges: u32,
}

pub struct TernaryTree {
    nodes: Vec<TernaryNode>,
    /// Ids of discarded nodes, for reuse.
    free: Vec<u32>,
    /// The node each object lives in.
    home: Vec<u32>,
    /// Each object's box as last inserted.
    bounds: Vec<Aabb>,
    pub params: TreeParams,
    /// Time spent computing TightBoxes since it was last taken.
    tight_time: Duration,
}

impl TernaryTree {
    /// A tree over `bounds` (one box per object id), cut recursively at the
    /// middle of the longest side (001 §3.4's common case) while a leaf holds
    /// more objects than `o_merge` and a cut separates some. Leaves start as
    /// small as merging leaves them; split and merge adapt them to the view.
    pub fn build(bounds: &[Aabb], params: TreeParams) -> TernaryTree {
        let root_cell = bounds.iter().fold(Aabb::EMPTY, |b, o| b.union(*o));
        let mut tree = TernaryTree {
            nodes: vec![node(root_cell, NO_NODE, 0, false)],
            free: Vec::new(),
            home: vec![NO_NODE; bounds.len()],
            bounds: bounds.to_vec(),
            params,
            tight_time: Duration::ZERO,
        };
        for object in 0..bounds.len() as u32 {
            tree.insert(object, 0);
        }
        let mut pending = vec![0];
        while let Some(n) = pending.pop() {
            if tree.nodes[n as usize].objects.len() > params.o_merge as usize {
                let axis = tree.nodes[n as usize].cell.extent().max_position();
                if tree.split_preferring(n, axis) {
                    pending.extend(tree.children(n));
                }
            }
        }
        tree
    }

    pub fn node(&self, id: u32) -> &TernaryNode {
        &self.nodes[id as usize]
    }

    pub fn node_mut(&mut self, id: u32) -> &mut TernaryNode {
        &mut self.nodes[id as usize]
    }

    /// The children of an inner node, or none for a leaf (by value, so the
    /// tree can be changed while they are visited).
    pub fn children(&self, id: u32) -> impl Iterator<Item = u32> + use<> {
        self.node(id).split.map(|s| s.children).into_iter().flatten()
    }

    /// The node `object` lives in (for tests of moves, splits and merges).
    #[cfg(test)]
    fn home(&self, object: u32) -> u32 {
        self.home[object as usize]
    }

    /// Whether node `id` is in use: a node discarded by a merge has no
    /// parent.
    fn is_live(&self, id: u32) -> bool {
        id == 0 || self.nodes[id as usize].parent != NO_NODE
    }

    /// Marks `node` and its ancestors visible (CHC's pull-up).
    pub fn pull_up_visibility(&mut self, mut node: u32) {
        while node != NO_NODE && !self.nodes[node as usize].visible {
            self.nodes[node as usize].visible = true;
            node = self.nodes[node as usize].parent;
        }
    }

    /// Takes `visible` (objects) as what a traversal in `frame` found: every
    /// node visited then, and visible where an object below it was, as
    /// CHC's pull-up leaves them. Ids the tree does not hold are passed
    /// over.
    pub fn assume_visited(&mut self, visible: &[u32], frame: u32) {
        for n in &mut self.nodes {
            n.visible = false;
            n.last_visited = Some(frame);
        }
        for &object in visible {
            if let Some(&home) = self.home.get(object as usize).filter(|&&home| home != NO_NODE) {
                self.pull_up_visibility(home);
            }
        }
    }

    /// The box a query of `id` tests in `frame` (see the module comment).
    pub fn query_box(&mut self, id: u32, frame: u32) -> Aabb {
        let n = &self.nodes[id as usize];
        let settled = frame.saturating_sub(n.changed) >= self.params.tight_after;
        if n.straddle || settled {
            self.tight_box(id)
        } else {
            n.cell
        }
    }

    /// The union of the objects below `id`, cached until something below
    /// changes.
    fn tight_box(&mut self, id: u32) -> Aabb {
        if let Some(b) = self.nodes[id as usize].tight {
            return b;
        }
        let start = Instant::now();
        let b = self.union_below(id);
        self.nodes[id as usize].tight = Some(b);
        self.tight_time += start.elapsed();
        b
    }

    fn union_below(&mut self, id: u32) -> Aabb {
        if let Some(b) = self.nodes[id as usize].tight {
            return b;
        }
        let b = match self.nodes[id as usize].split {
            Some(s) => s
                .children
                .iter()
                .fold(Aabb::EMPTY, |b, &c| b.union(self.union_below(c))),
            None => {
                let n = &self.nodes[id as usize];
                n.objects
                    .iter()
                    .fold(Aabb::EMPTY, |b, &o| b.union(self.bounds[o as usize]))
            }
        };
        self.nodes[id as usize].tight = Some(b);
        b
    }

    /// Time spent computing TightBoxes since the last call.
    pub fn take_tight_time(&mut self) -> Duration {
        std::mem::take(&mut self.tight_time)
    }

    /// Moves `object` to `bounds`: it stays in its node if the node would
    /// still take it, else it goes where it now belongs; nothing changes
    /// where it is already there. Returns whether it changed node.
    pub fn update(&mut self, object: u32, bounds: Aabb, frame: u32) -> bool {
        if self.bounds[object as usize] == bounds {
            return false;
        }
        let home = self.home[object as usize];
        self.bounds[object as usize] = bounds;
        self.grow_root(&bounds);
        self.touch(home, frame);
        if self.fits(home, &bounds) {
            return false;
        }
        self.remove(object, frame);
        self.insert(object, frame);
        true
    }

    /// Whether insertion would put an object with `bounds` (inside the
    /// root's cell) in `id`: every step from the root down to it takes it.
    fn fits(&self, id: u32, bounds: &Aabb) -> bool {
        let mut child = id;
        let mut parent = self.nodes[id as usize].parent;
        while parent != NO_NODE {
            if self.place(parent, bounds) != child {
                return false;
            }
            child = parent;
            parent = self.nodes[parent as usize].parent;
        }
        true
    }

    /// Grows the root's cell to hold `bounds`. Its children keep their
    /// cells: an object beyond them goes to the straddle child.
    fn grow_root(&mut self, bounds: &Aabb) {
        let root = &mut self.nodes[0];
        if !root.cell.contains(bounds) {
            root.cell = root.cell.union(*bounds);
        }
    }

    /// The child of inner node `id` an object with `bounds` goes to.
    fn place(&self, id: u32, bounds: &Aabb) -> u32 {
        let s = self.nodes[id as usize].split.expect("placed below inner nodes only");
        s.children
            .into_iter()
            .take(2)
            .find(|&c| self.nodes[c as usize].cell.contains(bounds))
            .unwrap_or(s.children[2])
    }

    fn insert(&mut self, object: u32, frame: u32) {
        let bounds = self.bounds[object as usize];
        self.grow_root(&bounds);
        let mut n = 0;
        while self.nodes[n as usize].split.is_some() {
            n = self.place(n, &bounds);
        }
        self.nodes[n as usize].objects.push(object);
        self.home[object as usize] = n;
        self.count_along(n, 1);
        self.touch(n, frame);
    }

    fn remove(&mut self, object: u32, frame: u32) {
        let home = self.home[object as usize];
        let objects = &mut self.nodes[home as usize].objects;
        let at = objects
            .iter()
            .position(|&o| o == object)
            .expect("an object is listed in its home node");
        objects.swap_remove(at);
        self.count_along(home, -1);
        self.touch(home, frame);
    }

    fn count_along(&mut self, mut n: u32, delta: i32) {
        while n != NO_NODE {
            let node = &mut self.nodes[n as usize];
            node.count = node.count.wrapping_add_signed(delta);
            n = node.parent;
        }
    }

    /// Records a change at `n`: its ancestors' TightBoxes no longer hold.
    fn touch(&mut self, mut n: u32, frame: u32) {
        while n != NO_NODE {
            let node = &mut self.nodes[n as usize];
            node.changed = frame;
            node.tight = None;
            n = node.parent;
        }
    }

    /// Cuts leaf `id` at the middle of its cell on `axis`, moving its
    /// objects to the three new children. Refused (false) at the depth
    /// limit and when no object would leave the new straddle child.
    pub fn split(&mut self, id: u32, axis: usize) -> bool {
        let n = &self.nodes[id as usize];
        if n.split.is_some() || n.depth >= MAX_DEPTH {
            return false;
        }
        let (cell, depth) = (n.cell, n.depth);
        let position = cell.center()[axis];
        let (mut low, mut high) = (cell, cell);
        low.max[axis] = position;
        high.min[axis] = position;
        let separates = n
            .objects
            .iter()
            .any(|&o| low.contains(&self.bounds[o as usize]) || high.contains(&self.bounds[o as usize]));
        if !separates {
            return false;
        }
        let children = [
            self.allocate(node(low, id, depth + 1, false)),
            self.allocate(node(high, id, depth + 1, false)),
            self.allocate(node(cell, id, depth + 1, true)),
        ];
        let parent = &mut self.nodes[id as usize];
        parent.split = Some(Split {
            axis,
            position,
            children,
        });
        let objects = std::mem::take(&mut parent.objects);
        let (visible, last_visited, changed) = (parent.visible, parent.last_visited, parent.changed);
        for &c in &children {
            // The halves inherit the parent's coherence state, so a visible
            // leaf's parts are drawn at once next frame as it was.
            let child = &mut self.nodes[c as usize];
            (child.visible, child.last_visited, child.changed) = (visible, last_visited, changed);
        }
        for o in objects {
            let c = self.place(id, &self.bounds[o as usize]);
            self.nodes[c as usize].objects.push(o);
            self.nodes[c as usize].count += 1;
            self.home[o as usize] = c;
        }
        true
    }

    /// Splits leaf `id` on `axis`, or else on the first other axis that
    /// separates some objects.
    pub fn split_preferring(&mut self, id: u32, axis: usize) -> bool {
        [axis, (axis + 1) % 3, (axis + 2) % 3]
            .into_iter()
            .any(|a| self.split(id, a))
    }

    /// Gives the objects of inner node `id`'s children (all leaves) back to
    /// it and discards the children.
    pub fn merge(&mut self, id: u32) {
        let s = self.nodes[id as usize].split.expect("merging an inner node");
        let mut objects = Vec::new();
        let mut visible = false;
        for &c in &s.children {
            let child = &mut self.nodes[c as usize];
            debug_assert!(child.split.is_none(), "merged children are leaves");
            objects.append(&mut child.objects);
            visible |= child.visible;
            child.parent = NO_NODE;
            self.free.push(c);
        }
        for &o in &objects {
            self.home[o as usize] = id;
        }
        let parent = &mut self.nodes[id as usize];
        parent.objects = objects;
        parent.split = None;
        parent.visible = visible;
        parent.pixels = None;
    }

    fn allocate(&mut self, n: TernaryNode) -> u32 {
        match self.free.pop() {
            Some(id) => {
                self.nodes[id as usize] = n;
                id
            }
            None => {
                self.nodes.push(n);
                self.nodes.len() as u32 - 1
            }
        }
    }

    /// 001 §3.4 at the end of `frame`: leaves measured this frame are split
    /// along `axis` or merged with their siblings by their pixel ratios.
    pub fn split_and_merge(&mut self, frame: u32, axis: usize) -> Reshaped {
        let mut out = Reshaped::default();
        let params = self.params;
        let measured = |n: &TernaryNode| n.pixels.filter(|p| p.frame == frame);
        // Nodes a split adds in this pass have no pixels yet: the ids
        // standing at its start are all there is to look at.
        for id in 0..self.nodes.len() as u32 {
            if !self.is_live(id) {
                continue;
            }
            let n = &self.nodes[id as usize];
            match n.split {
                None => {
                    if measured(n).is_some_and(|p| split_wanted(&params, p, n.objects.len()))
                        && self.split_preferring(id, axis)
                    {
                        out.splits += 1;
                    }
                }
                Some(s) => {
                    let all_merge = s.children.iter().all(|&c| {
                        let child = &self.nodes[c as usize];
                        child.split.is_none()
                            && measured(child).is_some_and(|p| merge_wanted(&params, p, child.objects.len()))
                    });
                    if all_merge {
                        self.merge(id);
                        out.merges += 1;
                    }
                }
            }
        }
        out
    }
}

fn node(cell: Aabb, parent: u32, depth: u32, straddle: bool) -> TernaryNode {
    TernaryNode {
        cell,
        parent,
        split: None,
        straddle,
        depth,
        objects: Vec::new(),
        count: 0,
        changed: 0,
        tight: None,
        visible: false,
        last_visited: None,
        pixels: None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cube(x: f64, z: f64, size: f64) -> Aabb {
        Aabb::new(DVec3::new(x, 0.0, z), DVec3::new(x + size, size, z + size))
    }

    /// Every promise of the module comment, checked from scratch.
    fn check(tree: &TernaryTree, bounds: &[Aabb]) {
        let mut seen = vec![0; bounds.len()];
        for id in (0..tree.nodes.len() as u32).filter(|&n| tree.is_live(n)) {
            let n = tree.node(id);
            for &o in &n.objects {
                seen[o as usize] += 1;
                assert_eq!(tree.home(o), id);
            }
            if let Some(s) = n.split {
                assert!(n.objects.is_empty(), "objects live in leaves");
                assert!(tree.node(s.children[2]).straddle);
                assert_eq!(s.children.iter().map(|&c| tree.node(c).count).sum::<u32>(), n.count);
                for &c in &s.children[..2] {
                    for &o in &tree.node(c).objects {
                        assert!(
                            tree.node(c).cell.contains(&bounds[o as usize]),
                            "halves hold their objects"
                        );
                    }
                }
            } else {
                assert_eq!(n.count as usize, n.objects.len());
            }
            // The box a query would test holds every object below.
            let below = subtree_objects(tree, id);
            let cell_or_union = if n.straddle {
                below.iter().fold(Aabb::EMPTY, |b, &o| b.union(bounds[o as usize]))
            } else {
                n.cell
            };
            for o in below {
                assert!(
                    cell_or_union.contains(&bounds[o as usize]),
                    "node {id} box misses object {o}"
                );
            }
        }
        assert!(seen.iter().all(|&k| k == 1), "every object in exactly one node");
    }

    fn subtree_objects(tree: &TernaryTree, id: u32) -> Vec<u32> {
        let mut out = tree.node(id).objects.clone();
        for c in tree.children(id) {
            out.extend(subtree_objects(tree, c));
        }
        out
    }

    #[test]
    fn objects_on_the_split_plane_go_to_the_third_child() {
        // 30 cubes in a row along x from 0 to 60: the root is cut at x = 30.
        let mut bounds: Vec<Aabb> = (0..30).map(|i| cube(f64::from(i) * 2.0, 0.0, 1.0)).collect();
        bounds.push(cube(29.0, 0.0, 1.0)); // across x = 29.5
        let tree = TernaryTree::build(&bounds, TreeParams::default());
        check(&tree, &bounds);
        let root = tree.node(0).split.expect("31 objects are more than o_split");
        assert_eq!((root.axis, root.position), (0, 29.5));
        let straddle = tree.node(root.children[2]);
        assert!(straddle.straddle && straddle.split.is_none());
        assert_eq!(straddle.objects, [30], "only the cube across the plane");
        assert_eq!(tree.node(root.children[0]).count, 15);
        assert_eq!(tree.node(root.children[1]).count, 15);
    }

    #[test]
    fn a_straddle_child_of_nested_objects_is_cut_on_another_axis() {
        // Small cubes either side of x = 25, and across it a tall shell with
        // six floors inside: shell and floors all cross the root's plane.
        let mut bounds: Vec<Aabb> = (0..12)
            .map(|i| cube(f64::from(i % 6) * 2.0 + f64::from(i / 6) * 40.0, 0.0, 1.0))
            .collect();
        let shell = Aabb::new(DVec3::new(20.0, 0.0, 0.0), DVec3::new(30.0, 40.0, 10.0));
        bounds.push(shell);
        bounds.extend((0..6).map(|f| {
            let y = f64::from(f) * 6.0 + 0.5;
            Aabb::new(DVec3::new(20.5, y, 0.5), DVec3::new(29.5, y + 1.0, 9.5))
        }));
        let tree = TernaryTree::build(&bounds, TreeParams::default());
        check(&tree, &bounds);
        let root = tree.node(0).split.unwrap();
        assert_eq!(root.axis, 0);
        let straddle = tree.node(root.children[2]);
        assert_eq!(straddle.count, 7, "the shell and its floors");
        let cut = straddle.split.expect("seven objects are more than o_merge");
        assert_eq!(cut.axis, 1, "only a horizontal cut separates floors");
        assert_eq!(
            subtree_objects(&tree, cut.children[2]),
            [12],
            "the shell alone spans it"
        );
    }

    #[test]
    fn a_mover_crossing_a_split_plane_changes_node_and_keeps_the_tree_sound() {
        let mut bounds: Vec<Aabb> = (0..30).map(|i| cube(f64::from(i) * 2.0, 0.0, 1.0)).collect();
        let mut tree = TernaryTree::build(&bounds, TreeParams::default());
        let root = tree.node(0).split.unwrap();
        let car = 3;
        assert!(subtree_objects(&tree, root.children[0]).contains(&car));
        // Drive the car from x = 6 along +x over the root's plane at x = 29.5.
        let mut homes = vec![tree.home(car)];
        for (frame, x) in (1..).zip([20.0, 28.8, 29.0, 32.0, 45.0]) {
            bounds[car as usize] = cube(x, 0.0, 1.0);
            let relocated = tree.update(car, bounds[car as usize], frame);
            check(&tree, &bounds);
            assert_eq!(relocated, homes.last() != Some(&tree.home(car)));
            homes.push(tree.home(car));
        }
        assert!(
            subtree_objects(&tree, root.children[1]).contains(&car),
            "ends in the high half"
        );
        assert_eq!(homes[3], root.children[2], "on the plane it is in the straddle child");
        assert_eq!(
            tree.node(root.children[2]).changed,
            4,
            "the straddle child changed when it left"
        );
        // A move that stays inside its leaf relocates nothing but still
        // invalidates the TightBoxes above it.
        let before = tree.home(car);
        bounds[car as usize] = cube(45.1, 0.0, 1.0);
        assert!(!tree.update(car, bounds[car as usize], 6));
        assert_eq!(tree.home(car), before);
        assert_eq!(tree.node(0).changed, 6);
    }

    #[test]
    fn an_object_leaving_the_root_grows_it_and_stays_inside_a_tested_box() {
        let mut bounds: Vec<Aabb> = (0..30).map(|i| cube(f64::from(i) * 2.0, 0.0, 1.0)).collect();
        let mut tree = TernaryTree::build(&bounds, TreeParams::default());
        bounds[0] = cube(-500.0, 0.0, 1.0);
        tree.update(0, bounds[0], 1);
        check(&tree, &bounds);
        assert!(tree.node(0).cell.contains(&bounds[0]));
        let straddle = tree.node(0).split.unwrap().children[2];
        assert_eq!(tree.home(0), straddle, "outside both halves");
        assert!(tree.query_box(straddle, 1).contains(&bounds[0]));
        // A root that is a leaf keeps the object, and its cell grows too.
        let mut few = vec![cube(0.0, 0.0, 1.0), cube(3.0, 0.0, 1.0)];
        let mut leaf_root = TernaryTree::build(&few, TreeParams::default());
        assert!(leaf_root.node(0).split.is_none());
        few[1] = cube(90.0, 0.0, 1.0);
        assert!(!leaf_root.update(1, few[1], 1));
        check(&leaf_root, &few);
        assert!(
            leaf_root.query_box(0, 1).contains(&few[1]),
            "the cell a query tests holds it"
        );
    }

    #[test]
    fn tight_boxes_replace_cells_once_nothing_moved_for_a_few_frames() {
        // Three small cubes in a big cell.
        let bounds = vec![cube(0.0, 0.0, 1.0), cube(2.0, 0.0, 1.0), cube(100.0, 100.0, 1.0)];
        let mut tree = TernaryTree::build(&bounds, TreeParams::default());
        assert!(tree.split(0, 0));
        let low = tree.node(0).split.unwrap().children[0];
        let cell = tree.node(low).cell;
        assert_eq!(tree.query_box(low, 1), cell, "recently changed: the cell");
        let tight = Aabb::new(DVec3::ZERO, DVec3::new(3.0, 1.0, 1.0));
        assert_eq!(tree.query_box(low, 3), tight, "settled: the TightBox");
        tree.update(1, cube(2.5, 0.0, 1.0), 4);
        assert_eq!(tree.query_box(low, 5), cell, "a move makes it the cell again");
        assert_eq!(
            tree.query_box(low, 7),
            Aabb::new(DVec3::ZERO, DVec3::new(3.5, 1.0, 1.0))
        );
    }

    fn pixels(frame: u32, visible: u64, total: u64) -> Pixels {
        Pixels { frame, visible, total }
    }

    #[test]
    fn split_and_merge_follow_the_papers_criteria() {
        let p = TreeParams::default();
        // Split: ratio ≥ 0.25 and ≥ 12 objects.
        assert!(split_wanted(&p, pixels(0, 25, 100), 12));
        assert!(!split_wanted(&p, pixels(0, 24, 100), 12));
        assert!(!split_wanted(&p, pixels(0, 100, 100), 11));
        assert!(
            !split_wanted(&p, pixels(0, 0, 0), 50),
            "a box on no pixel gives no ratio"
        );
        // Merge: ratio ≤ 0.75 and ≤ 5 objects.
        assert!(merge_wanted(&p, pixels(0, 75, 100), 5));
        assert!(merge_wanted(&p, pixels(0, 0, 100), 0), "a hidden leaf merges");
        assert!(!merge_wanted(&p, pixels(0, 76, 100), 5));
        assert!(!merge_wanted(&p, pixels(0, 10, 100), 6));
    }

    #[test]
    fn leaves_split_and_merge_on_measured_ratios() {
        // 20 cubes along z; the root stays a leaf when o_merge is high.
        let bounds: Vec<Aabb> = (0..20).map(|i| cube(0.0, f64::from(i) * 3.0, 1.0)).collect();
        let params = TreeParams {
            o_merge: 100,
            ..TreeParams::default()
        };
        let mut tree = TernaryTree::build(&bounds, params);
        assert!(tree.node(0).split.is_none());
        tree.params.o_merge = 5;
        // A ratio measured in an earlier frame decides nothing.
        tree.node_mut(0).pixels = Some(pixels(1, 50, 100));
        assert_eq!(tree.split_and_merge(2, 2), Reshaped::default());
        // Half visible, 20 objects: split, across the camera's axis (z).
        tree.node_mut(0).pixels = Some(pixels(2, 50, 100));
        assert_eq!(tree.split_and_merge(2, 2).splits, 1);
        let s = tree.node(0).split.unwrap();
        assert_eq!(s.axis, 2);
        check(&tree, &bounds);
        // The halves hold 10 objects each: more than o_merge, no merge.
        for (k, &c) in s.children.iter().enumerate() {
            tree.node_mut(c).pixels = Some(pixels(3, k as u64, 100));
        }
        assert_eq!(tree.split_and_merge(3, 2), Reshaped::default());
        // With o_merge 10 they merge, unless one sibling is mostly visible.
        tree.params.o_merge = 10;
        tree.node_mut(s.children[1]).pixels = Some(pixels(4, 80, 100));
        tree.node_mut(s.children[0]).pixels = Some(pixels(4, 0, 100));
        tree.node_mut(s.children[2]).pixels = Some(pixels(4, 0, 100));
        assert_eq!(
            tree.split_and_merge(4, 2).merges,
            0,
            "one sibling above r_merge keeps them apart"
        );
        tree.node_mut(s.children[1]).pixels = Some(pixels(5, 70, 100));
        tree.node_mut(s.children[0]).pixels = Some(pixels(5, 0, 100));
        tree.node_mut(s.children[2]).pixels = Some(pixels(5, 0, 100));
        assert_eq!(tree.split_and_merge(5, 2).merges, 1);
        assert!(tree.node(0).split.is_none());
        assert_eq!(tree.node(0).objects.len(), 20);
        check(&tree, &bounds);
        // The discarded children's ids are reused by the next split.
        assert!(tree.split(0, 0) || tree.split(0, 2));
        assert!(tree.node(0).split.unwrap().children.iter().all(|&c| c <= 3));
    }

    #[test]
    fn the_split_axis_faces_the_camera() {
        assert_eq!(facing_axis(DVec3::new(0.9, -0.1, 0.4)), 0);
        assert_eq!(facing_axis(DVec3::new(0.1, -0.9, 0.4)), 1);
        assert_eq!(facing_axis(DVec3::new(-0.5, 0.0, -0.7)), 2);
    }
}
