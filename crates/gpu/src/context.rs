//! Headless device creation and the limits a scene needs.
//!
//! The adapter is chosen the way wgpu's `initialize_adapter_from_env_or_default` does
//! (`WGPU_ADAPTER_NAME` picks by name, `WGPU_POWER_PREF` the preference) but never panics: a
//! name that matches nothing is an error listing the adapters found. Without a hardware
//! adapter the software/fallback one (lavapipe's "llvmpipe" on Linux) is accepted, and its
//! name is always reported.
//!
//! Limits: the device asks for the adapter's own storage-buffer binding and buffer sizes
//! (scenes are big) but keeps WebGPU's default of 8 storage buffers per stage, so the same
//! shaders run in a browser. A scene whose buffers exceed the limits gets
//! [`GpuError::BufferTooLarge`] naming the buffer, never a device loss.
//!
//! Errors the device reports outside an error scope (validation, out of memory) are collected
//! rather than left to wgpu's default handler, which panics: [`GpuContext::check_device`] turns
//! them into [`GpuError::Device`], and the app shows them.

use std::sync::{Arc, Mutex};

use thiserror::Error;

#[derive(Debug, Error)]
pub enum GpuError {
    #[error(
        "no GPU adapter found (backends {backends:?}); on Linux install mesa-vulkan-drivers for the lavapipe software adapter"
    )]
    NoAdapter { backends: wgpu::Backends },
    #[error("WGPU_ADAPTER_NAME=\"{wanted}\" matches no adapter; found: {found:?}")]
    AdapterNotFound { wanted: String, found: Vec<String> },
    #[error("the adapter \"{adapter}\" cannot run compute shaders")]
    NoCompute { adapter: String },
    #[error("requesting a device from \"{adapter}\": {source}")]
    RequestDevice {
        adapter: String,
        #[source]
        source: wgpu::RequestDeviceError,
    },
    #[error(
        "{buffer} needs {size} bytes, more than this device's limit of {limit} bytes ({which}); use a smaller scene or resolution"
    )]
    BufferTooLarge { buffer: &'static str, size: u64, limit: u64, which: &'static str },
    #[error("reading back {what} failed: {detail}")]
    Readback { what: &'static str, detail: String },
    #[error("shader {0}")]
    Shader(#[from] crate::shaders::ComposeError),
    #[error("{0}")]
    Unsupported(String),
    #[error("the GPU device reported: {0}")]
    Device(String),
    #[error(transparent)]
    Build(#[from] gridrt_grid::BuildError),
}

/// A device and queue with what is known about them.
#[derive(Debug, Clone)]
pub struct GpuContext {
    pub adapter: wgpu::Adapter,
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    /// Uncaptured device errors since the last [`GpuContext::check_device`].
    device_errors: Arc<Mutex<Vec<String>>>,
}

/// Routes `device`'s uncaptured errors into a list instead of wgpu's panicking default.
fn collect_device_errors(device: &wgpu::Device) -> Arc<Mutex<Vec<String>>> {
    let errors = Arc::new(Mutex::new(Vec::new()));
    let sink = errors.clone();
    device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
        if let Ok(mut v) = sink.lock() {
            // Each error in the chain on one line ("Validation Error" alone names no cause); the
            // first line of each names the failed call, the rest repeats the labels.
            let mut parts = vec![first_line(&e.to_string())];
            let mut cause = std::error::Error::source(&e);
            while let Some(c) = cause {
                parts.push(first_line(&c.to_string()));
                cause = c.source();
            }
            parts.dedup();
            v.push(parts.join(": "));
        }
    }));
    errors
}

fn first_line(s: &str) -> String {
    s.lines().next().unwrap_or("unknown error").trim().to_string()
}

/// The features gridrt asks for, of those `adapter` offers: f64 in shaders, for hits bit-identical
/// to the CPU's ([`crate::shaders::HitFloat`]; WebGPU offers none).
pub fn required_features(adapter: wgpu::Features) -> wgpu::Features {
    adapter & wgpu::Features::SHADER_F64
}

/// The limits gridrt asks for, within what `adapter` offers.
pub fn required_limits(adapter: &wgpu::Limits) -> wgpu::Limits {
    let mut l = wgpu::Limits::downlevel_defaults().using_resolution(adapter.clone());
    l.max_storage_buffer_binding_size = adapter.max_storage_buffer_binding_size;
    l.max_buffer_size = adapter.max_buffer_size;
    l.max_storage_buffers_per_shader_stage = adapter.max_storage_buffers_per_shader_stage.min(8);
    l.max_compute_workgroups_per_dimension = adapter.max_compute_workgroups_per_dimension;
    l.max_compute_invocations_per_workgroup = adapter.max_compute_invocations_per_workgroup.min(256);
    l.max_compute_workgroup_size_x = adapter.max_compute_workgroup_size_x.min(256);
    l
}

impl GpuContext {
    /// Waits until the queue is idle: natively; in a browser the passes just queue (a time
    /// taken after it measures their submission).
    pub fn wait_idle(&self, what: &str) -> Result<(), GpuError> {
        #[cfg(target_arch = "wasm32")]
        {
            let _ = what;
            Ok(())
        }
        #[cfg(not(target_arch = "wasm32"))]
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map(|_| ())
            .map_err(|e| GpuError::Device(format!("waiting for {what}: {e}")))
    }

