//! decophantom: evaluate decompression schedules with a three-dimensional bubble model of a
//! tissue phantom (Walsh et al. 2017, J. R. Soc. Interface 14: 20170653).
//!
//! Data flow: profile / algorithm → [`profile::PressureHistory`] → [`phantom`] → bubble
//! history → risk criteria → report. See README.md for the module map.
#![warn(missing_docs)]

pub mod algorithm;
pub mod app;
pub mod error;
pub mod gas;
pub mod phantom;
pub mod profile;
pub mod report;
pub mod units;
