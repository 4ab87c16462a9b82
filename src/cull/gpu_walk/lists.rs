//! What a GPU walk carries from one frame to the next, on the GPU: the
//! visible set (a word per object, visible in the last walk; the visible
//! and newly visible draw lists `cs_compact` builds, and their lengths),
//! and every object's box as of the last frame (frustum.rs).
//!
//! Each mode owns one. `auto` gives one to all the walks it runs
//! ([`crate::cull::Culler::share_visible_lists`]), so a walk it switches to
//! starts from the set the last walk found, as if it had run all along,
//! and the boxes are uploaded once, not once a walk; and it fills the
//! lists from the CPU ([`VisibleLists::upload`]) after frames the CPU
//! decided.

use std::cell::Cell;

use std::rc::Rc;

use super::frustum::ObjectBoxes;
use super::layout::{DRAW_COMMAND_BYTES, VISIBLE_LAST_FRAME};
use crate::gpu::{DrawRange, GpuContext, GpuError, storage_buffer};

pub struct VisibleLists {
    objects: u32,
    /// Every object's draw command, in object order, on the CPU (for
    /// [`VisibleLists::upload`]) and on the GPU (what `cs_compact` copies
    /// from).
    draw_commands: Vec<u8>,
    pub(super) all_commands: wgpu::Buffer,
    /// A word per object: [`VISIBLE_LAST_FRAME`] (and, during a walk,
    /// `MARKED`).
    pub(super) object_state: wgpu::Buffer,
    /// The visible list at [0, n), the newly visible one at [n, 2n).
    pub(super) commands: wgpu::Buffer,
    /// The two lists' lengths.
    pub(super) counts: wgpu::Buffer,
    /// The lengths as last read back or uploaded, where draws cannot take
    /// them from `counts`.
    known_counts: Cell<[u32; 2]>,
    /// Every object's box as of the last frame.
    pub(super) boxes: Rc<ObjectBoxes>,
}

impl VisibleLists {
    /// Empty lists (nothing visible yet) and no boxes yet for objects drawn
    /// by `draws`; fails where the adapter cannot bind a box for each.
    pub fn new(gpu: &GpuContext, draws: &[DrawRange]) -> Result<VisibleLists, GpuError> {
        let draw_commands: Vec<u8> = draws
            .iter()
            .enumerate()
            .flat_map(|(o, d)| {
                wgpu::util::DrawIndexedIndirectArgs {
                    index_count: d.index_count,
                    instance_count: 1,
                    first_index: d.first_index,
                    base_vertex: 0,
                    first_instance: o as u32,
                }
                .as_bytes()
                .to_vec()
            })
            .collect();
        let objects = draws.len() as u32;
        let words = u64::from(objects.max(1)) * 4;
        let copy = wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST;
        Ok(VisibleLists {
            objects,
            all_commands: gpu.buffer_with("all draw commands", &draw_commands, wgpu::BufferUsages::STORAGE),
            draw_commands,
            object_state: storage_buffer(gpu, "object state", words, copy),
            commands: storage_buffer(
                gpu,
                "draw lists",
                2 * u64::from(objects.max(1)) * DRAW_COMMAND_BYTES,
                wgpu::BufferUsages::INDIRECT | wgpu::BufferUsages::COPY_DST,
            ),
            counts: storage_buffer(gpu, "draw list lengths", 8, wgpu::BufferUsages::INDIRECT | copy),
            known_counts: Cell::new([0; 2]),
            boxes: Rc::new(ObjectBoxes::new(gpu, objects)?),
        })
    }

    pub fn objects(&self) -> u32 {
        self.objects
    }

    pub(super) fn known_counts(&self) -> [u32; 2] {
        self.known_counts.get()
    }

    pub(super) fn set_known_counts(&self, counts: [u32; 2]) {
        self.known_counts.set(counts);
    }

    /// Makes `visible` (object ids, each once) the set visible in the last
    /// walk, as if a walk had found it: the next walk draws it first. The
    /// writes reach the GPU at the next submit, before anything it carries.
    pub fn upload(&self, gpu: &GpuContext, visible: &[u32]) {
        let mut states = vec![0u32; self.objects as usize];
        let mut commands = Vec::with_capacity(visible.len() * DRAW_COMMAND_BYTES as usize);
        for &o in visible {
            states[o as usize] = VISIBLE_LAST_FRAME;
            let at = o as usize * DRAW_COMMAND_BYTES as usize;
            commands.extend_from_slice(&self.draw_commands[at..at + DRAW_COMMAND_BYTES as usize]);
        }
        let counts = [visible.len() as u32, 0];
        if !states.is_empty() {
            gpu.queue
                .write_buffer(&self.object_state, 0, bytemuck::cast_slice(&states));
        }
        if !commands.is_empty() {
            gpu.queue.write_buffer(&self.commands, 0, &commands);
        }
        gpu.queue.write_buffer(&self.counts, 0, bytemuck::cast_slice(&counts));
        self.known_counts.set(counts);
    }
}
