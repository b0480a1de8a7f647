//! Test modules of the GPU crate (one binary; see ../gpu.rs).
pub mod build;
pub mod common;
pub mod layout;
pub mod naga_validate;
pub mod packets;
pub mod render;
pub mod soft_f64;
pub mod trace;
