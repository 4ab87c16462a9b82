//! The adapter and device: which API and adapter a run uses
//! ([`BackendChoice`], [`AdapterReport`]), what the adapter can do, and the
//! errors the GPU can raise ([`GpuContext`], [`GpuError`]).

use std::fmt;
use std::sync::{Arc, Mutex};

use serde::Serialize;

use super::conservative::{DepthMargins, SubpixelPrecision};

/// Which graphics API to use.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, serde::Deserialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum BackendChoice {
    /// The best adapter of any API; `WGPU_BACKEND` (e.g. `gl`) narrows it.
    #[default]
    Auto,
    Vulkan,
    Gl,
    Metal,
    Dx12,
}

impl BackendChoice {
    /// The backends the choice allows. `auto` takes `WGPU_BACKEND` into
    /// account, as wgpu does; a name in it that wgpu does not know is
    /// refused (wgpu would drop it, and with it every adapter), so a
    /// misspelt variable fails at once as bad input, before any work.
    pub fn backends(self) -> Result<wgpu::Backends, GpuError> {
        Ok(match self {
            BackendChoice::Auto => {
                if let Ok(names) = std::env::var("WGPU_BACKEND") {
                    let unknown = names
                        .split(',')
                        .find(|name| wgpu::Backends::from_comma_list(name).is_empty());
                    if let Some(name) = unknown {
                        return Err(GpuError::UnknownBackend(name.trim().to_string()));
                    }
                }
                wgpu::Backends::all().with_env()
            }
            // An API this system never has is a bad flag, not a machine
            // without a driver.
            BackendChoice::Metal if !cfg!(target_vendor = "apple") => {
                return Err(GpuError::NotOnThisSystem(self, "macOS and iOS"));
            }
            BackendChoice::Dx12 if !cfg!(windows) => return Err(GpuError::NotOnThisSystem(self, "Windows")),
            BackendChoice::Vulkan => wgpu::Backends::VULKAN,
            BackendChoice::Gl => wgpu::Backends::GL,
            BackendChoice::Metal => wgpu::Backends::METAL,
            BackendChoice::Dx12 => wgpu::Backends::DX12,
        })
    }
}

impl fmt::Display for BackendChoice {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        let v = clap::ValueEnum::to_possible_value(self).expect("no skipped variants");
        f.write_str(v.get_name())
    }
}

/// What every result file records about the adapter that produced it.
#[derive(Clone, Debug, Serialize, serde::Deserialize, PartialEq)]
pub struct AdapterReport {
    pub name: String,
    pub backend: String,
    pub device_type: String,
    pub driver: String,
    pub driver_info: String,
    /// Whether per-frame GPU time comes from timestamp queries.
    pub timestamps: bool,
    /// Whether visible pixels can be counted per box (forced early depth
    /// test and storage writes in fragment shaders).
    pub pixel_counts: bool,
    /// Whether culling can run on the GPU alone: pixel counts, compute
    /// shaders, and indirect draws that name their first instance.
    #[serde(default)]
    pub gpu_driven: bool,
    /// Whether an indirect multi-draw can take its count from a GPU buffer
    /// (no read-back before drawing a list the GPU built).
    #[serde(default)]
    pub indirect_count: bool,
    /// The bits of sub-pixel precision the adapter reports, as box tests
    /// and swr's occluders take them ([`SubpixelPrecision`]; 4, Vulkan's
    /// least, where it reports none or less).
    #[serde(default = "coarsest_subpixel_bits")]
    pub subpixel_bits: u32,
    /// On Mesa's software adapters (llvmpipe, and lavapipe, which names its
    /// device after it), `LP_NUM_THREADS` as the run saw it, escaped to one
    /// line ([`crate::text::one_line`]): they rasterise on that many
    /// threads of their own (0: on the thread that submits; unset, `None`:
    /// one per core), on the cores the culling runs on. It changes every
    /// mode's frame time, and how the modes compare, so `compare` takes
    /// runs that differ in it for runs on different adapters (a merge,
    /// which keys its columns by name and backend, refuses two such results
    /// of one run as two results on one adapter). Files written before it
    /// was recorded read as unset.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lp_num_threads: Option<String>,
}

impl AdapterReport {
    /// Whether frame times of runs on `self` and `other` compare: the same
    /// adapter, backend and software threads.
    pub fn times_compare_with(&self, other: &AdapterReport) -> bool {
        (&self.name, &self.backend, &self.lp_num_threads) == (&other.name, &other.backend, &other.lp_num_threads)
    }

