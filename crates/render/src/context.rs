//! The GPU context: instance, adapter, device and queue.
//!
//! The adapter is chosen from the environment the way wgpu's own tools do:
//! `WGPU_BACKEND` (e.g. `vulkan`), `WGPU_ADAPTER_NAME` (a substring of the adapter name),
//! `WGPU_POWER_PREF`. With none set, the system's default adapter is used. A context can
//! also wrap a device created elsewhere (the editor shares eframe's).

use std::time::Duration;

use crate::error::{RenderError, Result};

/// How long to wait for the GPU before giving up. lavapipe is slow, so this is generous.
pub const GPU_TIMEOUT: Duration = Duration::from_secs(600);

/// What the path tracer's choices depend on in an adapter (found without opening a device:
/// [`GpuContext::default_adapter_traits`]; of an open one: [`GpuContext::traits`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct AdapterTraits {
    /// A CPU implementation (lavapipe).
    pub cpu: bool,
    /// Where the device has ray queries: the most primitives one of its acceleration
    /// structures holds.
    pub ray_query_limit: Option<u32>,
}

/// Instance, adapter, device and queue, plus what the device can do.
#[derive(Clone, Debug)]
pub struct GpuContext {
    /// The adapter.
    pub adapter: wgpu::Adapter,
    /// The device.
    pub device: wgpu::Device,
    /// The queue.
    pub queue: wgpu::Queue,
    /// Adapter name, backend, driver.
    pub info: wgpu::AdapterInfo,
    /// Whether compute passes can be timed with timestamp queries.
    pub timestamps: bool,
    /// The first GPU error no error scope caught (see [`GpuContext::take_error`]).
    errors: std::sync::Arc<std::sync::Mutex<Option<String>>>,
    /// Why the device was lost, once it is (see [`GpuContext::lost`]).
    lost: std::sync::Arc<std::sync::Mutex<Option<String>>>,
    /// Kernels compiled on this device, reused when the same shader is built again
    /// ([`crate::kernel::KernelCache`]).
    pub(crate) kernels: std::sync::Arc<crate::kernel::KernelCache>,
}

impl GpuContext {
    /// Opens a headless context on the adapter the environment asks for.
    ///
    /// # Errors
    /// When no adapter matches or the device cannot be opened.
    pub fn headless() -> Result<Self> {
        pollster::block_on(Self::headless_async(false))
    }

    /// Like [`Self::headless`], but when the environment names no adapter, a CPU adapter
    /// (lavapipe) is taken if there is one, so tests compare against references made on
    /// the same kind of device wherever they run.
    ///
    /// # Errors
    /// When no adapter matches or the device cannot be opened.
    pub fn headless_prefer_cpu() -> Result<Self> {
        pollster::block_on(Self::headless_async(true))
    }

    async fn headless_async(prefer_cpu: bool) -> Result<Self> {
        Self::from_adapter(Self::select_adapter(prefer_cpu).await?).await
    }

    /// What [`GpuContext::headless`] would run on, without opening a device (`lumagraph
    /// plan` shows the shader choices made for it).
    ///
    /// # Errors
    /// When no adapter matches.
    pub fn default_adapter_info() -> Result<wgpu::AdapterInfo> {
        pollster::block_on(Self::select_adapter(false)).map(|a| a.get_info())
    }

