//! What the user does to the app: the menu (open, default scene, save image, windows), camera
//! input on the image (mouse and keys), and files dropped on the window.

use eframe::egui::{self, Key, PointerButton};

#[cfg(not(target_arch = "wasm32"))]
use gridrt_gpu::FrameSource;

use super::GridrtApp;
use super::errors::ErrorKind;
use super::jobs::SceneSource;
use super::orbit::Orbit;
use crate::cli::CameraArg;
use crate::lab::views;

impl GridrtApp {
    pub(super) fn menu(&mut self, ui: &mut egui::Ui) {
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                #[cfg(not(target_arch = "wasm32"))]
                if ui.button("Open…").clicked() {
                    if let Some(p) = rfd::FileDialog::new().add_filter("glTF", &["glb", "gltf"]).pick_file() {
                        self.open(ui.ctx(), SceneSource::Path(p));
                    }
                    ui.close();
                }
                // In the browser the picker is asynchronous: its bytes arrive like a dropped file's.
                #[cfg(target_arch = "wasm32")]
                if ui.button("Open…").clicked() {
                    let (tx, rx) = std::sync::mpsc::channel();
                    let ui_ctx = ui.ctx().clone();
                    wasm_bindgen_futures::spawn_local(async move {
                        let picked = rfd::AsyncFileDialog::new().add_filter("glTF", &["glb", "gltf"]).pick_file().await;
                        if let Some(f) = picked {
                            let _ = tx.send(Ok((f.file_name(), f.read().await)));
                            ui_ctx.request_repaint();
                        }
                    });
                    self.dropped = Some(rx);
                    ui.close();
                }
                if ui.button("Default scene").clicked() {
                    self.open(ui.ctx(), SceneSource::Default);
                    ui.close();
                }
                #[cfg(not(target_arch = "wasm32"))]
                if ui.button("Save image…").clicked() {
                    self.save_image();
                    ui.close();
                }
                #[cfg(not(target_arch = "wasm32"))]
                if ui.button("Quit").clicked() {
                    ui.ctx().send_viewport_cmd(egui::ViewportCommand::Close);
                }
            });
            ui.menu_button("Windows", |ui| {
                ui.checkbox(&mut self.settings.show_cost_plot, "Cost model");
                ui.checkbox(&mut self.settings.show_explainer, "Traversal explainer");
            });
            ui.menu_button("Camera", |ui| {
                if ui
                    .button("Frame the bounds (F)")
                    .on_hover_text("--camera auto: the whole scene box in view")
                    .clicked()
                {
                    self.reset_camera();
                    ui.close();
                }
                let built = self.built.is_some();
                let framed = ui
                    .add_enabled(built, egui::Button::new("Fill with the model"))
                    .on_hover_text("The benchmark's framed view: aimed and narrowed until 75% of a probe image hits");
                if framed.clicked() {
                    self.view_camera(CameraArg::Framed);
                    ui.close();
                }
                let interior = ui.add_enabled(built, egui::Button::new("Inside, along the scene")).on_hover_text(
                    "The benchmark's interior view of architectural scenes: from inside, down the longer axis",
                );
                if interior.clicked() {
                    self.view_camera(CameraArg::Interior);
                    ui.close();
                }
            });
            ui.label("drag: orbit · right/shift-drag: pan · wheel: zoom · F: reset · drop a .glb to open");
        });
    }

    pub(super) fn reset_camera(&mut self) {
        if let Some(s) = &self.scene {
            self.orbit = Orbit::fit(&s.loaded.bounds, self.frame_aspect());
        }
    }

    /// Width over height of the last frame asked for (1.5 before the first).
    fn frame_aspect(&self) -> f32 {
        self.last_key.map_or(1.5, |k| k.size[0] as f32 / k.size[1].max(1) as f32)
    }

    /// Points the camera as `--camera` would (the framed and interior views as `gridrt bench`
    /// aims them, probing the structure on screen with the triangles it was built over).
    pub(super) fn view_camera(&mut self, arg: CameraArg) {
        let (Some(s), Some(b)) = (&self.scene, &self.built) else { return };
        let tris = b.built.pose.as_ref().map_or(&s.loaded.tris, |p| &p.tris);
        let cam = views::camera(arg, tris, &s.loaded.bounds, &b.built.grid, self.frame_aspect());
        self.orbit = Orbit::from_camera(&cam, &s.loaded.bounds);
    }

    #[cfg(not(target_arch = "wasm32"))]
    pub(super) fn save_image(&mut self) {
        let Some(path) = rfd::FileDialog::new().add_filter("PNG", &["png"]).set_file_name("gridrt.png").save_file()
        else {
            return;
        };
        let (Some(gpu), Some(scene), Some(b), Some(key)) = (&self.gpu, &self.scene, &self.built, self.last_key) else {
            return;
        };
        let opts = self.render_options(key.camera, key.size);
        // The posed triangles when the scene plays; on the CPU when the device cannot hold them.
        let rgba = match (b.posed_gpu.as_ref().or(scene.gpu.as_ref()), &b.gpu) {
            (Some(gs), Some(s)) => gpu
                .renderer
                .render(&gpu.ctx, &FrameSource { scene: gs, structure: s, bounds: &scene.loaded.bounds }, &opts)
                .map(|f| f.rgba)
                .map_err(|e| e.to_string()),
            _ => {
                let tris = b.built.pose.as_ref().map_or_else(|| scene.loaded.tris.clone(), |p| p.tris.clone());
                let req =
                    super::viewport::CpuRequest { opts, grid: b.built.grid.clone(), tris, bounds: scene.loaded.bounds };
                Ok(super::viewport::trace_on_cpu(req).rgba)
            }
        };
        let result = rgba.and_then(|rgba| {
            image::save_buffer(&path, &rgba, opts.width, opts.height, image::ExtendedColorType::Rgba8)
                .map_err(|e| e.to_string())
        });
        if let Err(e) = result {
            self.errors.report(ErrorKind::Other, format!("saving {}: {e}", path.display()));
        }
    }

    /// Camera input on the image: mouse and keys.
    pub(super) fn camera_input(&mut self, ui: &egui::Ui, resp: &egui::Response) {
        let d = resp.drag_delta();
        let shift = ui.input(|i| i.modifiers.shift);
        let h = resp.rect.height().max(1.0);
        if resp.dragged_by(PointerButton::Primary) && !shift {
            self.orbit.rotate(d.x * 0.008, d.y * 0.008);
        } else if resp.dragged_by(PointerButton::Secondary)
            || resp.dragged_by(PointerButton::Middle)
            || (resp.dragged_by(PointerButton::Primary) && shift)
        {
            self.orbit.pan(d.x / h, d.y / h);
        }
        if resp.hovered() {
            let scroll = ui.input(|i| i.smooth_scroll_delta.y);
            if scroll != 0.0 {
                self.orbit.zoom((-scroll * 0.0015).exp());
            }
        }
        if resp.double_clicked() {
            self.reset_camera();
        }
        if ui.ctx().egui_wants_keyboard_input() {
            return;
        }
        let step = 0.04;
        let (l, r, u, dn, zin, zout, reset) = ui.input(|i| {
            (
                i.key_down(Key::ArrowLeft) || i.key_down(Key::A),
                i.key_down(Key::ArrowRight) || i.key_down(Key::D),
                i.key_down(Key::ArrowUp) || i.key_down(Key::W),
                i.key_down(Key::ArrowDown) || i.key_down(Key::S),
                i.key_down(Key::Plus) || i.key_down(Key::Equals) || i.key_down(Key::E),
                i.key_down(Key::Minus) || i.key_down(Key::Q),
                i.key_pressed(Key::F) || i.key_pressed(Key::Home),
            )
        });
        if l {
            self.orbit.rotate(-step, 0.0);
        }
        if r {
            self.orbit.rotate(step, 0.0);
        }
        if u {
            self.orbit.rotate(0.0, step);
        }
        if dn {
            self.orbit.rotate(0.0, -step);
        }
        if zin {
            self.orbit.zoom(0.96);
        }
        if zout {
            self.orbit.zoom(1.04);
        }
        if reset {
            self.reset_camera();
        }
        if l || r || u || dn || zin || zout {
            ui.ctx().request_repaint();
        }
    }

    /// A .glb/.gltf dropped on the window opens (the first one, if several).
    #[cfg(not(target_arch = "wasm32"))]
    pub(super) fn dropped_files(&mut self, ctx: &egui::Context) {
        let dropped = ctx.input(|i| i.raw.dropped_files.clone());
        if let Some(f) = dropped.into_iter().next() {
            self.open(ctx, SceneSource::Path(f.path().to_path_buf()));
        }
    }

    /// In the browser a dropped file's bytes arrive asynchronously; the load starts when they
    /// are here.
    #[cfg(target_arch = "wasm32")]
    pub(super) fn dropped_files(&mut self, ctx: &egui::Context) {
        let dropped = ctx.input(|i| i.raw.dropped_files.clone());
        if let Some(f) = dropped.into_iter().next() {
            let (tx, rx) = std::sync::mpsc::channel();
            let name = f.path().to_string_lossy().into_owned();
            let ui = ctx.clone();
            wasm_bindgen_futures::spawn_local(async move {
                let _ = tx.send(f.bytes_async().await.map(|b| (name, b)));
                ui.request_repaint();
            });
            self.dropped = Some(rx);
        }
        if let Some(rx) = &self.dropped
            && let Ok(r) = rx.try_recv()
        {
            self.dropped = None;
            match r {
                Ok((name, bytes)) => self.open(ctx, SceneSource::Bytes { name, bytes: bytes.into() }),
                Err(e) => self.errors.report(ErrorKind::Other, format!("reading the dropped file: {e}")),
            }
        }
    }
}
