//! The scene load limits of this process: set once from the command line (`--max-triangles`,
//! `--max-load-bytes`) and read wherever a scene is loaded — the commands and the app's load
//! jobs — so that a file opened by any route meets the same budget.

use std::sync::OnceLock;

use gridrt_scene::LoadLimits;

static LIMITS: OnceLock<LoadLimits> = OnceLock::new();

/// Sets the limits (the first call wins).
#[cfg_attr(target_arch = "wasm32", allow(dead_code))]
pub fn set(limits: LoadLimits) {
    let _ = LIMITS.set(limits);
}

/// The limits set, else the defaults.
pub fn get() -> LoadLimits {
    LIMITS.get().copied().unwrap_or_default()
}
