//! The shared GPU context. GPU tests fail when no adapter is found, unless
//! GRIDRT_SKIP_GPU_TESTS=1 is set explicitly (never in CI).

use std::sync::OnceLock;

use gridrt_gpu::GpuContext;

/// The device, or `None` when GPU tests are explicitly skipped.
pub fn gpu() -> Option<&'static GpuContext> {
    if std::env::var("GRIDRT_SKIP_GPU_TESTS").is_ok_and(|v| v == "1") {
        eprintln!("GRIDRT_SKIP_GPU_TESTS=1: skipping a GPU test");
        return None;
    }
    static CTX: OnceLock<GpuContext> = OnceLock::new();
    Some(CTX.get_or_init(|| match GpuContext::new_headless_blocking() {
        Ok(c) => {
            println!("GPU adapter: {}", c.adapter_name());
            c
        }
        Err(e) => panic!("no usable GPU adapter: {e}\n(install mesa-vulkan-drivers for lavapipe, or set GRIDRT_SKIP_GPU_TESTS=1 to skip GPU tests explicitly)"),
    }))
}
