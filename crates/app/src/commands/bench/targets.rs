//! The targets, judged as ratios taken in one run on this machine (never as timed
//! tests): build speed against the peers on the largest scanned model, linear build time,
//! Mrays/s of the best grid against each peer on every scene, the auto resolution against the
//! sweep around it, and agreement of every structure's hits with the flat grid's.

use serde::Serialize;

use super::scaling::{ScalePoint, slope};
use super::{AutoPoint, Row};
use crate::lab::report::print_table;

#[derive(Clone, Debug, Serialize)]
pub struct Target {
    pub target: String,
    pub scene: String,
    pub measured: f64,
    /// "≥ 5", "≤ 1.10", "0.9–1.1", …
    pub goal: String,
    pub met: bool,
}

fn peer<'a>(rows: &'a [Row], scene: &str, prefix: &str) -> Vec<&'a Row> {
    rows.iter().filter(|r| r.scene == scene && r.family == "peer" && r.structure.starts_with(prefix)).collect()
}

fn max_by(rows: &[&Row], f: impl Fn(&Row) -> f64) -> Option<f64> {
    rows.iter().map(|r| f(r)).filter(|v| v.is_finite()).max_by(f64::total_cmp)
}

pub fn evaluate(rows: &[Row], auto: &[AutoPoint], scale: &[ScalePoint]) -> Vec<Target> {
    let mut out = Vec::new();
    let mut push = |target: &str, scene: &str, measured: f64, goal: &str, met: bool| {
        out.push(Target { target: target.into(), scene: scene.into(), measured, goal: goal.into(), met });
    };
    let mut scenes: Vec<(&str, &str, usize)> = Vec::new();
    for r in rows {
        if !scenes.iter().any(|s| s.0 == r.scene) {
            scenes.push((&r.scene, &r.kind, r.triangles));
        }
    }
    // Build speed on the largest scanned model (or the largest scene without one).
    let largest = scenes
        .iter()
        .filter(|s| s.1.starts_with("scanned"))
        .max_by_key(|s| s.2)
        .or_else(|| scenes.iter().max_by_key(|s| s.2));
    if let Some(&(scene, _, _)) = largest
        && let Some(flat) = rows.iter().find(|r| r.scene == scene && r.structure == "flat")
    {
        if let Some(b) = peer(rows, scene, "bvh").first() {
            let k = b.build_ms / flat.build_ms;
            push("flat build speed-up over bvh build_par", scene, k, "≥ 5", k >= 5.0);
        }
        if let Some(o) = peer(rows, scene, "obvhs BVH2 fastest").first() {
            let k = o.build_ms / flat.build_ms;
            push("flat build speed-up over obvhs fastest_build", scene, k, "≥ 2", k >= 2.0);
        }
    }
    for (scene, label) in [("particles", "particles, scaled up"), ("mountain", "mountain, scaled up")] {
        if let Some(k) = slope(scale, scene, "flat") {
            push("flat build: log–log slope of time against N", label, k, "0.9–1.1", (0.9..=1.1).contains(&k));
        }
    }

    for &(scene, kind, _) in &scenes {
        let grids: Vec<&Row> = rows.iter().filter(|r| r.scene == scene && r.family == "grid").collect();
        for (set, f) in
            [("primary", (|r: &Row| r.primary_mrays_s) as fn(&Row) -> f64), ("random", |r| r.random_mrays_s)]
        {
            let Some(best) = max_by(&grids, f) else { continue };
            if let Some(b) = max_by(&peer(rows, scene, "bvh"), f) {
                let k = best / b;
                push(&format!("best grid / bvh Mrays/s, {set}"), scene, k, "≥ 1.0", k >= 1.0);
            }
            if kind.starts_with("scanned")
                && let Some(o) = max_by(&peer(rows, scene, "obvhs"), f)
            {
                let k = best / o;
                push(&format!("best grid / best obvhs Mrays/s, {set}"), scene, k, "≥ 0.5", k >= 0.5);
            }
        }
    }
    let mut auto_scenes: Vec<&str> = auto.iter().map(|a| a.scene.as_str()).collect();
    auto_scenes.dedup();
    for scene in auto_scenes {
        let pts: Vec<&AutoPoint> = auto.iter().filter(|a| a.scene == scene).collect();
        let at_auto = pts.iter().find(|a| a.factor == 1.0).map(|a| a.cpu_ns_per_ray);
        let best = pts.iter().map(|a| a.cpu_ns_per_ray).min_by(f64::total_cmp);
        if let (Some(a), Some(b)) = (at_auto, best) {
            let k = a / b;
            push("auto m time / best swept time (CPU)", scene, k, "≤ 1.10", k <= 1.10);
        }
    }
    for r in rows {
        // Peers on the shared triangle test must agree exactly; obvhs' own test is reported.
        if r.shared_triangle_test {
            push(
                &format!("{}: rays disagreeing with flat", r.structure),
                &r.scene,
                r.mismatches as f64,
                "= 0",
                r.mismatches == 0,
            );
        }
        // Brute force settles each disagreement: the flat grid must never be the wrong one.
        if r.flat_wrong > 0 {
            push(
                &format!("flat wrong where {} is right (brute force)", r.structure),
                &r.scene,
                r.flat_wrong as f64,
                "= 0",
                false,
            );
        }
    }
    out
}

pub fn print(targets: &[Target]) {
    let (met, all) = (targets.iter().filter(|t| t.met).count(), targets.len());
    println!("targets: {met} of {all} met (ratios from this run)");
    // Agreement rows are printed only when they fail: there is one per structure and scene.
    let rows: Vec<Vec<String>> = targets
        .iter()
        .filter(|t| !t.target.contains("disagreeing") || !t.met)
        .map(|t| {
            vec![
                t.target.clone(),
                t.scene.trim_end_matches(".glb").to_string(),
                format!("{:.3}", t.measured),
                t.goal.clone(),
                if t.met { "met".into() } else { "MISSED".into() },
            ]
        })
        .collect();
    print_table(&["target", "scene", "measured", "goal", ""], &rows);
    let agreeing = targets.iter().filter(|t| t.target.contains("disagreeing") && t.met).count();
    println!("  + {agreeing} structure × scene pairs whose hits all agree with the flat grid's");
}
