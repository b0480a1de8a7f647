// IEEE 754 binary64 arithmetic on u32 words, for what must round exactly as the CPU's f64 does
// where WGSL has no f64 (WebGPU) or may fuse a product into an FMA (native f64): exact
// insertion's overlap test (shared/overlap.wgsl). Round to nearest, ties to even; the
// operations follow Berkeley SoftFloat 3e (f64_add, f64_sub, f64_mul, roundPackToF64), so each
// result's bits are the CPU's. A value is its bit pattern, x the low word and y the high one.
//
// Domain: finite values. A result below f64's normal range would be flushed to zero (IEEE would
// give a subnormal); exact insertion never makes one: its inputs are f32 grid coordinates of at
// least 2^-149 times 1/extent (≥ 1e-84) or zero, its edges differences of such values (≥ 1e-100
// or zero), and its products at most cubic in them (≥ 1e-299, above f64's 2.2e-308). The unit
// test (crates/gpu/tests/suite/soft_f64.rs) compares every operation with the CPU's bit for bit.
//!include shared/u64.wgsl

alias F64 = vec2<u32>;

// A vector of three f64 (glam's DVec3), indexed so that its helpers below are loops: the
// shader compiler inlines every call, and each loop body holds one copy of an operation.
alias D3 = array<F64, 3>;

const F64_SIGN: u32 = 0x80000000u;

fn f64_is_zero(a: F64) -> bool {
    return a.x == 0u && (a.y & ~F64_SIGN) == 0u;
}

fn f64_neg(a: F64) -> F64 {
    return F64(a.x, a.y ^ F64_SIGN);
}

fn f64_abs(a: F64) -> F64 {
    return F64(a.x, a.y & ~F64_SIGN);
}

fn f64_sign(a: F64) -> u32 {
    return a.y >> 31u;
}

fn f64_exp(a: F64) -> i32 {
    return i32((a.y >> 20u) & 0x7ffu);
}

// The 52 fraction bits.
fn f64_frac(a: F64) -> U64 {
    return U64(a.x, a.y & 0xfffffu);
}

// SoftFloat's packToF64UI: the fields added, so a significand's leading bit at 52 adds one to
// the exponent.
fn f64_pack(sign: u32, exp: i32, sig: U64) -> F64 {
    return u64_add(U64(0u, (sign << 31u) | (u32(exp) << 20u)), sig);
}

// SoftFloat's roundPackToF64 (round to nearest even): `sig` has its leading bit at 62, `exp` is
// the biased exponent minus one. Overflow gives infinity, underflow zero (see the domain above).
fn f64_round_pack(sign: u32, exp: i32, sig: U64) -> F64 {
    if exp < 0 {
        return F64(0u, sign << 31u);
    }
    if exp > 0x7fc {
        return F64(0u, (sign << 31u) | 0x7ff00000u);
    }
    let round_bits = sig.x & 0x3ffu;
    var s = u64_shr(u64_add(sig, U64(0x200u, 0u)), 10u);
    if round_bits == 0x200u {
        s.x &= ~1u;
    }
    // A carry out of the rounding (s = 2^53) moves into the exponent through the addition.
    return f64_pack(sign, select(exp, 0, s.x == 0u && s.y == 0u), s);
}

// SoftFloat's normRoundPackToF64.
fn f64_norm_round_pack(sign: u32, exp: i32, sig: U64) -> F64 {
    let shift = i32(u64_clz(sig)) - 1;
    let e = exp - shift;
    if shift >= 10 && e >= 0 && e < 0x7fd {
        return f64_pack(sign, select(0, e, sig.x != 0u || sig.y != 0u), u64_shl(sig, u32(shift - 10)));
    }
    return f64_round_pack(sign, e, u64_shl(sig, u32(shift)));
}

