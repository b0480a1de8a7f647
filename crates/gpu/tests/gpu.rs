//! The GPU crate's tests, in one binary (see suite/).
mod suite;
