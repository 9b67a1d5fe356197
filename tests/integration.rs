//! All integration tests compile into this one binary; one module per concern.
#[path = "integration/analytic.rs"]
mod analytic;
#[path = "integration/common.rs"]
mod common;
