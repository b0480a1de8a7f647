//! The cost-model calibration file: `gridrt experiment cost-constants --save` writes the fitted
//! constants; the command line's auto resolution, `bench` and the experiments read them.

use std::path::PathBuf;

use gridrt_grid::CostModel;
use serde::{Deserialize, Serialize};

/// Fitted constants in nanoseconds per ray, and how well they fit.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Fit {
    pub t_setup: f64,
    pub t_step: f64,
    pub t_inter: f64,
    /// RMS of (predicted − measured) / measured.
    pub rel_rms_error: f64,
    pub r_squared: f64,
    pub points: usize,
}

/// What the calibration file holds.
#[derive(Clone, Debug, Serialize, Deserialize)]
pub struct Calibration {
    pub cpu: Fit,
    pub gpu: Option<Fit>,
    pub machine: String,
    pub date: String,
}

impl Calibration {
    /// Puts the CPU constants into `m`.
    pub fn apply_to(&self, m: &mut CostModel) {
        (m.t_setup, m.t_step, m.t_inter) = (self.cpu.t_setup, self.cpu.t_step, self.cpu.t_inter);
    }

    /// Writes the calibration to [`path`] (creating its folder) and returns where.
    pub fn save(&self) -> anyhow::Result<PathBuf> {
        let path = path().ok_or_else(|| anyhow::anyhow!("no HOME or XDG_CONFIG_HOME for the calibration file"))?;
        if let Some(parent) = path.parent() {
            std::fs::create_dir_all(parent)?;
        }
        std::fs::write(&path, serde_json::to_string_pretty(self)?)?;
        Ok(path)
    }
}

/// Where `--save` writes the calibration and where the command line looks for it:
/// `$GRIDRT_CALIBRATION`, else `$XDG_CONFIG_HOME/gridrt/cost-constants.json`, else
/// `~/.config/gridrt/cost-constants.json`.
pub fn path() -> Option<PathBuf> {
    if let Some(p) = std::env::var_os("GRIDRT_CALIBRATION") {
        return Some(PathBuf::from(p));
    }
    let base = std::env::var_os("XDG_CONFIG_HOME")
        .map(PathBuf::from)
        .or_else(|| std::env::var_os("HOME").map(|h| PathBuf::from(h).join(".config")))?;
    Some(base.join("gridrt/cost-constants.json"))
}

/// The cost model the command line's auto resolution uses: the saved calibration's CPU
/// constants when there is one, else the memory-aware model's; and a note saying which.
pub fn active_cost_model() -> (CostModel, String) {
    let mut m = CostModel::memory_aware();
    let w = m.memory_weight;
    match load() {
        Some((path, c)) => {
            c.apply_to(&mut m);
            (m, format!("calibrated constants from {} and memory weight {w}", path.display()))
        }
        None => (
            m,
            format!(
                "the memory-aware constants (Tsetup {}, Tstep {}, Tinter {}) and memory weight {w}",
                m.t_setup, m.t_step, m.t_inter
            ),
        ),
    }
}

/// The saved calibration, if the file exists and is valid.
pub fn load() -> Option<(PathBuf, Calibration)> {
    let path = path()?;
    let text = std::fs::read_to_string(&path).ok()?;
    match serde_json::from_str::<Calibration>(&text) {
        Ok(c) if c.cpu.t_step > 0.0 && c.cpu.t_inter > 0.0 && c.cpu.t_setup >= 0.0 => Some((path, c)),
        _ => {
            log::warn!("ignoring {}: not a valid gridrt calibration", path.display());
            None
        }
    }
}
