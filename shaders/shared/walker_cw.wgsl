//!include shared/walker_common.wgsl
// Cleary-Wyvill: distances to the next wall per axis in 2^30 fixed point over the clipped
// segment, advanced by integer increments.
// CPU port (same names, same arithmetic): crates/grid/src/traversal/cleary_wyvill.rs.

const CW_SCALE: u32 = 1073741824u; // 2^30
const CW_BEYOND: u32 = 1073741825u;

struct Walker {
    done: bool,
    g: GridRay,
    res: vec3<i32>,
    cell: vec3<i32>,
    step: vec3<i32>,
    dist: vec3<u32>,
    delta: vec3<u32>,
    scale: f32,
    // Output of walker_next.
    out_cell: vec3<i32>,
    out_t_exit: f32,
}

fn argmin3u(v: vec3<u32>) -> u32 {
    if v.x <= v.y && v.x <= v.z {
        return 0u;
    }
    if v.y <= v.z {
        return 1u;
    }
    return 2u;
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
    w.done = false;
    w.g = g;
    w.res = vec3<i32>(res_u);
    let c = cell_at(g, g.t0, res_u);
    w.cell = c;
    let seg = g.t1 - g.t0;
    w.scale = f32(CW_SCALE) * (1.0 / seg);
    let single = seg != seg || seg <= 0.0 || !(w.scale < inf());
    w.dist = vec3<u32>(CW_BEYOND);
    w.delta = vec3<u32>(CW_BEYOND);
    for (var a = 0u; a < 3u; a++) {
        w.step[a] = sign_step(g.d[a]);
        if g.d[a] == 0.0 || single {
            w.step[a] = 0;
            continue;
        }
        let plane = select(f32(c[a]), f32(c[a]) + 1.0, g.d[a] > 0.0);
        let t_cross = (plane - g.o[a]) * g.inv_d[a];
        w.dist[a] = cw_to_fixed((t_cross - g.t0) * w.scale);
        w.delta[a] = max(cw_to_fixed(abs(g.inv_d[a]) * w.scale), 1u);
    }
    return w;
}

// Advances to the next cell: sets out_cell / out_t_exit and returns true, or false when done.
fn walker_next(w: ptr<function, Walker>) -> bool {
    if (*w).done {
        return false;
    }
    let a = argmin3u((*w).dist);
    let d = (*w).dist[a];
    (*w).out_cell = (*w).cell;
    if d >= CW_SCALE {
        (*w).out_t_exit = (*w).g.t1;
    } else {
        (*w).out_t_exit = (*w).g.t0 + f32(d) / (*w).scale;
    }
    if d > CW_SCALE {
        (*w).done = true;
    } else {
        (*w).cell[a] += (*w).step[a];
        if (*w).cell[a] < 0 || (*w).cell[a] >= (*w).res[a] {
            (*w).done = true;
        }
        (*w).dist[a] = min((*w).dist[a] + (*w).delta[a], CW_BEYOND);
    }
    return true;
}
