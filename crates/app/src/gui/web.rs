//! Browser-only glue: `window.gridrt` (the test hook over [`HookState`]), giving control back
//! to the browser between long steps, and the page-visible panic report.
//!
//! `window.gridrt` functions:
//! - `stats()` → the [`super::hook::HookStats`] snapshot as an object;
//! - `set_grid(kind)`, `set_view(name)`, `set_traversal(aw|cw|liu)`,
//!   `set_camera("ex,ey,ez,tx,ty,tz,fov")`, `set_frame_size(w, h)` (0, 0 follows the window):
//!   throw on a bad value;
//! - `set_playing("play"|"pause")`, `seek("seconds")`: the animated scene's timeline;
//! - `set_gpu_build("on"|"off")`: build flat and macrocell grids on the GPU;
//! - `set_packets("on"|"off")`: trace primary and shadow rays in coherent 8×8 packets;
//! - `open_bytes(name, Uint8Array)`: opens a .glb/.gltf as a dropped file would;
//! - `dismiss_error()`: clears the error the UI shows (like its "dismiss" button);
//! - `capture()` → id; then `last_frame()` → `{id, width, height, rgba: Uint8Array}` or null;
//! - `panic()` → the panic message, or null.

use wasm_bindgen::{JsCast as _, JsValue, closure::Closure};

use super::hook::{Hook, HookCommand};

fn set(obj: &js_sys::Object, name: &str, f: &JsValue) {
    let _ = js_sys::Reflect::set(obj, &JsValue::from_str(name), f);
}

fn js_error(e: String) -> JsValue {
    js_sys::Error::new(&e).into()
}

/// Queues a command and wakes the app so that it applies it.
fn push(hook: &Hook, c: HookCommand) {
    let mut h = hook.lock().expect("hook lock");
    h.commands.push_back(c);
    if let Some(ctx) = &h.repaint {
        ctx.request_repaint();
    }
}

/// Defines `window.gridrt`.
pub fn install(hook: Hook, runner: eframe::WebRunner) {
    let Some(window) = web_sys::window() else { return };
    let obj = js_sys::Object::new();

    let h = hook.clone();
    let f = Closure::<dyn Fn() -> JsValue>::new(move || {
        let s = h.lock().expect("hook lock").snapshot();
        serde_json::to_string(&s).ok().and_then(|t| js_sys::JSON::parse(&t).ok()).unwrap_or(JsValue::NULL)
    });
    set(&obj, "stats", f.as_ref());
    f.forget();

    let setters: [(&str, fn(&str) -> Result<HookCommand, String>); 8] = [
        ("set_grid", HookCommand::grid),
        ("set_view", HookCommand::view),
        ("set_traversal", HookCommand::traversal),
        ("set_camera", HookCommand::camera),
        ("set_playing", HookCommand::playing),
        ("seek", HookCommand::seek),
        ("set_gpu_build", HookCommand::gpu_build),
        ("set_packets", HookCommand::packets),
    ];
    for (name, parse) in setters {
        let h = hook.clone();
        let f = Closure::<dyn Fn(String) -> Result<(), JsValue>>::new(move |s: String| {
            push(&h, parse(&s).map_err(js_error)?);
            Ok(())
        });
        set(&obj, name, f.as_ref());
        f.forget();
    }

    let h = hook.clone();
    let f = Closure::<dyn Fn()>::new(move || push(&h, HookCommand::DismissError));
    set(&obj, "dismiss_error", f.as_ref());
    f.forget();

    let h = hook.clone();
    let f = Closure::<dyn Fn(u32, u32) -> Result<(), JsValue>>::new(move |w: u32, hh: u32| {
        push(&h, HookCommand::frame_size(w, hh).map_err(js_error)?);
        Ok(())
    });
    set(&obj, "set_frame_size", f.as_ref());
    f.forget();

    let h = hook.clone();
    let f = Closure::<dyn Fn(String, js_sys::Uint8Array)>::new(move |name: String, bytes: js_sys::Uint8Array| {
        push(&h, HookCommand::Open { name, bytes: bytes.to_vec().into() });
    });
    set(&obj, "open_bytes", f.as_ref());
    f.forget();

    let h = hook.clone();
    let f = Closure::<dyn Fn() -> f64>::new(move || {
        let id = h.lock().expect("hook lock").capture();
        if let Some(ctx) = &h.lock().expect("hook lock").repaint {
            ctx.request_repaint();
        }
        id as f64
    });
    set(&obj, "capture", f.as_ref());
    f.forget();

    let h = hook.clone();
    let f = Closure::<dyn Fn() -> JsValue>::new(move || {
        let guard = h.lock().expect("hook lock");
        let Some(frame) = &guard.frame else { return JsValue::NULL };
        let o = js_sys::Object::new();
        set(&o, "id", &JsValue::from_f64(frame.id as f64));
        set(&o, "width", &JsValue::from_f64(frame.width as f64));
        set(&o, "height", &JsValue::from_f64(frame.height as f64));
        set(&o, "rgba", &js_sys::Uint8Array::from(frame.rgba.as_slice()).into());
        o.into()
    });
    set(&obj, "last_frame", f.as_ref());
    f.forget();

    let f = Closure::<dyn Fn() -> JsValue>::new(move || match runner.panic_summary() {
        Some(p) => JsValue::from_str(&p.message()),
        None => JsValue::NULL,
    });
    set(&obj, "panic", f.as_ref());
    f.forget();

    let _ = js_sys::Reflect::set(&window, &JsValue::from_str("gridrt"), &obj);
}

/// Milliseconds since the page started (the browser's performance clock).
pub fn page_ms() -> Option<f64> {
    web_sys::window().and_then(|w| w.performance()).map(|p| p.now())
}

