//! Procedural scenes: deterministic, closed where promised, and unchanged by a .glb round trip.

use gridrt_scene::glb_write::to_glb;
use gridrt_scene::gltf_load::load_slice;
use gridrt_scene::procedural::{SceneKind, generate, icosphere};

#[test]
fn every_kind_round_trips_through_glb() {
    for kind in SceneKind::ALL {
        let (_, size) = kind.size_help();
        let size = match kind {
            SceneKind::Particles | SceneKind::Slivers => 500,
            _ => size.min(2),
        };
        let g = generate(kind, size, 9);
        assert!(g.mesh.triangle_count() > 0, "{kind:?}");
        assert_eq!(g.mesh, generate(kind, size, 9).mesh, "{kind:?} not deterministic");
        let (back, report) = load_slice(&to_glb(&g.mesh, "test"), "gen.glb", None).unwrap();
        assert_eq!(back, g.mesh, "{kind:?}");
        assert_eq!(report.triangles, g.mesh.triangle_count());
    }
}

#[test]
fn icosphere_is_closed_and_manifold() {
    for s in 0..4 {
        let m = icosphere(s);
        assert_eq!(m.triangle_count(), 20 * 4usize.pow(s));
        // Every undirected edge is shared by exactly two triangles with opposite directions.
        let mut edges = std::collections::HashMap::new();
        for t in &m.indices {
            for k in 0..3 {
                *edges.entry((t[k], t[(k + 1) % 3])).or_insert(0) += 1;
            }
        }
        for (&(a, b), &n) in &edges {
            assert_eq!(n, 1);
            assert_eq!(edges.get(&(b, a)), Some(&1), "edge {a}-{b} has no twin");
        }
    }
}

#[test]
fn teapot_in_stadium_is_uneven() {
    let g = generate(SceneKind::TeapotInStadium, 2, 0);
    let b = g.mesh.bounds();
    assert!(b.extent().min_element() >= 199.0);
    // All but the 12 room triangles fit in a tiny box at the centre.
    let knot = gridrt_scene::Aabb::from_points(g.mesh.positions[8..].iter());
    assert!(knot.extent().max_element() < 0.5, "{knot:?}");
}
