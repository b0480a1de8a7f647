//! The WGSL binary64 arithmetic on u32 words (shaders/shared/soft_f64.wgsl) against the CPU's
//! f64, bit for bit: sums, differences, products, comparisons and the f32 conversion of values
//! in its domain (normal results), with the cases rounding gets wrong first: ties, carries out of
//! the rounding, cancellation, exponent gaps from 0 to past 64, signed zeros, subnormal f32.

use gridrt_gpu::shaders::compose;
use wgpu::util::DeviceExt;

use super::common::gpu;

/// Each case: a, b (f64 bits) and an f32's bits; each result: a + b, a − b, a · b (two words
/// each, low first), the f32 as f64, a < b, and a as an approximate f32.
const ENTRY: &str = r#"
@group(0) @binding(0) var<storage, read> cases: array<u32>;
@group(0) @binding(1) var<storage, read_write> results: array<u32>;

@compute @workgroup_size(64)
fn soft_f64_check(@builtin(global_invocation_id) id: vec3<u32>) {
    let i = id.x;
    if 5u * i >= arrayLength(&cases) {
        return;
    }
    let a = F64(cases[5u * i], cases[5u * i + 1u]);
    let b = F64(cases[5u * i + 2u], cases[5u * i + 3u]);
    let f = f64_from_f32(bitcast<f32>(cases[5u * i + 4u]));
    let out = array<F64, 4>(f64_add(a, b), f64_sub(a, b), f64_mul(a, b), f);
    for (var k = 0u; k < 4u; k++) {
        results[10u * i + 2u * k] = out[k].x;
        results[10u * i + 2u * k + 1u] = out[k].y;
    }
    results[10u * i + 8u] = select(0u, 1u, f64_lt(a, b));
    results[10u * i + 9u] = bitcast<u32>(f64_to_f32_approx(a));
}
"#;

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    /// A finite f64 with a binary exponent in [−e, e] and random sign and fraction, whose fraction
    /// sometimes keeps only a few high or low bits (sums of such values tie).
    fn value(&mut self, e: i64) -> f64 {
        let r = self.next();
        let exp = (1023 + (r % (2 * e as u64 + 1)) as i64 - e) as u64;
        let mut frac = self.next() & ((1 << 52) - 1);
        match r >> 60 {
            0 => frac &= 0xF << 48,
            1 => frac &= 0xF,
            2 => frac = (1 << 52) - 1,
            3 => frac = 0,
            _ => {}
        }
        f64::from_bits((r >> 63) << 63 | exp << 52 | frac)
    }
}

fn cases() -> Vec<(f64, f64, f32)> {
    let mut rng = Rng(0x2545_f491_4f6c_dd1d);
    let mut out = Vec::new();
    let special = [0.0, -0.0, 1.0, -1.0, 0.5, 1.5, 2.0, f64::EPSILON, 1.0 + f64::EPSILON, 1.0 - f64::EPSILON / 2.0];
    for &a in &special {
        for &b in &special {
            out.push((a, b, a as f32));
        }
    }
    // Ties and carries: 1 + 2^-53 (ties to even: down), (1 + 2^-52) + 2^-53 (ties to even: up),
    // 2 − 2^-53 + 2^-53, the largest fraction plus half an ulp.
    let u = f64::EPSILON;
    for (a, b) in [
        (1.0, u / 2.0),
        (1.0 + u, u / 2.0),
        (2.0 - u, u / 2.0),
        (2.0 - u, u),
        (1.0, -u / 4.0),
        (1.0, -u / 2.0),
        (1.0 + u, -u / 2.0),
    ] {
        out.push((a, b, 0.0));
        out.push((-a, -b, 0.0));
    }
    let f32s = [f32::MIN_POSITIVE, f32::from_bits(1), f32::from_bits(0x7f_ffff), -f32::from_bits(3), 1e-40, 3.4e38];
    for _ in 0..200_000 {
        let r = rng.next();
        let a = rng.value(480);
        let b = match r % 6 {
            // Exponent gaps 0 to 70: alignment, sticky bits, cancellation.
            0 => a * f64::from_bits((1023 - (rng.next() % 71)) << 52) * if r & 64 == 0 { 1.0 } else { -1.0 },
            // Near a: a few ulps away, either sign (catastrophic cancellation).
            1 => -f64::from_bits(a.to_bits().wrapping_add(rng.next() % 5)),
            2 => f64::from_bits(a.to_bits() ^ (rng.next() & 0xFF)),
            // Products of f32 values as exact insertion makes them.
            3 => (rng.value(60) as f32) as f64 * (rng.value(60) as f32) as f64,
            _ => rng.value(480),
        };
        let f = if r.is_multiple_of(11) {
            f32s[(r >> 8) as usize % f32s.len()]
        } else {
            f32::from_bits(rng.next() as u32 & 0xFF7F_FFFF)
        };
        out.push((a, b, f));
    }
    out
}

