//! Plinth host library: run directories, batch identification, the machine
//! simulator, the paper reproduction, plots, streaming from the field box and
//! the model-discrepancy workflow. The `plinth` binary is a thin CLI over it.
#![warn(missing_docs)]

pub mod args;
pub mod base_csv;
pub mod csv_layout;
pub mod demo;
pub mod diagnose;
pub mod effects;
pub mod identify;
pub mod output;
pub mod paper;
pub mod plots;
pub mod progress;
pub mod rundir;
pub mod sim;
pub mod stream;
