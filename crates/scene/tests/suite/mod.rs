pub mod builder;
pub mod gltf_valid;
pub mod malformed;
pub mod procedural;
pub mod rays;
