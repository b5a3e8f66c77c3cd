//! Rotor-bearing-pedestal machine simulator.
pub mod cli;
