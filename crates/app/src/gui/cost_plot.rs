//! The cost-model window: the predicted T(m) = Tsetup + m·Tstep + μ·Tinter over the resolutions
//! guess-and-check sampled (survey §3.3), the chosen m marked, and, on demand, the measured GPU
//! frame time of a flat grid at each sampled resolution for comparison.

use eframe::egui;
use egui_plot::{Legend, Line, Plot, Points, VLine};
use gridrt_grid::resolution::CostSample;

/// The on-demand measurement: one flat grid per sampled resolution, built off the UI thread,
/// each rendered once with the current view and timed.
#[derive(Debug, Default)]
pub struct Measurement {
    /// Resolutions still to measure (front first).
    pub pending: Vec<[u32; 3]>,
    /// (m, frame ms) measured so far.
    pub results: Vec<(f64, f64)>,
    /// Samples in the whole run (progress).
    pub total: usize,
}

impl Measurement {
    pub fn running(&self) -> bool {
        !self.pending.is_empty()
    }
}

/// What the window shows.
#[derive(Debug)]
pub struct CostView<'a> {
    pub curve: Option<&'a [CostSample]>,
    pub chosen: Option<[u32; 3]>,
    pub policy: String,
    pub measurement: &'a Measurement,
}

/// The window body; returns true when the user asks for a measurement.
pub fn ui(ui: &mut egui::Ui, v: &CostView) -> bool {
    let Some(curve) = v.curve.filter(|c| !c.is_empty()) else {
        ui.label(format!(
            "The resolution of this structure was not chosen by the cost model (policy: {}). \
             Choose \"auto\" resolution on a flat or macrocell grid to see the sampled T(m).",
            v.policy
        ));
        return false;
    };
    let chosen_m = v.chosen.map(|r| (r[0] as f64 * r[1] as f64 * r[2] as f64).cbrt());
    ui.label(
        "T(m) = Tsetup + m·Tstep + μ·Tinter, m = cbrt(cells), μ = N_m / m² (survey §3.2); guess-and-check samples m \
         over [(2rN)^(1/3), (rN)^(1/2)] and keeps the cheapest.",
    );
    let link = egui::Id::unique("cost plot x");
    let h = if v.measurement.results.is_empty() {
        ui.available_height() - 40.0
    } else {
        (ui.available_height() - 40.0) / 2.0
    };
    let pts: Vec<[f64; 2]> = curve.iter().map(|s| [s.m, s.cost]).collect();
    curve_plot(ui, "predicted T(m)", "samples", "predicted T(m)", pts, chosen_m, link, h);
    if !v.measurement.results.is_empty() {
        let mut pts: Vec<[f64; 2]> = v.measurement.results.iter().map(|&(m, ms)| [m, ms]).collect();
        pts.sort_by(|a, b| a[0].total_cmp(&b[0]));
        curve_plot(ui, "measured frame ms", "measured", "frame ms (flat grid, GPU)", pts, chosen_m, link, h);
    }
    let mut start = false;
    ui.horizontal(|ui| {
        if v.measurement.running() {
            ui.spinner();
            let done = v.measurement.total - v.measurement.pending.len();
            ui.add(
                egui::ProgressBar::new(done as f32 / v.measurement.total.max(1) as f32)
                    .text(format!("measuring {done} / {}", v.measurement.total)),
            );
        } else {
            start = ui
                .button("Measure frame time at these m")
                .on_hover_text(
                    "Builds a flat grid at each sampled resolution and times one GPU frame of the current view.",
                )
                .clicked();
            if let Some(best) = v.measurement.results.iter().min_by(|a, b| a.1.total_cmp(&b.1)) {
                ui.label(format!("fastest measured: m = {:.1} ({:.1} ms)", best.0, best.1));
            }
        }
    });
    start
}

/// One curve over m (a line through its points) with the chosen m marked; the plots of the
/// window share their x axis.
#[allow(clippy::too_many_arguments)]
fn curve_plot(
    ui: &mut egui::Ui,
    line: &str,
    points: &str,
    y_label: &str,
    pts: Vec<[f64; 2]>,
    chosen_m: Option<f64>,
    link: egui::Id,
    height: f32,
) {
    Plot::new(line)
        .legend(Legend::default())
        .height(height.max(120.0))
        .x_axis_label("m = cbrt(cells)")
        .y_axis_label(y_label)
        .link_axis(link, [true, false])
        .show(ui, |p| {
            p.line(Line::new(line, pts.clone()));
            p.points(Points::new(points, pts).radius(3.0));
            if let Some(m) = chosen_m {
                p.vline(VLine::new(format!("chosen m = {m:.1}"), m));
            }
        });
}
