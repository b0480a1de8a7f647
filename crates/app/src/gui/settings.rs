//! What the app remembers between runs (eframe storage): the structure configuration and the
//! view options. The scene is not remembered: the app always opens on the default scene or
//! on the file named on the command line.

use gridrt_gpu::View;
use gridrt_grid::{GridConfig, Traversal};
use serde::{Deserialize, Serialize};

/// Key of the settings in eframe's storage.
pub const STORAGE_KEY: &str = "gridrt-settings";

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct Settings {
    /// Grid kind, resolution policy, insertion, structure options, cost constants.
    pub grid: GridConfig,
    pub traversal: Traversal,
    pub mailbox: bool,
    /// Primary and shadow rays in 8×8 coherent packets (flat and macrocell grids).
    pub packets: bool,
    /// What the image shows (stored by name, e.g. "heatmap-cells").
    pub view: View,
    /// Count at the top of the heatmap colour scale.
    pub heat_max: f32,
    /// Rendered pixels per screen pixel (the software adapter is slow: below 1 keeps it fluid).
    pub render_scale: f32,
    /// Build flat and macrocell grids (box or exact insertion) on the GPU (the native app; the result is
    /// the CPU build's, bit for bit).
    pub gpu_build: bool,
    /// Where the frames are traced (native app; the browser always traces on the GPU).
    pub trace_on: TraceOn,
    pub show_cost_plot: bool,
    pub show_explainer: bool,
    pub explainer: super::explainer::ExplainerState,
}

/// Where the app traces its frames: the render kernels on the GPU, or their CPU ports on
/// every core (the same image, pixel for pixel).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize, clap::ValueEnum)]
#[serde(rename_all = "kebab-case")]
pub enum TraceOn {
    /// The CPU when the adapter is a software one (lavapipe, SwiftShader, WARP: it runs the
    /// kernels on the same cores, slower than the CPU ports), the GPU otherwise.
    #[default]
    Auto,
    /// The render kernels on the GPU (compute shaders; packets where the settings ask).
    Gpu,
    /// The kernels' CPU ports on every core.
    Cpu,
}

impl TraceOn {
    pub fn name(self) -> &'static str {
        match self {
            TraceOn::Auto => "auto",
            TraceOn::Gpu => "GPU",
            TraceOn::Cpu => "CPU",
        }
    }
}

impl Settings {
    /// Whether the CPU traces the frames when the adapter is (`software_adapter`) or is not a
    /// software one. Only natively: the browser always traces on the GPU.
    pub fn cpu_traces(&self, software_adapter: bool) -> bool {
        cfg!(not(target_arch = "wasm32"))
            && match self.trace_on {
                TraceOn::Auto => software_adapter,
                TraceOn::Gpu => false,
                TraceOn::Cpu => true,
            }
    }
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            grid: GridConfig::default(),
            traversal: Traversal::AmanatidesWoo,
            mailbox: true,
            // Natively on: the CPU's packets are faster than its single rays, and on a software
            // adapter (where the GPU's packet kernels are slower than its single rays) the CPU
            // traces by default. Off in the browser, which traces on the GPU (README, "Coherent
            // grid traversal").
            packets: cfg!(not(target_arch = "wasm32")),
            view: View::Shaded,
            heat_max: 64.0,
            render_scale: 0.5,
            gpu_build: false,
            trace_on: TraceOn::Auto,
            show_cost_plot: false,
            show_explainer: false,
            explainer: Default::default(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use gridrt_grid::{GridKind, Resolution};

    #[test]
    fn settings_survive_a_round_trip_and_old_files_fill_in_defaults() {
        let mut s = Settings::default();
        s.grid.kind = GridKind::Multires;
        s.grid.resolution = Some(Resolution::Cubic(40));
        s.traversal = Traversal::Liu;
        s.view = View::HeatmapTests;
        s.explainer.nx = 20;
        let text = serde_json::to_string(&s).unwrap();
        let back: Settings = serde_json::from_str(&text).unwrap();
        assert_eq!(back, s);
        // A file from an older version, with fields missing, still loads.
        let old: Settings = serde_json::from_str(r#"{"mailbox": false, "render_scale": 0.25}"#).unwrap();
        assert_eq!(old, Settings { mailbox: false, render_scale: 0.25, ..Settings::default() });
        // Before `trace_on` there was a `cpu_trace` switch: such a file loads, with auto.
        let old: Settings = serde_json::from_str(r#"{"cpu_trace": true, "packets": false}"#).unwrap();
        assert_eq!(old, Settings { packets: false, ..Settings::default() });
        let cpu: Settings = serde_json::from_str(r#"{"trace_on": "cpu"}"#).unwrap();
        assert!(cpu.cpu_traces(false) == cfg!(not(target_arch = "wasm32")));
        assert!(!Settings::default().cpu_traces(false));
        assert!(Settings::default().cpu_traces(true) == cfg!(not(target_arch = "wasm32")));
    }
}