    /// The adapter [`GpuContext::headless`] would choose and what the path tracer's choices
    /// depend on in it, without opening a device.
    ///
    /// # Errors
    /// When no adapter matches.
    pub fn default_adapter_traits() -> Result<(wgpu::AdapterInfo, AdapterTraits)> {
        let adapter = pollster::block_on(Self::select_adapter(false))?;
        let info = adapter.get_info();
        let rq = adapter.features() & Self::optional_features();
        let traits = AdapterTraits {
            cpu: info.device_type == wgpu::DeviceType::Cpu,
            ray_query_limit: rq
                .contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY)
                .then(|| adapter.limits().max_blas_primitive_count),
        };
        Ok((info, traits))
    }

    /// Every adapter the environment's backends offer, one line each, then the one
    /// [`GpuContext::headless`] would choose: name, kind, backend and driver, and what
    /// decides how lumagraph runs there (ray queries, timestamp queries, the largest storage
    /// binding and buffer). `lumagraph adapters` prints it.
    ///
    /// # Errors
    /// When no adapter is found at all.
    pub fn describe_adapters() -> Result<String> {
        use std::fmt::Write as _;
        let desc = Self::instance_descriptor();
        let backends = desc.backends;
        let instance = wgpu::Instance::new(desc);
        let adapters = pollster::block_on(instance.enumerate_adapters(backends));
        if adapters.is_empty() {
            return Err(RenderError::NoAdapter(String::new()));
        }
        let mib = |x: u64| x / (1024 * 1024);
        let mut out = String::new();
        for a in &adapters {
            let info = a.get_info();
            let features = a.features();
            let limits = a.limits();
            let has = |f: wgpu::Features| if features.contains(f) { "yes" } else { "no" };
            let _ = writeln!(
                out,
                "{} ({:?}, {:?}, {} {})\n    ray queries: {}, ray-tracing pipelines: {}, timestamp queries: {}, \
                 largest storage binding: {} MiB, largest buffer: {} MiB",
                info.name,
                info.device_type,
                info.backend,
                info.driver,
                info.driver_info,
                has(wgpu::Features::EXPERIMENTAL_RAY_QUERY),
                has(wgpu::Features::EXPERIMENTAL_RAY_TRACING_PIPELINES),
                has(wgpu::Features::TIMESTAMP_QUERY),
                mib(limits.max_storage_buffer_binding_size),
                mib(limits.max_buffer_size),
            );
        }
        let chosen = pollster::block_on(Self::select_adapter(false))?.get_info();
        let _ = writeln!(
            out,
            "chosen (WGPU_BACKEND, WGPU_ADAPTER_NAME, WGPU_POWER_PREF or the system's default): {} ({:?})",
            chosen.name, chosen.backend
        );
        Ok(out)
    }

    async fn select_adapter(prefer_cpu: bool) -> Result<wgpu::Adapter> {
        let desc = Self::instance_descriptor();
        let backends = desc.backends;
        let instance = wgpu::Instance::new(desc);
        let adapter = if let Ok(name) = std::env::var("WGPU_ADAPTER_NAME") {
            let wanted = name.to_lowercase();
            let adapters = instance.enumerate_adapters(backends).await;
            let names: Vec<String> = adapters.iter().map(|a| a.get_info().name).collect();
            adapters
                .into_iter()
                .find(|a| a.get_info().name.to_lowercase().contains(&wanted))
                .ok_or_else(|| {
                    RenderError::NoAdapter(format!(
                        " named like WGPU_ADAPTER_NAME={name:?} (adapters: {})",
                        names.join(", ")
                    ))
                })?
        } else if let Some(cpu) = if prefer_cpu {
            instance
                .enumerate_adapters(backends)
                .await
                .into_iter()
                .find(|a| a.get_info().device_type == wgpu::DeviceType::Cpu)
        } else {
            None
        } {
            cpu
        } else {
            instance
                .request_adapter(&wgpu::RequestAdapterOptions {
                    power_preference: wgpu::PowerPreference::from_env().unwrap_or_default(),
                    ..Default::default()
                })
                .await
                .map_err(|e| RenderError::NoAdapter(format!(": {e}")))?
        };
        Ok(adapter)
    }

    /// The instance lumagraph creates: Vulkan, Metal and DX12 unless `WGPU_BACKEND` says
    /// otherwise (the GL backend's EGL contexts are not safe to share between the threads
    /// of a test run), other flags from the environment as wgpu's own tools read them.
    ///
    /// Debug builds leave out wgpu's `DEBUG` flag unless `WGPU_DEBUG=1` asks for it: it
    /// writes the WGSL source and line of every statement into the SPIR-V (for shader
    /// debuggers), which naga does in time quadratic in the source's length; the path
    /// tracer's process then started 0.4–0.6 s slower on lavapipe (three runs each).
    ///
    /// It first switches off what would print a bogus error on a machine without a session
    /// runtime folder ([`Self::quiet_device_select`]).
    pub fn instance_descriptor() -> wgpu::InstanceDescriptor {
        Self::quiet_device_select();
        let mut desc = wgpu::InstanceDescriptor::new_without_display_handle();
        desc.backends = wgpu::Backends::PRIMARY;
        desc.flags = wgpu::InstanceFlags::from_build_config() - wgpu::InstanceFlags::DEBUG;
        desc.with_env()
    }

    /// Keeps libwayland from printing `error: XDG_RUNTIME_DIR is invalid or not set in the
    /// environment.` (once per Vulkan instance) where nothing failed: on a render box, in a
    /// container or a batch job, which have no session runtime folder.
    ///
    /// Mesa's Vulkan device-select layer, which the Vulkan loader loads into every instance,
    /// asks Wayland for its display while it orders the devices (Debian 12's Mesa 22.3 does
    /// so even without `WAYLAND_DISPLAY`), and libwayland prints that line when
    /// `XDG_RUNTIME_DIR` is unset or not an absolute path. lumagraph chooses its adapter
    /// itself, so there the layer is switched off by its own switch, `NODEVICE_SELECT=1`,
    /// read by the loader when an instance is created. Pointing `XDG_RUNTIME_DIR` at a
    /// private empty folder silences it too, but that variable is read by everything else
    /// in the process and its children (D-Bus, audio, the editor's window system), which
    /// would then look for their sockets there, and the folder would outlive the process;
    /// `NODEVICE_SELECT` concerns the layer only. Nothing is changed when the user set
    /// `NODEVICE_SELECT`, or chose a device through the layer (`MESA_VK_DEVICE_SELECT`,
    /// `DRI_PRIME`), and nothing outside Linux and the BSDs.
    ///
    /// It runs once per process: [`Self::instance_descriptor`] calls it before every
    /// instance lumagraph creates; a program calls it at its start, before it starts threads
    /// (`lumagraph::cli::main_with` does, and the Python module when it is imported), so the
    /// variable is set before anything else can read it.
    pub fn quiet_device_select() {
        static ONCE: std::sync::Once = std::sync::Once::new();
        ONCE.call_once(|| {
            if !cfg!(all(
                unix,
                not(any(
                    target_os = "macos",
                    target_os = "ios",
                    target_os = "android"
                ))
            )) {
                return;
            }
            let runtime_dir = std::env::var_os("XDG_RUNTIME_DIR")
                .is_some_and(|d| std::path::Path::new(&d).is_absolute());
            let chosen = ["NODEVICE_SELECT", "MESA_VK_DEVICE_SELECT", "DRI_PRIME"]
                .iter()
                .any(|v| std::env::var_os(v).is_some());
            if runtime_dir || chosen {
                return;
            }
            // SAFETY: setting a variable races with another thread reading the environment
            // at the same moment. Rust code reads it under std's environment lock, which
            // `set_var` takes too; the race left is with C code calling `getenv`. This runs
            // once, before lumagraph's first instance (so before the Vulkan loader and the
            // driver's threads exist), and the programs call it first thing: the command
            // line before it starts a thread, the Python module at import under the GIL
            // (where `os.environ[...] = ...` would set it just the same). A program that
            // opens a context while threads of its own read the environment from C, on a
            // machine without XDG_RUNTIME_DIR, can set NODEVICE_SELECT itself; this then
            // changes nothing.
            #[expect(unsafe_code, reason = "set_var once, before the first Vulkan instance")]
            unsafe {
                std::env::set_var("NODEVICE_SELECT", "1");
            }
        });
    }

    /// Opens a device on `adapter` with the features lumagraph uses where available.
    ///
    /// # Errors
    /// When the device cannot be opened.
    pub async fn from_adapter(adapter: wgpu::Adapter) -> Result<Self> {
        let info = adapter.get_info();
        let (device, queue) = adapter
            .request_device(&Self::device_descriptor(&adapter, "lumagraph"))
            .await
            .map_err(|e| RenderError::Device {
                adapter: info.name.clone(),
                message: e.to_string(),
            })?;
        Ok(Self::from_parts(adapter, device, queue))
    }

    /// The device lumagraph asks `adapter` for: the features of
    /// [`Self::optional_features`] it has, and its own limits.
    pub fn device_descriptor(
        adapter: &wgpu::Adapter,
        label: &'static str,
    ) -> wgpu::DeviceDescriptor<'static> {
        let features = adapter.features() & Self::optional_features();
        #[expect(unsafe_code, reason = "wgpu's token for experimental features")]
        let experimental_features = if features.contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY) {
            // SAFETY: wgpu marks ray queries experimental (its API may change, and bugs in
            // it may be undefined behaviour). lumagraph uses them only through
            // `lumagraph_pathtrace::accel` and `pathtrace/intersect/ray_query.wgsl`, whose images the tests compare
            // with the WGSL BVH's; `turn_off_ray_queries` leaves them out.
            unsafe { wgpu::ExperimentalFeatures::enabled() }
        } else {
            wgpu::ExperimentalFeatures::disabled()
        };
        wgpu::DeviceDescriptor {
            label: Some(label),
            required_features: features,
            required_limits: Self::limits(adapter),
            experimental_features,
            ..Default::default()
        }
    }

    /// Features lumagraph enables when the adapter has them.
    pub fn optional_features() -> wgpu::Features {
        // Filtering rgba32float images (bilinear taps in blur, bloom, resize and LUT
        // nodes): every desktop GPU and lavapipe have it; a shader that samples needs it.
        let mut f = wgpu::Features::TIMESTAMP_QUERY | wgpu::Features::FLOAT32_FILTERABLE;
        // Ray queries: the path tracer's intersector where the device has them
        // (`lumagraph_pathtrace::accel`), unless LUMAGRAPH_RAY_QUERY=off.
        if !ray_queries_turned_off() {
            f |= wgpu::Features::EXPERIMENTAL_RAY_QUERY;
        }
        f
    }

    /// What the path tracer's choices depend on in this device.
    pub fn traits(&self) -> AdapterTraits {
        AdapterTraits {
            cpu: self.is_cpu(),
            ray_query_limit: self
                .ray_queries()
                .then(|| self.device.limits().max_blas_primitive_count),
        }
    }

    /// Whether the device can trace the path tracer's rays through ray queries
    /// (`wgpu::Features::EXPERIMENTAL_RAY_QUERY`, asked for where the adapter has it).
    pub fn ray_queries(&self) -> bool {
        self.device
            .features()
            .contains(wgpu::Features::EXPERIMENTAL_RAY_QUERY)
    }

    /// Limits lumagraph asks for: the adapter's own (large images, big scene buffers).
    pub fn limits(adapter: &wgpu::Adapter) -> wgpu::Limits {
        adapter.limits()
    }

    /// Wraps a device created elsewhere.
    pub fn from_parts(adapter: wgpu::Adapter, device: wgpu::Device, queue: wgpu::Queue) -> Self {
        let info = adapter.get_info();
        let timestamps = device.features().contains(wgpu::Features::TIMESTAMP_QUERY);
        // wgpu's default handler panics on an error no scope caught; keep it instead, to
        // be returned as an error by the next wait.
        let errors = std::sync::Arc::new(std::sync::Mutex::new(None::<String>));
        let slot = std::sync::Arc::clone(&errors);
        device.on_uncaptured_error(std::sync::Arc::new(move |e: wgpu::Error| {
            let mut first = slot
                .lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner);
            first.get_or_insert_with(|| e.to_string());
        }));
        // A lost device (driver reset, GPU removed, `destroy`) is remembered, to be
        // returned by the next wait as `RenderError::DeviceLost`.
        let lost = std::sync::Arc::new(std::sync::Mutex::new(None::<String>));
        let slot = std::sync::Arc::clone(&lost);
        device.set_device_lost_callback(move |reason, message| {
            let why = match reason {
                wgpu::DeviceLostReason::Destroyed => "destroyed".to_owned(),
                wgpu::DeviceLostReason::Unknown => "lost by the driver".to_owned(),
            };
            let why = if message.is_empty() {
                why
            } else {
                format!("{why}: {message}")
            };
            slot.lock()
                .unwrap_or_else(std::sync::PoisonError::into_inner)
                .get_or_insert(why);
        });
        Self {
            adapter,
            device,
            queue,
            info,
            timestamps,
            errors,
            lost,
            kernels: std::sync::Arc::default(),
        }
    }

    /// Why the device was lost, once it is: nothing more runs on it, and a new context on
    /// the same adapter ([`GpuContext::from_adapter`]) is the way on.
    pub fn lost(&self) -> Option<String> {
        self.lost
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .clone()
    }

    /// `message` (a GPU error) as a [`RenderError`]: [`RenderError::DeviceLost`] when the
    /// device was lost (the error most likely came from that), else [`RenderError::Gpu`].
    pub fn error(&self, message: impl std::fmt::Display) -> RenderError {
        match self.lost() {
            Some(reason) => RenderError::DeviceLost {
                adapter: self.info.name.clone(),
                reason,
            },
            None => RenderError::Gpu(message.to_string()),
        }
    }

    /// A new device on the same adapter, with the same features and limits (after the
    /// device was lost).
    ///
    /// # Errors
    /// When the device cannot be opened.
    pub fn reopen(&self) -> Result<Self> {
        pollster::block_on(Self::from_adapter(self.adapter.clone()))
    }

    /// Takes the first GPU error that no error scope caught since the last call, if any.
    pub fn take_error(&self) -> Option<String> {
        self.errors
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .take()
    }

    /// Checks that `extent` fits the device's largest 2D texture.
    ///
    /// # Errors
    /// [`RenderError::TooLarge`] naming `what`, the size and the limit.
    pub fn check_extent(&self, what: &str, width: u32, height: u32) -> Result<()> {
        let max = self.device.limits().max_texture_dimension_2d;
        if width > max || height > max {
            return Err(RenderError::TooLarge {
                what: format!("{what}: {width}×{height} image"),
                adapter: self.info.name.clone(),
                message: format!(
                    "the largest image this device holds is {max}×{max} pixels (render at most \
                     {max} pixels wide and high)"
                ),
            });
        }
        Ok(())
    }

    /// One line naming the adapter, backend and driver.
    pub fn describe(&self) -> String {
        let i = &self.info;
        let driver = if i.driver_info.is_empty() {
            i.driver.clone()
        } else {
            format!("{} {}", i.driver, i.driver_info)
        };
        format!(
            "{} ({:?}, {:?}, {driver})",
            i.name, i.backend, i.device_type
        )
    }

    /// Whether the adapter is a CPU implementation (lavapipe, llvmpipe, WARP).
    pub fn is_cpu(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// Blocks until all submitted work is done.
    ///
    /// # Errors
    /// When the GPU does not finish within [`GPU_TIMEOUT`] or the device is lost.
    pub fn wait(&self) -> Result<()> {
        let polled = self.device.poll(wgpu::PollType::Wait {
            submission_index: None,
            timeout: Some(GPU_TIMEOUT),
        });
        if let Some(reason) = self.lost() {
            return Err(RenderError::DeviceLost {
                adapter: self.info.name.clone(),
                reason,
            });
        }
        polled.map_err(|e| RenderError::Gpu(e.to_string()))?;
        match self.take_error() {
            Some(e) => Err(RenderError::Gpu(e)),
            None => Ok(()),
        }
    }
}

