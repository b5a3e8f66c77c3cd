//! The noise of a whole run ([`RunNoise`]): every measured bearing's
//! [`BearingNoise`], estimated once before any fit, and the noise of the run
//! with a convention mistake undone derived from it.

use super::*;

/// The noise model of every measured bearing of a run, estimated once
/// before any fit and shared by every use of it (the fits, the noise floor,
/// the convention refits, which transform it as they transform the data).
#[derive(Clone, Debug, PartialEq)]
pub struct RunNoise {
    /// How the digits were taken to be reduced.
    pub quantisation: Quantisation,
    /// Per measured bearing, in order of first appearance: its name, the
    /// indices of its rows in `run.measurements` and their noise (row for
    /// row).
    pub bearings: Vec<(String, Vec<usize>, BearingNoise)>,
}

impl RunNoise {
    /// The noise of every measured bearing of `run`, with the digits of
    /// each bearing's columns counted on its own rows
    /// ([`ColumnDigits::of_rows`]).
    pub fn estimate(run: &crate::rundir::RunDir, quantisation: Quantisation) -> Self {
        let bearings = run
            .measured_bearings()
            .into_iter()
            .map(|bearing| {
                let index: Vec<usize> = (0..run.measurements.len())
                    .filter(|&i| run.measurements[i].bearing == bearing)
                    .collect();
                let rows: Vec<&Measurement> = index.iter().map(|&i| &run.measurements[i]).collect();
                let columns = ColumnDigits::of_rows(&rows);
                let noise = BearingNoise::estimate(&rows, &columns, quantisation);
                (bearing.to_string(), index, noise)
            })
            .collect();
        Self {
            quantisation,
            bearings,
        }
    }

    /// The noise of `fixed`, the measurements of the run this noise was
    /// estimated on with their pedestal phasors changed and their speeds and
    /// rotor-relative phasors not (pedestal velocities integrated; row for
    /// row, bearing names not read): exactly [`RunNoise::estimate`] of a run
    /// with these measurements, with the rotor-relative channels' scatter
    /// laws kept and the digits and the pedestal channels' scatter
    /// estimated anew. Estimated afresh when this noise is no longer as
    /// estimated (switched to the scatter or rescaled by a fit).
    pub fn with_pedestal_of(&self, fixed: &[Measurement]) -> Self {
        let pristine = self.bearings.iter().all(|(_, index, noise)| {
            noise.variance_scale == 1.0
                && noise.var.len() == index.len()
                && index.iter().all(|&i| i < fixed.len())
                && match noise.source {
                    NoiseSource::Columns => true,
                    NoiseSource::Digits => noise.scatter_var.is_some(),
                    NoiseSource::Scatter => false,
                }
        });
        if !pristine {
            // [`RunNoise::estimate`] of `fixed`, its rows grouped as this
            // noise groups them (the same bearings, row for row).
            let bearings = self
                .bearings
                .iter()
                .map(|(name, index, _)| {
                    let rows: Vec<&Measurement> =
                        index.iter().filter_map(|&i| fixed.get(i)).collect();
                    let columns = ColumnDigits::of_rows(&rows);
                    let noise = BearingNoise::estimate(&rows, &columns, self.quantisation);
                    (name.clone(), index.clone(), noise)
                })
                .collect();
            return Self {
                quantisation: self.quantisation,
                bearings,
            };
        }
        // The digits of every number of `fixed`, counted once (a changed
        // number's are counted on its value: the slow part).
        let digits: Vec<[Option<(u32, i32)>; 8]> = fixed
            .iter()
            .map(|m| std::array::from_fn(|c| digits_of(m, c)))
            .collect();
        let bearings = self
            .bearings
            .iter()
            .map(|(name, index, noise)| {
                let rows: Vec<&Measurement> = index.iter().map(|&i| &fixed[i]).collect();
                // [`ColumnDigits::of_rows`] of this bearing's rows.
                let columns = ColumnDigits::of_digit_rows(index.iter().map(|&i| digits[i]));
                let noise = match noise.source {
                    NoiseSource::Columns => {
                        BearingNoise::estimate(&rows, &columns, self.quantisation)
                    }
                    _ => {
                        let (s, left) = (noise.scatter, noise.scatter_left_out);
                        // `digits_variances`, from the digits counted above.
                        let digits_var = index
                            .iter()
                            .zip(&rows)
                            .map(|(&i, m)| {
                                std::array::from_fn(|c| {
                                    let ulp =
                                        columns[c].ulp_of_digits(digits[i][c], real_value(m, c));
                                    rounding_variance(self.quantisation, ulp, m, c)
                                })
                            })
                            .collect();
                        BearingNoise::with_scatter(
                            &rows,
                            digits_var,
                            self.quantisation,
                            [Some((s[0], left[0])), Some((s[1], left[1])), None, None],
                        )
                    }
                };
                (name.clone(), index.clone(), noise)
            })
            .collect();
        Self {
            quantisation: self.quantisation,
            bearings,
        }
    }

    /// The noise of the rows of `bearing`, with their indices in
    /// `run.measurements`.
    pub fn bearing(&self, bearing: &str) -> Option<(&[usize], &BearingNoise)> {
        self.bearings
            .iter()
            .find(|(name, _, _)| name == bearing)
            .map(|(_, index, noise)| (index.as_slice(), noise))
    }

    /// [`BearingNoise::swapped_yz`] of every bearing.
    pub fn swapped_yz(&self) -> Self {
        Self {
            quantisation: self.quantisation,
            bearings: self
                .bearings
                .iter()
                .map(|(name, index, noise)| (name.clone(), index.clone(), noise.swapped_yz()))
                .collect(),
        }
    }
}
