//! Every struct shared between Rust and WGSL has the same size and member offsets on both
//! sides (naga's layout of the composed WGSL vs `size_of` / `offset_of!`).

use std::mem::{offset_of, size_of};

use gridrt_gpu::layout::*;
use gridrt_gpu::shaders::compose;

fn wgsl_layout(module: &naga::Module, name: &str) -> (u32, Vec<(String, u32)>) {
    for (_, ty) in module.types.iter() {
        if ty.name.as_deref() == Some(name)
            && let naga::TypeInner::Struct { members, span } = &ty.inner
        {
            return (*span, members.iter().map(|m| (m.name.clone().unwrap_or_default(), m.offset)).collect());
        }
    }
    panic!("struct {name} not found in the WGSL");
}

macro_rules! check {
    ($module:expr, $wgsl:literal, $rust:ty, [$($field:ident),*]) => {{
        let (span, members) = wgsl_layout(&$module, $wgsl);
        assert_eq!(span as usize, size_of::<$rust>(), "size of {} vs {}", $wgsl, stringify!($rust));
        let rust: Vec<(String, u32)> = vec![$((stringify!($field).to_string(), offset_of!($rust, $field) as u32)),*];
        assert_eq!(members, rust, "members of {} vs {}", $wgsl, stringify!($rust));
    }};
}

#[test]
fn rust_and_wgsl_structs_have_the_same_layout() {
    let trace = naga::front::wgsl::parse_str(&compose("hierarchy.wgsl").unwrap()).unwrap();
    check!(trace, "Ray", GpuRay, [origin_tmin, dir_tmax]);
    check!(trace, "Hit", gridrt_scene::Hit, [t, triangle, u, v]);
    check!(trace, "RayStats", gridrt_grid::RayStats, [cells, tests]);
    check!(
        trace,
        "Params",
        GridParams,
        [grid_min, inv_cell, res, ray_count, mailbox, macro_edge, first_ray, image_width, query, _pad0, _pad1, _pad2]
    );
    check!(trace, "Node", GpuNode, [res_first]);
    let render = naga::front::wgsl::parse_str(&compose("shade.wgsl").unwrap()).unwrap();
    check!(render, "Camera", GpuCamera, [eye, tan_half_vfov, right, width, up, height, forward, aspect]);
    check!(
        render,
        "ShadeParams",
        ShadeParams,
        [light, diagonal, view, heat_max, width, height, depth_near, depth_far, first_pixel, pixel_count]
    );
    let build = naga::front::wgsl::parse_str(&compose("build_count.wgsl").unwrap()).unwrap();
    check!(
        build,
        "BuildParams",
        BuildParams,
        [grid_min, inv_cell, res, triangle_count, margin, count, groups_x, macro_edge, scatter]
    );
    // The ray record is also the ray file's.
    assert_eq!(size_of::<GpuRay>(), size_of::<gridrt_scene::Ray>());
}
