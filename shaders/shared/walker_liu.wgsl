//!include shared/walker_common.wgsl
//!include shared/u64.wgsl
// Liu's integer one-pass walker: slice by slice along the dominant axis in 20-bit fixed point,
// the cells of each slice queued in order (exact 64-bit wall comparisons).
// CPU port (same names, same arithmetic): crates/grid/src/traversal/liu.rs.

const LIU_FRAC_BITS: u32 = 20u;
const LIU_ONE: f32 = 1048576.0;
const LIU_QUEUE: u32 = 8u;

struct Walker {
    cur: Cursor,
    g: GridRay,
    u: u32,
    v: u32,
    w: u32,
    slices_left: i32,
    k: vec2<i32>,
    end: vec2<i32>,
    last: vec2<i32>,
    // The slice's queue of LIU_QUEUE cells, in named members (liu_queue_store/load): an
    // array<vec3<i32>, 8> indexed by the queue position is per-lane scratch memory on
    // lavapipe, read and written lane by lane; a switch over named members stays in registers.
    q0: vec3<i32>,
    q1: vec3<i32>,
    q2: vec3<i32>,
    q3: vec3<i32>,
    q4: vec3<i32>,
    q5: vec3<i32>,
    q6: vec3<i32>,
    q7: vec3<i32>,
    queued: u32,
    emitted: u32,
    // Output of walker_next.
    out_cell: vec3<i32>,
    out_t_exit: f32,
}

fn liu_fix(x: f32, hi: i32) -> i32 {
    return i32(floor(clamp(x, -1.0, f32(hi) + 1.0) * LIU_ONE + 0.5));
}

fn liu_fix_slope(k: f32) -> i32 {
    return i32(floor(clamp(k, -1.0, 1.0) * LIU_ONE + 0.5));
}

fn liu_cell_of(x: i32, s: i32) -> i32 {
    if s >= 0 {
        return x >> LIU_FRAC_BITS;
    }
    return -((-x) >> LIU_FRAC_BITS) - 1;
}

fn liu_target(x: i32, s: i32, c: i32, hi: i32) -> i32 {
    if s == 0 {
        return c;
    }
    let t = clamp(liu_cell_of(x, s), 0, hi - 1);
    if (t - c) * s < 0 {
        return c;
    }
    return t;
}

fn liu_queue_store(w: ptr<function, Walker>, i: u32, c: vec3<i32>) {
    switch i {
        case 0u: { (*w).q0 = c; }
        case 1u: { (*w).q1 = c; }
        case 2u: { (*w).q2 = c; }
        case 3u: { (*w).q3 = c; }
        case 4u: { (*w).q4 = c; }
        case 5u: { (*w).q5 = c; }
        case 6u: { (*w).q6 = c; }
        default: { (*w).q7 = c; }
    }
}

fn liu_queue_load(w: ptr<function, Walker>, i: u32) -> vec3<i32> {
    switch i {
        case 0u: { return (*w).q0; }
        case 1u: { return (*w).q1; }
        case 2u: { return (*w).q2; }
        case 3u: { return (*w).q3; }
        case 4u: { return (*w).q4; }
        case 5u: { return (*w).q5; }
        case 6u: { return (*w).q6; }
        default: { return (*w).q7; }
    }
}

fn liu_fill_slice(w: ptr<function, Walker>) {
    let v = (*w).v;
    let ww = (*w).w;
    let res = (*w).cur.res;
    var cell = (*w).cur.cell;
    (*w).q0 = cell;
    (*w).queued = 1u;
    (*w).emitted = 0u;
    let sv = (*w).cur.step[v];
    let sw = (*w).cur.step[ww];
    let tv = liu_target((*w).end.x, sv, cell[v], res[v]);
    let tw = liu_target((*w).end.y, sw, cell[ww], res[ww]);
    loop {
        if !((cell[v] != tv || cell[ww] != tw) && (*w).queued < LIU_QUEUE) {
            break;
        }
        var move_v = false;
        if cell[v] == tv {
            move_v = false;
        } else if cell[ww] == tw {
            move_v = true;
        } else {
            let wall_v = (cell[v] + select(0, 1, sv > 0)) << LIU_FRAC_BITS;
            let wall_w = (cell[ww] + select(0, 1, sw > 0)) << LIU_FRAC_BITS;
            let ev = u32(abs((*w).end.x - wall_v));
            let ew = u32(abs((*w).end.y - wall_w));
            move_v = !u64_lt(u32_mul_wide(ev, u32(abs((*w).k.y))), u32_mul_wide(ew, u32(abs((*w).k.x))));
        }
        if move_v {
            cell[v] += sv;
        } else {
            cell[ww] += sw;
        }
        liu_queue_store(w, (*w).queued, cell);
        (*w).queued += 1u;
    }
    (*w).cur.cell = cell;
}

fn liu_next_slice(w: ptr<function, Walker>) -> bool {
    if (*w).slices_left == 0 {
        return false;
    }
    (*w).slices_left -= 1;
    (*w).cur = cursor_cross((*w).cur, (*w).u);
    if (*w).cur.done {
        return false;
    }
    if (*w).slices_left == 0 {
        (*w).end = (*w).last;
    } else {
        (*w).end += (*w).k;
    }
    liu_fill_slice(w);
    return true;
}

fn walker_init(g: GridRay, res_u: vec3<u32>) -> Walker {
    var w: Walker;
    w.cur = cursor_start(g, res_u);
    w.g = g;
    let c = w.cur.cell;
    let u = argmax3(abs(g.d));
    let v = (u + 1u) % 3u;
    let ww = (u + 2u) % 3u;
    w.u = u;
    w.v = v;
    w.w = ww;
    let end_cell = cell_at(g, g.t1, res_u);
    let p0 = g.o + g.d * g.t0;
    let p1 = g.o + g.d * g.t1;
    var su = w.cur.step[u];
    if su == 0 {
        su = 1;
    }
    w.cur.step[u] = su;
    w.slices_left = max((end_cell[u] - c[u]) * su, 0);
    var kv = 0.0;
    var kw = 0.0;
    if g.d[u] != 0.0 {
        kv = g.d[v] * g.inv_d[u];
        kw = g.d[ww] * g.inv_d[u];
    }
    w.k = vec2<i32>(liu_fix_slope(kv * f32(su)), liu_fix_slope(kw * f32(su)));
    w.last = vec2<i32>(liu_fix(p1[v], w.cur.res[v]), liu_fix(p1[ww], w.cur.res[ww]));
    if w.slices_left == 0 {
        w.end = w.last;
    } else {
        let du = cursor_wall(w.cur, u) - p0[u];
        w.end = vec2<i32>(liu_fix(p0[v] + du * kv, w.cur.res[v]), liu_fix(p0[ww] + du * kw, w.cur.res[ww]));
    }
    liu_fill_slice(&w);
    return w;
}

// The next queued cell, moving into the next slice when the queue is empty.
fn walker_advance(w: ptr<function, Walker>) -> bool {
    if (*w).emitted == (*w).queued && !liu_next_slice(w) {
        (*w).cur.done = true;
        return false;
    }
    let c = liu_queue_load(w, (*w).emitted);
    (*w).emitted += 1u;
    (*w).out_cell = c;
    (*w).out_t_exit = exit_of_cell((*w).g, c);
    return true;
}