// |a| + |b| with the sign `sign` (SoftFloat's addMagsF64), both non-zero.
fn f64_add_mags(a: F64, b: F64, sign: u32) -> F64 {
    let ea = f64_exp(a);
    let eb = f64_exp(b);
    var sa = f64_frac(a);
    var sb = f64_frac(b);
    let diff = ea - eb;
    if diff == 0 {
        let s = u64_shl(u64_add(U64(0u, 0x200000u), u64_add(sa, sb)), 9u);
        return f64_round_pack(sign, ea, s);
    }
    sa = u64_shl(sa, 9u);
    sb = u64_shl(sb, 9u);
    var e = ea;
    if diff < 0 {
        e = eb;
        sa = u64_shr_jam(u64_add(sa, U64(0u, 0x20000000u)), u32(-diff));
    } else {
        sb = u64_shr_jam(u64_add(sb, U64(0u, 0x20000000u)), u32(diff));
    }
    var s = u64_add(U64(0u, 0x20000000u), u64_add(sa, sb));
    if s.y < 0x40000000u {
        e -= 1;
        s = u64_shl(s, 1u);
    }
    return f64_round_pack(sign, e, s);
}

// |a| − |b| with the sign of a being `sign` (SoftFloat's subMagsF64), both non-zero.
fn f64_sub_mags(a: F64, b: F64, sign: u32) -> F64 {
    let ea = f64_exp(a);
    let eb = f64_exp(b);
    var sa = f64_frac(a);
    var sb = f64_frac(b);
    let diff = ea - eb;
    if diff == 0 {
        if sa.x == sb.x && sa.y == sb.y {
            return F64(0u, 0u);
        }
        var s = sign;
        var d: U64;
        if u64_lt(sa, sb) {
            s ^= 1u;
            d = u64_sub(sb, sa);
        } else {
            d = u64_sub(sa, sb);
        }
        let shift = i32(u64_clz(d)) - 11;
        let e = ea - 1 - shift;
        if e < 0 {
            return F64(0u, s << 31u);
        }
        return f64_pack(s, e, u64_shl(d, u32(shift)));
    }
    sa = u64_shl(sa, 10u);
    sb = u64_shl(sb, 10u);
    if diff < 0 {
        sa = u64_shr_jam(u64_add(sa, U64(0u, 0x40000000u)), u32(-diff));
        sb.y |= 0x40000000u;
        return f64_norm_round_pack(sign ^ 1u, eb - 1, u64_sub(sb, sa));
    }
    sb = u64_shr_jam(u64_add(sb, U64(0u, 0x40000000u)), u32(diff));
    sa.y |= 0x40000000u;
    return f64_norm_round_pack(sign, ea - 1, u64_sub(sa, sb));
}

fn f64_add(a: F64, b: F64) -> F64 {
    if f64_is_zero(a) {
        if f64_is_zero(b) {
            // −0 only for −0 + −0.
            return F64(0u, a.y & b.y);
        }
        return b;
    }
    if f64_is_zero(b) {
        return a;
    }
    let sign = f64_sign(a);
    if sign == f64_sign(b) {
        return f64_add_mags(a, b, sign);
    }
    return f64_sub_mags(a, b, sign);
}

fn f64_sub(a: F64, b: F64) -> F64 {
    return f64_add(a, f64_neg(b));
}

fn f64_mul(a: F64, b: F64) -> F64 {
    let sign = f64_sign(a) ^ f64_sign(b);
    if f64_is_zero(a) || f64_is_zero(b) {
        return F64(0u, sign << 31u);
    }
    var e = f64_exp(a) + f64_exp(b) - 0x3ff;
    let sa = u64_shl(u64_add(f64_frac(a), U64(0u, 0x100000u)), 10u);
    let sb = u64_shl(u64_add(f64_frac(b), U64(0u, 0x100000u)), 11u);
    // The 128-bit product's words w0 (lowest) to w3.
    let p00 = u32_mul_wide(sa.x, sb.x);
    let p01 = u32_mul_wide(sa.x, sb.y);
    let p10 = u32_mul_wide(sa.y, sb.x);
    let p11 = u32_mul_wide(sa.y, sb.y);
    let mid = u64_add(u64_add(U64(p00.y, 0u), U64(p01.x, 0u)), U64(p10.x, 0u));
    let high = u64_add(u64_add(p11, U64(p01.y, 0u)), u64_add(U64(p10.y, 0u), U64(mid.y, 0u)));
    var s = U64(high.x | select(0u, 1u, (p00.x | mid.x) != 0u), high.y);
    if s.y < 0x40000000u {
        e -= 1;
        s = u64_shl(s, 1u);
    }
    return f64_round_pack(sign, e, s);
}

