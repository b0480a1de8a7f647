//!include shared/closest_hit.wgsl
// Coherent grid traversal (Wald, Ize, Kensler, Knoll, Parker 2006; the survey's §2.2): one
// workgroup traces an 8×8 tile of an image's rays as a packet. The workgroup finds the axis every
// ray crosses with the same sign and bounds the rays' lines; then every invocation walks the
// same slices along that axis and visits the same rectangle of cells in each (`test_box`,
// defined by the kernel file), testing the cells' triangles against its own ray, so the
// invocations read the same cells and triangles in lockstep. An invocation stops when its best
// hit lies before the slice's far plane or its segment ends. Packets whose rays do not share a
// sign on one axis trace each ray with the structure's own `walk`.
// CPU port: crates/grid/src/coherent/ (`Packet::trace`, `trace_image`); the CPU port narrows
// the frustum as rays leave and tests eight rays at once, the kernel keeps the frustum.
//
// Exactness: every bound is computed in f32 and widened by PACKET_MARGIN cells plus a relative
// slack of 1e-6 (about 8 ulp) of the magnitudes it was computed from, more than the rounding
// of the few operations behind it, so each slice's rectangle holds every cell the ray's line
// crosses there and a ray stops only when its hit lies in a slice already visited. The
// triangle test and the closest-hit rule are the single-ray ones: hits are bit-identical.

// Packet edge in pixels (the workgroup is PACKET_EDGE × PACKET_EDGE).
const PACKET_EDGE: u32 = 8u;
// Widening of each bound, in cells, on top of the relative slack.
const PACKET_MARGIN: f32 = 0.001953125;
// Relative slack of a bound computed in f32 (about 8 ulp).
const PACKET_SLACK: f32 = 1e-6;

// Reductions over the packet as atomic maxima of order keys (workgroup memory starts at zero,
// the identity of a maximum; a minimum is the maximum of the inverted key):
// 0-5: direction min (inverted) and max per axis; 6-11: origin min (inverted) and max per axis;
// 12-17: the same for the segment ends. No valid ray leaves the direction keys at zero.
const KEY_DIR: u32 = 0u;
const KEY_ORG: u32 = 6u;
const KEY_END: u32 = 12u;
// The axis keys at AXIS_KEYS, the line keys (below) at LINE_KEYS.
const AXIS_KEYS: u32 = 0u;
const LINE_KEYS: u32 = 18u;
var<workgroup> wg_keys: array<atomic<u32>, 36>;
// Per reference plane p (0: origins, 1: ends) and other axis k: intercept min (inverted) and max
// at 4p + 2k, +1; slopes' min (inverted) and max at 8 + 2k, +1; the steps' first (inverted) and
// last at 12, 13 (18 entries, as the axis keys, so one function loads both).
// Plain copies for uniform loads.
var<workgroup> wg_copy: array<u32, 18>;

// A float's key, ordered as the float (for atomicMax).
fn order_key(f: f32) -> u32 {
    let b = bitcast<u32>(f);
    return select(b | 0x80000000u, ~b, (b & 0x80000000u) != 0u);
}

fn from_key(k: u32) -> f32 {
    return bitcast<f32>(select(~k, k & 0x7fffffffu, (k & 0x80000000u) != 0u));
}

fn slack(magnitude: f32) -> f32 {
    return PACKET_MARGIN + PACKET_SLACK * magnitude;
}

// A reduction's results, copied into `wg_copy` and loaded uniformly (barriers included).
fn uniform_keys(base: u32) -> array<u32, 18> {
    workgroupBarrier();
    if all(local_id == vec3<u32>(0u)) {
        for (var k = 0u; k < 18u; k++) {
            wg_copy[k] = atomicLoad(&wg_keys[base + k]);
        }
    }
    return workgroupUniformLoad(&wg_copy);
}

// Tests the triangles of every occupied cell in the box lo..=hi of a flat grid
// (shared/flat_grid.wgsl) whose cell is among this ray's own (own_lo..=own_hi) against this
// invocation's ray.
fn test_cells(lo: vec3<u32>, hi: vec3<u32>, own_lo: vec3<u32>, own_hi: vec3<u32>) {
    let use_mailbox = params.mailbox != 0u;
    for (var z = max(lo.z, own_lo.z); z <= min(hi.z, own_hi.z); z++) {
        for (var y = max(lo.y, own_lo.y); y <= min(hi.y, own_hi.y); y++) {
            let row = params.res.x * (y + params.res.y * z);
            for (var x = max(lo.x, own_lo.x); x <= min(hi.x, own_hi.x); x++) {
                visit_cell();
                let idx = row + x;
                if !is_occupied(idx) {
                    continue;
                }
                let r = refs_of(idx);
                for (var k = r.x; k < r.y; k++) {
                    test_triangle(refs[k], use_mailbox);
                }
            }
        }
    }
}

var<private> local_id: vec3<u32>;