    /// Creates a headless device on the adapter chosen from the environment (module doc).
    pub async fn new_headless() -> Result<GpuContext, GpuError> {
        let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle().with_env());
        let adapter = choose_adapter(&instance).await?;
        GpuContext::from_adapter(adapter).await
    }

    /// Blocking [`GpuContext::new_headless`] (native only).
    #[cfg(not(target_arch = "wasm32"))]
    pub fn new_headless_blocking() -> Result<GpuContext, GpuError> {
        pollster::block_on(GpuContext::new_headless())
    }

    /// Creates the device on a given adapter (the app passes the one its window uses).
    pub async fn from_adapter(adapter: wgpu::Adapter) -> Result<GpuContext, GpuError> {
        let info = adapter.get_info();
        if !adapter.get_downlevel_capabilities().flags.contains(wgpu::DownlevelFlags::COMPUTE_SHADERS) {
            return Err(GpuError::NoCompute { adapter: info.name });
        }
        let desc = wgpu::DeviceDescriptor {
            label: Some("gridrt device"),
            required_features: required_features(adapter.features()),
            required_limits: required_limits(&adapter.limits()),
            ..Default::default()
        };
        let (device, queue) = adapter
            .request_device(&desc)
            .await
            .map_err(|source| GpuError::RequestDevice { adapter: info.name.clone(), source })?;
        let device_errors = collect_device_errors(&device);
        Ok(GpuContext { adapter, device, queue, info, device_errors })
    }

    /// Wraps a device created elsewhere (eframe's), sharing it.
    pub fn from_parts(adapter: wgpu::Adapter, device: wgpu::Device, queue: wgpu::Queue) -> GpuContext {
        let info = adapter.get_info();
        let device_errors = collect_device_errors(&device);
        GpuContext { adapter, device, queue, info, device_errors }
    }

    /// Whether the adapter is a software one running on the CPU's cores (lavapipe,
    /// SwiftShader, WARP), which traces slower than the kernels' CPU ports.
    pub fn is_software(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// The adapter with its driver and version, as every benchmark names it:
    /// "llvmpipe (LLVM 15.0.6, 256 bits), Mesa 25.0.7 (LLVM 15.0.6) (Vulkan, Cpu)".
    pub fn adapter_name(&self) -> String {
        // Browsers do not name WebGPU adapters (privacy); show what they do tell.
        let name = [&self.info.name, &self.info.driver, &self.info.driver_info]
            .into_iter()
            .find(|s| !s.is_empty())
            .map_or("unnamed adapter", |s| s.as_str());
        let driver = &self.info.driver_info;
        let driver =
            if driver.is_empty() || name.contains(driver.as_str()) { String::new() } else { format!(", {driver}") };
        format!("{name}{driver} ({:?}, {:?})", self.info.backend, self.info.device_type)
    }

    /// The device errors reported since the last call, as one [`GpuError::Device`].
    pub fn check_device(&self) -> Result<(), GpuError> {
        let errors = std::mem::take(
            &mut *self.device_errors.lock().map_err(|_| GpuError::Device("error list poisoned".into()))?,
        );
        match errors.len() {
            0 => Ok(()),
            1 => Err(GpuError::Device(errors[0].clone())),
            k => Err(GpuError::Device(format!("{} (and {} more)", errors[0], k - 1))),
        }
    }

    /// Checks one buffer against the device limits.
    pub fn check_buffer(&self, buffer: &'static str, size: u64, storage_binding: bool) -> Result<(), GpuError> {
        let l = self.device.limits();
        if size > l.max_buffer_size {
            return Err(GpuError::BufferTooLarge { buffer, size, limit: l.max_buffer_size, which: "max_buffer_size" });
        }
        if storage_binding && size > l.max_storage_buffer_binding_size {
            return Err(GpuError::BufferTooLarge {
                buffer,
                size,
                limit: l.max_storage_buffer_binding_size,
                which: "max_storage_buffer_binding_size",
            });
        }
        Ok(())
    }
}

async fn choose_adapter(instance: &wgpu::Instance) -> Result<wgpu::Adapter, GpuError> {
    if let Ok(wanted) = std::env::var("WGPU_ADAPTER_NAME") {
        let wanted_lc = wanted.to_lowercase();
        let adapters = instance.enumerate_adapters(wgpu::Backends::all()).await;
        let found: Vec<String> = adapters.iter().map(|a| a.get_info().name).collect();
        return adapters
            .into_iter()
            .find(|a| a.get_info().name.to_lowercase().contains(&wanted_lc))
            .ok_or(GpuError::AdapterNotFound { wanted, found });
    }
    let power_preference = wgpu::PowerPreference::from_env().unwrap_or_default();
    let opts = wgpu::RequestAdapterOptions { power_preference, ..Default::default() };
    if let Ok(a) = instance.request_adapter(&opts).await {
        return Ok(a);
    }
    let fallback = wgpu::RequestAdapterOptions { force_fallback_adapter: true, ..opts };
    instance.request_adapter(&fallback).await.map_err(|_| GpuError::NoAdapter { backends: wgpu::Backends::all() })
}
