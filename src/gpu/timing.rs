//! GPU time per span (one span per mode and frame) from timestamp queries,
//! and where each span lies on the GPU's clock ([`GpuSpan`]).

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

    /// Each span, after [`GpuTimer::resolve`] was submitted.
    pub fn read_spans(&mut self, gpu: &GpuContext) -> Vec<GpuSpan> {
        self.readback.read(gpu, u64::from(self.spans) * 16, &mut self.ticks);
        self.ticks
            .chunks_exact(2)
            .map(|t| GpuSpan::of_ticks(t[0], t[1], self.period_ns))
            .collect()
    }
}

/// A stretch of GPU work between two timestamps: where it starts on the
/// GPU's clock (which no CPU clock shares: only spans of one device compare)
/// and how long it took.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GpuSpan {
    /// Nanoseconds on the GPU's clock.
    pub start_ns: f64,
    pub duration_ns: f64,
}

impl GpuSpan {
    /// The span between two timestamps of `period_ns` nanoseconds a tick.
    pub fn of_ticks(begin: u64, end: u64, period_ns: f64) -> GpuSpan {
        GpuSpan {
            start_ns: begin as f64 * period_ns,
            duration_ns: end.saturating_sub(begin) as f64 * period_ns,
        }
    }

    pub fn end_ns(&self) -> f64 {
        self.start_ns + self.duration_ns
    }

    pub fn ms(&self) -> f64 {
        self.duration_ns / 1e6
    }

    pub fn duration(&self) -> std::time::Duration {
        std::time::Duration::from_nanos(self.duration_ns as u64)
    }
}
