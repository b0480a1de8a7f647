pub mod common;
pub mod layout;
pub mod naga_validate;
pub mod render;
pub mod trace;
