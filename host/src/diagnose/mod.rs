//! `plinth diagnose`: find, name and fix what the pedestal model is missing.
//!
//! The workflow (one module per idea):
//! - [`data`]: the run arranged per bearing and speed, with the complex bearing
//!   stiffness and every number's noise standard deviation;
//! - [`noise`]: the noise floor the data support (digits written, scatter);
//! - [`model`]: augmented pedestal models, linear in their parameters apart
//!   from a loss factor or a delay;
//! - [`fit`]: noise-weighted least squares (errors in variables propagated)
//!   and the 1-D profile search;
//! - [`gap`]: the disagreement measure (defined there) and its noise floor;
//! - [`bearing_table`]: `bearing_coefficients`, an oil-film table written
//!   for another clearance;
//! - [`candidates`]: the library of linear effects (every formats.md name
//!   but the two base models);
//! - [`foundation`]: `foundation_coupling` (pedestals on a shared unmeasured
//!   base) and `pedestal_sub_base` (one pedestal on its own), the model of
//!   `crate::estimate::base`, with the bootstrap likelihood-ratio test;
//! - [`criterion`]: the significance test and ranking of candidates;
//! - [`locate`]: where the disagreement lives;
//! - [`state`]: a fitted model (the base model, joint refits) and its
//!   parameter inference;
//! - [`outliers`]: the base model's outlier speeds, left out of the search
//!   and tested again under the model it chose;
//! - [`forward`]: one forward step, every library candidate fitted and tested;
//! - [`backward`]: chosen effects tested again in later joint refits;
//! - [`bases`]: the two base candidates of a round on the corrected data;
//! - [`summaries`]: tried and chosen effects as report entries;
//! - [`workflow`]: forward selection with joint refits and a backward check;
//! - [`trust`]: the verdict, and whether the numbers can be trusted;
//! - [`report`]: the diagnosis as JSON and text;
//! - [`machine`]: the machine-level re-simulation (`--machine`);
//! - [`refute`]: steps the machine-level check refutes dropped, with the
//!   steps chosen after them;
//! - [`base_floor`]: a chosen base's uncertainty in its noise floor;
//! - [`plots`]: measured-versus-predicted figures;
//! - [`cli`]: the `plinth diagnose` command.

pub use workflow::{diagnose, Options, Outcome};

pub mod backward;
pub mod base_floor;
pub mod bases;
pub mod bearing_table;
pub mod candidates;
pub mod cli;
pub mod correct;
pub mod criterion;
pub mod data;
pub mod fit;
pub mod forward;
pub mod foundation;
pub mod gap;
pub mod locate;
pub mod machine;
pub mod ml_final;
pub mod model;
pub mod noise;
pub mod outliers;
pub mod plots;
pub mod refute;
pub mod report;
pub mod state;
pub mod summaries;
#[cfg(test)]
mod test_runs;
pub mod trust;
pub mod workflow;

pub use cli::{run, Args};
