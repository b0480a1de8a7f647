//! Every .wgsl under shaders/ composes, parses and validates with naga (all validation flags);
//! the closest-hit include, which calls its kernel's `walk`, through every kernel.

use gridrt_gpu::GpuWalker;
use gridrt_gpu::shaders::{HitFloat, SOURCES, compose_for};

#[test]
fn every_wgsl_file_composes_parses_and_validates() {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shaders");
    let mut on_disk = Vec::new();
    let mut stack = vec![dir.clone()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            if p.is_dir() {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "wgsl") {
                on_disk.push(p.strip_prefix(&dir).unwrap().to_string_lossy().replace('\\', "/"));
            }
        }
    }
    on_disk.sort();
    assert!(!on_disk.is_empty(), "no shaders found under {}", dir.display());
    let mut embedded: Vec<String> = SOURCES.iter().map(|(n, _)| n.to_string()).collect();
    embedded.sort();
    assert_eq!(on_disk, embedded, "shaders/ and the embedded list in crates/gpu/src/shaders.rs differ");
    let mut failures = Vec::new();
    // Every file with every walker a trace kernel can be composed with. Some includes call what
    // their includer defines, so they are validated through it: the closest-hit include calls
    // each kernel's `walk`, the walkers' common part each walker's `walker_advance`, the packet
    // kernel each packet file's `test_box`, the macrocell kernel's walks (one per walker) its
    // bindings and `macrocell_empty`; the hit files are validated through the triangle test, f64
    // with naga's FLOAT64 capability.
    let through_includer = [
        "shared/closest_hit.wgsl",
        "shared/walker_common.wgsl",
        "shared/coherent.wgsl",
        "shared/macrocell_aw.wgsl",
        "shared/macrocell_cw.wgsl",
        "shared/macrocell_liu.wgsl",
        "shared/macrocell_nested.wgsl",
        "shared/hit_f32.wgsl",
        "shared/hit_f64.wgsl",
    ];
    let standalone = on_disk.iter().filter(|n| !through_includer.contains(&n.as_str()));
    let variants = GpuWalker::ALL.into_iter().flat_map(|w| HitFloat::ALL.map(|h| (w, h))).collect::<Vec<_>>();
    for (name, (walker, hit)) in standalone.flat_map(|n| variants.iter().map(move |&v| (n, v))) {
        let src = match compose_for(name, walker, hit) {
            Ok(s) => s,
            Err(e) => {
                failures.push(format!("{name} ({walker}): {e}"));
                continue;
            }
        };
        let name = &format!("{name} (walker {walker}, {} hits)", hit.name());
        let module = match naga::front::wgsl::parse_str(&src) {
            Ok(m) => m,
            Err(e) => {
                failures.push(format!("{name}: parse error:\n{}", e.emit_to_string_with_path(&src, name)));
                continue;
            }
        };
        let caps = match hit {
            HitFloat::F32 => naga::valid::Capabilities::default(),
            HitFloat::F64 => naga::valid::Capabilities::FLOAT64,
        };
        let mut v = naga::valid::Validator::new(naga::valid::ValidationFlags::all(), caps);
        if let Err(e) = v.validate(&module) {
            failures.push(format!("{name}: validation error:\n{}", e.emit_to_string_with_path(&src, name)));
        }
    }
    assert!(failures.is_empty(), "{} of {} shaders failed:\n{}", failures.len(), on_disk.len(), failures.join("\n\n"));
    println!("{} shaders validated with each of {} walkers and f32 / f64 hits", on_disk.len(), GpuWalker::ALL.len());
}
