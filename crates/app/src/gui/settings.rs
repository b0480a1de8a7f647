//! What the app remembers between runs (eframe storage): the structure configuration and the
//! view options. The scene is not remembered: the app always opens on the default scene or
//! on the file named on the command line.

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
    /// View name (`gridrt_gpu::View::name`).
    pub view: String,
    /// Count at the top of the heatmap colour scale.
    pub heat_max: f32,
    /// Rendered pixels per screen pixel (the software adapter is slow: below 1 keeps it fluid).
    pub render_scale: f32,
    pub show_cost_plot: bool,
    pub show_explainer: bool,
    pub explainer: super::explainer::ExplainerState,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            grid: GridConfig::default(),
            traversal: Traversal::AmanatidesWoo,
            mailbox: true,
            view: "shaded".into(),
            heat_max: 64.0,
            render_scale: 0.5,
            show_cost_plot: false,
            show_explainer: false,
            explainer: Default::default(),
        }
    }
}
