//! The 2-D traversal explainer (survey Figures 1–3): a ray over a small 2-D grid, with its two
//! ends dragged by the user, and the cells Amanatides–Woo, Cleary–Wyvill, Liu and naive
//! Bresenham visit. Cells the exact walkers visit but Bresenham skips are highlighted; the
//! distances along the ray between successive x-wall and y-wall crossings (Cleary–Wyvill's dx
//! and dy, Amanatides–Woo's tDelta) are labelled.
//!
//! The walkers are the real ones from `gridrt-grid`, run on a grid one cell deep in z with a
//! ray parallel to the xy plane: a 2-D traversal is exactly the 3-D one in that case.

use std::collections::BTreeSet;

use eframe::egui::{self, Color32, Pos2, Rect, Sense, Stroke, Vec2};
use glam::{UVec3, Vec3};
use gridrt_grid::Traversal;
use gridrt_grid::geometry::GridRay;
use gridrt_grid::traversal::Walker;
use serde::{Deserialize, Serialize};

#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default)]
pub struct ExplainerState {
    pub nx: u32,
    pub ny: u32,
    /// Ray start and end in grid units (cell (i, j) is the unit square at (i, j)).
    pub a: [f32; 2],
    pub b: [f32; 2],
    /// Whose visiting order is numbered in the cells.
    pub numbered: Traversal,
    pub show_crossings: bool,
    #[serde(skip)]
    dragging: Option<usize>,
}

impl Default for ExplainerState {
    fn default() -> Self {
        ExplainerState {
            nx: 12,
            ny: 8,
            a: [0.7, 1.3],
            b: [11.2, 6.1],
            numbered: Traversal::AmanatidesWoo,
            show_crossings: true,
            dragging: None,
        }
    }
}

/// Cells (x, y) visited by `kind` along the segment a → b on an nx × ny grid, in order.
pub fn walk_2d(kind: Traversal, nx: u32, ny: u32, a: [f32; 2], b: [f32; 2]) -> Vec<[u32; 2]> {
    let res = UVec3::new(nx.max(1), ny.max(1), 1);
    let o = Vec3::new(a[0], a[1], 0.5);
    let d = Vec3::new(b[0] - a[0], b[1] - a[1], 0.0);
    if d.length_squared() < 1e-12 {
        return Vec::new();
    }
    let Some(ray) = GridRay::clipped(o, d, res, 0.0, 1.0) else { return Vec::new() };
    Walker::new(kind, &ray, res).map(|s| [s.cell.x, s.cell.y]).collect()
}

/// Distances along the ray between successive crossings of x walls and of y walls, in cells
/// (infinite when the ray is parallel to those walls).
pub fn crossing_distances(a: [f32; 2], b: [f32; 2]) -> (f32, f32) {
    let d = Vec3::new(b[0] - a[0], b[1] - a[1], 0.0);
    let len = d.length();
    let dx = if d.x != 0.0 { len / d.x.abs() } else { f32::INFINITY };
    let dy = if d.y != 0.0 { len / d.y.abs() } else { f32::INFINITY };
    (dx, dy)
}

const WALKERS: [(Traversal, &str); 4] = [
    (Traversal::AmanatidesWoo, "Amanatides–Woo"),
    (Traversal::ClearyWyvill, "Cleary–Wyvill"),
    (Traversal::Liu, "Liu (integer one-pass)"),
    (Traversal::Bresenham, "naive Bresenham"),
];

