//! Plinth host library: run directories, batch identification, the machine
//! simulator, the paper reproduction, plots, streaming from the field box and
//! the model-discrepancy workflow. The `plinth` binary is a thin CLI over it.
#![warn(missing_docs)]

pub mod accuracy;
pub mod demo;
pub mod diagnose;
pub mod effects;
pub mod estimate;
pub mod identify;
pub mod paper;
pub mod plots;
pub mod rundir;
pub mod sim;
pub mod stream;
