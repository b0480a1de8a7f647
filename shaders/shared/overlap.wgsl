// Exact insertion's triangle–cube overlap test: gridrt_grid::insert::OverlapTest (separating
// axes, Akenine-Möller) operation for operation, in the binary64 of shared/soft_f64.wgsl, so
// that the GPU build puts a triangle in exactly the CPU's cells. What depends on the triangle
// alone is computed once (per axis its projected interval and the cube's projected radius).
//
// Binary64 on u32 words costs dozens of operations a step, so each comparison is first made in
// f32, relative to the triangle's first corner (kept as two f32, so a cube's offset from it is
// exact to f32's precision), against a tolerance of OVERLAP_TOL times the magnitudes involved
// (plus OVERLAP_TINY). The f32 axes (the f64 edges rounded, their cross product in f32), the
// corners' offsets, the dot products and the radii are within about 8 · 2^-23 ≈ 1e-6 of those
// magnitudes of the values the CPU computes in f64 (whose own rounding is far smaller), so a
// comparison decided by more than the tolerance is decided the same way in f64. Only a
// triangle with a comparison within the tolerance (a cube touching one of its planes within
// ~1e-5 of a cell) has its axes computed in f64 (`overlap_test_f64`), and only such a comparison
// is made in f64. For the same reason a row's candidate cubes are first narrowed to an interval
// (`overlap_row_bounds`, widened by the tolerance): no cube the f64 test accepts lies outside
// it, so the row's first and last overlapped cells, and thus the cells inserted, are the CPU's.
//!include shared/soft_f64.wgsl

// The pre-filter's relative tolerance (16 times the f32 error bound above) and its absolute
// floor (above what f32 flushes to zero, times the grid's extent).
const OVERLAP_TOL: f32 = 1.6e-5;
const OVERLAP_TINY: f32 = 1e-30;

struct OverlapAxis {
    a: D3,
    // The triangle's projected interval [lo, hi] and the cube's projected radius.
    lo: F64,
    hi: F64,
    r: F64,
}

struct OverlapTest {
    // The triangle's corners and edges in grid space and the cubes' half size, from which the
    // f64 axes are made when a comparison first needs them, and which axis each entry is
    // (`overlap_axis_vector`'s k: the f32 set-up decides which are skipped, for both).
    v: array<D3, 3>,
    e: array<D3, 3>,
    h: F64,
    ks: array<u32, 13>,
    has_f64: bool,
    // The box axes (the triangle's bounding box: the CPU tests it first), the nine edge ×
    // box-axis cross products that are not zero, then the normal. A box axis is the CPU's box
    // test exactly: its dot products with a point are the point's coordinate, and its radius h.
    axes: array<OverlapAxis, 13>,
    n: u32,
    // The pre-filter, the same axes in f32: (a, r); the triangle's interval relative to corner
    // 0 and a bound on |a|₁ (for the normal also |e0|₁ |e1|₁, its rounding's scale).
    axes32: array<vec4<f32>, 13>,
    bounds32: array<vec3<f32>, 13>,
    // Corner 0 as hi + lo, and the larger of the other corners' offsets from it (|·|₁).
    v0_hi: vec3<f32>,
    v0_lo: vec3<f32>,
    extent: f32,
}

fn l1(v: vec3<f32>) -> f32 {
    return abs(v.x) + abs(v.y) + abs(v.z);
}

// For an edge axis (3 ≤ k < 12, box axis k % 3 crossed with edge k / 3 − 1): the edge and the
// two components (i, j) of the cross product that are not zero, a[i] = −d[j] and a[j] = d[i]
// (glam's cross of a unit vector, up to the sign of zero, which no comparison sees).
fn overlap_edge_axis(k: u32) -> vec3<u32> {
    return vec3<u32>(k / 3u - 1u, (k + 1u) % 3u, (k + 2u) % 3u);
}

// Separating axis k of a triangle with edges `e`: for k < 3 box axis k; for k < 12 an edge axis
// (`overlap_edge_axis`); for k = 12 the normal e0 × e1.
fn overlap_axis_vector(e: ptr<function, array<D3, 3>>, k: u32) -> D3 {
    let zero = F64(0u, 0u);
    var a = D3(zero, zero, zero);
    if k < 3u {
        a[k] = f64_from_f32(1.0);
    } else if k < 12u {
        let x = overlap_edge_axis(k);
        let d = (*e)[x.x];
        a[x.y] = f64_neg(d[x.z]);
        a[x.z] = d[x.y];
    } else {
        a = d3_cross((*e)[0], (*e)[1]);
    }
    return a;
}