#[test]
fn soft_f64_equals_the_cpu_bit_for_bit() {
    let Some(ctx) = gpu() else { return };
    let source = compose("shared/soft_f64.wgsl").unwrap() + ENTRY;
    let module = ctx.device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("soft_f64 check"),
        source: wgpu::ShaderSource::Wgsl(source.into()),
    });
    let pipe = ctx.device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("soft_f64 check"),
        layout: None,
        module: &module,
        entry_point: Some("soft_f64_check"),
        compilation_options: Default::default(),
        cache: None,
    });
    let cases = cases();
    let mut words = Vec::with_capacity(cases.len() * 5);
    for &(a, b, f) in &cases {
        let (a, b) = (a.to_bits(), b.to_bits());
        words.extend([a as u32, (a >> 32) as u32, b as u32, (b >> 32) as u32, f.to_bits()]);
    }
    let input = ctx.device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("soft_f64 cases"),
        contents: bytemuck::cast_slice(&words),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let size = (cases.len() * 10 * 4) as u64;
    let output = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("soft_f64 results"),
        size,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let bind = ctx.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("soft_f64 check"),
        layout: &pipe.get_bind_group_layout(0),
        entries: &[
            wgpu::BindGroupEntry { binding: 0, resource: input.as_entire_binding() },
            wgpu::BindGroupEntry { binding: 1, resource: output.as_entire_binding() },
        ],
    });
    let read = ctx.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("soft_f64 readback"),
        size,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = ctx.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("soft_f64 check") });
    {
        let mut p = enc
            .begin_compute_pass(&wgpu::ComputePassDescriptor { label: Some("soft_f64 check"), timestamp_writes: None });
        p.set_pipeline(&pipe);
        p.set_bind_group(0, &bind, &[]);
        p.dispatch_workgroups((cases.len() as u32).div_ceil(64), 1, 1);
    }
    enc.copy_buffer_to_buffer(&output, 0, &read, 0, size);
    ctx.queue.submit([enc.finish()]);
    let got: Vec<u32> = gridrt_gpu::trace::read_back(ctx, &read, size, "soft_f64 results").unwrap();
    let word = |k: usize| got[k] as u64 | (got[k + 1] as u64) << 32;
    let mut wrong = Vec::new();
    for (i, &(a, b, f)) in cases.iter().enumerate() {
        let r = 10 * i;
        let expect = [(a + b).to_bits(), (a - b).to_bits(), (a * b).to_bits(), (f as f64).to_bits()];
        for (k, (name, e)) in ["+", "-", "*", "from f32"].iter().zip(expect).enumerate() {
            let g = word(r + 2 * k);
            // Signed zeros are not compared (no decision depends on them), nor results whose
            // exact value lies below the normal range (flushed to zero by design).
            let e_value = f64::from_bits(e);
            if g != e
                && !(e_value == 0.0 && f64::from_bits(g) == 0.0)
                && (e_value == 0.0 || e_value.abs() >= f64::MIN_POSITIVE)
            {
                wrong.push(format!("{a:e} {name} {b:e} (f32 {f:e}): expected {e:016x}, got {g:016x}"));
            }
        }
        if (got[r + 8] == 1) != (a < b) {
            wrong.push(format!("{a:e} < {b:e}: got {}", got[r + 8]));
        }
        // Within a relative 2^-23, never larger in magnitude, the same sign; zero below f32's
        // normal range.
        let approx = f32::from_bits(got[r + 9]) as f64;
        let close = if a.abs() < f32::MIN_POSITIVE as f64 {
            approx == 0.0
        } else if a.abs() >= 2f64.powi(128) {
            approx.is_infinite()
        } else {
            (approx - a).abs() <= a.abs() * 2f64.powi(-23) && approx.abs() <= a.abs() && approx.signum() == a.signum()
        };
        if !close {
            wrong.push(format!("{a:e} as f32: got {approx:e}"));
        }
    }
    assert!(
        wrong.is_empty(),
        "{} of {} cases wrong, e.g.:\n{}",
        wrong.len(),
        cases.len(),
        wrong[..wrong.len().min(20)].join("\n")
    );
}