/// The rule every GPU test follows for the device `made` for it (`ctx` gives its context):
/// with an adapter, use it, but with `CI` set only a CPU one (lavapipe), so a test never
/// runs silently on another device than its references; without one, fail, unless
/// `LUMAGRAPH_ALLOW_NO_GPU=1` is set, then return `None` (the test returns early) and say so.
///
/// # Panics
/// When there is no adapter and skipping is not allowed, or `CI` is set and the adapter is
/// not a CPU one.
pub fn for_tests<T, E: std::fmt::Display>(
    made: std::result::Result<T, E>,
    ctx: impl Fn(&T) -> &GpuContext,
) -> Option<T> {
    match made {
        Ok(made) => {
            let c = ctx(&made);
            if std::env::var_os("CI").is_some() {
                assert!(
                    c.is_cpu(),
                    "CI must run GPU tests on a CPU adapter (lavapipe), got {}",
                    c.describe()
                );
            }
            eprintln!("GPU tests on {}", c.describe());
            Some(made)
        }
        Err(e) if std::env::var("LUMAGRAPH_ALLOW_NO_GPU").as_deref() == Ok("1") => {
            eprintln!("skipping GPU test (LUMAGRAPH_ALLOW_NO_GPU=1): {e}");
            None
        }
        Err(e) => {
            panic!("{e}\nGPU tests need an adapter; set LUMAGRAPH_ALLOW_NO_GPU=1 to skip them")
        }
    }
}

/// `bytes` in KiB, MiB or GiB, one decimal.
pub fn human_bytes(bytes: u64) -> String {
    #[expect(clippy::cast_precision_loss, reason = "a figure for people")]
    let b = bytes as f64;
    match bytes {
        0..1024 => format!("{bytes} B"),
        1024..1_048_576 => format!("{:.1} KiB", b / 1024.0),
        1_048_576..1_073_741_824 => format!("{:.1} MiB", b / 1_048_576.0),
        _ => format!("{:.1} GiB", b / 1_073_741_824.0),
    }
}

static RAY_QUERIES_OFF: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Keeps devices opened from now on from enabling ray queries, where the application asks so
/// (the command line, the editor and the Python module do for `LUMAGRAPH_RAY_QUERY=off`:
/// `lumagraph::overrides`); the path tracer then traces through its WGSL BVHs.
pub fn turn_off_ray_queries() {
    RAY_QUERIES_OFF.store(true, std::sync::atomic::Ordering::Relaxed);
}

/// Whether [`turn_off_ray_queries`] was called.
pub fn ray_queries_turned_off() -> bool {
    RAY_QUERIES_OFF.load(std::sync::atomic::Ordering::Relaxed)
}
