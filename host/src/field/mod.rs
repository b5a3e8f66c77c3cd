//! Field data in: 1X vector tables (`plinth import`) and the pieces they
//! share with recorded waveforms (`plinth extract`, [`crate::extract`]):
//! amplitude units and phase conventions ([`units`]), transducer angles and
//! their resolution into y and z ([`angle`], [`transducer`]), slow-roll
//! compensation ([`slow_roll`]), the transducers' placement kept in the run
//! directory ([`transducers_csv`]), Bode and polar plots ([`plot`]) and the
//! all-or-nothing output directory ([`output`]). The contract is formats.md,
//! "Field data".

pub mod angle;
pub mod import;
pub mod plausible;
pub mod plot;
pub mod resolution;
pub mod slow_roll;
pub mod transducer;
pub mod transducers_csv;
pub mod units;
