//! Whether a transducer's readings in a 1X vector table can be real: an
//! amplitude beyond any machine's vibration (a typo such as `1e300`, or the
//! wrong unit) is refused at its line and column, and a transducer that
//! reads zero, or the same amplitude and phase, at every speed is named as
//! dead before its zeros are fitted; phases that all lie within ±2π where
//! degrees are expected (a table written in radians) are named.

use plinth_shared::extractor::SensorKind;

/// The largest plausible 1X amplitude [SI, 0-pk] of a reading of `kind`:
/// 50 mm of displacement, 10 m/s of velocity, 10 000 m/s² (about 1000 g) of
/// acceleration, each far beyond any bearing's vibration (tens of µm, tens of
/// mm/s, a few g) yet short of a unit mistake by a factor 1000.
pub fn max_amplitude_si(kind: SensorKind) -> f64 {
    match kind {
        SensorKind::Displacement => 0.05,
        SensorKind::Velocity => 10.0,
        SensorKind::Acceleration => 1e4,
    }
}

/// The SI unit of a reading of `kind`, for messages.
pub fn si_unit(kind: SensorKind) -> &'static str {
    match kind {
        SensorKind::Displacement => "m",
        SensorKind::Velocity => "m/s",
        SensorKind::Acceleration => "m/s²",
    }
}

/// One transducer's readings over the rows of a table, kept as running
/// facts (no rows stored).
#[derive(Clone, Debug, Default)]
pub struct ReadingsWatch {
    rows: u64,
    first: Option<(f64, f64)>,
    all_zero: bool,
    all_same: bool,
    /// Largest |phase| read [deg, as written].
    max_abs_phase: f64,
    /// Whether some phase is not a whole number (instruments print whole
    /// degrees; radians need decimals).
    fractional_phase: bool,
}

/// The fewest rows over which [`radians_suspected`] judges a table.
pub const RADIANS_MIN_ROWS: u64 = 5;

impl ReadingsWatch {
    /// Takes one row's amplitude (in the table's unit) and phase [deg].
    pub fn push(&mut self, amplitude: f64, phase_deg: f64) {
        if self.rows == 0 {
            self.all_zero = true;
            self.all_same = true;
        }
        self.rows += 1;
        self.all_zero &= amplitude == 0.0;
        self.max_abs_phase = self.max_abs_phase.max(phase_deg.abs());
        self.fractional_phase |= phase_deg.fract() != 0.0;
        match self.first {
            None => self.first = Some((amplitude, phase_deg)),
            Some(f) => self.all_same &= f == (amplitude, phase_deg),
        }
    }

    /// `Err` naming why the transducer is dead (`what` names it).
    pub fn check(&self, what: &str) -> Result<(), String> {
        if self.rows == 0 {
            return Ok(());
        }
        if self.all_zero {
            return Err(format!(
                "{what} reads 0 at every one of the {} speeds: a dead pick-up or probe (disconnected, unpowered) or an empty column; its bearing cannot be identified from zeros: fix or leave out the transducer",
                self.rows
            ));
        }
        if self.all_same && self.rows >= 3 {
            let (a, p) = self.first.unwrap_or_default();
            return Err(format!(
                "{what} reads the same {a} at {p}° at every one of the {} speeds: a stuck channel (a copied or frozen column), not a 1X response",
                self.rows
            ));
        }
        Ok(())
    }
}

/// Whether the phases of a table look like radians where degrees are
/// expected: every transducer read over at least [`RADIANS_MIN_ROWS`] rows,
/// every phase within ±2π (6.28) and some phase with decimals. A run-down in
/// degrees turns its phases by tens of degrees through any resonance, so all
/// of them inside ±6.3° does not happen (measured: 0 of the bundled example
/// and of 200 simulated noisy run-downs, docs/robustness.md).
pub fn radians_suspected(watches: &[ReadingsWatch]) -> bool {
    !watches.is_empty()
        && watches
            .iter()
            .all(|w| w.rows >= RADIANS_MIN_ROWS && w.max_abs_phase <= std::f64::consts::TAU + 1e-9)
        && watches.iter().any(|w| w.fractional_phase)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn zeros_and_copies_are_dead_and_a_response_is_not() {
        let mut zero = ReadingsWatch::default();
        let mut stuck = ReadingsWatch::default();
        let mut live = ReadingsWatch::default();
        for k in 0..5 {
            zero.push(0.0, 10.0 * k as f64);
            stuck.push(1.5, 30.0);
            live.push(1.0 + k as f64, 30.0);
        }
        assert!(zero
            .check("a")
            .unwrap_err()
            .contains("reads 0 at every one of the 5"));
        assert!(stuck.check("b").unwrap_err().contains("same 1.5 at 30°"));
        assert!(live.check("c").is_ok());
        // Two equal rows are not yet a stuck channel.
        let mut two = ReadingsWatch::default();
        two.push(1.0, 2.0);
        two.push(1.0, 2.0);
        assert!(two.check("d").is_ok());
    }

    #[test]
    fn phases_in_radians_are_suspected_and_degrees_are_not() {
        let rows = |scale: f64| {
            let mut w = ReadingsWatch::default();
            for k in 0..8 {
                // A resonance: the phase lag turns through 180° over the rows.
                w.push(1.0, scale * (10.0 + 22.5 * k as f64));
            }
            w
        };
        let radians = std::f64::consts::PI / 180.0;
        assert!(radians_suspected(&[rows(radians), rows(radians)]));
        assert!(!radians_suspected(&[rows(1.0), rows(radians)]));
        assert!(!radians_suspected(&[rows(1.0)]));
        // Too few rows to judge.
        let mut short = ReadingsWatch::default();
        short.push(1.0, 0.5);
        assert!(!radians_suspected(&[short]));
    }

    #[test]
    fn the_bounds_pass_real_vibration_and_refuse_unit_mistakes() {
        // 500 µm pp, 50 mm/s, 10 g are real; 50 in `m` where µm was meant is not.
        assert!(250e-6 < max_amplitude_si(SensorKind::Displacement));
        assert!(0.05 < max_amplitude_si(SensorKind::Velocity));
        assert!(98.0 < max_amplitude_si(SensorKind::Acceleration));
        assert!(50.0 > max_amplitude_si(SensorKind::Displacement));
    }
}
