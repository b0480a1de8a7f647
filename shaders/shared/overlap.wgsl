// Exact insertion's triangle–cube overlap test: gridrt_grid::insert::OverlapTest (separating
// axes, Akenine-Möller) operation for operation, in the binary64 of shared/soft_f64.wgsl, so
// that the GPU build puts a triangle in exactly the CPU's cells. What depends on the triangle
// alone is computed once (per axis its projected interval and the cube's projected radius).
//!include shared/soft_f64.wgsl

struct OverlapAxis {
    a: D3,
    // The triangle's projected interval [lo, hi] and the cube's projected radius.
    lo: F64,
    hi: F64,
    r: F64,
}

struct OverlapTest {
    // The triangle's bounding box.
    lo: D3,
    hi: D3,
    // The cubes' half size.
    h: F64,
    // The nine edge × box-axis cross products that are not zero, then the normal.
    axes: array<OverlapAxis, 10>,
    n: u32,
}

// h · (|a.x| + |a.y| + |a.z|).
fn overlap_radius(a: D3, h: F64) -> F64 {
    return f64_mul(h, f64_add(f64_add(f64_abs(a.x), f64_abs(a.y)), f64_abs(a.z)));
}

fn overlap_test_new(v: array<D3, 3>, h: F64) -> OverlapTest {
    var t: OverlapTest;
    var vs = v;
    var e = array<D3, 3>(d3_sub(v[1], v[0]), d3_sub(v[2], v[1]), d3_sub(v[0], v[2]));
    let zero = F64(0u, 0u);
    let one = f64_from_f32(1.0);
    var basis = array<D3, 3>(D3(one, zero, zero), D3(zero, one, zero), D3(zero, zero, one));
    var n = 0u;
    for (var i = 0u; i < 3u; i++) {
        for (var k = 0u; k < 3u; k++) {
            let a = d3_cross(basis[k], e[i]);
            if d3_is_zero(a) {
                continue;
            }
            let p0 = d3_dot(a, vs[0]);
            let p1 = d3_dot(a, vs[1]);
            let p2 = d3_dot(a, vs[2]);
            t.axes[n] = OverlapAxis(a, f64_min(f64_min(p0, p1), p2), f64_max(f64_max(p0, p1), p2), overlap_radius(a, h));
            n += 1u;
        }
    }
    // The plane (a degenerate triangle's zero normal never separates).
    let normal = d3_cross(e[0], e[1]);
    let d = d3_dot(normal, vs[0]);
    t.axes[n] = OverlapAxis(normal, d, d, overlap_radius(normal, h));
    t.n = n + 1u;
    t.lo = d3_min(d3_min(v[0], v[1]), v[2]);
    t.hi = d3_max(d3_max(v[0], v[1]), v[2]);
    t.h = h;
    return t;
}

// Whether the cube at `c` overlaps (or touches) the triangle.
fn overlap_test_overlaps(t: ptr<function, OverlapTest>, c: D3) -> bool {
    let lo = d3_sub((*t).lo, c);
    let hi = d3_sub((*t).hi, c);
    let h = (*t).h;
    let nh = f64_neg(h);
    if f64_gt(lo.x, h) || f64_gt(lo.y, h) || f64_gt(lo.z, h) || f64_lt(hi.x, nh) || f64_lt(hi.y, nh) || f64_lt(hi.z, nh) {
        return false;
    }
    for (var i = 0u; i < (*t).n; i++) {
        let axis = (*t).axes[i];
        let ac = d3_dot(axis.a, c);
        if f64_gt(f64_sub(axis.lo, ac), axis.r) || f64_lt(f64_sub(axis.hi, ac), f64_neg(axis.r)) {
            return false;
        }
    }
    return true;
}

// The center of cell (x, y, z) (exact: coordinates below 2^23).
fn overlap_cell_center(x: u32, y: u32, z: u32) -> D3 {
    return d3_from_f32(vec3<f32>(f32(x), f32(y), f32(z)) + vec3<f32>(0.5));
}

// The cells of row (y, z) between x0 and x1 the triangle goes into: from its first overlapped
// cell to its last (gridrt_grid::insert::for_each_run_in_layers: the cells between are taken
// untested), as (first, last); first > last when it overlaps none.
fn overlap_row_run(t: ptr<function, OverlapTest>, x0: u32, x1: u32, y: u32, z: u32) -> vec2<u32> {
    var first = x0;
    loop {
        if first > x1 {
            return vec2<u32>(1u, 0u);
        }
        if overlap_test_overlaps(t, overlap_cell_center(first, y, z)) {
            break;
        }
        first += 1u;
    }
    var last = x1;
    while last > first && !overlap_test_overlaps(t, overlap_cell_center(last, y, z)) {
        last -= 1u;
    }
    return vec2<u32>(first, last);
}
