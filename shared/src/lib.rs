//! Plinth's `no_std` core, shared by the field box firmware and the host tool:
//! 1X phasors, bearing forces, the paper's regression and a recursive
//! least-squares estimator per pedestal, the keyphasor-synchronous phasor
//! extractor, and the wire protocol between box and laptop.
//!
//! Everything here is allocation-free with fixed, const-generic sizes, and does
//! not panic on the hot path.
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]
// Index loops read like the linear algebra they implement.
#![allow(clippy::needless_range_loop)]

pub mod bearing;
pub mod extractor;
pub mod phasor;
pub mod protocol;
pub mod regression;
pub mod rls;

#[cfg(test)]
pub(crate) mod testing;
