//! The grid crate's tests, in one binary (one link of the test harness; see suite/).
mod suite;
