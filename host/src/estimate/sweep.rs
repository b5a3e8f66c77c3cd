//! A phasor averaged over a span of speed (`averaging.toml`, optional,
//! docs/formats.md "Extensions of the run directory"): the averaging's
//! error counted in each phasor's noise, once, where the run directory is
//! read, so every fit and every rule (identify's lack-of-fit, delay, gain
//! and speed tests; diagnose) sees it.
//!
//! **What is wrong without it.** The pedestal equations are pointwise:
//! Z(Ω)·P(Ω) = K_b(Ω)·R(Ω) at one speed Ω, Z = k − Ω²m + iΩc the pedestal's
//! dynamic stiffness [N/m], K_b the bearing table, P and R the pedestal and
//! relative phasors [m]. A box that averages R revolutions per phasor in a
//! run-down (the field box, `plinth extract`, a monitoring system's
//! tracking filter) writes P̄ = the mean of P over the speeds those
//! revolutions span, at the span's mean speed Ω_c. With δ = Ω − Ω_c and
//! σ² = E[δ²] over the window, P̄ = P(Ω_c) + ½σ²P''(Ω_c) + O(σ⁴): the
//! measured phasor is not the pointwise one, by a term of order (speed
//! span)² × the phasor's curvature in speed (in the equations' own terms,
//! Z'σ²P' + ½Z''σ²P − K'σ²R' − ½K''σ²R: the same, by twice differentiating
//! ZP = KR), large only where the phasors turn fast with speed, through a
//! resonance. On the bundled demo (150 → 20 Hz at 20 Hz/s, 4 revolutions a
//! phasor) a phasor near the rotor modes at 27 and 45 Hz and the pedestal
//! resonances at 50-58 Hz spans 1.4-3 Hz against resonances 0.1-0.2 Hz
//! wide, and identify's lack-of-fit, delay and sensor-gain rules read the
//! difference as model error (docs/trust-sweep.md).
//!
//! **Counted, not corrected.** Where the span is narrow against the
//! resonance, P(Ω_c) = P̄ − ½σ²P'' with P'' from neighbouring rows would
//! correct it; where it is wider (the demo) the response turns within one
//! phasor, the data do not hold P(Ω_c) and a correction from three
//! neighbouring means is of the size of its own error. The error's size
//! is what the data do show: per phasor and channel, d = ½σ²·P̂'' (P̂'' the
//! second difference of the row and its neighbours of the same bearing, in
//! speed), counted as a noise of that phasor: sd² + |d|² in place of the
//! noise column's sd² ([`count_in_noise`]). Where the phasors do not turn
//! (away from resonances) d is a percent of the noise (the second
//! difference's own noise, 6 sd²·(σ²/2h²)² = sd²/96 at σ² = h²/12) and
//! nothing changes that matters; through a resonance those speeds weigh
//! less, as their agreement with the pointwise model is worse.
//!
//! **The window** ([`Averaging`]): R revolutions each weighted alike (the
//! box's extractor: a phasor the mean of R one-revolution phasors; a
//! tracking filter's block of R revolutions taken the same way), speed
//! nearly linear in revolution count over a block, so δ is uniform over
//! the span w and σ² = w²/12. The span of a row at f [Hz] is a·R/f
//! (`rate_hz_per_s` a given: R revolutions at f last R/f s) or, without a
//! rate, the rows being consecutive blocks (the box, `plinth extract`), the
//! smaller distance in speed to its neighbouring rows ([`spans_hz`]).

use crate::rundir::{Measurement, RunDirError};
use plinth_shared::phasor::Complex;
use serde::Deserialize;
use std::collections::BTreeMap;
use std::path::Path;

/// File name of the averaging statement in a run directory.
pub const AVERAGING_FILE: &str = "averaging.toml";