// The slice of grid coordinate `s` on axis `a` (clamped into the grid).
fn slice_of(s: f32, n: u32) -> u32 {
    return u32(clamp(floor(s), 0.0, f32(n - 1u)));
}

@compute @workgroup_size(8, 8)
fn trace_packets(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>) {
    local_id = lid;
    let width = params.image_width;
    // This invocation's pixel of the image, and its ray in this dispatch (rays hold the pixels
    // first_ray .. first_ray + ray_count of the image, row-major).
    let row = params.first_ray / width + wg.y * PACKET_EDGE + lid.y;
    let col = wg.x * PACKET_EDGE + lid.x;
    let pixel = row * width + col;
    let mine = col < width && pixel >= params.first_ray && pixel - params.first_ray < params.ray_count;
    let i = pixel - params.first_ray;
    var live = false;
    if mine {
        live = begin_ray(i);
    } else {
        best = miss();
    }
    let g = top_ray;
    if live {
        let end = g.o + g.d * g.t1;
        for (var a = 0u; a < 3u; a++) {
            atomicMax(&wg_keys[AXIS_KEYS + KEY_DIR + 2u * a], ~order_key(g.d[a]));
            atomicMax(&wg_keys[AXIS_KEYS + KEY_DIR + 2u * a + 1u], order_key(g.d[a]));
            atomicMax(&wg_keys[AXIS_KEYS + KEY_ORG + 2u * a], ~order_key(g.o[a]));
            atomicMax(&wg_keys[AXIS_KEYS + KEY_ORG + 2u * a + 1u], order_key(g.o[a]));
            atomicMax(&wg_keys[AXIS_KEYS + KEY_END + 2u * a], ~order_key(end[a]));
            atomicMax(&wg_keys[AXIS_KEYS + KEY_END + 2u * a + 1u], order_key(end[a]));
            // A ray of a scaled walk (a direction of 2^16 or more) makes the packet incoherent:
            // its rays are traced alone, where the walk widens its segment and stops by the hits'
            // rounded t (as the CPU's packets do: SliceWalk::new).
            if ray.t_scale > 1.0 {
                atomicMax(&wg_keys[AXIS_KEYS + KEY_DIR + 2u * a], ~order_key(-1.0));
                atomicMax(&wg_keys[AXIS_KEYS + KEY_DIR + 2u * a + 1u], order_key(1.0));
            }
        }
    }
    let keys = uniform_keys(AXIS_KEYS);
    // Any real float's key is above zero.
    let any_valid = keys[KEY_DIR + 1u] != 0u;
    // The walk axis: the dominant axis of the middle of the directions' box; the packet is
    // coherent when every valid ray moves along it with the same sign.
    var lo_d: vec3<f32>;
    var hi_d: vec3<f32>;
    for (var a = 0u; a < 3u; a++) {
        lo_d[a] = from_key(~keys[KEY_DIR + 2u * a]);
        hi_d[a] = from_key(keys[KEY_DIR + 2u * a + 1u]);
    }
    let axis = argmax3(abs(lo_d + hi_d));
    let positive = lo_d[axis] > 0.0;
    let same_sign = any_valid && (positive || hi_d[axis] < 0.0);
    if !same_sign {
        if live {
            walk(top_ray);
        }
        if mine {
            end_ray(i);
        }
        return;
    }
    let n_axis = params.res[axis];
    let u = array<u32, 2>((axis + 1u) % 3u, (axis + 2u) % 3u);
    // Candidate reference planes: the middle of the origins (camera rays share theirs) and of the
    // segments' ends (shadow rays share the light).
    let planes = array<f32, 2>(
        0.5 * (from_key(~keys[KEY_ORG + 2u * axis]) + from_key(keys[KEY_ORG + 2u * axis + 1u])),
        0.5 * (from_key(~keys[KEY_END + 2u * axis]) + from_key(keys[KEY_END + 2u * axis + 1u])));
    // This ray's line: the other coordinates as c + slope · (s − plane) of the axis coordinate s;
    // its first and last step.
    var first = 0xffffffffu;
    var last = 0u;
    if live {
        let t_per_cell = 1.0 / g.d[axis];
        for (var k = 0u; k < 2u; k++) {
            let slope = g.d[u[k]] * t_per_cell;
            let slope_err = PACKET_SLACK * abs(slope);
            atomicMax(&wg_keys[LINE_KEYS + 8u + 2u * k], ~order_key(slope - slope_err));
            atomicMax(&wg_keys[LINE_KEYS + 9u + 2u * k], order_key(slope + slope_err));
            for (var p = 0u; p < 2u; p++) {
                let run = slope * (planes[p] - g.o[axis]);
                let c = g.o[u[k]] + run;
                let err = PACKET_SLACK * (abs(g.o[u[k]]) + abs(run) + abs(c));
                atomicMax(&wg_keys[LINE_KEYS + 4u * p + 2u * k], ~order_key(c - err));
                atomicMax(&wg_keys[LINE_KEYS + 4u * p + 2u * k + 1u], order_key(c + err));
            }
        }
        let e = g.o[axis] + g.d[axis] * g.t0;
        let x = g.o[axis] + g.d[axis] * g.t1;
        let m0 = slack(abs(g.o[axis]) + abs(g.d[axis] * g.t0));
        let m1 = slack(abs(g.o[axis]) + abs(g.d[axis] * g.t1));
        if positive {
            first = slice_of(e - m0, n_axis);
            last = slice_of(x + m1, n_axis);
        } else {
            first = n_axis - 1u - slice_of(e + m0, n_axis);
            last = n_axis - 1u - slice_of(x - m1, n_axis);
        }
        atomicMax(&wg_keys[LINE_KEYS + 12], ~first);
        atomicMax(&wg_keys[LINE_KEYS + 13], last);
    }
    let lines = uniform_keys(LINE_KEYS);
    var c_lo: array<array<f32, 2>, 2>;
    var c_hi: array<array<f32, 2>, 2>;
    var spread = array<f32, 2>(0.0, 0.0);
    for (var p = 0u; p < 2u; p++) {
        for (var k = 0u; k < 2u; k++) {
            c_lo[p][k] = from_key(~lines[4u * p + 2u * k]);
            c_hi[p][k] = from_key(lines[4u * p + 2u * k + 1u]);
            spread[p] += c_hi[p][k] - c_lo[p][k];
        }
    }
    // The plane the rays are closest together at (a non-finite spread is never chosen).
    let pick = select(0u, 1u, spread[1] < spread[0]);
    let s_ref = planes[pick];
    let slope_lo = array<f32, 2>(from_key(~lines[8]), from_key(~lines[10]));
    let slope_hi = array<f32, 2>(from_key(lines[9]), from_key(lines[11]));
    let first_step = ~lines[12];
    let last_step = lines[13];
    var walking = live;
    for (var j = first_step; j <= last_step && walking; j++) {
        let k = select(n_axis - 1u - j, j, positive);
        let near = select(f32(k + 1u), f32(k), positive);
        let far = select(f32(k), f32(k + 1u), positive);
        var lo = vec3<u32>(0u);
        var hi = vec3<u32>(0u);
        lo[axis] = k;
        hi[axis] = k;
        var inside = true;
        for (var n = 0u; n < 2u; n++) {
            var a = inf();
            var b = -inf();
            for (var q = 0u; q < 2u; q++) {
                let ds = select(far, near, q == 0u) - s_ref;
                let sl = select(slope_hi[n], slope_lo[n], ds >= 0.0);
                let sh = select(slope_lo[n], slope_hi[n], ds >= 0.0);
                let va = c_lo[pick][n] + sl * ds;
                let vb = c_hi[pick][n] + sh * ds;
                a = min(a, va - slack(abs(c_lo[pick][n]) + abs(sl * ds)));
                b = max(b, vb + slack(abs(c_hi[pick][n]) + abs(sh * ds)));
            }
            let r = f32(params.res[u[n]]);
            if b < 0.0 || a >= r || a != a || b != b {
                inside = false;
            }
            lo[u[n]] = slice_of(a, params.res[u[n]]);
            hi[u[n]] = slice_of(b, params.res[u[n]]);
        }
        if inside {
            // This ray's own cells in the slice (its line between the two planes, widened as
            // the rectangle is): the invocation tests only their triangles, while every
            // invocation steps through the packet's box together.
            var own_lo = lo;
            var own_hi = hi;
            if walking {
                let t_near = (near - g.o[axis]) / g.d[axis];
                let t_far = (far - g.o[axis]) / g.d[axis];
                for (var n = 0u; n < 2u; n++) {
                    let va = g.o[u[n]] + g.d[u[n]] * t_near;
                    let vb = g.o[u[n]] + g.d[u[n]] * t_far;
                    // The planes' offsets from the origin are rounded too: times the slope.
                    let offsets = abs(g.d[u[n]] / g.d[axis]) * (abs(near) + abs(far) + 2.0 * abs(g.o[axis]));
                    let m = slack(abs(g.o[u[n]]) + abs(g.d[u[n]] * t_near) + abs(g.d[u[n]] * t_far) + offsets);
                    own_lo[u[n]] = max(lo[u[n]], slice_of(min(va, vb) - m, params.res[u[n]]));
                    own_hi[u[n]] = min(hi[u[n]], slice_of(max(va, vb) + m, params.res[u[n]]));
                }
            }
            test_box(lo, hi, own_lo, own_hi);
        }
        // This ray stops after its last slice, or once its best hit lies in a slice visited
        // (an occlusion query: once it has a hit).
        if j >= last || (params.query == QUERY_ANY && best.t < inf()) {
            walking = false;
        } else if best.t < inf() {
            let best_t = best.t * ray.t_scale;
            let s = g.o[axis] + g.d[axis] * best_t;
            let m = slack(abs(g.o[axis]) + abs(g.d[axis] * best_t));
            walking = select(s - m <= far, s + m >= far, positive);
        }
    }
    if mine {
        end_ray(i);
    }
}
