//! gridrt's GPU passes: the WGSL grid traversals and the render pass, run through wgpu. The
//! only crate of the workspace that depends on wgpu.
//!
//! Data flows one way: a built structure ([`gridrt_grid::AnyGrid`]) → GPU buffers
//! ([`upload`]) → a trace kernel per structure ([`kernel`], `shaders/<kernel>.wgsl`, [`trace`]) → hits and
//! per-ray stats; the render pass ([`render`]) adds camera rays, shadow rays and shading.

pub mod build;
pub mod context;
pub mod cpu;
pub mod kernel;
pub mod layout;
pub mod render;
pub mod session;
pub mod shaders;
pub mod trace;
pub mod upload;
pub mod view;

pub use context::{GpuContext, GpuError};
pub use kernel::{GpuWalker, Kernel};
pub use render::{Frame, FrameSource, FrameTarget, RenderOptions, Renderer};
pub use session::GpuSession;
pub use trace::Tracer;
pub use view::View;
