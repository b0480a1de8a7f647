//! The side panels: structure and view controls on the left, statistics on the right, and the
//! heatmap colour legend. They only edit [`Settings`] and read results; the app reacts to the
//! changes (rebuild, re-render).

use eframe::egui::{self, Color32, Sense, Vec2};
use gridrt_gpu::View;
use gridrt_grid::cell_plane::CellPlanes;
use gridrt_grid::multires::Policy;
use gridrt_grid::{GridKind, InsertMode, Resolution, Traversal};

use super::built::Built;
use super::settings::Settings;
use super::viewport::FrameStats;
use crate::format::human_bytes;

fn kind_blurb(kind: GridKind) -> &'static str {
    match kind {
        GridKind::Flat => "uniform grid, resolution from the cost model",
        GridKind::Macrocell => "uniform grid plus coarse occupancy cells that skip empty space",
        GridKind::Multires => "cells that hold many triangles get their own sub-grid",
        GridKind::TwoLevel => "Kalojanov's two-level grid: a leaf grid in each top cell where it pays",
        GridKind::Proximity => "empty cells store the distance to the nearest full cell; rays jump",
    }
}

#[derive(Clone, Copy, PartialEq, Eq)]
enum ResChoice {
    KindDefault,
    Auto,
    Manual,
    Density,
    Point,
    Line,
}

fn res_choice(r: Option<Resolution>) -> ResChoice {
    match r {
        None => ResChoice::KindDefault,
        Some(Resolution::Auto) => ResChoice::Auto,
        Some(Resolution::Cubic(_) | Resolution::Explicit(_)) => ResChoice::Manual,
        Some(Resolution::Density(_)) => ResChoice::Density,
        Some(Resolution::Point) => ResChoice::Point,
        Some(Resolution::Line) => ResChoice::Line,
    }
}

