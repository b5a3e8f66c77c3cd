//! How results are shown to people: the modal view of a pedestal
//! ([`modal`]: natural frequency and damping ratio with ±) and the one
//! printer of identified pedestals ([`table`]) that `identify`, `diagnose`,
//! `stream` and `demo` share, so that one fit reads the same everywhere.

pub mod modal;
pub mod table;