    /// What, if anything, makes every mode's work differ on `self` and
    /// `other` whatever the code: another backend (GL's depth range keeps
    /// less precision than the others', which moves what box tests hide)
    /// or another sub-pixel precision (it sets box tests' margins and what
    /// `swr`'s occluders vouch for). The first that differs.
    pub fn work_differs_from(&self, other: &AdapterReport) -> Option<&'static str> {
        [
            ("backends", self.backend != other.backend),
            ("sub-pixel precisions", self.subpixel_bits != other.subpixel_bits),
        ]
        .into_iter()
        .find_map(|(what, differs)| differs.then_some(what))
    }

    /// Whether the GPU walks' round trips differ on `self` and `other`
    /// whatever the code: without indirect counts they read their lists'
    /// lengths back, one a frame.
    pub fn round_trips_differ_from(&self, other: &AdapterReport) -> bool {
        self.indirect_count != other.indirect_count
    }
}

/// What a result file written before adapters recorded their precision
/// is read as: the coarsest, which occlu then assumed everywhere.
fn coarsest_subpixel_bits() -> u32 {
    SubpixelPrecision::COARSEST.bits()
}

impl fmt::Display for AdapterReport {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        write!(f, "{} ({}, {}", self.name, self.backend, self.device_type)?;
        if !self.driver_info.is_empty() {
            write!(f, ", {}", self.driver_info)?;
        }
        if let Some(threads) = &self.lp_num_threads {
            write!(f, ", LP_NUM_THREADS={threads}")?;
        }
        f.write_str(")")
    }
}

#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "no graphics adapter found for backend '{0}'{env} (on Debian, Mesa's llvmpipe gives GL and mesa-vulkan-drivers gives Vulkan: scripts/install-deps)",
        env = narrowed_by_env(*.0)
    )]
    NoAdapter(BackendChoice),
    #[error(
        "WGPU_BACKEND names '{0}', which is no backend wgpu knows (vulkan, gl, metal, dx12, comma-separated): correct or unset it, or give --backend"
    )]
    UnknownBackend(String),
    #[error("the {0} backend exists only on {1}: give another --backend (auto takes the best here)")]
    NotOnThisSystem(BackendChoice, &'static str),
    #[error("the adapter {adapter} refused a device: {message}")]
    Device { adapter: String, message: String },
    #[error("the run needs a {what} of {need}, but the adapter allows {limit}")]
    TooLarge { what: &'static str, need: u64, limit: u64 },
    /// An error the GPU reported while running (validation, out of memory,
    /// device lost), caught instead of wgpu's default panic.
    #[error("the GPU failed: {0}")]
    Failed(String),
    /// A mode's own memory on the CPU (swr's buffer) more than the system
    /// says this process may still take: refused before it is allocated,
    /// where allocating would end the process.
    #[error("{what} need about {need} MiB, and this machine lets occlu take {left} MiB more: {hint}")]
    HostMemory {
        what: &'static str,
        need: u64,
        left: u64,
        hint: &'static str,
    },
}

impl GpuError {
    /// Whether the user's input was at fault: a size the adapter cannot
    /// hold (a smaller --resolution or model fits), or a backend no
    /// adapter here can have, as opposed to the GPU or its driver failing.
    pub fn is_input_error(&self) -> bool {
        matches!(
            self,
            GpuError::TooLarge { .. }
                | GpuError::UnknownBackend(_)
                | GpuError::NotOnThisSystem(..)
                | GpuError::HostMemory { .. }
        )
    }
}

/// What `WGPU_BACKEND` did to an `auto` choice, for the no-adapter message
/// (wgpu reads it and drops names it does not know).
fn narrowed_by_env(choice: BackendChoice) -> String {
    match std::env::var("WGPU_BACKEND") {
        Ok(value) if choice == BackendChoice::Auto => {
            format!(" narrowed by WGPU_BACKEND={value} (names wgpu knows: vulkan, gl, metal, dx12, comma-separated)")
        }
        _ => String::new(),
    }
}

/// The sub-pixel precision `adapter` reports through its API: Vulkan's
/// `subPixelPrecisionBits`, GL's `GL_SUBPIXEL_BITS` (where wgpu builds
/// those backends by default, as Cargo.toml's `glow` says). Metal and
/// Direct3D 12 report none, so they get [`SubpixelPrecision::COARSEST`], as
/// does a report that cannot be read.
fn subpixel_precision(adapter: &wgpu::Adapter) -> SubpixelPrecision {
    reported_subpixel_bits(adapter).map_or(SubpixelPrecision::COARSEST, SubpixelPrecision::reported)
}

#[cfg(any(windows, target_os = "linux", target_os = "android", target_os = "freebsd"))]
fn reported_subpixel_bits(adapter: &wgpu::Adapter) -> Option<u32> {
    use glow::HasContext;
    // SAFETY: the adapter's own handles are only read (a property, a
    // parameter of its context), and none outlives this function.
    unsafe {
        if let Some(vulkan) = adapter.as_hal::<wgpu::hal::api::Vulkan>() {
            let properties = vulkan.physical_device_capabilities().properties();
            Some(properties.limits.sub_pixel_precision_bits)
        } else if let Some(gl) = adapter.as_hal::<wgpu::hal::api::Gles>() {
            u32::try_from(gl.adapter_context().lock().get_parameter_i32(glow::SUBPIXEL_BITS)).ok()
        } else {
            None
        }
    }
}

#[cfg(not(any(windows, target_os = "linux", target_os = "android", target_os = "freebsd")))]
fn reported_subpixel_bits(_: &wgpu::Adapter) -> Option<u32> {
    None
}

/// The device and queue of the chosen adapter.
pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub adapter: AdapterReport,
    /// Timestamp writes inside command encoders are available.
    pub timestamps: bool,
    /// See [`AdapterReport::pixel_counts`].
    pub pixel_counts: bool,
    /// See [`AdapterReport::gpu_driven`].
    pub gpu_driven: bool,
    /// See [`AdapterReport::indirect_count`].
    pub indirect_count: bool,
    /// How far box tests stay clear of rounding on this backend.
    pub depth_margins: DepthMargins,
    /// How finely the adapter snaps vertices on screen.
    pub subpixel: SubpixelPrecision,
    /// The first error the device reported outside any error scope, or its
    /// loss; [`GpuContext::check`] turns it into a [`GpuError`].
    failure: Arc<Mutex<Option<String>>>,
}