/// Structure, traversal and view controls. `built` gives the live numbers next to them.
/// `off_gpu`: natively, why the CPU traces whatever the settings say (the device cannot hold
/// the scene or the structure); `software_adapter`: what "auto" picks for the trace.
pub fn controls(
    ui: &mut egui::Ui,
    s: &mut Settings,
    built: Option<&Built>,
    off_gpu: Option<&str>,
    software_adapter: bool,
) {
    #[cfg(target_arch = "wasm32")]
    let _ = software_adapter;
    ui.heading("Structure");
    let g = &mut s.grid;
    egui::ComboBox::from_label("grid").selected_text(g.kind.name()).show_ui(ui, |ui| {
        for k in GridKind::ALL {
            ui.selectable_value(&mut g.kind, k, k.name()).on_hover_text(kind_blurb(k));
        }
    });
    ui.small(kind_blurb(g.kind));

    let choice = res_choice(g.resolution);
    let names = |c: ResChoice| match c {
        ResChoice::KindDefault => "default for the kind",
        ResChoice::Auto => "auto (cost model)",
        ResChoice::Manual => "manual m",
        ResChoice::Density => "density λ",
        ResChoice::Point => "point model (eq. 1)",
        ResChoice::Line => "line model (eq. 2)",
    };
    let mut new_choice = choice;
    egui::ComboBox::from_label("resolution").selected_text(names(choice)).show_ui(ui, |ui| {
        for c in [
            ResChoice::KindDefault,
            ResChoice::Auto,
            ResChoice::Manual,
            ResChoice::Density,
            ResChoice::Point,
            ResChoice::Line,
        ] {
            ui.selectable_value(&mut new_choice, c, names(c));
        }
    });
    if new_choice != choice {
        let current_m = built.map_or(64, |b| b.report.stats.resolution.into_iter().max().unwrap_or(64));
        g.resolution = match new_choice {
            ResChoice::KindDefault => None,
            ResChoice::Auto => Some(Resolution::Auto),
            ResChoice::Manual => Some(Resolution::Cubic(current_m.clamp(1, 512))),
            ResChoice::Density => Some(Resolution::Density(1.0)),
            ResChoice::Point => Some(Resolution::Point),
            ResChoice::Line => Some(Resolution::Line),
        };
    }
    match &mut g.resolution {
        Some(Resolution::Cubic(m)) => {
            ui.add(egui::Slider::new(m, 1..=512).logarithmic(true).text("m (cells on the long axis)"));
        }
        Some(Resolution::Explicit(r)) => {
            ui.label(format!("{}×{}×{}", r[0], r[1], r[2]));
        }
        Some(Resolution::Density(l)) => {
            ui.add(egui::Slider::new(l, 0.01..=16.0).logarithmic(true).text("cells per triangle"));
        }
        _ => {}
    }
    if let Some(b) = built {
        let st = &b.report.stats;
        ui.small(format!(
            "{}×{}×{}: {} cells, {} refs, {}",
            st.resolution[0],
            st.resolution[1],
            st.resolution[2],
            st.cells,
            st.refs,
            human_bytes(st.memory_bytes)
        ));
    }
    ui.horizontal(|ui| {
        ui.radio_value(&mut g.build.insert, InsertMode::BoundingBox, "box insertion");
        ui.radio_value(&mut g.build.insert, InsertMode::Exact, "exact (SAT)");
    });
    ui.checkbox(&mut g.build.parallel, "parallel build");
    if matches!(g.kind, GridKind::Flat | GridKind::Macrocell) {
        ui.horizontal(|ui| {
            for (v, label) in [(CellPlanes::Auto, "auto"), (CellPlanes::On, "on"), (CellPlanes::Off, "off")] {
                ui.radio_value(&mut g.cell_planes, v, label);
            }
            ui.label("cell slabs").on_hover_text(
                "A slab per occupied cell that holds its triangles: a CPU ray whose segment in \
                 the cell misses it skips the cell's tests (the same hits). Auto: macrocell and \
                 exact-insertion flat grids of scanned or CAD meshes, built only while the CPU traces \
                 (the GPU never reads them).",
            );
        });
    }
    let buildable = gridrt_gpu::build::GridBuilder::supports(g);
    ui.add_enabled(off_gpu.is_none(), egui::Checkbox::new(&mut s.gpu_build, "build on the GPU")).on_hover_text(
        "Flat and macrocell grids (box or exact insertion) are built by WGSL kernels on this \
         device (bit-identical to the CPU build); other structures are built on the CPU.",
    );
    if s.gpu_build && !buildable {
        ui.small(format!("{}: built on the CPU", g.kind));
    }
    match g.kind {
        GridKind::Macrocell => {
            let label = g.macro_size.map_or("auto (cost model)".to_string(), |a| a.to_string());
            egui::ComboBox::from_label("macrocell edge A").selected_text(label).show_ui(ui, |ui| {
                ui.selectable_value(&mut g.macro_size, None, "auto (cost model)");
                for a in [2, 4, 8, 16] {
                    ui.selectable_value(&mut g.macro_size, Some(a), a.to_string());
                }
            });
        }
        GridKind::Multires => {
            let m = &mut g.multires;
            let name = |p: &Policy| match p {
                Policy::Adaptive => "adaptive (cost)",
                Policy::Octree => "octree (2x2x2)",
                Policy::Constant(_) => "constant k x k x k",
                Policy::MaxDepth { .. } => "max depth",
            };
            egui::ComboBox::from_label("sub-grid policy").selected_text(name(&m.policy)).show_ui(ui, |ui| {
                for p in [Policy::Adaptive, Policy::Octree, Policy::Constant(4), Policy::MaxDepth { leaf_size: 8 }] {
                    let same = std::mem::discriminant(&p) == std::mem::discriminant(&m.policy);
                    if ui.selectable_label(same, name(&p)).clicked() && !same {
                        m.policy = p;
                    }
                }
            });
            match &mut m.policy {
                Policy::Constant(k) => {
                    ui.add(egui::Slider::new(k, 2..=16).text("k"));
                }
                Policy::MaxDepth { leaf_size } => {
                    ui.add(egui::Slider::new(leaf_size, 1..=64).text("leaf size"));
                }
                _ => {}
            }
            ui.add(egui::Slider::new(&mut m.max_depth, 1..=7).text("max depth"));
            ui.add(egui::Slider::new(&mut m.density, 0.05..=8.0).logarithmic(true).text("sub-grid density"));
        }
        GridKind::TwoLevel => {
            let t = &mut g.twolevel;
            ui.add(
                egui::Slider::new(&mut t.top_density, 0.005..=2.0)
                    .logarithmic(true)
                    .text("lambda1 (top cells per triangle)"),
            );
            ui.add(
                egui::Slider::new(&mut t.leaf_density, 0.1..=8.0)
                    .logarithmic(true)
                    .text("lambda2 (leaf cells per triangle)"),
            );
            ui.checkbox(&mut t.every_cell, "a leaf grid under every top cell (no cost test)");
        }
        _ => {}
    }
    egui::CollapsingHeader::new("cost model constants").show(ui, |ui| {
        let c = &mut g.cost;
        ui.add(egui::Slider::new(&mut c.t_setup, 0.0..=10.0).text("Tsetup"));
        ui.add(egui::Slider::new(&mut c.t_step, 0.01..=10.0).logarithmic(true).text("Tstep"));
        ui.add(egui::Slider::new(&mut c.t_inter, 0.01..=10.0).logarithmic(true).text("Tinter"));
        ui.add(egui::Slider::new(&mut c.samples, 2..=64).text("samples"));
        ui.add(egui::Slider::new(&mut c.memory_weight, 0.0..=10.0).text("memory weight (steps per byte per triangle)"));
        let mut cache_kib = c.cache_bytes / 1024.0;
        ui.add(egui::Slider::new(&mut cache_kib, 0.0..=65536.0).logarithmic(true).text("cache (KiB)"));
        c.cache_bytes = cache_kib * 1024.0;
        let mut dram_mib = c.dram_bytes / (1024.0 * 1024.0);
        ui.add(egui::Slider::new(&mut dram_mib, 0.0..=4096.0).logarithmic(true).text("DRAM tier from (MiB)"));
        c.dram_bytes = dram_mib * 1024.0 * 1024.0;
        ui.add(egui::Slider::new(&mut c.dram_weight, 0.0..=32.0).text("DRAM weight"));
        ui.add(egui::Slider::new(&mut c.tie_tolerance, 0.0..=0.2).text("tie tolerance (toward coarser)"));
        ui.horizontal(|ui| {
            if ui.button("survey defaults").clicked() {
                *c = Default::default();
            }
            if ui.button("memory-aware defaults").clicked() {
                *c = gridrt_grid::CostModel::memory_aware();
            }
        });
    });
    g.multires.cost = g.cost;

    ui.separator();
    ui.heading("Traversal");
    egui::ComboBox::from_label("walker").selected_text(s.traversal.short_name()).show_ui(ui, |ui| {
        for (t, name) in [
            (Traversal::AmanatidesWoo, "aw: Amanatides–Woo"),
            (Traversal::ClearyWyvill, "cw: Cleary–Wyvill"),
            (Traversal::Liu, "liu: Liu integer one-pass"),
        ] {
            ui.selectable_value(&mut s.traversal, t, name);
        }
    });
    ui.small("Naive Bresenham misses cells: see the traversal explainer.");
    ui.checkbox(&mut s.mailbox, "mailboxing");
    ui.checkbox(&mut s.packets, "coherent packets (8×8)")
        .on_hover_text("Primary and shadow rays traced in 8×8 packets that walk the grid slice by slice (on the GPU: flat and macrocell grids, the others single rays; on the CPU: every grid, a hierarchy's child grids layer by layer)");
    #[cfg(not(target_arch = "wasm32"))]
    {
        use super::settings::TraceOn;
        let auto = if software_adapter { "auto (CPU: software adapter)" } else { "auto (GPU)" };
        let label = |t: TraceOn| if t == TraceOn::Auto { auto.to_string() } else { t.name().to_string() };
        ui.add_enabled_ui(off_gpu.is_none(), |ui| {
            egui::ComboBox::from_label("trace on")
                .selected_text(if off_gpu.is_some() { "CPU".to_string() } else { label(s.trace_on) })
                .show_ui(ui, |ui| {
                    for &t in <TraceOn as clap::ValueEnum>::value_variants() {
                        ui.selectable_value(&mut s.trace_on, t, label(t));
                    }
                })
                .response
                .on_hover_text(
                    "Where the frames are traced (`--trace-on`): the render kernels on the GPU, or their \
                     CPU ports on every core; the same image. Auto takes the CPU when the adapter is a \
                     software one, which runs the kernels on the same cores, slower. Packets are faster \
                     than single rays on the CPU.",
                );
        });
        if let Some(why) = off_gpu {
            ui.small(why);
        }
    }

    ui.separator();
    ui.heading("View");
    egui::ComboBox::from_label("view").selected_text(s.view.name()).show_ui(ui, |ui| {
        for v in View::ALL {
            ui.selectable_value(&mut s.view, v, v.name());
        }
    });
    if s.view.is_heatmap() {
        ui.add(egui::Slider::new(&mut s.heat_max, 1.0..=4096.0).logarithmic(true).text("scale top"));
        legend(ui, s.heat_max, if s.view == View::HeatmapCells { "cells visited" } else { "triangle tests" });
    }
    ui.add(egui::Slider::new(&mut s.render_scale, 0.1..=1.0).text("render scale"))
        .on_hover_text("Rendered pixels per screen pixel: lower is faster on a software adapter.");
}

