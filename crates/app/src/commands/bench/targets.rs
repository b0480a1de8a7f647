//! The targets, judged as ratios taken in one run on this machine (never as timed tests): the
//! flat build against obvhs' fastest build on every scene of 50k triangles or more, linear
//! build time, the best grid's memory against obvhs BVH2 medium, Mrays/s of the best grid
//! against the best BVH on every ray set of every scene (and the grids' coherent packets against
//! it on the camera sets), the auto resolution against the sweep
//! around it, and agreement of every structure's hits with the flat grid's.

use serde::Serialize;

use super::scaling::{ScalePoint, slope, slope_in_refs, slope_of_first};
use super::{AutoPoint, Row};
use crate::lab::report::print_table;
use crate::lab::views::RaySet;

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

/// Above this share of a set's rays answered wrongly (hits that differ from the exact ones), a
/// peer is not counted as the best BVH of that set.
pub const MAX_WRONG_SHARE: f64 = 1e-3;

impl Row {
    /// The share of the set's rays whose hits disagree with the exact ones (the flat grid's,
    /// checked against brute force: a ray where the grid is the wrong one does not count
    /// against the subject).
    fn wrong_share(&self) -> f64 {
        (self.mismatches - self.flat_wrong) as f64 / self.ray_count.max(1) as f64
    }
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
    // Build: the flat grid at auto resolution against obvhs' fastest build on every scene of at
    // least 50k triangles (and `bvh`'s parallel build, reported); memory: the best grid against
    // obvhs BVH2 medium. Build and memory stand on every set's row: the first is read.
    for &(scene, _, n) in &scenes {
        let Some(flat) = rows.iter().find(|r| r.scene == scene && r.structure == "flat") else { continue };
        if n >= 50_000 {
            if let Some(o) = peer(rows, scene, "obvhs BVH2 fastest").first() {
                let k = o.build_ms / flat.build_ms;
                push("flat build speed-up over obvhs fastest_build", scene, k, "≥ 2", k >= 2.0);
            }
            if let Some(b) = peer(rows, scene, "bvh").first() {
                let k = b.build_ms / flat.build_ms;
                push("flat build speed-up over bvh build_par", scene, k, "(reported)", true);
            }
        }
        let grids: Vec<&Row> = rows.iter().filter(|r| r.scene == scene && r.family == "grid").collect();
        let least = grids.iter().map(|r| r.bytes_per_triangle).min_by(f64::total_cmp);
        if let (Some(g), Some(o)) = (least, peer(rows, scene, "obvhs BVH2 medium").first()) {
            let k = g / o.bytes_per_triangle;
            push("best grid B/tri / obvhs BVH2 medium B/tri", scene, k, "≤ 1.0", k <= 1.0);
        }
    }
    for (scene, label) in [
        ("particles", "particles, scaled up"),
        ("particles, size ∝ N^-1/3", "particles, size ∝ N^-1/3"),
        ("mountain", "mountain, scaled up"),
    ] {
        if let Some(k) = slope(scale, scene, "flat") {
            push("flat build: log–log slope of time against N", label, k, "≤ 1.05", k <= 1.05);
        }
        if let Some(k) = slope_of_first(scale, scene, "flat") {
            push("flat build: log–log slope of the first build (fresh memory) against N", label, k, "(reported)", true);
        }
        if let Some(k) = slope_in_refs(scale, scene, "flat") {
            push("flat build: log–log slope of time against references", label, k, "(reported)", true);
        }
    }
    // Traversal, on every ray set: the best grid against the best BVH crate (`bvh`, obvhs);
    // Embree (feature `embree`) is reported beside it, not judged.
    for &(scene, _, _) in &scenes {
        for set in [RaySet::Framed, RaySet::Interior, RaySet::Random] {
            let of_set = |r: &&Row| r.scene == scene && r.rays == set;
            let grids: Vec<&Row> = rows.iter().filter(of_set).filter(|r| r.family == "grid").collect();
            let (embree, peers): (Vec<&Row>, Vec<&Row>) = rows
                .iter()
                .filter(of_set)
                .filter(|r| r.family == "peer")
                .partition(|r| r.structure.starts_with("Embree"));
            // A peer that answers many rays wrongly is no yardstick: it is left out of the best
            // BVH (and reported) when more than `MAX_WRONG_SHARE` of the set disagrees with the
            // exact hits (a handful of rays, ties and blind-distance hits, does not count).
            let (peers, wrong): (Vec<&Row>, Vec<&Row>) =
                peers.into_iter().partition(|r| r.wrong_share() <= MAX_WRONG_SHARE);
            for r in wrong {
                let target = format!("{} left out of the best BVH: share of rays wrong, {}", r.structure, set.name());
                push(&target, scene, r.wrong_share(), "(reported)", true);
            }
            let Some(g) = max_by(&grids, |r| r.mrays_s) else { continue };
            if let Some(p) = max_by(&peers, |r| r.mrays_s) {
                let (k, goal) = (g / p, if set == RaySet::Random { 0.7 } else { 1.0 });
                let target = format!("best grid / best BVH Mrays/s, {}", set.name());
                push(&target, scene, k, &format!("≥ {goal}"), k >= goal);
            }
            if let Some(e) = max_by(&embree, |r| r.mrays_s) {
                push(&format!("best grid / best Embree Mrays/s, {}", set.name()), scene, g / e, "(reported)", true);
            }
            // Coherent packets (issue 19), on the camera sets: against the best BVH crate's
            // single rays, and how much they gain over the best single-ray grid.
            let packets: Vec<&Row> = rows.iter().filter(of_set).filter(|r| r.family == "grid packets").collect();
            if let Some(k) = max_by(&packets, |r| r.mrays_s) {
                if let Some(p) = max_by(&peers, |r| r.mrays_s) {
                    let target = format!("best grid packets / best BVH Mrays/s, {}", set.name());
                    push(&target, scene, k / p, "≥ 1.5", k / p >= 1.5);
                }
                let target = format!("best grid packets / best grid single rays, {}", set.name());
                push(&target, scene, k / g, "(reported)", true);
                if let Some(e) = max_by(&embree, |r| r.mrays_s) {
                    push(
                        &format!("best grid packets / best Embree Mrays/s, {}", set.name()),
                        scene,
                        k / e,
                        "(reported)",
                        true,
                    );
                }
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
        // Peers on the shared triangle test must agree exactly, except for hits a peer cannot
        // see by design (closer than its blind distance: counted apart); obvhs' own test is
        // reported.
        if r.shared_triangle_test {
            let unexplained = r.mismatches - r.blind_near;
            // (target, count, judged): the blind-spot count is reported, not judged.
            let lines = [
                Some((format!("{}: rays disagreeing with flat", r.structure), unexplained, true)),
                (r.blind_near > 0).then(|| {
                    (format!("{}: true hits closer than its blind distance (missed)", r.structure), r.blind_near, false)
                }),
            ];
            for (target, n, judged) in lines.into_iter().flatten() {
                push(&target, &r.scene, n as f64, if judged { "= 0" } else { "(reported)" }, !judged || n == 0);
            }
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
    println!("  + {agreeing} structure × scene × ray set rows whose hits all agree with the flat grid's");
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(structure: &str, family: &'static str, mrays_s: f64, mismatches: u64) -> Row {
        Row {
            scene: "s".into(),
            kind: "scanned".into(),
            triangles: 10,
            structure: structure.into(),
            family,
            build_ms: 1.0,
            memory_bytes: 100,
            bytes_per_triangle: 10.0,
            rays: RaySet::Random,
            ray_count: 10_000,
            hit_share: 0.5,
            mrays_s,
            gpu_mrays_s: None,
            parallel_build: true,
            shared_triangle_test: false,
            mismatches,
            flat_wrong: 0,
            blind_near: 0,
        }
    }

    /// The fastest BVH is the yardstick unless it answers more than 0.1% of the rays wrongly:
    /// then the next one is, and the wrong one gets a reported row.
    #[test]
    fn a_mostly_wrong_peer_is_not_the_best_bvh() {
        let ratio = |rows: &[Row]| {
            let t = evaluate(rows, &[], &[]);
            let best = t.iter().find(|t| t.target == "best grid / best BVH Mrays/s, random").unwrap().measured;
            (best, t.iter().filter(|t| t.target.contains("left out of the best BVH")).count())
        };
        let grid = row("flat", "grid", 2.0, 0);
        // 10 wrong rays of 10,000 (0.1%): still counted.
        assert_eq!(ratio(&[grid.clone(), row("fast", "peer", 8.0, 10), row("slow", "peer", 4.0, 0)]), (0.25, 0));
        // 11 wrong rays: left out, the next peer is the yardstick.
        assert_eq!(ratio(&[grid.clone(), row("fast", "peer", 8.0, 11), row("slow", "peer", 4.0, 0)]), (0.5, 1));
        // Rays where the flat grid is the wrong one do not count against the peer.
        let mut fast = row("fast", "peer", 8.0, 11);
        fast.flat_wrong = 5;
        assert_eq!(ratio(&[grid, fast, row("slow", "peer", 4.0, 0)]), (0.25, 0));
    }
}