/// Resolves after the browser had a chance to paint (a zero-delay timeout): long jobs await
/// this first so the page shows what is about to happen before the work blocks it.
pub async fn yield_to_browser() {
    let promise = js_sys::Promise::new(&mut |resolve, _reject| {
        if let Some(w) = web_sys::window() {
            let _ = w.set_timeout_with_callback_and_timeout_and_arguments_0(resolve.unchecked_ref(), 0);
        }
    });
    let _ = wasm_bindgen_futures::JsFuture::from(promise).await;
}

/// The worker's entry (called from web/worker.js): builds `config` (JSON) over `tris` (9 floats
/// per triangle) and returns the structure and its report as postcard bytes.
#[wasm_bindgen::prelude::wasm_bindgen]
pub fn build_in_worker(tris: &[f32], config: &str) -> Result<Vec<u8>, JsValue> {
    let config: gridrt_grid::GridConfig =
        serde_json::from_str(config).map_err(|e| js_error(format!("the build configuration: {e}")))?;
    let tris: Vec<[glam::Vec3; 3]> = tris
        .chunks_exact(9)
        .map(|c| {
            [glam::Vec3::new(c[0], c[1], c[2]), glam::Vec3::new(c[3], c[4], c[5]), glam::Vec3::new(c[6], c[7], c[8])]
        })
        .collect();
    let built = super::built::build_structure(&tris, &config, 0).map_err(js_error)?;
    super::built::encode_structure(&built.grid, &built.report).map_err(js_error)
}

type Reply = Box<dyn FnOnce(Result<Vec<u8>, String>)>;

/// The page's side of the build worker: started on first use, requests matched by id.
struct BuildWorker {
    worker: web_sys::Worker,
    next_id: u32,
    pending: std::rc::Rc<std::cell::RefCell<Vec<(u32, Reply)>>>,
    /// Set when the worker failed to load: builds then run on the page's thread.
    broken: std::rc::Rc<std::cell::Cell<bool>>,
}

thread_local! {
    static WORKER: std::cell::RefCell<Option<BuildWorker>> = const { std::cell::RefCell::new(None) };
}

fn start_worker() -> Result<BuildWorker, String> {
    use std::cell::{Cell, RefCell};
    use std::rc::Rc;
    let opts = web_sys::WorkerOptions::new();
    opts.set_type(web_sys::WorkerType::Module);
    opts.set_name("gridrt build worker");
    let worker = web_sys::Worker::new_with_options("./worker.js", &opts).map_err(|e| format!("{e:?}"))?;
    let pending: Rc<RefCell<Vec<(u32, Reply)>>> = Default::default();
    let broken = Rc::new(Cell::new(false));
    let p = pending.clone();
    let on_message = Closure::<dyn Fn(web_sys::MessageEvent)>::new(move |e: web_sys::MessageEvent| {
        let data = e.data();
        let get = |k: &str| js_sys::Reflect::get(&data, &JsValue::from_str(k)).unwrap_or(JsValue::UNDEFINED);
        let id = get("id").as_f64().unwrap_or(-1.0) as u32;
        let result = match get("error").as_string() {
            Some(err) => Err(err),
            None => Ok(js_sys::Uint8Array::new(&get("bytes")).to_vec()),
        };
        let reply = {
            let mut p = p.borrow_mut();
            p.iter().position(|(i, _)| *i == id).map(|at| p.remove(at).1)
        };
        if let Some(reply) = reply {
            reply(result);
        }
    });
    worker.set_onmessage(Some(on_message.as_ref().unchecked_ref()));
    on_message.forget();
    let (p, b) = (pending.clone(), broken.clone());
    let on_error = Closure::<dyn Fn(web_sys::ErrorEvent)>::new(move |e: web_sys::ErrorEvent| {
        // The worker script or its wasm failed to load: fail what waits, build inline from now.
        b.set(true);
        let msg = format!("the build worker failed: {}", e.message());
        for (_, reply) in p.borrow_mut().drain(..) {
            reply(Err(msg.clone()));
        }
    });
    worker.set_onerror(Some(on_error.as_ref().unchecked_ref()));
    on_error.forget();
    Ok(BuildWorker { worker, next_id: 0, pending, broken })
}

/// Sends a build to the worker; `reply` gets the encoded structure or an error. `Err` when
/// the worker cannot be used (the caller then builds on the page's thread).
pub fn build_in_worker_async(
    tris: &[[glam::Vec3; 3]],
    config: &gridrt_grid::GridConfig,
    reply: impl FnOnce(Result<Vec<u8>, String>) + 'static,
) -> Result<(), String> {
    WORKER.with(|w| {
        let mut w = w.borrow_mut();
        if w.as_ref().is_some_and(|w| w.broken.get()) {
            return Err("it failed to load earlier".to_string());
        }
        if w.is_none() {
            *w = Some(start_worker()?);
        }
        let w = w.as_mut().expect("worker");
        w.next_id += 1;
        let flat: &[f32] = bytemuck::cast_slice(tris);
        let msg = js_sys::Object::new();
        set(&msg, "id", &JsValue::from_f64(w.next_id as f64));
        set(&msg, "tris", &js_sys::Float32Array::from(flat).into());
        let config = serde_json::to_string(config).map_err(|e| e.to_string())?;
        set(&msg, "config", &JsValue::from_str(&config));
        w.pending.borrow_mut().push((w.next_id, Box::new(reply)));
        w.worker.post_message(&msg).map_err(|e| {
            w.pending.borrow_mut().pop();
            format!("{e:?}")
        })
    })
}
