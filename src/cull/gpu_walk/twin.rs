//! A CPU twin of the walk's compute stages, `cs_expand` and `cs_compact`,
//! written from 004 §2 and the stages' contract (module above), not from
//! the shader: given the tree, the node states the walk left (the CPU's
//! frustum and near-plane rules and `fs_mark`'s marks) and the objects
//! visible in the last frame, what the walk must have counted, marked and
//! drawn. The test below holds the GPU's audit against it, frame by frame.

use super::CullTree;
use super::pool::{OUTSIDE_FRUSTUM, REACHES_NEAR, TO_TEST};

/// What one walk did, by the CPU's reckoning.
#[derive(Debug, Default, PartialEq)]
pub(super) struct CpuWalk {
    /// Nodes reached: the seed, and every child of a visible inner node.
    pub visited: u64,
    /// Reached nodes whose box was drawn into the visibility buffer.
    pub tested: u64,
    /// Tested, and no fragment passed: the subtree is culled.
    pub hidden: u64,
    /// Reached, and outside the frustum: culled untested.
    pub outside: u64,
    /// Objects of visible leaves: this frame's visible list.
    pub marked: Vec<bool>,
    /// Objects drawn: visible in the last frame (drawn first, as
    /// occluders) or marked now (drawn after the walk).
    pub drawn: Vec<bool>,
}

/// The walk of `tree` whose nodes ended in `states`, after a frame in
/// which `visible_last` were visible.
pub(super) fn walk(tree: &CullTree, states: &[u32], visible_last: &[bool]) -> CpuWalk {
    let objects = tree.order.len();
    let mut w = CpuWalk {
        marked: vec![false; objects],
        ..CpuWalk::default()
    };
    let mut near = 0;
    let reach = |node: u32, w: &mut CpuWalk, queue: &mut Vec<u32>| {
        w.visited += 1;
        if states[node as usize] == OUTSIDE_FRUSTUM {
            w.outside += 1;
        } else {
            queue.push(node);
        }
    };
    let mut queue = Vec::new();
    for &node in &tree.seed {
        reach(node, &mut w, &mut queue);
    }
    while !queue.is_empty() {
        let mut next = Vec::new();
        for node in std::mem::take(&mut queue) {
            match states[node as usize] {
                TO_TEST => {
                    w.hidden += 1;
                    continue;
                }
                REACHES_NEAR => near += 1,
                _ => {}
            }
            let n = tree.nodes[node as usize];
            if n.child_count == 0 {
                let first = n.first_object as usize;
                for &object in &tree.order[first..first + n.object_count as usize] {
                    w.marked[object as usize] = true;
                }
            } else {
                for child in n.first_child..n.first_child + n.child_count {
                    reach(child, &mut w, &mut next);
                }
            }
        }
        queue = next;
    }
    w.tested = w.visited - w.outside - near;
    w.drawn = w.marked.iter().zip(visible_last).map(|(&m, &v)| m || v).collect();
    w
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bench::{RunOptions, Session};
    use crate::camera::generate::default_path;
    use crate::camera::path::CameraPath;
    use crate::cull::culler::Culler;
    use crate::cull::gpu_walk::GpuWalk;
    use crate::cull::gpu_walk::ioc::{Depth, IocParams, IterativeOcclusionCulling};
    use crate::cull::gpu_walk::roc::RasterOcclusionCulling;
    use crate::gpu::{BackendChoice, GpuContext, Resolution};
    use crate::hierarchy::{Hierarchy, HierarchyParams};
    use crate::scene::{LoadOptions, SceneSpec, load};
    use crate::world::World;

    const RESOLUTION: Resolution = Resolution {
        width: 160,
        height: 120,
    };

    /// Runs `mode` (its walk shown by `walk_of`) through `world` along
    /// `path` on `gpu`, holding every frame against the twin's walk of
    /// `tree`; returns the nodes the walks hid.
    fn compare<C: Culler>(
        gpu: &GpuContext,
        mut world: World,
        path: &CameraPath,
        mode: &mut C,
        walk_of: fn(&C) -> Option<&GpuWalk>,
        tree: &CullTree,
    ) -> u64 {
        let options = RunOptions {
            warmup: 0,
            resolution: RESOLUTION,
            measure_error: false,
        };
        let mut session = Session::new(gpu, &world, &mut [Box::new(&mut *mode)], false, &options).unwrap();
        let objects = world.scene.objects.len();
        let (mut visible_last, mut hidden) = (vec![false; objects], 0);
        for frame in 0..path.frames {
            world.advance(frame);
            let camera = path.camera(frame, RESOLUTION.aspect());
            let row = session
                .frame(frame, &camera, &mut world, &mut [Box::new(&mut *mode)], 0)
                .unwrap()
                .remove(0);
            let on_gpu = walk_of(mode).expect("roc and ioc walk on the GPU");
            let twin = walk(tree, &on_gpu.node_states(gpu), &visible_last);
            let at = format!("{} frame {frame} on {}", row.mode, gpu.adapter);
            assert_eq!(row.traversal.nodes_visited, twin.visited, "{at}");
            assert_eq!(row.traversal.nodes_culled_frustum, twin.outside, "{at}");
            assert_eq!(row.traversal.nodes_culled_occlusion, twin.hidden, "{at}");
            assert_eq!(row.queries, twin.tested, "{at}");
            let drawn: Vec<bool> = (0..objects as u32).map(|o| session.drawn[0].contains(o)).collect();
            assert_eq!(drawn, twin.drawn, "{at}");
            hidden += twin.hidden;
            visible_last = twin.marked;
        }
        hidden
    }

    #[test]
    fn the_gpu_walk_counts_marks_and_draws_what_its_cpu_twin_does() {
        let scene = load(
            &SceneSpec::Builtin("city:blocks=2,movers=12".into()),
            &LoadOptions::default(),
        )
        .unwrap();
        let (path, _) = default_path(&scene).unwrap();
        let path = path.with_frames(12).unwrap();
        let hierarchy = Hierarchy::build(&scene.objects, &HierarchyParams::default());
        let gpus: Vec<GpuContext> = [BackendChoice::Vulkan, BackendChoice::Gl]
            .into_iter()
            .filter_map(|b| GpuContext::new(b).ok())
            .filter(|g| g.gpu_driven)
            .collect();
        // Needs a GPU: scripts/test installs Mesa's software ones, which
        // cull on the GPU.
        assert!(
            !gpus.is_empty(),
            "no adapter culls on the GPU: install Mesa (scripts/install-deps)"
        );
        assert!(
            !gpus.is_empty(),
            "no Vulkan or GL adapter: install Mesa (scripts/install-deps)"
        );
        // roc's flat tree, and ioc's hierarchy cut from depth 2 to 6.
        let flat = CullTree::flat(scene.objects.len() as u32);
        let (cut, _) = CullTree::cut(&hierarchy, 2, 6);
        for gpu in &gpus {
            let world = || World::new(scene.clone(), hierarchy.clone());
            let mut roc = RasterOcclusionCulling::new();
            let hidden = compare(gpu, world(), &path, &mut roc, RasterOcclusionCulling::gpu_walk, &flat);
            assert!(
                hidden > 50,
                "roc's walks hide nodes, so the comparison means something ({hidden})"
            );
            let mut ioc = IterativeOcclusionCulling::new(IocParams {
                start: Depth::Fixed(2),
                bottom: Depth::Fixed(6),
            });
            let hidden = compare(gpu, world(), &path, &mut ioc, IterativeOcclusionCulling::gpu_walk, &cut);
            assert!(hidden > 50, "ioc's walks hide nodes ({hidden})");
        }
    }
}
