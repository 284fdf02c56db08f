//! GPU time per pass from timestamp queries, read back asynchronously (a frame never waits).

use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::Arc;

/// Passes timed, in order; each uses two timestamps (begin, end).
pub const TIMED_PASSES: [&str; 3] = ["scene", "sky", "glare"];
const QUERIES: u32 = TIMED_PASSES.len() as u32 * 2;

const IDLE: u8 = 0;
const PENDING: u8 = 1;
const DONE: u8 = 2;
const FAILED: u8 = 3;

/// Timestamp queries of the renderer's passes.
pub struct GpuTimer {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
    state: Arc<AtomicU8>,
    /// Whether this frame records timestamps (only when the readback buffer is free).
    recording: bool,
    /// Which passes wrote timestamps in the recorded frame.
    written: [bool; TIMED_PASSES.len()],
    pending_written: [bool; TIMED_PASSES.len()],
    period_ns: f32,
    /// Latest GPU time per pass, ms (passes not drawn in that frame are absent).
    pub last_ms: Vec<(&'static str, f32)>,
}

impl GpuTimer {
    /// Creates the query set and buffers.
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue) -> Self {
        let size = QUERIES as u64 * 8;
        Self {
            set: device.create_query_set(&wgpu::QuerySetDescriptor { label: Some("GpuTimer::queries"), ty: wgpu::QueryType::Timestamp, count: QUERIES }),
            resolve: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("GpuTimer::resolve"),
                size,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            readback: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("GpuTimer::readback"),
                size,
                usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
            state: Arc::new(AtomicU8::new(IDLE)),
            recording: false,
            written: [false; TIMED_PASSES.len()],
            pending_written: [false; TIMED_PASSES.len()],
            period_ns: queue.get_timestamp_period(),
            last_ms: Vec::new(),
        }
    }

    /// Start of a frame: collects a finished readback and decides whether to record this frame.
    pub fn begin_frame(&mut self) {
        match self.state.load(Ordering::Acquire) {
            DONE => {
                if let Ok(view) = self.readback.get_mapped_range(..) {
                    let ticks: Vec<u64> = view.chunks_exact(8).map(|c| u64::from_le_bytes(c.try_into().expect("8 bytes"))).collect();
                    self.last_ms = TIMED_PASSES
                        .iter()
                        .enumerate()
                        .filter(|(i, _)| self.pending_written[*i])
                        .map(|(i, name)| (*name, ticks[2 * i + 1].saturating_sub(ticks[2 * i]) as f32 * self.period_ns / 1e6))
                        .collect();
                }
                self.readback.unmap();
                self.state.store(IDLE, Ordering::Release);
            }
            FAILED => self.state.store(IDLE, Ordering::Release),
            _ => {}
        }
        self.recording = self.state.load(Ordering::Acquire) == IDLE;
        self.written = [false; TIMED_PASSES.len()];
    }

    /// Timestamp writes for pass `index` of [`TIMED_PASSES`], if this frame records.
    pub fn writes(&mut self, index: usize) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        if !self.recording {
            return None;
        }
        self.written[index] = true;
        Some(wgpu::RenderPassTimestampWrites { query_set: &self.set, beginning_of_pass_write_index: Some(2 * index as u32), end_of_pass_write_index: Some(2 * index as u32 + 1) })
    }

    /// After the last pass: resolves the queries written this frame.
    pub fn resolve(&self, encoder: &mut wgpu::CommandEncoder) {
        if self.recording && self.written.iter().any(|w| *w) {
            encoder.resolve_query_set(&self.set, 0..QUERIES, &self.resolve, 0);
            encoder.copy_buffer_to_buffer(&self.resolve, 0, &self.readback, 0, QUERIES as u64 * 8);
        }
    }

    /// After submit: maps the readback buffer asynchronously.
    pub fn after_submit(&mut self) {
        if self.recording && self.written.iter().any(|w| *w) {
            self.pending_written = self.written;
            let state = self.state.clone();
            state.store(PENDING, Ordering::Release);
            self.readback.map_async(wgpu::MapMode::Read, .., move |r| state.store(if r.is_ok() { DONE } else { FAILED }, Ordering::Release));
        }
        self.recording = false;
    }
}
