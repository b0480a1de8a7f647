// The grid-build worker: a second instance of the app's wasm that only builds structures
// (`build_in_worker` in crates/app/src/gui/web.rs), so that the page keeps drawing while a
// large scene builds (the wasm build has no threads). The page sends {id, tris, config} and
// gets back {id, bytes} (the structure, postcard-encoded) or {id, error}.
import init, { build_in_worker } from "./gridrt.js";

const ready = init();

self.onmessage = async (e) => {
  const { id, tris, config } = e.data;
  try {
    await ready;
    const bytes = build_in_worker(tris, config);
    self.postMessage({ id, bytes }, [bytes.buffer]);
  } catch (err) {
    self.postMessage({ id, error: String((err && err.message) || err) });
  }
};