// The f64 axes (`OverlapTest::new` on the CPU) of the entries the f32 set-up kept.
fn overlap_test_f64(t: ptr<function, OverlapTest>) {
    var vs = (*t).v;
    var e = (*t).e;
    let h = (*t).h;
    for (var n = 0u; n < (*t).n; n++) {
        let k = (*t).ks[n];
        let a = overlap_axis_vector(&e, k);
        // A box axis' dot products are the corners' coordinates and its radius is h, exactly
        // (products with 1 and 0, sums with zeros), so they are taken as such; every axis, the
        // normal too, takes its interval from all three corners (a nearly collinear triangle's
        // normal is rounding noise, not perpendicular to its edges).
        let box_axis = k < 3u;
        var lo: F64;
        var hi: F64;
        for (var j = 0u; j < 3u; j++) {
            var p: F64;
            if box_axis {
                p = vs[j][k];
            } else {
                p = d3_dot(a, vs[j]);
            }
            if j == 0u {
                lo = p;
                hi = p;
            } else {
                lo = f64_min(lo, p);
                hi = f64_max(hi, p);
            }
        }
        // h · (|a.x| + |a.y| + |a.z|).
        var r = h;
        if !box_axis {
            var sum = f64_abs(a[0]);
            for (var c = 1u; c < 3u; c++) {
                sum = f64_add(sum, f64_abs(a[c]));
            }
            r = f64_mul(h, sum);
        }
        (*t).axes[n] = OverlapAxis(a, lo, hi, r);
    }
    (*t).has_f64 = true;
}

// The test of a triangle with corners `v` (grid space) against cubes of half size `h`: the f32
// pre-filter; the f64 axes wait until a comparison needs them.
fn overlap_test_new(v: array<D3, 3>, h: F64) -> OverlapTest {
    var t: OverlapTest;
    t.v = v;
    t.h = h;
    t.has_f64 = false;
    var vs = v;
    var e32: array<vec3<f32>, 3>;
    for (var i = 0u; i < 3u; i++) {
        t.e[i] = d3_sub(vs[(i + 1u) % 3u], vs[i]);
        e32[i] = d3_to_f32_approx(t.e[i]);
    }
    // The other corners' offsets from corner 0: e0 and −e2.
    let c1 = e32[0];
    let c2 = -e32[2];
    t.v0_hi = d3_to_f32_approx(vs[0]);
    t.v0_lo = d3_to_f32_approx(d3_sub(vs[0], d3_from_f32(t.v0_hi)));
    t.extent = max(l1(c1), l1(c2));
    let h32 = f64_to_f32_approx(h);
    var n = 0u;
    for (var k = 0u; k < 13u; k++) {
        var a = vec3<f32>(0.0);
        var bound = 0.0;
        if k < 3u {
            a[k] = 1.0;
        } else if k < 12u {
            // Skipped where the CPU's (f64) edge axis is zero.
            let x = overlap_edge_axis(k);
            let d = t.e[x.x];
            if f64_is_zero(d[x.y]) && f64_is_zero(d[x.z]) {
                continue;
            }
            a[x.y] = -e32[x.x][x.z];
            a[x.z] = e32[x.x][x.y];
        } else {
            a = cross(e32[0], e32[1]);
            bound = l1(e32[0]) * l1(e32[1]);
        }
        let p1 = dot(a, c1);
        let p2 = dot(a, c2);
        let lo = min(0.0, min(p1, p2));
        let hi = max(0.0, max(p1, p2));
        t.ks[n] = k;
        t.axes32[n] = vec4<f32>(a, h32 * l1(a));
        t.bounds32[n] = vec3<f32>(lo, hi, l1(a) + bound);
        n += 1u;
    }
    t.n = n;
    return t;
}