/// The heatmap colour scale with its numbers.
pub fn legend(ui: &mut egui::Ui, max: f32, what: &str) {
    let width = ui.available_width().min(240.0);
    let (resp, painter) = ui.allocate_painter(Vec2::new(width, 14.0), Sense::hover());
    let r = resp.rect;
    let steps = 48;
    for i in 0..steps {
        let x0 = r.left() + r.width() * i as f32 / steps as f32;
        let x1 = r.left() + r.width() * (i + 1) as f32 / steps as f32;
        let c = gridrt_gpu::cpu::heat((i as f32 + 0.5) / steps as f32);
        let c = Color32::from_rgb((c.x * 255.0) as u8, (c.y * 255.0) as u8, (c.z * 255.0) as u8);
        painter.rect_filled(egui::Rect::from_min_max(egui::pos2(x0, r.top()), egui::pos2(x1, r.bottom())), 0.0, c);
    }
    ui.horizontal(|ui| {
        ui.small("0");
        ui.add_space((width / 2.0 - 30.0).max(0.0));
        ui.small(format!("{:.0}", max / 2.0));
        ui.add_space((width / 2.0 - 40.0).max(0.0));
        ui.small(format!(">= {max:.0} {what}"));
    });
}

/// Statistics: adapter, scene, structure, build phases, last frame.
pub fn stats(
    ui: &mut egui::Ui,
    adapter: &str,
    scene: Option<&super::jobs::LoadedScene>,
    built: Option<&Built>,
    building: Option<(String, f64)>,
    frame: Option<&FrameStats>,
    off_gpu: Option<&str>,
) {
    ui.add(egui::Label::new(egui::RichText::new(adapter).small()).wrap());
    egui::Grid::new("stats grid").num_columns(2).striped(true).show(ui, |ui| {
        let mut row = |k: &str, v: String| {
            ui.label(k);
            ui.add(egui::Label::new(v).wrap());
            ui.end_row();
        };
        if let Some(sc) = scene {
            let r = &sc.report;
            row("scene", sc.name.clone());
            row("triangles", format!("{} ({} degenerate)", r.triangles, r.degenerate_triangles));
            row("meshes / primitives", format!("{} / {}", r.meshes, r.primitives));
            if !r.skipped_primitives.is_empty() {
                row("skipped", r.skipped_primitives.join("; "));
            }
        }
        if let Some(b) = built {
            let st = &b.report.stats;
            row("structure", b.report.kind.name().to_string());
            row("resolution", format!("{}×{}×{}", st.resolution[0], st.resolution[1], st.resolution[2]));
            row(
                "cells",
                format!("{} ({:.1}% empty)", st.cells, 100.0 * st.empty_cells as f64 / st.cells.max(1) as f64),
            );
            row("refs", format!("{} ({:.2} per triangle)", st.refs, st.refs as f64 / b.report.triangles.max(1) as f64));
            if st.nodes > 1 {
                row("nodes / levels", format!("{} / {}", st.nodes, st.levels));
            }
            if let Some(a) = st.macro_size {
                row("macrocell A", a.to_string());
            }
            row("memory", format!("{} ({:.1} B/tri)", human_bytes(st.memory_bytes), st.memory_bytes_per_triangle));
            row("built on", b.built_on.name().into());
            row("build ms", format!("{:.1}", b.report.times.total()));
            for (phase, ms) in &b.report.times.0 {
                row(&format!("  {phase}"), format!("{ms:.1}"));
            }
        }
        if let Some(f) = frame {
            row("frame", format!("{}×{}", f.width, f.height));
            row("frame ms", format!("{:.1} ({})", f.ms, if f.on_cpu { "CPU" } else { "GPU" }));
            if let Some(why) = off_gpu {
                row("GPU", why.to_string());
            }
            row("Mrays/s", format!("{:.2} ({} rays)", f.mrays_per_s(), f.rays()));
            row("cells / ray", format!("{:.2}", f.mean_cells()));
            row("tests / ray", format!("{:.2}", f.mean_tests()));
            row("hit pixels", format!("{:.1}%", 100.0 * f.totals.hits as f64 / f.totals.rays.max(1) as f64));
        }
    });
    if let Some((what, secs)) = building {
        ui.horizontal(|ui| {
            ui.spinner();
            ui.label(format!("{what}… {secs:.1} s"));
        });
    }
}
