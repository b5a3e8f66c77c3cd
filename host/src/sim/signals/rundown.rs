//! The run-down's kinematics: a linear speed ramp, its shaft angle and
//! keyphasor pulse times.

use super::*;

/// A linear speed ramp: from `start_hz` to `end_hz` at `rate_hz_per_s`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunDown {
    /// Speed at t = 0 [Hz].
    pub start_hz: f64,
    /// Speed at the end [Hz].
    pub end_hz: f64,
    /// Magnitude of the speed change per second [Hz/s] (> 0).
    pub rate_hz_per_s: f64,
}

impl RunDown {
    /// Parses `START:END:RATE` [Hz, Hz, Hz/s], e.g. `200:5:5`.
    pub fn parse(text: &str) -> Result<RunDown, SignalsError> {
        let parts: Vec<&str> = text.split(':').collect();
        let [a, b, c] = parts.as_slice() else {
            return Err(SignalsError::Request(format!(
                "--rundown {text:?}: use START:END:RATE [Hz:Hz:Hz/s], e.g. 200:5:5"
            )));
        };
        let num = |s: &str, what: &str| -> Result<f64, SignalsError> {
            s.trim().parse::<f64>().map_err(|_| {
                SignalsError::Request(format!("--rundown {text:?}: {what} {s:?} is not a number"))
            })
        };
        let r = RunDown {
            start_hz: num(a, "START")?,
            end_hz: num(b, "END")?,
            rate_hz_per_s: num(c, "RATE")?,
        };
        r.validate()
            .map_err(|m| SignalsError::Request(format!("--rundown {text:?}: {m}")))?;
        Ok(r)
    }

    /// Checks speeds are positive and distinct and the rate positive.
    pub fn validate(&self) -> Result<(), String> {
        let ok = |v: f64| v.is_finite() && v > 0.0;
        if !(ok(self.start_hz) && ok(self.end_hz)) {
            return Err(format!(
                "speeds must be finite and > 0 Hz (got {} and {})",
                self.start_hz, self.end_hz
            ));
        }
        let most = crate::args::MAX_SPEED_HZ;
        if self.start_hz.max(self.end_hz) > most {
            return Err(format!(
                "{:e} Hz is above {most:e} Hz (6 million rpm): a typo or rpm where Hz is meant?",
                self.start_hz.max(self.end_hz)
            ));
        }
        if self.start_hz == self.end_hz {
            return Err("START and END must differ".into());
        }
        if !ok(self.rate_hz_per_s) {
            return Err(format!(
                "RATE must be finite and > 0 Hz/s (got {})",
                self.rate_hz_per_s
            ));
        }
        Ok(())
    }

    /// Signed speed slope s [Hz/s]: negative for a run-down.
    pub fn slope(&self) -> f64 {
        if self.end_hz < self.start_hz {
            -self.rate_hz_per_s
        } else {
            self.rate_hz_per_s
        }
    }

    /// Duration [s].
    pub fn duration_s(&self) -> f64 {
        (self.end_hz - self.start_hz).abs() / self.rate_hz_per_s
    }

    /// Speed at time t [Hz].
    pub fn speed_hz(&self, t: f64) -> f64 {
        self.start_hz + self.slope() * t
    }

    /// Shaft angle at time t [rad], 0 at t = 0.
    pub fn angle_rad(&self, t: f64) -> f64 {
        TAU * t * (self.start_hz + 0.5 * self.slope() * t)
    }

    /// Time of keyphasor pulse j (shaft angle 2πj) [s], numerically stable
    /// root of f₀t + s·t²/2 = j.
    pub fn pulse_time(&self, j: u64) -> f64 {
        let j = j as f64;
        let f0 = self.start_hz;
        let disc = (f0 * f0 + 2.0 * self.slope() * j).max(0.0);
        2.0 * j / (f0 + disc.sqrt())
    }

    /// Number of complete revolutions within the run.
    pub fn revolutions(&self) -> u64 {
        let t = self.duration_s();
        (t * (self.start_hz + 0.5 * self.slope() * t))
            .floor()
            .max(0.0) as u64
    }
}