/// `averaging.toml`: how each row's phasors were averaged.
#[derive(Clone, Copy, Debug, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Averaging {
    /// Keyphasor revolutions averaged into each phasor, each weighted alike
    /// (≥ 1) [-].
    pub revolutions: u32,
    /// The run-down's (or run-up's) rate of speed change [Hz/s], when known;
    /// absent: the rows are consecutive blocks of `revolutions` and the
    /// span is read from the distance between rows ([`spans_hz`]).
    #[serde(default)]
    pub rate_hz_per_s: Option<f64>,
}

impl Averaging {
    /// The text Plinth writes for `revolutions` per phasor, rows consecutive
    /// blocks (the box and `plinth extract`).
    pub fn consecutive_text(revolutions: u32) -> String {
        format!(
            "# Each phasor of measurements.csv is the mean of this many keyphasor revolutions,\n# each weighted alike; rows are consecutive blocks (docs/formats.md).\nrevolutions = {revolutions}\n"
        )
    }
}

/// Writes [`AVERAGING_FILE`] into `dir` for `measurements` that are
/// consecutive blocks of `revolutions` revolutions
/// ([`Averaging::consecutive_text`]); where a row lacks the noise columns
/// (the file then has none, and the count needs them) none is written and
/// an earlier one in `dir` is removed. Returns whether it was written.
pub fn write_consecutive(
    dir: &Path,
    measurements: &[Measurement],
    revolutions: u32,
) -> Result<bool, RunDirError> {
    let path = dir.join(AVERAGING_FILE);
    if measurements.is_empty() || measurements.iter().any(|m| m.noise_sd.is_none()) {
        return match std::fs::remove_file(&path) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => Err(RunDirError::Io {
                file: path,
                source: e,
            }),
            _ => Ok(false),
        };
    }
    std::fs::write(&path, Averaging::consecutive_text(revolutions))
        .map_err(|source| RunDirError::Io { file: path, source })?;
    Ok(true)
}

/// Reads [`AVERAGING_FILE`] of `dir`, `None` when there is none. Errors
/// name the file, line and key.
pub fn read(dir: &Path) -> Result<Option<Averaging>, RunDirError> {
    let path = dir.join(AVERAGING_FILE);
    let text = match std::fs::read_to_string(&path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => return Ok(None),
        Err(source) => return Err(RunDirError::Io { file: path, source }),
        Ok(t) => t,
    };
    parse(&text)
        .map(Some)
        .map_err(|(line, message)| RunDirError::Csv {
            file: path,
            line,
            message,
        })
}

/// Parses the text of [`AVERAGING_FILE`]; on error the 1-based line and a
/// message naming the key.
fn parse(text: &str) -> Result<Averaging, (u64, String)> {
    let line_of = |offset: usize| text[..offset.min(text.len())].matches('\n').count() as u64 + 1;
    let a: Averaging = toml::from_str(text).map_err(|e| {
        let line = e.span().map_or(1, |s| line_of(s.start));
        (line, e.message().to_string())
    })?;
    let key_line = |key: &str| {
        text.lines()
            .position(|l| l.trim_start().starts_with(key))
            .map_or(1, |i| i as u64 + 1)
    };
    if a.revolutions == 0 {
        return Err((
            key_line("revolutions"),
            "key `revolutions`: must be at least 1".into(),
        ));
    }
    if let Some(r) = a.rate_hz_per_s {
        if !(r.is_finite() && r > 0.0) {
            return Err((
                key_line("rate_hz_per_s"),
                format!("key `rate_hz_per_s`: {r} must be a finite number above 0 [Hz/s] (a run-up's rate too)"),
            ));
        }
    }
    Ok(a)
}

/// The speed span [Hz] each of a bearing's rows at `speeds` [Hz] (sorted,
/// distinct) averages (module docs, "The window"): a·R/f with a rate, else
/// the smaller distance to a neighbouring row (the rows consecutive
/// blocks); 0 for a lone row without a rate.
pub fn spans_hz(speeds: &[f64], averaging: &Averaging) -> Vec<f64> {
    let r = f64::from(averaging.revolutions);
    (0..speeds.len())
        .map(|j| match averaging.rate_hz_per_s {
            Some(a) => a * r / speeds[j],
            None => {
                let below = j.checked_sub(1).map(|i| speeds[j] - speeds[i]);
                let above = speeds.get(j + 1).map(|s| s - speeds[j]);
                match (below, above) {
                    (Some(b), Some(a)) => b.min(a),
                    (Some(d), None) | (None, Some(d)) => d,
                    (None, None) => 0.0,
                }
            }
        })
        .collect()
}