// Whether the cube at cell (x, y, z)'s center overlaps (or touches) the triangle: the CPU's
// `OverlapTest::overlaps`, each comparison decided in f32 where the tolerance allows.
fn overlap_test_overlaps(t: ptr<function, OverlapTest>, x: u32, y: u32, z: u32) -> bool {
    let c32 = vec3<f32>(f32(x), f32(y), f32(z)) + vec3<f32>(0.5);
    let cv = (c32 - (*t).v0_hi) - (*t).v0_lo;
    let size = (*t).extent + l1(cv);
    for (var i = 0u; i < (*t).n; i++) {
        let a = (*t).axes32[i];
        let p = (*t).bounds32[i];
        let ac = dot(a.xyz, cv);
        let tol = OVERLAP_TOL * (p.z * size + a.w + abs(p.x) + abs(p.y) + abs(ac)) + OVERLAP_TINY;
        let below = p.x - ac;
        let above = p.y - ac;
        if below > a.w + tol || above < -a.w - tol {
            return false;
        }
        if below >= a.w - tol || above <= -a.w + tol {
            if !(*t).has_f64 {
                overlap_test_f64(t);
            }
            let axis = (*t).axes[i];
            let ac64 = d3_dot(axis.a, d3_from_f32(c32));
            if f64_gt(f64_sub(axis.lo, ac64), axis.r) || f64_lt(f64_sub(axis.hi, ac64), f64_neg(axis.r)) {
                return false;
            }
        }
    }
    return true;
}

// The x of the centers of the cubes at (·, y, z), x0 ≤ x ≤ x1, that may overlap the triangle,
// as an interval (lo > hi: none): per axis, its condition solved for x with the tolerance added
// (at its largest over the row), so that it holds wherever the f64 test's does.
fn overlap_row_bounds(t: ptr<function, OverlapTest>, x0: u32, x1: u32, y: u32, z: u32) -> vec2<f32> {
    let v0 = (*t).v0_hi;
    let v0_lo = (*t).v0_lo;
    let cvy = ((f32(y) + 0.5) - v0.y) - v0_lo.y;
    let cvz = ((f32(z) + 0.5) - v0.z) - v0_lo.z;
    let cvx = max(abs((f32(x0) + 0.5 - v0.x) - v0_lo.x), abs((f32(x1) + 0.5 - v0.x) - v0_lo.x)) + 1.0;
    let size = (*t).extent + cvx + abs(cvy) + abs(cvz);
    var lo = -3.0e38;
    var hi = 3.0e38;
    for (var i = 0u; i < (*t).n; i++) {
        let a = (*t).axes32[i];
        let p = (*t).bounds32[i];
        let rest = a.y * cvy + a.z * cvz;
        let ac = abs(a.x) * cvx + abs(rest);
        let tol = OVERLAP_TOL * (p.z * size + a.w + abs(p.x) + abs(p.y) + ac) + OVERLAP_TINY;
        // min − a·cv ≤ r and max − a·cv ≥ −r, with a·cv = a.x·cvx + rest.
        let below = p.x - a.w - tol - rest;
        let above = p.y + a.w + tol - rest;
        if a.x == 0.0 {
            if below > 0.0 || above < 0.0 {
                return vec2<f32>(1.0, 0.0);
            }
            continue;
        }
        let q0 = below / a.x;
        let q1 = above / a.x;
        lo = max(lo, min(q0, q1));
        hi = min(hi, max(q0, q1));
    }
    // Back to grid x, widened for the divisions' and this sum's rounding.
    let x_lo = (lo + v0.x) + v0_lo.x;
    let x_hi = (hi + v0.x) + v0_lo.x;
    return vec2<f32>(x_lo - 1e-3 - 1e-6 * abs(x_lo), x_hi + 1e-3 + 1e-6 * abs(x_hi));
}

// The cells of row (y, z) between x0 and x1 the triangle goes into: from its first overlapped
// cell to its last (gridrt_grid::insert::for_each_run_in_layers: the cells between are taken
// untested), as (first, last); first > last when it overlaps none.
fn overlap_row_run(t: ptr<function, OverlapTest>, x0: u32, x1: u32, y: u32, z: u32) -> vec2<u32> {
    // Centers x + 0.5 within the bounds: x from ceil(lo − 0.5) to floor(hi − 0.5).
    let b = overlap_row_bounds(t, x0, x1, y, z);
    if !(b.x <= b.y) {
        return vec2<u32>(1u, 0u);
    }
    let lo = clamp(ceil(b.x - 0.5), f32(x0), f32(x1) + 1.0);
    let hi = clamp(floor(b.y - 0.5), f32(x0) - 1.0, f32(x1));
    if lo > hi {
        return vec2<u32>(1u, 0u);
    }
    var first = u32(lo);
    let end = u32(hi);
    loop {
        if first > end {
            return vec2<u32>(1u, 0u);
        }
        if overlap_test_overlaps(t, first, y, z) {
            break;
        }
        first += 1u;
    }
    var last = end;
    while last > first && !overlap_test_overlaps(t, last, y, z) {
        last -= 1u;
    }
    return vec2<u32>(first, last);
}