pub fn ui(ui: &mut egui::Ui, st: &mut ExplainerState) {
    ui.horizontal(|ui| {
        ui.add(egui::Slider::new(&mut st.nx, 2..=32).text("columns"));
        ui.add(egui::Slider::new(&mut st.ny, 2..=32).text("rows"));
        ui.checkbox(&mut st.show_crossings, "wall crossings");
    });
    ui.horizontal(|ui| {
        ui.label("Numbered:");
        for (t, name) in WALKERS {
            ui.radio_value(&mut st.numbered, t, name);
        }
    });
    for p in [&mut st.a, &mut st.b] {
        p[0] = p[0].clamp(0.0, st.nx as f32);
        p[1] = p[1].clamp(0.0, st.ny as f32);
    }
    let walks: Vec<Vec<[u32; 2]>> = WALKERS.iter().map(|(t, _)| walk_2d(*t, st.nx, st.ny, st.a, st.b)).collect();
    let exact: BTreeSet<[u32; 2]> = walks[0].iter().copied().collect();
    let bres: BTreeSet<[u32; 2]> = walks[3].iter().copied().collect();
    let missed: BTreeSet<[u32; 2]> = exact.difference(&bres).copied().collect();
    let extra: BTreeSet<[u32; 2]> = bres.difference(&exact).copied().collect();
    let (dx, dy) = crossing_distances(st.a, st.b);
    for (i, (_, name)) in WALKERS.iter().enumerate() {
        let verdict = if i == 0 {
            String::new()
        } else if i < 3 {
            if walks[i] == walks[0] {
                "same cells, same order as Amanatides–Woo".into()
            } else {
                "DIFFERS from Amanatides–Woo".into()
            }
        } else {
            format!("misses {} of {} crossed cells", missed.len(), exact.len())
        };
        ui.label(format!("{name}: {} cells {verdict}", walks[i].len()));
    }
    ui.label(format!(
        "Along the ray, x walls are crossed every dx = {dx:.3} cells and y walls every dy = {dy:.3}: \
         Amanatides–Woo's tDelta, Cleary–Wyvill's dx/dy. Each step goes to the nearer crossing."
    ));

    // Canvas: grid y up, screen y down.
    let avail = ui.available_size();
    let cell = (avail.x / st.nx as f32).min((avail.y - 8.0).max(120.0) / st.ny as f32).clamp(8.0, 64.0);
    let size = Vec2::new(cell * st.nx as f32, cell * st.ny as f32);
    let (resp, painter) = ui.allocate_painter(size, Sense::drag());
    let rect = resp.rect;
    let to_screen = |p: [f32; 2]| Pos2::new(rect.left() + p[0] * cell, rect.bottom() - p[1] * cell);
    let to_grid = |p: Pos2| [(p.x - rect.left()) / cell, (rect.bottom() - p.y) / cell];
    let cell_rect = |c: [u32; 2]| {
        Rect::from_min_max(to_screen([c[0] as f32, c[1] as f32 + 1.0]), to_screen([c[0] as f32 + 1.0, c[1] as f32]))
    };
    let visuals = ui.visuals();
    painter.rect_filled(rect, 0.0, visuals.extreme_bg_color);
    for c in &exact {
        painter.rect_filled(cell_rect(*c).shrink(1.0), 0.0, Color32::from_rgb(60, 110, 170));
    }
    for c in &missed {
        painter.rect_filled(cell_rect(*c).shrink(1.0), 0.0, Color32::from_rgb(200, 60, 50));
    }
    for c in &extra {
        painter.rect_filled(cell_rect(*c).shrink(1.0), 0.0, Color32::from_rgb(150, 80, 170));
    }
    for c in &bres {
        painter.circle_stroke(cell_rect(*c).center(), cell * 0.3, Stroke::new(2.0, Color32::from_rgb(250, 170, 40)));
    }
    let grid_stroke = Stroke::new(1.0, visuals.weak_text_color());
    for i in 0..=st.nx {
        painter.line_segment([to_screen([i as f32, 0.0]), to_screen([i as f32, st.ny as f32])], grid_stroke);
    }
    for j in 0..=st.ny {
        painter.line_segment([to_screen([0.0, j as f32]), to_screen([st.nx as f32, j as f32])], grid_stroke);
    }
    let numbered = WALKERS.iter().position(|(t, _)| *t == st.numbered).unwrap_or(0);
    if cell >= 14.0 {
        for (k, c) in walks[numbered].iter().enumerate() {
            painter.text(
                cell_rect(*c).left_top() + Vec2::splat(2.0),
                egui::Align2::LEFT_TOP,
                format!("{}", k + 1),
                egui::FontId::proportional((cell * 0.3).clamp(8.0, 14.0)),
                Color32::WHITE,
            );
        }
    }
    let (pa, pb) = (to_screen(st.a), to_screen(st.b));
    painter.line_segment([pa, pb], Stroke::new(2.5, Color32::WHITE));
    if st.show_crossings {
        let d = [st.b[0] - st.a[0], st.b[1] - st.a[1]];
        for (axis, n, colour) in
            [(0, st.nx, Color32::from_rgb(90, 220, 120)), (1, st.ny, Color32::from_rgb(240, 90, 220))]
        {
            if d[axis] == 0.0 {
                continue;
            }
            for wall in 0..=n {
                let t = (wall as f32 - st.a[axis]) / d[axis];
                if (0.0..=1.0).contains(&t) {
                    let p = [st.a[0] + d[0] * t, st.a[1] + d[1] * t];
                    painter.circle_filled(to_screen(p), 3.5, colour);
                }
            }
        }
    }
    for (i, p) in [pa, pb].into_iter().enumerate() {
        painter.circle_filled(p, 7.0, if i == 0 { Color32::from_rgb(90, 200, 250) } else { Color32::YELLOW });
    }
    // Dragging an end point.
    if resp.drag_started()
        && let Some(pos) = resp.interact_pointer_pos()
    {
        let da = pos.distance(pa);
        let db = pos.distance(pb);
        st.dragging = if da.min(db) < 16.0 { Some(if da <= db { 0 } else { 1 }) } else { None };
    }
    if resp.dragged()
        && let (Some(i), Some(pos)) = (st.dragging, resp.interact_pointer_pos())
    {
        let g = to_grid(pos);
        let p = [g[0].clamp(0.0, st.nx as f32), g[1].clamp(0.0, st.ny as f32)];
        if i == 0 { st.a = p } else { st.b = p }
    }
    if resp.drag_stopped() {
        st.dragging = None;
    }
    ui.horizontal_wrapped(|ui| {
        let swatch = |ui: &mut egui::Ui, c: Color32, text: &str| {
            let (r, p) = ui.allocate_painter(Vec2::splat(12.0), Sense::hover());
            p.rect_filled(r.rect, 2.0, c);
            ui.label(text);
        };
        swatch(ui, Color32::from_rgb(60, 110, 170), "crossed (exact walkers)");
        swatch(ui, Color32::from_rgb(200, 60, 50), "missed by Bresenham");
        swatch(ui, Color32::from_rgb(150, 80, 170), "Bresenham only");
        swatch(ui, Color32::from_rgb(250, 170, 40), "Bresenham's cells (rings)");
        ui.label("Drag the blue and yellow ends.");
    });
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_diagonal_ray_is_walked_alike_by_the_exact_walkers_and_bresenham_misses_cells() {
        let (a, b) = ([0.7, 1.3], [11.2, 6.1]);
        let aw = walk_2d(Traversal::AmanatidesWoo, 12, 8, a, b);
        assert_eq!(aw.first(), Some(&[0, 1]));
        assert_eq!(aw.last(), Some(&[11, 6]));
        // Every step moves to a 4-neighbour.
        for w in aw.windows(2) {
            assert_eq!(w[0][0].abs_diff(w[1][0]) + w[0][1].abs_diff(w[1][1]), 1, "{aw:?}");
        }
        // 11 x walls + 5 y walls crossed: 17 cells.
        assert_eq!(aw.len(), 17);
        assert_eq!(walk_2d(Traversal::ClearyWyvill, 12, 8, a, b), aw);
        assert_eq!(walk_2d(Traversal::Liu, 12, 8, a, b), aw);
        let br = walk_2d(Traversal::Bresenham, 12, 8, a, b);
        assert_eq!(br.len(), 12, "one cell per column");
        // Bresenham's 12 cells lie on the ray here, so it misses exactly the other 5.
        assert!(br.iter().all(|c| aw.contains(c)), "{br:?}");
        assert_eq!(aw.iter().filter(|c| !br.contains(c)).count(), 5);
        let (dx, dy) = crossing_distances(a, b);
        assert!((dx - (10.5f32.hypot(4.8) / 10.5)).abs() < 1e-5);
        assert!((dy - (10.5f32.hypot(4.8) / 4.8)).abs() < 1e-5);
    }

    #[test]
    fn degenerate_rays_do_not_panic() {
        assert!(walk_2d(Traversal::AmanatidesWoo, 4, 4, [1.0, 1.0], [1.0, 1.0]).is_empty());
        let v = walk_2d(Traversal::Liu, 4, 4, [0.5, 0.0], [0.5, 4.0]);
        assert_eq!(v, vec![[0, 0], [0, 1], [0, 2], [0, 3]]);
        let h = walk_2d(Traversal::Bresenham, 4, 4, [4.0, 2.5], [0.0, 2.5]);
        assert_eq!(h, vec![[3, 2], [2, 2], [1, 2], [0, 2]]);
    }
}
