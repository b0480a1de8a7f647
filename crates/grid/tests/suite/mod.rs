//! Test modules and shared helpers.
pub mod build;
pub mod closest_hit;
pub mod coherent;
pub mod common;
pub mod degenerate;
pub mod hostile;
pub mod irregular;
pub mod traversal;
pub mod triangle;
