//! Plots an engineer puts in a report (amplitude, phase, phase difference).
