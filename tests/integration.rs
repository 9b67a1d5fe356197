//! All integration tests compile into this one binary; one module per concern.
#[path = "integration/algorithms.rs"]
mod algorithms;
#[path = "integration/common.rs"]
mod common;
