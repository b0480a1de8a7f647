//! What benchmarks and experiments share: their scenes, timed measurements (sweeps, best-of
//! timing, the machine's description) and reports (tables, CSV/JSON rows, charts). In the
//! browser only [`views`] is built (the app aims its camera with it).

#[cfg(not(target_arch = "wasm32"))]
pub mod animation;
#[cfg(not(target_arch = "wasm32"))]
pub mod frame;
#[cfg(not(target_arch = "wasm32"))]
pub mod report;
#[cfg(not(target_arch = "wasm32"))]
pub mod scenes;
#[cfg(not(target_arch = "wasm32"))]
pub mod sweep;
pub mod views;
