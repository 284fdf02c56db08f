//! GPU device creation: headless (offscreen) or for a window surface. Vulkan only, so CI runs on
//! Mesa's lavapipe and desktops on their native driver.

use crate::render::gpu::error::{RenderError, RenderResult};

/// Which adapter to ask for.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum AdapterChoice {
    /// The best adapter available (a real GPU when there is one).
    #[default]
    Auto,
    /// A software adapter (lavapipe): deterministic images for tests and CI.
    Cpu,
}

impl AdapterChoice {
    /// `SKYTUNE_ADAPTER=cpu` forces the software adapter; tests set it.
    pub fn from_env() -> Self {
        match std::env::var("SKYTUNE_ADAPTER").as_deref() {
            Ok("cpu") => AdapterChoice::Cpu,
            _ => AdapterChoice::Auto,
        }
    }
}

/// Device, queue and what they can do. Cloning shares the same device (the handles are shared).
#[derive(Clone)]
pub struct GpuContext {
    /// The wgpu instance (kept to create surfaces).
    pub instance: wgpu::Instance,
    /// Adapter in use.
    pub adapter: wgpu::Adapter,
    /// Logical device.
    pub device: wgpu::Device,
    /// Its queue.
    pub queue: wgpu::Queue,
    /// Whether GPU timestamp queries work (per-pass GPU timings).
    pub timestamps: bool,
    /// Why the device was lost, once it is (driver reset, GPU removed, `destroy`).
    lost: std::sync::Arc<std::sync::Mutex<Option<String>>>,
    /// wgpu errors raised outside any error scope so far (bugs of ours: logged, counted).
    uncaptured: std::sync::Arc<std::sync::atomic::AtomicU64>,
}

/// Default time to wait for the GPU; lavapipe on 2 cores can take seconds for a big frame.
pub const POLL_TIMEOUT: std::time::Duration = std::time::Duration::from_secs(120);

impl GpuContext {
    /// Creates a context; with `surface`, the adapter must be able to present to it.
    pub fn new(instance: wgpu::Instance, choice: AdapterChoice, surface: Option<&wgpu::Surface<'_>>) -> RenderResult<Self> {
        let adapter = Self::pick_adapter(&instance, choice, surface)?;
        let info = adapter.get_info();
        log::info!("adapter: {} (driver {})", describe(&info), info.driver);
        let timestamps = adapter.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        let mut features = wgpu::Features::empty();
        if timestamps {
            features |= wgpu::Features::TIMESTAMP_QUERY;
        }
        // Downlevel limits, but WebGPU's 8 storage buffers per stage where the adapter has them:
        // the physical sky models' compute passes read their tables as storage buffers.
        let mut limits = wgpu::Limits::downlevel_defaults().using_resolution(adapter.limits());
        limits.max_storage_buffers_per_shader_stage = adapter.limits().max_storage_buffers_per_shader_stage.clamp(limits.max_storage_buffers_per_shader_stage, 8);
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("skytune::device"),
            required_features: features,
            required_limits: limits,
            memory_hints: wgpu::MemoryHints::MemoryUsage,
            ..Default::default()
        }))?;
        // Errors outside an error scope are bugs of ours; log them rather than abort the artist's session.
        let uncaptured = std::sync::Arc::new(std::sync::atomic::AtomicU64::new(0));
        let count = uncaptured.clone();
        device.on_uncaptured_error(std::sync::Arc::new(move |e| {
            count.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
            log::error!("wgpu: {e}");
        }));
        let lost = std::sync::Arc::new(std::sync::Mutex::new(None));
        let flag = lost.clone();
        device.set_device_lost_callback(move |reason, message| {
            log::error!("the GPU device was lost ({reason:?}): {message}");
            if let Ok(mut l) = flag.lock() {
                *l = Some(format!("{reason:?}: {message}"));
            }
        });
        Ok(Self { instance, adapter, device, queue, timestamps, lost, uncaptured })
    }

    /// The same device for renderers that record no GPU timestamps: what a frame costs without
    /// measuring it (lavapipe charges a sky frame's phase timestamps about 3% of its time).
    pub fn without_timestamps(&self) -> Self {
        Self { timestamps: false, ..self.clone() }
    }

    /// Why the device was lost, if it was: everything made from it is dead, and a new context
    /// (and renderer) must replace it.
    pub fn lost_reason(&self) -> Option<String> {
        self.lost.lock().ok().and_then(|l| l.clone())
    }

    /// wgpu errors raised outside any error scope so far.
    pub fn uncaptured_errors(&self) -> u64 {
        self.uncaptured.load(std::sync::atomic::Ordering::Relaxed)
    }

    /// A headless context (no surface).
    pub fn headless(choice: AdapterChoice) -> RenderResult<Self> {
        Self::new(new_instance(), choice, None)
    }

    fn pick_adapter(instance: &wgpu::Instance, choice: AdapterChoice, surface: Option<&wgpu::Surface<'_>>) -> RenderResult<wgpu::Adapter> {
        let adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::VULKAN));
        let usable = |a: &wgpu::Adapter| surface.is_none_or(|s| a.is_surface_supported(s));
        let cpu = adapters.iter().find(|a| a.get_info().device_type == wgpu::DeviceType::Cpu && usable(a));
        let pick = match choice {
            AdapterChoice::Cpu => cpu,
            AdapterChoice::Auto => adapters.iter().filter(|a| usable(a)).max_by_key(|a| match a.get_info().device_type {
                wgpu::DeviceType::DiscreteGpu => 3,
                wgpu::DeviceType::IntegratedGpu => 2,
                wgpu::DeviceType::VirtualGpu => 1,
                _ => 0,
            }),
        };
        pick.cloned().ok_or_else(|| {
            let names: Vec<String> = adapters.iter().map(|a| format!("{} ({:?})", a.get_info().name, a.get_info().device_type)).collect();
            RenderError::NoAdapter { wanted: format!("{choice:?}"), found: names.join(", ") }
        })
    }

    /// One line naming the adapter, for logs and the UI.
    pub fn adapter_line(&self) -> String {
        describe(&self.adapter.get_info())
    }

    /// Waits for submitted work, with a generous timeout for software rasterisers.
    pub fn wait_idle(&self) -> RenderResult<()> {
        self.device.poll(wgpu::PollType::Wait { submission_index: None, timeout: Some(POLL_TIMEOUT) })?;
        Ok(())
    }
}

/// A Vulkan-only instance.
pub fn new_instance() -> wgpu::Instance {
    let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
    desc.backends = wgpu::Backends::VULKAN;
    wgpu::Instance::new(desc)
}

/// An adapter's name, kind, backend and driver version in one line. The driver's version (Mesa's,
/// for lavapipe) matters as much as the adapter: the same llvmpipe runs the sky's frames about a
/// quarter faster in Mesa 25 than in Mesa 22.
fn describe(i: &wgpu::AdapterInfo) -> String {
    if i.driver_info.is_empty() {
        format!("{} ({:?}, {:?})", i.name, i.device_type, i.backend)
    } else {
        format!("{} ({:?}, {:?}; {})", i.name, i.device_type, i.backend, i.driver_info)
    }
}
