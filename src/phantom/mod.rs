//! The three-dimensional tissue-phantom bubble model (Walsh et al. 2017, section 2.1).

pub mod bubble;
pub mod checkpoint;
pub mod config;
pub mod diffusion;
pub mod displacement;
pub mod elasticity;
pub mod elasticity_compare;
pub mod fields;
mod gel_pass;
pub mod grid;
pub mod keep_warm;
pub mod nucleation;
pub mod params;
pub mod sim;
pub mod surface;
