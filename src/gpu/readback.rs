//! GPU→CPU copies: one mappable buffer reused frame after frame.

use super::context::GpuContext;

pub struct Readback {
    buffer: wgpu::Buffer,
}

impl Readback {
    pub fn new(gpu: &GpuContext, label: &str, size: u64) -> Readback {
        Readback {
            buffer: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some(label),
                size: size.max(4),
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        }
    }

    /// Encodes a copy of `size` bytes of `source` from `source_offset` to
    /// `offset` in this buffer.
    pub fn copy(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        source: &wgpu::Buffer,
        source_offset: u64,
        offset: u64,
        size: u64,
    ) {
        encoder.copy_buffer_to_buffer(source, source_offset, &self.buffer, offset, size);
    }

    /// Encodes a copy of a whole 2D texture (`rows` rows of `row_bytes`,
    /// padded as copies require) into this buffer.
    pub fn copy_texture(&self, encoder: &mut wgpu::CommandEncoder, texture: &wgpu::Texture, row_bytes: u32, rows: u32) {
        encoder.copy_texture_to_buffer(
            texture.as_image_copy(),
            wgpu::TexelCopyBufferInfo {
                buffer: &self.buffer,
                layout: wgpu::TexelCopyBufferLayout {
                    offset: 0,
                    bytes_per_row: Some(row_bytes),
                    rows_per_image: Some(rows),
                },
            },
            texture.size(),
        );
    }

    /// Waits for the GPU and returns the first `size` bytes as `T`s. Where
    /// the GPU failed (a lost device) the buffer cannot be mapped: `out`
    /// gets zeros instead, and the failure is recorded for
    /// [`GpuContext::check`], which ends the run after the frame.
    pub fn read<T: bytemuck::Pod>(&self, gpu: &GpuContext, size: u64, out: &mut Vec<T>) {
        let slice = self.buffer.slice(..size);
        slice.map_async(wgpu::MapMode::Read, |_| {});
        gpu.wait_idle();
        out.clear();
        match slice.get_mapped_range() {
            Ok(view) => out.extend_from_slice(bytemuck::cast_slice(&view)),
            Err(e) => {
                gpu.fail(&format!("reading results back: {e}"));
                out.resize(size as usize / std::mem::size_of::<T>(), T::zeroed());
                return;
            }
        }
        self.buffer.unmap();
    }
}
