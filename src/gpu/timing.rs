//! GPU time per span (one span per mode and frame) from timestamp queries.

use super::context::GpuContext;
use super::readback::Readback;

pub struct GpuTimer {
    queries: wgpu::QuerySet,
    resolved: wgpu::Buffer,
    readback: Readback,
    spans: u32,
    /// Nanoseconds per timestamp tick.
    period_ns: f64,
    ticks: Vec<u64>,
}

impl GpuTimer {
    /// A timer of `spans` begin/end pairs, or `None` when the adapter has no
    /// timestamps inside command encoders.
    pub fn new(gpu: &GpuContext, spans: usize) -> Option<GpuTimer> {
        if !gpu.timestamps {
            return None;
        }
        let count = 2 * spans as u32;
        let bytes = u64::from(count) * 8;
        Some(GpuTimer {
            queries: gpu.device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("frame timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count,
            }),
            resolved: gpu.device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("resolved timestamps"),
                size: bytes,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            readback: Readback::new(gpu, "timestamp readback", bytes),
            spans: spans as u32,
            period_ns: f64::from(gpu.queue.get_timestamp_period()),
            ticks: Vec::with_capacity(count as usize),
        })
    }

    pub fn begin(&self, encoder: &mut wgpu::CommandEncoder, span: usize) {
        encoder.write_timestamp(&self.queries, 2 * span as u32);
    }

    pub fn end(&self, encoder: &mut wgpu::CommandEncoder, span: usize) {
        encoder.write_timestamp(&self.queries, 2 * span as u32 + 1);
    }

    /// Encodes the copy of every span's timestamps to the CPU side.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        encoder.resolve_query_set(&self.queries, 0..2 * self.spans, &self.resolved, 0);
        self.readback
            .copy(encoder, &self.resolved, 0, 0, u64::from(self.spans) * 16);
    }

    /// Milliseconds of each span, after [`GpuTimer::resolve`] was submitted.
    pub fn read_ms(&mut self, gpu: &GpuContext) -> Vec<f64> {
        self.readback.read(gpu, u64::from(self.spans) * 16, &mut self.ticks);
        self.ticks
            .chunks_exact(2)
            .map(|t| t[1].saturating_sub(t[0]) as f64 * self.period_ns / 1e6)
            .collect()
    }
}
