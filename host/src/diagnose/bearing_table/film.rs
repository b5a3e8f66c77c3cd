//! The oil-film table: a bearing table that is the short-bearing oil film
//! of the machine file's geometry at some clearance c_w, and its clearance
//! correction K*_film(ρ·c_w) − K*_film(c_w) (see the parent module).

use super::super::data::Complex2x2;
use crate::sim::oil_film::OilFilmBearing;
use num_complex::Complex;

/// Widest clearance ratios searched: ρ ∈ [1 + LOWEST, 1 + HIGHEST].
pub const LOWEST: f64 = -0.5;
/// See [`LOWEST`].
pub const HIGHEST: f64 = 1.0;

/// Relative RMS misfit of the oil film to the written table above which the
/// table is not taken for an oil-film table of this geometry [-].
pub const MATCH_TOLERANCE: f64 = 0.05;

/// A bearing table that is an oil film of known geometry at clearance
/// `film.clearance` (the written clearance c_w).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WrittenTable {
    /// The machine file's bearing with the clearance the table was written for.
    pub film: OilFilmBearing,
    /// The clearance the machine file gives [m].
    pub file_clearance: f64,
    /// Relative RMS misfit of the film at `film.clearance` to the table [-].
    pub misfit: f64,
}

/// The complex stiffness K + iΩC [N/m] of `film` at `speed_hz` [Hz].
pub fn film_kstar(film: &OilFilmBearing, speed_hz: f64) -> Option<Complex2x2> {
    let bc = film.coefficients(speed_hz).ok()?;
    let omega = std::f64::consts::TAU * speed_hz;
    Some(std::array::from_fn(|r| {
        std::array::from_fn(|c| Complex::new(bc.k[r][c], omega * bc.c[r][c]))
    }))
}

/// Σ‖K*_film − K*_table‖²/Σ‖K*_table‖² over `table` (speed [Hz], K*).
fn misfit(film: &OilFilmBearing, table: &[(f64, Complex2x2)]) -> f64 {
    let (mut num, mut den) = (0.0, 0.0);
    for (f, k) in table {
        let Some(m) = film_kstar(film, *f) else {
            return f64::INFINITY;
        };
        for r in 0..2 {
            for c in 0..2 {
                num += (m[r][c] - k[r][c]).norm_sqr();
                den += k[r][c].norm_sqr();
            }
        }
    }
    if den > 0.0 {
        (num / den).sqrt()
    } else {
        f64::INFINITY
    }
}

impl WrittenTable {
    /// Finds the clearance the written `table` (speed [Hz], K*) corresponds
    /// to for the geometry of `film` (grid over a factor 3 either side of the
    /// machine file's clearance, then golden-section refinement); `None`
    /// when no clearance reproduces the table within [`MATCH_TOLERANCE`].
    pub fn matched(film: &OilFilmBearing, table: &[(f64, Complex2x2)]) -> Option<Self> {
        if table.is_empty() || film.clearance.is_nan() || film.clearance <= 0.0 {
            return None;
        }
        let at = |ln_c: f64| {
            let mut f = *film;
            f.clearance = ln_c.exp();
            misfit(&f, table)
        };
        let c0 = film.clearance.ln();
        let (lo, hi) = (c0 - 3f64.ln(), c0 + 3f64.ln());
        const GRID: usize = 61;
        let step = (hi - lo) / (GRID - 1) as f64;
        let (ib, _) = (0..GRID)
            .map(|i| (i, at(lo + step * i as f64)))
            .min_by(|a, b| a.1.total_cmp(&b.1))?;
        let (mut a, mut b) = (
            lo + step * ib.saturating_sub(1) as f64,
            lo + step * (ib + 1).min(GRID - 1) as f64,
        );
        let phi = 0.5 * (5f64.sqrt() - 1.0);
        for _ in 0..60 {
            let c = b - phi * (b - a);
            let d = a + phi * (b - a);
            if at(c) < at(d) {
                b = d;
            } else {
                a = c;
            }
        }
        let ln_c = 0.5 * (a + b);
        let mut f = *film;
        f.clearance = ln_c.exp();
        let m = misfit(&f, table);
        (m <= MATCH_TOLERANCE).then_some(Self {
            film: f,
            file_clearance: film.clearance,
            misfit: m,
        })
    }

    /// The correction K*_film(ρ·c_w) − K*_film(c_w) [N/m] at `speed_hz`
    /// [Hz] for δ = ρ − 1; `None` where the film cannot be computed.
    pub fn correction(&self, speed_hz: f64, delta: f64) -> Option<Complex2x2> {
        if delta == 0.0 {
            return Some([[Complex::new(0.0, 0.0); 2]; 2]);
        }
        let written = film_kstar(&self.film, speed_hz)?;
        let mut f = self.film;
        f.clearance *= 1.0 + delta;
        let true_ = film_kstar(&f, speed_hz)?;
        Some(std::array::from_fn(|r| {
            std::array::from_fn(|c| true_[r][c] - written[r][c])
        }))
    }
}

#[cfg(test)]
pub(super) mod tests {
    use super::*;

    /// A short oil-film bearing (100 mm × 40 mm, 0.1 mm clearance, 5 kN).
    pub(in crate::diagnose::bearing_table) fn film() -> OilFilmBearing {
        OilFilmBearing {
            diameter: 0.1,
            length: 0.04,
            clearance: 1.0e-4,
            viscosity: 0.02,
            load: 5.0e3,
        }
    }

    /// A table written for 85 % of the file's clearance is matched at that
    /// clearance, and the correction at ρ = 1/0.85 gives the file's film.
    #[test]
    fn matches_the_written_clearance_and_corrects_to_the_true_one() {
        let truth = film();
        let mut written = truth;
        written.clearance *= 0.85;
        let speeds: Vec<f64> = (0..40).map(|i| 10.0 + 2.0 * i as f64).collect();
        let table: Vec<(f64, Complex2x2)> = speeds
            .iter()
            .map(|&f| (f, film_kstar(&written, f).expect("film")))
            .collect();
        let t = WrittenTable::matched(&truth, &table).expect("matched");
        assert!((t.film.clearance / written.clearance - 1.0).abs() < 1e-6);
        assert!(t.misfit < 1e-6);
        let delta = 1.0 / 0.85 - 1.0;
        for (f, k) in &table {
            let corr = t.correction(*f, delta).expect("correction");
            let want = film_kstar(&truth, *f).expect("film");
            for r in 0..2 {
                for c in 0..2 {
                    let got = k[r][c] + corr[r][c];
                    assert!((got - want[r][c]).norm() <= 1e-6 * want[r][c].norm().max(1.0));
                }
            }
        }
    }

    /// A table that is no oil film of this geometry is not matched.
    #[test]
    fn a_foreign_table_is_not_matched() {
        let k = Complex::new(1.0e8, 1.0e5);
        let z = Complex::new(0.0, 0.0);
        let table: Vec<(f64, Complex2x2)> = (0..20)
            .map(|i| (10.0 + 5.0 * i as f64, [[k, z], [z, k]]))
            .collect();
        assert!(WrittenTable::matched(&film(), &table).is_none());
    }
}
