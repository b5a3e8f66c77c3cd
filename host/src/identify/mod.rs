//! Batch least-squares identification of pedestals (Feng & Hahn eq. 4), in f64.
pub mod cli;
