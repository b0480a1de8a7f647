//!include shared/bindings.wgsl
//!include shared/ray.wgsl
//!include shared/hit_{HIT_FLOAT}.wgsl
// Watertight ray/triangle test (Woop, Benthin, Wald 2013) with exact-sign edge functions.
// CPU port: crates/grid/src/triangle.rs (`intersect`), which computes the edge functions in
// f64; WebGPU's WGSL has no f64, so Kahan's FMA difference of products gives the same (exact)
// signs, and a hit's t, u, v come from shared/hit_f64.wgsl (bit-identical to the CPU) where the
// device has f64, else from shared/hit_f32.wgsl (`{HIT_FLOAT}`, crates/gpu/src/shaders.rs).

struct TriHit {
    hit: bool,
    t: f32,
    u: f32,
    v: f32,
}

// a*b - c*d with a relative error of ~1.5 ulp: the sign is exact.
fn diff_of_products(a: f32, b: f32, c: f32, d: f32) -> f32 {
    let w = c * d;
    let e = fma(-c, d, w);
    let f = fma(a, b, -w);
    return f + e;
}

// Triangle `tri` (packed, see `unpack_triangle`): 9 components read, not 12. On lavapipe each
// component of a storage read with a per-ray address costs a scalar loop over the SIMD lanes.
fn triangle_vertices(tri: u32) -> Vertices {
    return unpack_triangle(triangles[3u * tri], triangles[3u * tri + 1u], triangles[3u * tri + 2u].x);
}

fn intersect_triangle(r: PreparedRay, tri: u32) -> TriHit {
    var out: TriHit;
    out.hit = false;
    let vs = triangle_vertices(tri);
    let a = vs.a - r.org;
    let b = vs.b - r.org;
    let c = vs.c - r.org;
    let ax = a[r.kx] - r.sx * a[r.kz];
    let ay = a[r.ky] - r.sy * a[r.kz];
    let bx = b[r.kx] - r.sx * b[r.kz];
    let by = b[r.ky] - r.sy * b[r.kz];
    let cx = c[r.kx] - r.sx * c[r.kz];
    let cy = c[r.ky] - r.sy * c[r.kz];
    let u = diff_of_products(cx, by, cy, bx);
    let v = diff_of_products(ax, cy, ay, cx);
    let w = diff_of_products(bx, ay, by, ax);
    if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
        return out;
    }
    let z = r.sz * vec3<f32>(a[r.kz], b[r.kz], c[r.kz]);
    let h = hit_values(vec3<f32>(u, v, w), ax, ay, bx, by, cx, cy, z);
    let t = h.x;
    // A t that overflows f32 (either sign) is no hit (CPU: triangle.rs).
    if h.w == 0.0 || !(t >= r.tmin && t <= r.tmax && abs(t) < inf()) {
        return out;
    }
    out.hit = true;
    out.t = t;
    out.u = h.y;
    out.v = h.z;
    return out;
}

// Deterministic order: smaller t, then smaller triangle index.
fn closer(t: f32, tri: u32, b: Hit) -> bool {
    return t < b.t || (t == b.t && tri < b.triangle);
}

// Hashed per-ray mailbox (crates/grid/src/mailbox.rs): 16 direct-mapped entries.
const MAILBOX_SIZE: u32 = 16u;

fn miss() -> Hit {
    return Hit(inf(), NO_HIT, 0.0, 0.0);
}

fn empty_mailbox() -> array<u32, 16> {
    var m: array<u32, 16>;
    for (var i = 0u; i < MAILBOX_SIZE; i++) {
        m[i] = NO_HIT;
    }
    return m;
}
