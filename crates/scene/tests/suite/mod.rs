//! Test modules of the scene crate (one binary; see ../scene.rs).
pub mod builder;
pub mod gltf_valid;
pub mod malformed;
pub mod pose;
pub mod pose_three;
pub mod procedural;
pub mod rays;
