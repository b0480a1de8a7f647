//!include shared/walker_common.wgsl
// Amanatides-Woo 3DDDA in floating point: per axis the t of the next wall crossing, computed
// from the integer wall index (no drift, no FMA contraction).
// CPU port (same names, same arithmetic): crates/grid/src/traversal/amanatides_woo.rs.

struct Walker {
    cur: Cursor,
    g: GridRay,
    wall: vec3<f32>,
    t_max: vec3<f32>,
    // Output of walker_next.
    out_cell: vec3<i32>,
    out_t_exit: f32,
}

fn walker_init(g: GridRay, res_u: vec3<u32>) -> Walker {
    var w: Walker;
    w.cur = cursor_start(g, res_u);
    w.g = g;
    w.t_max = vec3<f32>(inf());
    for (var a = 0u; a < 3u; a++) {
        if g.d[a] != 0.0 {
            w.wall[a] = cursor_wall(w.cur, a);
            w.t_max[a] = (w.wall[a] - g.o[a]) * g.inv_d[a];
        }
    }
    return w;
}

// The current cell's exit; then the next crossing.
fn walker_advance(w: ptr<function, Walker>) -> bool {
    let tm = (*w).t_max;
    let a = argmin3_of(tm.x <= tm.y, tm.x <= tm.z, tm.y <= tm.z);
    let t = tm[a];
    (*w).out_t_exit = min(t, (*w).g.t1);
    if t != t || t > (*w).g.t1 {
        (*w).cur.done = true;
    } else {
        (*w).cur = cursor_cross((*w).cur, a);
        (*w).wall[a] += f32((*w).cur.step[a]);
        (*w).t_max[a] = ((*w).wall[a] - (*w).g.o[a]) * (*w).g.inv_d[a];
    }
    return true;
}