/// d = ½σ²·P'' [m] of one channel (module docs): the phasors `p` at speeds
/// `f` [Hz] of three neighbouring rows, the middle one's window of span
/// `span` [Hz] (σ² = span²/12); P'' the second difference in speed
/// (exact for a quadratic response, also of means over equal windows).
pub fn averaging_error(f: [f64; 3], p: [Complex<f64>; 3], span: f64) -> Complex<f64> {
    let (h_lo, h_hi) = (f[1] - f[0], f[2] - f[1]);
    let zero = Complex::new(0.0, 0.0);
    if !(h_lo > 0.0 && h_hi > 0.0 && span.is_finite()) {
        return zero;
    }
    let second = ((p[2] - p[1]) / h_hi - (p[1] - p[0]) / h_lo) * (2.0 / (h_lo + h_hi));
    let d = second * (0.5 * span * span / 12.0);
    if d.re.is_finite() && d.im.is_finite() {
        d
    } else {
        zero
    }
}

/// Counts the averaging's error in the noise of every row of
/// `measurements` (module docs): per bearing in speed order, each row's
/// four noise sds become √(sd² + |d|²), d from the row and its two
/// neighbours ([`averaging_error`]); a first or last row takes its
/// neighbour's d. Rows must carry the noise columns (`Err` with the first
/// row that does not, by index). Returns the number of rows whose noise
/// grew.
pub fn count_in_noise(
    measurements: &mut [Measurement],
    averaging: &Averaging,
) -> Result<usize, usize> {
    if let Some(i) = measurements.iter().position(|m| m.noise_sd.is_none()) {
        return Err(i);
    }
    let mut by_bearing: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
    for (i, m) in measurements.iter().enumerate() {
        by_bearing.entry(&m.bearing).or_default().push(i);
    }
    let mut errors: Vec<(usize, [f64; 4])> = Vec::new();
    for rows in by_bearing.values_mut() {
        rows.sort_by(|&a, &b| {
            measurements[a]
                .speed_hz
                .total_cmp(&measurements[b].speed_hz)
        });
        let speeds: Vec<f64> = rows.iter().map(|&i| measurements[i].speed_hz).collect();
        let spans = spans_hz(&speeds, averaging);
        if rows.len() < 3 {
            continue;
        }
        let channels = |m: &Measurement| [m.rel[0], m.rel[1], m.ped[0], m.ped[1]];
        let interior: Vec<[f64; 4]> = (1..rows.len() - 1)
            .map(|j| {
                let [a, b, c] =
                    [rows[j - 1], rows[j], rows[j + 1]].map(|i| channels(&measurements[i]));
                let f = [speeds[j - 1], speeds[j], speeds[j + 1]];
                std::array::from_fn(|k| averaging_error(f, [a[k], b[k], c[k]], spans[j]).norm())
            })
            .collect();
        for (j, &i) in rows.iter().enumerate() {
            // The ends take their neighbour's error.
            let d = interior[j.clamp(1, rows.len() - 2) - 1];
            errors.push((i, d));
        }
    }
    let mut grown = 0;
    for (i, d) in errors {
        if let Some(sd) = measurements[i].noise_sd.as_mut() {
            let before = *sd;
            for (s, e) in sd.iter_mut().zip(d) {
                *s = s.hypot(e);
            }
            grown += usize::from(*sd != before);
        }
    }
    Ok(grown)
}

