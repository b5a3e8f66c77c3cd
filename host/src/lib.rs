//! Plinth host library: run directories, batch identification, the machine
//! simulator, the paper reproduction, plots, streaming from the field box and
//! the model-discrepancy workflow. The `plinth` binary is a thin CLI over it.
#![warn(missing_docs)]

pub mod accuracy;
pub mod args;
pub mod base_csv;
pub mod compare;
pub mod csv_layout;
pub mod demo;
pub mod diagnose;
pub mod effects;
pub mod estimate;
pub mod extract;
pub mod field;
pub mod identify;
pub mod input_file;
pub mod names;
pub mod output;
pub mod paper;
pub mod pipe;
pub mod plots;
pub mod present;
pub mod progress;
pub mod report;
pub mod rundir;
pub mod sim;
pub mod stream;

/// An error and its causes as one line, each cause once: a cause whose text
/// the message already quotes (an operating-system error a message names)
/// is not repeated, as `{:#}` would.
pub fn error_text(e: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in e.chain() {
        let c = cause.to_string();
        if text.contains(&c) {
            continue;
        }
        if !text.is_empty() {
            text.push_str(": ");
        }
        text.push_str(&c);
    }
    text
}
