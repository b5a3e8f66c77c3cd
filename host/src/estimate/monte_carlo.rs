//! Monte-Carlo p-values: the one rule every resampling test of the
//! estimators reads its p-value by.

/// Besag & Clifford's (1991) sequential Monte-Carlo p-value [-]: `above`
/// of `done` draws under the null reached the observed statistic, the
/// drawing stopped once `stop` of them had. Stopped there it is
/// `above`/`done`; run to the end without reaching `stop` it is
/// (1 + `above`)/(1 + `done`), never zero.
pub fn sequential_p_value(above: usize, done: usize, stop: usize) -> f64 {
    if above >= stop {
        above as f64 / done.max(1) as f64
    } else {
        (1 + above) as f64 / (1 + done) as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stopped_early_and_run_to_the_end() {
        assert_eq!(sequential_p_value(20, 400, 20), 0.05);
        assert_eq!(sequential_p_value(0, 999, 20), 1e-3);
        assert_eq!(sequential_p_value(4, 999, 20), 5e-3);
    }
}