/// Reads [`AVERAGING_FILE`] of `dir`, when there is one, and counts the
/// averaging's error in the noise of `measurements` ([`count_in_noise`]);
/// `measurements_file` names the file in the error where a row lacks the
/// noise columns.
pub fn read_into(
    dir: &Path,
    measurements: &mut [Measurement],
    measurements_file: &Path,
) -> Result<(), RunDirError> {
    let Some(averaging) = read(dir)? else {
        return Ok(());
    };
    count_in_noise(measurements, &averaging).map_err(|i| RunDirError::Csv {
        file: dir.join(AVERAGING_FILE),
        line: 1,
        message: format!(
            "the run states its phasors are averages, whose error is counted in each phasor's noise, but {} (row {} of {}, bearing {}) has no noise columns (rel_y_sd, rel_z_sd, ped_y_sd, ped_z_sd)",
            measurements_file.display(),
            i + 1,
            measurements.len(),
            measurements[i].bearing
        ),
    })?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(speed_hz: f64, p: Complex<f64>) -> Measurement {
        Measurement {
            speed_hz,
            bearing: "B1".into(),
            rel: [p, p],
            ped: [p, p],
            noise_sd: Some([1e-9; 4]),
            written: None,
        }
    }

    /// The file's keys, its errors by key and line; the spans with and
    /// without a rate.
    #[test]
    fn the_file_and_the_spans() {
        let a = parse("revolutions = 32\nrate_hz_per_s = 0.5\n").unwrap();
        assert_eq!(a.revolutions, 32);
        // 32 revolutions at 16 Hz last 2 s: 1 Hz at 0.5 Hz/s.
        assert_eq!(spans_hz(&[16.0], &a), vec![1.0]);
        let e = parse("revolutions = 4\nrate_hz_per_s = -1\n").unwrap_err();
        assert_eq!(e.0, 2);
        assert!(e.1.contains("rate_hz_per_s"), "{}", e.1);
        let e = parse("revolutions = 0\n").unwrap_err();
        assert!(e.1.contains("revolutions"), "{}", e.1);
        let e = parse("\nrevolution = 4\n").unwrap_err();
        assert!(e.1.contains("revolution"), "{}", e.1);
        let c = parse(&Averaging::consecutive_text(4)).unwrap();
        assert_eq!(c.rate_hz_per_s, None);
        assert_eq!(
            spans_hz(&[10.0, 11.0, 13.0, 16.0], &c),
            vec![1.0, 1.0, 2.0, 3.0]
        );
        assert_eq!(spans_hz(&[10.0], &c), vec![0.0]);
    }

    /// d = ½σ²P'' is exact for a quadratic response: P = f², P'' = 2,
    /// d = σ² = span²/12; a straight line gives none; the noise of a row
    /// grows by it, the ends by their neighbour's.
    #[test]
    fn the_error_of_a_quadratic_response_and_its_count() {
        let c = |x: f64| Complex::new(x, 0.0);
        let d = averaging_error([1.0, 2.0, 4.0], [c(1.0), c(4.0), c(16.0)], 3.0);
        assert!((d.re - 9.0 / 12.0).abs() < 1e-12 && d.im == 0.0, "{d}");
        let d = averaging_error([1.0, 2.0, 4.0], [c(1.0), c(2.0), c(4.0)], 3.0);
        assert_eq!(d.norm(), 0.0);
        let mut rows: Vec<Measurement> = [3.0, 1.0, 2.0, 4.0]
            .iter()
            .map(|&f| row(f, c(1e-9 * f * f)))
            .collect();
        let a = Averaging {
            revolutions: 1,
            rate_hz_per_s: None,
        };
        assert_eq!(count_in_noise(&mut rows, &a), Ok(4));
        // Spans 1 Hz everywhere, P'' = 2e-9: d = ½·2e-9·1/12 on each channel.
        let want = 1e-9f64.hypot(1e-9 / 12.0);
        for r in &rows {
            for s in r.noise_sd.unwrap() {
                assert!((s - want).abs() < 1e-20, "{s} {want}");
            }
        }
        rows[2].noise_sd = None;
        assert_eq!(count_in_noise(&mut rows, &a), Err(2));
    }
}
