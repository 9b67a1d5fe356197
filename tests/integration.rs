//! All integration tests compile into this one binary; one module per concern.
#[path = "integration/algorithms.rs"]
mod algorithms;
#[path = "integration/analytic.rs"]
mod analytic;
#[path = "integration/bubble_steps.rs"]
mod bubble_steps;
#[path = "integration/checkpoint.rs"]
mod checkpoint;
#[path = "integration/cli_simulate.rs"]
mod cli_simulate;
#[path = "integration/common.rs"]
mod common;
#[path = "integration/convergence.rs"]
mod convergence;
#[path = "integration/defects.rs"]
mod defects;
#[path = "integration/discover.rs"]
mod discover;
#[path = "integration/displacement.rs"]
mod displacement;
#[path = "integration/evaluate.rs"]
mod evaluate;
#[path = "integration/events.rs"]
mod events;
#[path = "integration/figures.rs"]
mod figures;
#[path = "integration/fixed_gases.rs"]
mod fixed_gases;
#[path = "integration/gas_convention.rs"]
mod gas_convention;
#[path = "integration/growth.rs"]
mod growth;
#[path = "integration/hardening.rs"]
mod hardening;
#[path = "integration/mutants.rs"]
mod mutants;
#[path = "integration/nucleation.rs"]
mod nucleation;
#[path = "integration/paper_findings.rs"]
mod paper_findings;
#[path = "integration/perfusion.rs"]
mod perfusion;
#[path = "integration/planner_cli.rs"]
mod planner_cli;
#[path = "integration/profiles.rs"]
mod profiles;
#[path = "integration/report.rs"]
mod report;
#[path = "integration/reproduce.rs"]
mod reproduce;
#[path = "integration/robustness.rs"]
mod robustness;
#[path = "integration/small_runs.rs"]
mod small_runs;
#[path = "integration/sweep.rs"]
mod sweep;
#[path = "integration/verification.rs"]
mod verification;
#[path = "integration/vpmb.rs"]
mod vpmb;
