//! decophantom: evaluate decompression schedules with a three-dimensional bubble model of a
//! tissue phantom (Walsh et al. 2017, J. R. Soc. Interface 14: 20170653).
//!
//! Data flow: profile / algorithm → [`profile::PressureHistory`] → [`phantom`] → bubble
//! history → risk criteria → report. See README.md for the module map.
#![warn(missing_docs)]
// `!(x > 0.0)` is used on purpose: it rejects NaN as well as non-positive values.
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// The solver indexes parallel per-gas and per-bubble arrays; index loops say that most plainly.
#![allow(clippy::needless_range_loop)]

pub mod algorithm;
pub mod app;
pub mod discover;
pub mod error;
pub mod evaluate;
pub mod fit;
pub mod gas;
pub mod phantom;
pub mod profile;
pub mod report;
pub mod reproduce;
pub mod risk;
pub mod run;
pub mod sweep;
pub mod units;
