//!include shared/walker_common.wgsl
// Cleary-Wyvill: distances to the next wall per axis in 2^30 fixed point over the clipped
// segment, advanced by integer increments.
// CPU port (same names, same arithmetic): crates/grid/src/traversal/cleary_wyvill.rs.

const CW_SCALE: u32 = 1073741824u; // 2^30
const CW_BEYOND: u32 = 1073741825u;
const CW_UNIT: f32 = 9.313225746154785e-10; // 2^-30

struct Walker {
    cur: Cursor,
    g: GridRay,
    dist: vec3<u32>,
    delta: vec3<u32>,
    // 1 / (t1 - t0): fixed-point units are this times 2^30 per unit of t, applied in two
    // steps so that a segment shorter than 2^-98 (a huge direction) does not overflow them.
    inv_seg: f32,
    // Output of walker_next.
    out_cell: vec3<i32>,
    out_t_exit: f32,
}

fn cw_to_fixed(x: f32) -> u32 {
    if x >= f32(CW_BEYOND) {
        return CW_BEYOND;
    }
    if x > 0.0 {
        return u32(x);
    }
    return 0u;
}

fn walker_init(g: GridRay, res_u: vec3<u32>) -> Walker {
    var w: Walker;
    w.cur = cursor_start(g, res_u);
    w.g = g;
    let seg = g.t1 - g.t0;
    w.inv_seg = 1.0 / seg;
    let single = seg != seg || seg <= 0.0 || !(w.inv_seg < inf());
    w.dist = vec3<u32>(CW_BEYOND);
    w.delta = vec3<u32>(CW_BEYOND);
    for (var a = 0u; a < 3u; a++) {
        if g.d[a] == 0.0 || single {
            w.cur.step[a] = 0;
            continue;
        }
        let t_cross = (cursor_wall(w.cur, a) - g.o[a]) * g.inv_d[a];
        w.dist[a] = cw_to_fixed(((t_cross - g.t0) * w.inv_seg) * f32(CW_SCALE));
        w.delta[a] = max(cw_to_fixed((abs(g.inv_d[a]) * w.inv_seg) * f32(CW_SCALE)), 1u);
    }
    return w;
}

// The current cell's exit; then the next crossing.
fn walker_advance(w: ptr<function, Walker>) -> bool {
    let dv = (*w).dist;
    let a = argmin3_of(dv.x <= dv.y, dv.x <= dv.z, dv.y <= dv.z);
    let d = dv[a];
    if d >= CW_SCALE {
        (*w).out_t_exit = (*w).g.t1;
    } else {
        (*w).out_t_exit = (*w).g.t0 + (f32(d) * CW_UNIT) / (*w).inv_seg;
    }
    if d > CW_SCALE {
        (*w).cur.done = true;
    } else {
        (*w).cur = cursor_cross((*w).cur, a);
        (*w).dist[a] = min((*w).dist[a] + (*w).delta[a], CW_BEYOND);
    }
    return true;
}
