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
//! decided, and in a warm-up frame, in which it times every walk in turn,
//! starts each from the lists as the frame found them
//! ([`VisibleLists::keep`], [`VisibleLists::restore`]).

use std::cell::{Cell, OnceCell};

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
    /// A copy of the visible set and its lengths ([`VisibleLists::keep`]),
    /// made on first use. The boxes are not kept: the first walk of a
    /// frame writes this frame's, and a later one finds them current (the
    /// first alone pays for the movers' boxes).
    kept: OnceCell<[wgpu::Buffer; 3]>,
    kept_counts: Cell<[u32; 2]>,
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
                wgpu::BufferUsages::INDIRECT | copy,
            ),
            counts: storage_buffer(gpu, "draw list lengths", 8, wgpu::BufferUsages::INDIRECT | copy),
            known_counts: Cell::new([0; 2]),
            boxes: Rc::new(ObjectBoxes::new(gpu, objects)?),
            kept: OnceCell::new(),
            kept_counts: Cell::new([0; 2]),
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

    /// Copies the visible set aside, for [`VisibleLists::restore`]: `auto`
    /// times every walk of a warm-up frame in turn, and a walk that started
    /// from the lists another wrote in the same frame would start from that
    /// walk's result for this very frame, where a recorded frame hands it
    /// the last frame's; so it would be timed cheaper than it runs, the
    /// more so the farther apart warm-up's frames look. Waits for the GPU.
    pub fn keep(&self, gpu: &GpuContext) {
        let kept = self.kept.get_or_init(|| {
            self.visible_set().map(|b| {
                gpu.device.create_buffer(&wgpu::BufferDescriptor {
                    label: Some("kept visible set"),
                    size: b.size(),
                    usage: wgpu::BufferUsages::COPY_SRC | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                })
            })
        });
        copy_all(gpu, self.visible_set(), kept.each_ref());
        self.kept_counts.set(self.known_counts.get());
    }

    /// Puts back the visible set [`VisibleLists::keep`] copied aside (none
    /// where nothing was kept). Waits for the GPU.
    pub fn restore(&self, gpu: &GpuContext) {
        if let Some(kept) = self.kept.get() {
            copy_all(gpu, kept.each_ref(), self.visible_set());
            self.known_counts.set(self.kept_counts.get());
        }
    }

    /// The buffers that hold the visible set.
    fn visible_set(&self) -> [&wgpu::Buffer; 3] {
        [&self.object_state, &self.commands, &self.counts]
    }

    /// The visible set's buffers, read back: the object words, the draw
    /// lists and their two lengths.
    #[cfg(test)]
    pub(crate) fn read_back(&self, gpu: &GpuContext) -> [Vec<u32>; 3] {
        self.visible_set().map(|buffer| {
            let readback = crate::gpu::Readback::new(gpu, "visible set", buffer.size());
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            readback.copy(&mut encoder, buffer, 0, 0, buffer.size());
            gpu.queue.submit([encoder.finish()]);
            let mut words = Vec::new();
            readback.read(gpu, buffer.size(), &mut words);
            words
        })
    }
}

/// Copies each of `from` into the buffer of `to` in its place, and waits for
/// the GPU, so that no timed frame after it carries the copy.
fn copy_all(gpu: &GpuContext, from: [&wgpu::Buffer; 3], to: [&wgpu::Buffer; 3]) {
    let mut encoder = gpu.device.create_command_encoder(&wgpu::CommandEncoderDescriptor {
        label: Some("visible set copy"),
    });
    for (from, to) in from.into_iter().zip(to) {
        encoder.copy_buffer_to_buffer(from, 0, to, 0, from.size());
    }
    gpu.queue.submit([encoder.finish()]);
    gpu.wait_idle();
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::DrawRange;

    #[test]
    fn a_kept_visible_set_comes_back_whatever_was_written_since() {
        for gpu in &GpuContext::every_adapter() {
            let draws: Vec<DrawRange> = (0..7)
                .map(|o| DrawRange {
                    first_index: 3 * o,
                    index_count: 3,
                })
                .collect();
            let lists = VisibleLists::new(gpu, &draws).unwrap();
            // Nothing kept yet: nothing to put back.
            lists.upload(gpu, &[6]);
            lists.restore(gpu);
            assert_eq!(lists.known_counts(), [1, 0]);
            lists.upload(gpu, &[1, 4, 5]);
            let uploaded = lists.read_back(gpu);
            lists.keep(gpu);
            // What a walk before it in the frame would have left.
            lists.upload(gpu, &[0, 2]);
            assert_ne!(lists.read_back(gpu), uploaded);
            lists.restore(gpu);
            assert_eq!(lists.read_back(gpu), uploaded, "{}", gpu.adapter.backend);
            assert_eq!(lists.known_counts(), [3, 0]);
            gpu.check().expect("no GPU error");
        }
    }
}
