//! What `gridrt animate` and `gridrt bench --dynamic` see an animation with: a view (camera,
//! light, primary rays) fixed over the whole clip. The posing itself is
//! [`gridrt_scene::Player`]; the CPU frame is [`super::frame`]'s.

use gridrt_gpu::RenderOptions;
use gridrt_gpu::layout::ShadeParams;
use gridrt_grid::trace::TraceOptions;
use gridrt_scene::{Aabb, Ray};

/// What every frame of a clip is seen with: the shaded render's options (camera framing the
/// clip's bounds), its light and shading constants, and its primary rays.
#[derive(Debug)]
pub struct FixedView {
    pub opts: RenderOptions,
    pub shade: ShadeParams,
    pub primary: Vec<Ray>,
}

impl FixedView {
    pub fn new(bounds: &Aabb, width: u32, height: u32) -> FixedView {
        let opts = RenderOptions::fit(bounds, width, height);
        let shade = gridrt_gpu::render::shade_params(bounds, &opts);
        let primary = gridrt_gpu::cpu::camera_rays(&gridrt_gpu::cpu::gpu_camera(&opts.camera, width, height));
        FixedView { opts, shade, primary }
    }

    /// The render's traversal and mailbox, for CPU traces of the same frame.
    pub fn trace_options(&self) -> TraceOptions {
        TraceOptions { traversal: self.opts.traversal, mailbox: self.opts.mailbox, ..Default::default() }
    }
}