// a < b (finite values; −0 equals +0).
fn f64_lt(a: F64, b: F64) -> bool {
    if f64_is_zero(a) && f64_is_zero(b) {
        return false;
    }
    let sa = f64_sign(a);
    if sa != f64_sign(b) {
        return sa == 1u;
    }
    if sa == 0u {
        return u64_lt(a, b);
    }
    return u64_lt(f64_abs(b), f64_abs(a));
}

fn f64_gt(a: F64, b: F64) -> bool {
    return f64_lt(b, a);
}

// f64::min and f64::max of finite values (which of two equal values is returned does not matter).
fn f64_min(a: F64, b: F64) -> F64 {
    return select(b, a, f64_lt(a, b));
}

fn f64_max(a: F64, b: F64) -> F64 {
    return select(b, a, f64_gt(a, b));
}

// An f32, exactly (subnormal f32 values become normal f64 ones).
fn f64_from_f32(x: f32) -> F64 {
    let bits = bitcast<u32>(x);
    let sign = bits & F64_SIGN;
    var e = i32((bits >> 23u) & 0xffu);
    var f = bits & 0x7fffffu;
    if e == 0 {
        if f == 0u {
            return F64(0u, sign);
        }
        // Normalize: the leading bit to position 23.
        let shift = countLeadingZeros(f) - 8u;
        f = (f << shift) & 0x7fffffu;
        e = 1 - i32(shift);
    } else if e == 0xff {
        return F64(f << 29u, sign | 0x7ff00000u | (f >> 3u));
    }
    return F64(f << 29u, sign | (u32(e + 896) << 20u) | (f >> 3u));
}

// An f32 within a relative 2^-23 of `a` (truncated; below f32's normal range, zero): for
// pre-filters whose tolerance covers it, never for a result that must equal the CPU's.
fn f64_to_f32_approx(a: F64) -> f32 {
    let e = f64_exp(a) - 896;
    let sign = a.y & F64_SIGN;
    if e <= 0 {
        return bitcast<f32>(sign);
    }
    if e >= 255 {
        return bitcast<f32>(sign | 0x7f800000u);
    }
    return bitcast<f32>(sign | (u32(e) << 23u) | ((a.y & 0xfffffu) << 3u) | (a.x >> 29u));
}

fn d3_to_f32_approx(a: D3) -> vec3<f32> {
    return vec3<f32>(f64_to_f32_approx(a[0]), f64_to_f32_approx(a[1]), f64_to_f32_approx(a[2]));
}

fn d3_from_f32(v: vec3<f32>) -> D3 {
    var r: D3;
    for (var c = 0u; c < 3u; c++) {
        r[c] = f64_from_f32(v[c]);
    }
    return r;
}

fn d3_sub(a: D3, b: D3) -> D3 {
    var r: D3;
    for (var c = 0u; c < 3u; c++) {
        r[c] = f64_sub(a[c], b[c]);
    }
    return r;
}

fn d3_mul(a: D3, b: D3) -> D3 {
    var r: D3;
    for (var c = 0u; c < 3u; c++) {
        r[c] = f64_mul(a[c], b[c]);
    }
    return r;
}

// glam's DVec3::dot: (x·x' + y·y') + z·z'.
fn d3_dot(a: D3, b: D3) -> F64 {
    var r = f64_mul(a[0], b[0]);
    for (var c = 1u; c < 3u; c++) {
        r = f64_add(r, f64_mul(a[c], b[c]));
    }
    return r;
}

// glam's DVec3::cross: component c is a[c+1]·b[c+2] − b[c+1]·a[c+2].
fn d3_cross(a: D3, b: D3) -> D3 {
    var r: D3;
    for (var c = 0u; c < 3u; c++) {
        let i = (c + 1u) % 3u;
        let j = (c + 2u) % 3u;
        r[c] = f64_sub(f64_mul(a[i], b[j]), f64_mul(b[i], a[j]));
    }
    return r;
}
