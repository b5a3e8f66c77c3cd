//! Whether a recorded channel carries a signal worth fitting, checked on
//! its samples as they stream past (bounded memory): a dead channel (every
//! sample the same value) and a flat-topped one (an amplifier saturating
//! below the converter's full scale: runs of one identical value lasting a
//! sizeable part of a revolution), and whether the keyphasor covers the
//! recording.

/// Fewest identical samples in a row that count as a flat run, whatever the
/// revolution's length.
const MIN_FLAT_RUN: u64 = 8;

/// Fraction of a revolution's samples [-] a run of one value must last to
/// count as flat: a sine clipped at 95 % of its peak is flat for 10 % of a
/// revolution (at 80 %: 20 %); the quantisation of a sine of A codes keeps
/// one code at its peak for 1/(π√A) of a revolution (0.3 % at 10 000
/// codes, 8 % at 16 codes: weaker channels are below this check).
const FLAT_RUN_OF_REVOLUTION: f64 = 0.08;

/// Flat runs from which a channel is called clipped: one may be chance (a
/// dropout), three are a saturating amplifier, whose flat tops come back at
/// every revolution above its limit.
const MIN_FLAT_RUNS: u64 = 3;

/// What one channel's samples showed.
#[derive(Clone, Debug, Default)]
pub struct ChannelHealth {
    samples: u64,
    min: f32,
    max: f32,
    run_value: f32,
    run_len: u64,
    run_start: u64,
    /// Flat runs so far.
    flat_runs: u64,
    /// First frame of the first flat run.
    flat_first_frame: Option<u64>,
    /// The longest flat run [samples, fraction of its revolution] and its level [V].
    longest: (u64, f64, f32),
}

impl ChannelHealth {
    /// Takes the sample at `frame` [V]; `revolution` is the current
    /// revolution's length [samples] (`None` before the keyphasor gives one).
    pub fn push(&mut self, frame: u64, v: f32, revolution: Option<f64>) {
        if self.samples == 0 {
            self.min = v;
            self.max = v;
        }
        self.samples += 1;
        self.min = self.min.min(v);
        self.max = self.max.max(v);
        if self.run_len > 0 && v == self.run_value {
            self.run_len += 1;
            return;
        }
        self.close_run(revolution);
        self.run_value = v;
        self.run_len = 1;
        self.run_start = frame;
    }

    fn close_run(&mut self, revolution: Option<f64>) {
        let Some(rev) = revolution else {
            return;
        };
        let least = (FLAT_RUN_OF_REVOLUTION * rev).max(MIN_FLAT_RUN as f64);
        if self.run_len as f64 >= least {
            self.flat_runs += 1;
            self.flat_first_frame.get_or_insert(self.run_start);
            if self.run_len > self.longest.0 {
                self.longest = (self.run_len, self.run_len as f64 / rev, self.run_value);
            }
        }
    }

    /// Ends the channel (its last run counted with `revolution`); the error
    /// (for `what`, the channel's name) says how it is dead or clipped.
    pub fn finish(&mut self, what: &str, fs: f64, revolution: Option<f64>) -> Result<(), String> {
        self.close_run(revolution);
        if self.samples == 0 {
            return Ok(());
        }
        if self.min == self.max {
            return Err(format!(
                "{what} is dead: every one of its {} samples is {} V (a disconnected, unpowered or shorted pick-up or probe); leave it out of the channels file or fix the wiring",
                self.samples, self.min
            ));
        }
        if self.flat_runs >= MIN_FLAT_RUNS {
            let (len, of_rev, level) = self.longest;
            return Err(format!(
                "{what} is clipped: {} flat runs of one value (the first at {:.6} s; the longest {len} samples, {:.0} % of a revolution, at {level} V, while the channel spans {} .. {} V): an amplifier or probe driver saturating below the converter's full scale flattens the tops, so its 1X phasors would be wrong; lower the gain or leave the channel out",
                self.flat_runs,
                self.flat_first_frame.unwrap_or(0) as f64 / fs,
                100.0 * of_rev,
                self.min,
                self.max
            ));
        }
        Ok(())
    }
}

/// A warning when the keyphasor's edges cover less than 90 % of the
/// recording: edges from `first` to `last` [frames] of `frames` at `fs` [Hz].
pub fn keyphasor_coverage(first: f64, last: f64, frames: u64, fs: f64) -> Option<String> {
    if frames == 0 {
        return None;
    }
    let total = frames as f64;
    let unused = (first.max(0.0) + (total - last).max(0.0)) / total;
    (unused > 0.1).then(|| {
        format!(
            "keyphasor: pulses only from {:.3} s to {:.3} s of the recording's {:.3} s: {:.0} % of it has no keyphasor and was not used (the keyphasor was lost, or the rotor was not turning)",
            first / fs,
            last / fs,
            total / fs,
            100.0 * unused
        )
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `revs` revolutions of `n` samples of a sine of amplitude `a` [V],
    /// clipped at `clip` [V], quantised to `q` [V].
    fn health(n: usize, revs: usize, a: f64, clip: f64, q: f64) -> Result<(), String> {
        let mut h = ChannelHealth::default();
        for k in 0..n * revs {
            let v =
                (a * (std::f64::consts::TAU * k as f64 / n as f64 + 0.3).sin()).clamp(-clip, clip);
            let v = (v / q).round() * q;
            h.push(k as u64, v as f32, Some(n as f64));
        }
        h.finish("channel 1", 10_000.0, Some(n as f64))
    }

    #[test]
    fn a_sine_flat_topped_at_80_percent_is_clipped_and_a_quantised_one_is_not() {
        let e = health(1000, 20, 1.0, 0.8, 1e-6).unwrap_err();
        assert!(
            e.contains("channel 1 is clipped: 40 flat runs") && e.contains("at 0.8 V"),
            "{e}"
        );
        // 16-bit codes of a sine of 10 000 codes, 1000 samples a revolution.
        assert!(health(1000, 20, 10_000.0, 1e9, 1.0).is_ok());
        // Small ones: 300 and 30 codes, 4000 samples a revolution.
        assert!(health(4000, 10, 300.0, 1e9, 1.0).is_ok());
        assert!(health(4000, 10, 30.0, 1e9, 1.0).is_ok());
        // Clipped at 95 %: still found; two revolutions clipped are enough.
        assert!(health(1000, 20, 1.0, 0.95, 1e-6).is_err());
        assert!(health(1000, 2, 1.0, 0.8, 1e-6).is_err());
    }

    #[test]
    fn a_constant_channel_is_dead() {
        let mut h = ChannelHealth::default();
        for k in 0..5000 {
            h.push(k, 0.0, Some(500.0));
        }
        let e = h.finish("channel 2", 1000.0, Some(500.0)).unwrap_err();
        assert!(
            e.contains("channel 2 is dead") && e.contains("5000 samples"),
            "{e}"
        );
    }

    #[test]
    fn a_keyphasor_lost_after_the_start_is_named() {
        let w = keyphasor_coverage(0.0, 2_000.0, 100_000, 1000.0).unwrap();
        assert!(w.contains("98 %") && w.contains("2.000 s"), "{w}");
        assert!(keyphasor_coverage(100.0, 99_000.0, 100_000, 1000.0).is_none());
    }
}
