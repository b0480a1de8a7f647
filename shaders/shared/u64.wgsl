// 64-bit unsigned integers as two u32 words (x the low one, y the high one), which WGSL lacks:
// the wide product of two u32 (Liu's exact wall comparisons, shared/walker_liu.wgsl) and what
// binary64 on u32 words needs (shared/soft_f64.wgsl).

alias U64 = vec2<u32>;

fn u64_add(a: U64, b: U64) -> U64 {
    let lo = a.x + b.x;
    return U64(lo, a.y + b.y + select(0u, 1u, lo < a.x));
}

fn u64_sub(a: U64, b: U64) -> U64 {
    return U64(a.x - b.x, a.y - b.y - select(0u, 1u, a.x < b.x));
}

fn u64_lt(a: U64, b: U64) -> bool {
    return a.y < b.y || (a.y == b.y && a.x < b.x);
}

// a << n for n < 64 (WGSL takes a shift amount modulo 32, so every case is explicit).
fn u64_shl(a: U64, n: u32) -> U64 {
    if n == 0u {
        return a;
    }
    if n >= 32u {
        return U64(0u, a.x << (n - 32u));
    }
    return U64(a.x << n, (a.y << n) | (a.x >> (32u - n)));
}

// a >> n for n < 64.
fn u64_shr(a: U64, n: u32) -> U64 {
    if n == 0u {
        return a;
    }
    if n >= 32u {
        return U64(a.y >> (n - 32u), 0u);
    }
    return U64((a.x >> n) | (a.y << (32u - n)), a.y >> n);
}

// a >> n with every bit shifted out ORed into bit 0 (SoftFloat's shiftRightJam64).
fn u64_shr_jam(a: U64, n: u32) -> U64 {
    if n >= 64u {
        return U64(select(0u, 1u, (a.x | a.y) != 0u), 0u);
    }
    let r = u64_shr(a, n);
    let back = u64_shl(r, n);
    return U64(r.x | select(0u, 1u, back.x != a.x || back.y != a.y), r.y);
}

fn u64_clz(a: U64) -> u32 {
    if a.y != 0u {
        return countLeadingZeros(a.y);
    }
    return 32u + countLeadingZeros(a.x);
}

// The 64-bit product of two u32.
fn u32_mul_wide(a: u32, b: u32) -> U64 {
    let al = a & 0xffffu;
    let ah = a >> 16u;
    let bl = b & 0xffffu;
    let bh = b >> 16u;
    let p0 = al * bl;
    let p1 = al * bh;
    let p2 = ah * bl;
    let p3 = ah * bh;
    let mid = p1 + p2;
    let mid_carry = select(0u, 0x10000u, mid < p1);
    let lo = p0 + (mid << 16u);
    return U64(lo, p3 + (mid >> 16u) + mid_carry + select(0u, 1u, lo < p0));
}
