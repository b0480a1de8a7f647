use gridrt_grid::trace::TraceOptions;
use gridrt_grid::*;
use gridrt_scene::{Camera, gltf_load::load_path, rays::image_rays};
use std::time::Instant;
fn main() {
    let a: Vec<String> = std::env::args().collect();
    let (mesh, _) = load_path(std::path::Path::new(&a[1])).unwrap();
    let kind: GridKind = a.get(2).map(|s| s.parse().unwrap()).unwrap_or_default();
    let tile: u32 = a.get(3).map(|s| s.parse().unwrap()).unwrap_or(8);
    let par = a.get(4).map(|s| s == "par").unwrap_or(false);
    let tris = mesh.triangles();
    let b = mesh.bounds();
    let (grid, _) = structure::build(&tris, &GridConfig { kind, ..Default::default() }).unwrap();
    let mut cam = Camera::fit(&b, 1.0);
    cam.vfov_deg = 20.0;
    let (w, h) = (1024u32, 1024u32);
    let rays = image_rays(&cam, w, h);
    let opts = TraceOptions { mailbox: true, ..Default::default() };
    for _ in 0..3 {
        let s = Instant::now();
        let only = std::env::var("ONLY_PACKETS").is_ok();
        let (h1, st1) = if only { (vec![], BatchStats::default()) } else { grid.trace_batch(&tris, &rays, opts, par) };
        let t1 = s.elapsed().as_secs_f64();
        let s = Instant::now();
        let (h2, st2, ps) =
            grid.trace_packets(&tris, &rays, w as usize, opts, PacketOptions { tile, mailbox: true }, par);
        let t2 = s.elapsed().as_secs_f64();
        assert!(only || h1.iter().zip(&h2).all(|(a, b)| a.same_bits(b)));
        println!(
            "hits {:.0}% single {:.1} ms ({:.2} cells {:.2} tests/ray)  packets {:.1} ms ({:.2} cells {:.2} tests/ray, {} packets, {} single, {:.1} cells/packet) speedup {:.2}",
            st1.hits as f64 / rays.len() as f64 * 100.0,
            t1 * 1e3,
            st1.mean_cells(),
            st1.mean_tests(),
            t2 * 1e3,
            st2.mean_cells(),
            st2.mean_tests(),
            ps.packets,
            ps.single_ray_packets,
            ps.cells as f64 / ps.packets.max(1) as f64,
            t1 / t2
        );
    }
}
