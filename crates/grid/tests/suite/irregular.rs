//! The experimental irregular grid (merged and expanded cells of a flat grid) equals brute
//! force exactly on the procedural scenes, at the auto resolution and at twice it, with and
//! without expansion and with and without the mailbox.

use glam::Vec3;
use gridrt_grid::irregular::{IrregularGrid, IrregularOptions};
use gridrt_grid::{BuildOptions, CostModel, Resolution, TraceOptions, build_flat};

use super::common::*;

#[test]
fn irregular_grid_equals_brute_force() {
    for (name, g) in procedural_scenes() {
        let tris: Vec<[Vec3; 3]> = (0..g.mesh.triangle_count()).map(|i| g.mesh.triangle(i)).collect();
        let rays = mixed_rays(&g.mesh, &g.inside_points, matrix_rays(20_000), 17);
        let (expected, _) = reference(&tris, &rays);
        let model = CostModel::memory_aware();
        let opts = BuildOptions { insert: Default::default(), parallel: true };
        let (auto, choice, _) = build_flat(&tris, Resolution::Auto, &model, opts).unwrap();
        let twice = choice.resolution.map(|x| x * 2);
        let (fine, _, _) = build_flat(&tris, Resolution::Explicit(twice), &model, opts).unwrap();
        for (scale, flat) in [(1, &auto), (2, &fine)] {
            for expand in [false, true] {
                let irr = IrregularGrid::from_flat(flat, IrregularOptions { expand, ..Default::default() });
                assert!(irr.cells.len() as u64 <= flat.geom.cell_count(), "{name}: more cells than voxels");
                for mailbox in [false, true] {
                    let got: Vec<_> = rays
                        .iter()
                        .map(|r| irr.trace(&tris, r, TraceOptions { mailbox, ..Default::default() }).0)
                        .collect();
                    let what = format!("{name} irregular x{scale} expand={expand} mailbox={mailbox}");
                    assert_same_hits(&what, &rays, &expected, &got);
                }
            }
        }
    }
}
