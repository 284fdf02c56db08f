//! GPU time per phase from timestamp queries, read back asynchronously (a frame never waits).

use std::sync::atomic::{AtomicU8, Ordering};
use std::sync::Arc;

use crate::render::frame::pass::Phase;

/// Timed spans, in frame order: the phases, and the sky's dome layers drawn into reduced
/// buffers (before the scene). Each uses two timestamps (begin, end).
const TIMED: usize = Phase::ALL.len() + 1;
/// Slot of the reduced buffers' passes.
const REDUCED: usize = Phase::ALL.len();

/// Name of timed span `i`.
fn span_name(i: usize) -> &'static str {
    Phase::ALL.get(i).map_or("reduced", |p| p.name())
}
const QUERIES: u32 = TIMED as u32 * 2;

const IDLE: u8 = 0;
const PENDING: u8 = 1;
const DONE: u8 = 2;
const FAILED: u8 = 3;

/// Timestamp queries of the renderer's phases (compute and render passes alike).
pub struct GpuTimer {
    set: wgpu::QuerySet,
    resolve: wgpu::Buffer,
    readback: wgpu::Buffer,
    state: Arc<AtomicU8>,
    /// Whether this frame records timestamps (only when the readback buffer is free).
    recording: bool,
    /// Which passes wrote timestamps in the recorded frame.
    written: [bool; TIMED],
    pending_written: [bool; TIMED],
    period_ns: f32,
    /// Latest GPU time per phase, ms (phases not recorded in that frame are absent).
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
            written: [false; TIMED],
            pending_written: [false; TIMED],
            period_ns: queue.get_timestamp_period(),
            last_ms: Vec::new(),
        }
    }

    /// Start of a frame: collects a finished readback and decides whether to record this frame.
    pub fn begin_frame(&mut self) {
        self.collect();
        self.recording = self.state.load(Ordering::Acquire) == IDLE;
        self.written = [false; TIMED];
    }

    /// Takes in the timings of the last recorded frame if their readback has finished.
    pub fn collect(&mut self) {
        match self.state.load(Ordering::Acquire) {
            DONE => {
                if let Ok(view) = self.readback.get_mapped_range(..) {
                    let ticks: Vec<u64> = view.chunks_exact(8).map(|c| u64::from_le_bytes(c.try_into().expect("8 bytes"))).collect();
                    // The reduced buffers are drawn before the scene: listed first.
                    let order = std::iter::once(REDUCED).chain(0..Phase::ALL.len());
                    self.last_ms =
                        order.filter(|i| self.pending_written[*i]).map(|i| (span_name(i), ticks[2 * i + 1].saturating_sub(ticks[2 * i]) as f32 * self.period_ns / 1e6)).collect();
                }
                self.readback.unmap();
                self.state.store(IDLE, Ordering::Release);
            }
            FAILED => self.state.store(IDLE, Ordering::Release),
            _ => {}
        }
    }

    /// Marks span `i` as timed this frame; its (begin, end) query indices, if this frame records.
    fn claim(&mut self, i: usize) -> Option<(u32, u32)> {
        if !self.recording {
            return None;
        }
        self.written[i] = true;
        Some((2 * i as u32, 2 * i as u32 + 1))
    }

    /// Timestamp writes for the passes of the reduced buffers, if this frame records: the first
    /// pass writes the beginning (`first`), the last the end (`last`).
    pub fn reduced_writes(&mut self, first: bool, last: bool) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        if !(first || last) {
            return None;
        }
        let (begin, end) = self.claim(REDUCED)?;
        Some(wgpu::RenderPassTimestampWrites { query_set: &self.set, beginning_of_pass_write_index: first.then_some(begin), end_of_pass_write_index: last.then_some(end) })
    }

    /// Timestamp writes for a render phase, if this frame records.
    pub fn render_writes(&mut self, phase: Phase) -> Option<wgpu::RenderPassTimestampWrites<'_>> {
        let (begin, end) = self.claim(phase.index())?;
        Some(wgpu::RenderPassTimestampWrites { query_set: &self.set, beginning_of_pass_write_index: Some(begin), end_of_pass_write_index: Some(end) })
    }

    /// Timestamp writes for a compute phase, if this frame records.
    pub fn compute_writes(&mut self, phase: Phase) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let (begin, end) = self.claim(phase.index())?;
        Some(wgpu::ComputePassTimestampWrites { query_set: &self.set, beginning_of_pass_write_index: Some(begin), end_of_pass_write_index: Some(end) })
    }

    /// After the last phase: resolves the queries written this frame.
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
