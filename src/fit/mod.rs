//! Fitting the phantom model to measured bubble radii (`decophantom fit`) and making
//! measured-like data from it (`synth`): the readers of `measurements.csv` and
//! `experiments.toml`, parameters named by their phantom-TOML path, weighted least squares
//! with the `levenberg-marquardt` crate, asymptotic intervals, the paper's growth metrics
//! (plateau radius, half-life) and the model-comparison statistics `discover` uses.

pub mod data;
pub mod growth;
pub mod journal;
pub mod lsq;
pub mod model;
pub mod paths;
pub mod report;
pub mod stats;
pub mod synth;
