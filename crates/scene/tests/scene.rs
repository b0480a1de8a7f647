//! The scene crate's tests, in one binary (see suite/).
mod suite;
