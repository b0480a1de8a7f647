//!include shared/types.wgsl
// Rays: the watertight test's per-ray constants, and a ray in grid space.
// CPU port: crates/grid/src/triangle.rs (PreparedRay), crates/grid/src/geometry.rs (GridRay).

const INF: u32 = 0x7f800000u;
const NO_HIT: u32 = 0xffffffffu;

// +inf, built at run time: a constant expression may not evaluate to inf in WGSL, and Tint
// (Chrome's WebGPU) rejects `bitcast<f32>(INF)` as one; a `var` keeps it out of const-eval.
fn inf() -> f32 {
    var bits = INF;
    return bitcast<f32>(bits);
}

struct PreparedRay {
    org: vec3<f32>,
    dir: vec3<f32>,
    tmin: f32,
    tmax: f32,
    kx: u32,
    ky: u32,
    kz: u32,
    sx: f32,
    sy: f32,
    sz: f32,
    // A power of two >= 1: the walk's t per unit of the ray's (CPU: PreparedRay::t_scale; a
    // direction of 2^16 or more walks scaled down by it, so that grid space stays within f32).
    t_scale: f32,
    valid: bool,
}

const WALK_DIR_MAX: f32 = 65536.0; // 2^16

// Index of the largest component (the dominant axis); ties go to the lowest axis.
// CPU port: crates/grid/src/traversal/mod.rs `argmax3`.
fn argmax3(v: vec3<f32>) -> u32 {
    if v.x >= v.y && v.x >= v.z {
        return 0u;
    }
    if v.y >= v.z {
        return 1u;
    }
    return 2u;
}

fn is_finite3(v: vec3<f32>) -> bool {
    let a = abs(v);
    return a.x < inf() && a.y < inf() && a.z < inf();
}

fn prepare_ray(r: Ray) -> PreparedRay {
    var p: PreparedRay;
    p.org = r.origin_tmin.xyz;
    p.dir = r.dir_tmax.xyz;
    p.tmin = r.origin_tmin.w;
    p.tmax = r.dir_tmax.w;
    p.valid = is_finite3(p.org) && is_finite3(p.dir) && any(p.dir != vec3<f32>(0.0))
        && p.tmin == p.tmin && p.tmax == p.tmax && p.tmin <= p.tmax;
    if !p.valid {
        return p;
    }
    let kz = argmax3(abs(p.dir));
    var kx = (kz + 1u) % 3u;
    var ky = (kx + 1u) % 3u;
    if p.dir[kz] < 0.0 {
        let t = kx;
        kx = ky;
        ky = t;
    }
    p.kx = kx;
    p.ky = ky;
    p.kz = kz;
    p.sz = 1.0 / p.dir[kz];
    p.sx = p.dir[kx] * p.sz;
    p.sy = p.dir[ky] * p.sz;
    let m = max(max(abs(p.dir.x), abs(p.dir.y)), abs(p.dir.z));
    p.t_scale = 1.0;
    if m >= WALK_DIR_MAX {
        p.t_scale = bitcast<f32>(((bitcast<u32>(m) >> 23u) - 15u) << 23u);
    }
    return p;
}

// A ray in grid space: cells are unit cubes; [t0, t1] is the segment to walk.
struct GridRay {
    o: vec3<f32>,
    d: vec3<f32>,
    inv_d: vec3<f32>,
    t0: f32,
    t1: f32,
}

// Components whose reciprocal overflows count as exactly parallel (as on the CPU).
fn flush_parallel(d: vec3<f32>) -> vec3<f32> {
    var out = d;
    for (var a = 0u; a < 3u; a++) {
        if !(abs(1.0 / d[a]) < inf()) {
            out[a] = 0.0;
        }
    }
    return out;
}

// GridRay::clipped: the ray clipped to the box [0, res] and to [tmin, tmax].
// Returns t0 > t1 (an empty segment) when nothing is left.
fn clip_ray(o: vec3<f32>, d_in: vec3<f32>, res: vec3<u32>, tmin: f32, tmax: f32) -> GridRay {
    var g: GridRay;
    let d = flush_parallel(d_in);
    g.o = o;
    g.d = d;
    g.inv_d = 1.0 / d;
    var t0 = tmin;
    var t1 = tmax;
    let r = vec3<f32>(res);
    var empty = false;
    for (var a = 0u; a < 3u; a++) {
        if d[a] == 0.0 {
            if !(o[a] >= 0.0 && o[a] <= r[a]) {
                empty = true;
            }
            continue;
        }
        let ta = (0.0 - o[a]) * g.inv_d[a];
        let tb = (r[a] - o[a]) * g.inv_d[a];
        let lo = select(tb, ta, ta <= tb);
        let hi = select(ta, tb, ta <= tb);
        if lo > t0 {
            t0 = lo;
        }
        if hi < t1 {
            t1 = hi;
        }
    }
    if empty || !(abs(t0) < inf()) || !(abs(t1) < inf()) || t0 > t1 {
        g.t0 = 1.0;
        g.t1 = 0.0;
        return g;
    }
    g.t0 = t0;
    g.t1 = t1;
    return g;
}

fn ray_is_empty(g: GridRay) -> bool {
    return g.t0 > g.t1;
}

// The cell containing the point at t, clamped into the grid.
fn cell_at(g: GridRay, t: f32, res: vec3<u32>) -> vec3<i32> {
    let p = floor(g.o + g.d * t);
    return vec3<i32>(clamp(p, vec3<f32>(0.0), vec3<f32>(res - vec3<u32>(1u))));
}

// GridRay::exit_of_cell: where the ray leaves cell c, capped at t1.
fn exit_of_cell(g: GridRay, c: vec3<i32>) -> f32 {
    var t = g.t1;
    for (var a = 0u; a < 3u; a++) {
        if g.d[a] != 0.0 {
            let plane = select(f32(c[a]), f32(c[a]) + 1.0, g.d[a] > 0.0);
            let ta = (plane - g.o[a]) * g.inv_d[a];
            if ta < t {
                t = ta;
            }
        }
    }
    return t;
}

// GridRay::child: the ray seen from the sub-grid of `sub_res` cells filling cell c, over
// [t0, t1]; not clipped (the walker clamps).
fn child_ray(g: GridRay, c: vec3<i32>, sub_res: vec3<u32>, t0: f32, t1: f32) -> GridRay {
    var r: GridRay;
    let s = vec3<f32>(sub_res);
    r.d = flush_parallel(g.d * s);
    r.o = (g.o - vec3<f32>(c)) * s;
    r.inv_d = 1.0 / r.d;
    r.t0 = t0;
    r.t1 = t1;
    return r;
}