impl GpuContext {
    /// Opens the best adapter the choice allows: real GPUs before software
    /// ones, and a native API before GL on the same device.
    pub fn new(choice: BackendChoice) -> Result<GpuContext, GpuError> {
        let backends = choice.backends()?;
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
            backends,
            flags: wgpu::InstanceFlags::default().with_env(),
            ..wgpu::InstanceDescriptor::new_without_display_handle()
        });
        let adapter = pollster::block_on(instance.enumerate_adapters(backends))
            .into_iter()
            .min_by_key(|a| {
                let info = a.get_info();
                (
                    device_rank(info.device_type),
                    u8::from(info.backend == wgpu::Backend::Gl),
                )
            })
            .ok_or(GpuError::NoAdapter(choice))?;
        let info = adapter.get_info();
        let timing = wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::TIMESTAMP_QUERY_INSIDE_ENCODERS;
        let wanted = timing
            | wgpu::Features::SHADER_EARLY_DEPTH_TEST
            | wgpu::Features::INDIRECT_FIRST_INSTANCE
            | wgpu::Features::MULTI_DRAW_INDIRECT_COUNT;
        let features = adapter.features() & wanted;
        let downlevel = adapter.get_downlevel_capabilities().flags;
        let timestamps = features.contains(timing);
        let pixel_counts = features.contains(wgpu::Features::SHADER_EARLY_DEPTH_TEST)
            && downlevel.contains(wgpu::DownlevelFlags::FRAGMENT_WRITABLE_STORAGE);
        // walk.wgsl's expand pass binds 8 storage buffers.
        let gpu_driven = pixel_counts
            && features.contains(wgpu::Features::INDIRECT_FIRST_INSTANCE)
            && downlevel.contains(wgpu::DownlevelFlags::COMPUTE_SHADERS | wgpu::DownlevelFlags::INDIRECT_EXECUTION)
            && adapter.limits().max_storage_buffers_per_shader_stage >= 8;
        let indirect_count = features.contains(wgpu::Features::MULTI_DRAW_INDIRECT_COUNT);
        let subpixel = subpixel_precision(&adapter);
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("occlu"),
            required_features: features,
            // Large models need the adapter's full buffer sizes.
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| GpuError::Device {
            adapter: info.name.clone(),
            message: e.to_string(),
        })?;
        // wgpu's default handler panics; keep the first error for check().
        let failure = Arc::new(Mutex::new(None));
        let record = |failure: &Arc<Mutex<Option<String>>>| {
            let failure = Arc::clone(failure);
            move |message: String| record_failure(&failure, &message)
        };
        let on_error = record(&failure);
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| on_error(e.to_string())));
        let on_loss = record(&failure);
        device.set_device_lost_callback(move |reason, message| on_loss(format!("device lost ({reason:?}): {message}")));
        // Lavapipe names its device after llvmpipe, whose threads it uses.
        // The value is the user's, and is shown in reports: one line.
        let lp_num_threads = info
            .name
            .contains("llvmpipe")
            .then(|| std::env::var_os("LP_NUM_THREADS"))
            .flatten()
            .map(|value| crate::text::one_line(&value.to_string_lossy()));
        Ok(GpuContext {
            device,
            queue,
            adapter: AdapterReport {
                name: info.name,
                backend: info.backend.to_string(),
                device_type: format!("{:?}", info.device_type),
                driver: info.driver,
                driver_info: info.driver_info,
                timestamps,
                pixel_counts,
                gpu_driven,
                indirect_count,
                subpixel_bits: subpixel.bits(),
                lp_num_threads,
            },
            timestamps,
            pixel_counts,
            gpu_driven,
            indirect_count,
            depth_margins: DepthMargins::for_backend(info.backend),
            subpixel,
            failure,
        })
    }

    /// Records a failure found outside wgpu's callbacks (a read-back that
    /// could not be mapped), for [`GpuContext::check`].
    pub(crate) fn fail(&self, message: &str) {
        record_failure(&self.failure, message);
    }

    /// The first error the GPU reported since the device was opened, if any.
    pub fn check(&self) -> Result<(), GpuError> {
        // Callbacks (a lost device's) are delivered while polling.
        let _ = self.device.poll(wgpu::PollType::Poll);
        let failure = self.failure.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        match failure.as_ref() {
            Some(message) => Err(GpuError::Failed(message.clone())),
            None => Ok(()),
        }
    }

    /// The compute pipeline of `entry` in `module`, with bind groups of
    /// `layouts`, or of layouts taken from the shader (`None`: each then
    /// binds only groups made from the pipeline's own layouts).
    pub fn compute_pipeline(
        &self,
        module: &wgpu::ShaderModule,
        entry: &str,
        layouts: Option<&[Option<&wgpu::BindGroupLayout>]>,
    ) -> wgpu::ComputePipeline {
        let layout = layouts.map(|layouts| {
            self.device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
                label: Some(entry),
                bind_group_layouts: layouts,
                immediate_size: 0,
            })
        });
        self.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry),
            layout: layout.as_ref(),
            module,
            entry_point: Some(entry),
            // No compute shader of occlu reads workgroup memory it has not
            // written first (pyramid_test.wgsl's cs_pixels clears its own),
            // so wgpu's zero fill is only cost: on GL, one invocation of
            // every workgroup writing each word of it before a barrier.
            compilation_options: wgpu::PipelineCompilationOptions {
                zero_initialize_workgroup_memory: false,
                ..Default::default()
            },
            cache: None,
        })
    }

    /// A buffer holding `contents` (padded to whole words, at least one, as
    /// copies and bindings need), written through the queue. wgpu's
    /// `create_buffer_init` maps the new buffer instead, and panics when the
    /// device is lost; here a lost device only records the failure for
    /// [`GpuContext::check`].
    pub fn buffer_with(&self, label: &str, contents: &[u8], usage: wgpu::BufferUsages) -> wgpu::Buffer {
        let words = contents.len().div_ceil(4).max(1);
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size: (words * 4) as u64,
            usage: usage | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        if contents.len() == words * 4 {
            self.queue.write_buffer(&buffer, 0, contents);
        } else {
            let mut padded = contents.to_vec();
            padded.resize(words * 4, 0);
            self.queue.write_buffer(&buffer, 0, &padded);
        }
        buffer
    }

    /// Every backend that has an adapter here, for unit tests that run on
    /// each (Vulkan and GL on the reference machine). Fails where there is
    /// none: they need a GPU or a software rasteriser.
    #[cfg(test)]
    pub(crate) fn every_adapter() -> Vec<GpuContext> {
        let found: Vec<GpuContext> = [BackendChoice::Vulkan, BackendChoice::Gl]
            .into_iter()
            .filter_map(|b| GpuContext::new(b).ok())
            .collect();
        assert!(
            !found.is_empty(),
            "no Vulkan or GL adapter: install Mesa (scripts/install-deps)"
        );
        found
    }

    /// Every adapter here that culls on the GPU, of Vulkan and GL. Fails
    /// where there is none: Mesa's software ones, which scripts/test
    /// installs, cull on the GPU.
    #[cfg(test)]
    pub(crate) fn every_gpu_driven_adapter() -> Vec<GpuContext> {
        let gpus: Vec<GpuContext> = GpuContext::every_adapter()
            .into_iter()
            .filter(|g| g.gpu_driven)
            .collect();
        assert!(
            !gpus.is_empty(),
            "no adapter culls on the GPU: install Mesa (scripts/install-deps)"
        );
        gpus
    }

    /// Blocks until the GPU has finished everything submitted so far.
    pub fn wait_idle(&self) {
        // A lost device is recorded by the device-lost callback and reported
        // by check(); waiting on it cannot fail any other way here.
        let _ = self.device.poll(wgpu::PollType::wait_indefinitely());
    }
}

/// Keeps `message` as the device's failure unless one came first.
fn record_failure(failure: &Mutex<Option<String>>, message: &str) {
    let mut first = failure.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
    first.get_or_insert_with(|| message.to_string());
}

fn device_rank(t: wgpu::DeviceType) -> u8 {
    match t {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 3,
        wgpu::DeviceType::Other => 4,
    }
}
