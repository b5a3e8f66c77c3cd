//! The estimation core: one noise model ([`noise`]), one noise policy
//! ([`pedestal`]: which noise a pedestal's fit uses) and one maximum-likelihood
//! errors-in-variables fit of the pedestal model ([`ml`]), used by
//! `plinth identify` (its default estimator), `plinth diagnose` (its noise
//! floor) and `plinth accuracy` (the Monte-Carlo against the Cramér–Rao bound).
//!
//! The data of one pedestal at one speed are an [`Observation`]: the measured
//! phasors, the known complex bearing stiffness and the noise variance of
//! every real number that was measured. It is the one type of a bearing at
//! one speed: `identify`'s OLS and ML fits, the convention check, `diagnose`
//! and `accuracy` all take it.
//!
//! The pedestal's parameters, identified, simulated or true, and their
//! standard errors are a [`Pedestal`] ([`params`]).

pub mod base;
pub mod gauss_helmert;
pub mod lack_of_fit;
pub mod levenberg;
pub mod ml;
pub mod monte_carlo;
pub mod noise;
pub mod params;
pub mod pedestal;
pub mod robust;
pub mod serial;

pub use params::Pedestal;

use num_complex::Complex;
use plinth_shared::phasor::{omega_from_hz, Phasor2};

/// Complex 2×2 matrix indexed `[row][col]` over (y, z).
pub type Complex2x2 = [[Complex<f64>; 2]; 2];

/// One bearing at one speed, with the noise of every measured number.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Observation {
    /// Rotor speed [Hz].
    pub speed_hz: f64,
    /// Rotor displacement relative to the pedestal, (y, z) [m].
    pub rel: Phasor2<f64>,
    /// Absolute pedestal displacement, (y, z) [m].
    pub ped: Phasor2<f64>,
    /// Complex bearing stiffness K_b + iΩ·C_b [N/m], so that F = K*·rel.
    pub kstar: Complex2x2,
    /// Noise variance [m²] of each real number, in the order of
    /// [`noise::REAL_CHANNELS`] (rel y re, rel y im, rel z re, rel z im,
    /// ped y re, ped y im, ped z re, ped z im).
    pub var: [f64; 8],
}

impl Observation {
    /// Bearing data at `speed_hz` [Hz]: rotor-relative and pedestal phasors
    /// `rel`, `ped` [m], the complex stiffness of the bearing `coefficients`
    /// at that speed, and no noise known (every variance 0: what the paper's
    /// OLS needs; [`noise`] gives the variances).
    pub fn without_noise(
        speed_hz: f64,
        rel: Phasor2<f64>,
        ped: Phasor2<f64>,
        coefficients: &plinth_shared::bearing::BearingCoefficients<f64>,
    ) -> Self {
        Self {
            speed_hz,
            rel,
            ped,
            kstar: complex_stiffness(coefficients, omega_from_hz(speed_hz)),
            var: [0.0; 8],
        }
    }

    /// Rotor speed Ω [rad/s].
    pub fn omega(&self) -> f64 {
        omega_from_hz(self.speed_hz)
    }

    /// The force the bearing transmits to the pedestal [N]: F = K*·rel.
    pub fn force(&self) -> Phasor2<f64> {
        mul(&self.kstar, &self.rel)
    }

    /// The noise sd [m] of real number `c` ([`noise::REAL_CHANNELS`] order).
    pub fn sd(&self, c: usize) -> f64 {
        self.var[c].sqrt()
    }

    /// |phasor| [m] of the complex channel real number `c`
    /// ([`noise::REAL_CHANNELS`] order) belongs to.
    pub fn magnitude(&self, c: usize) -> f64 {
        if c < 4 {
            self.rel[c / 2].norm()
        } else {
            self.ped[(c - 4) / 2].norm()
        }
    }

    /// True when the speed, the pedestal phasors and the bearing force are
    /// finite: what eq. 3 needs (the paper's OLS uses no variances).
    pub fn equation_is_finite(&self) -> bool {
        self.speed_hz.is_finite()
            && self
                .ped
                .iter()
                .chain(&self.force())
                .all(|c| c.re.is_finite() && c.im.is_finite())
    }

    /// True when every number is finite.
    pub fn is_finite(&self) -> bool {
        self.speed_hz.is_finite()
            && self
                .rel
                .iter()
                .chain(&self.ped)
                .all(|z| z.re.is_finite() && z.im.is_finite())
            && self
                .kstar
                .iter()
                .flatten()
                .all(|z| z.re.is_finite() && z.im.is_finite())
            && self.var.iter().all(|v| v.is_finite() && *v >= 0.0)
    }
}

/// The complex bearing stiffness K_b + iΩ·C_b [N/m] of coefficients at Ω [rad/s].
pub fn complex_stiffness(
    coefficients: &plinth_shared::bearing::BearingCoefficients<f64>,
    omega: f64,
) -> Complex2x2 {
    let mut kstar = [[Complex::new(0.0, 0.0); 2]; 2];
    for (r, row) in kstar.iter_mut().enumerate() {
        for (c, v) in row.iter_mut().enumerate() {
            *v = Complex::new(coefficients.k[r][c], omega * coefficients.c[r][c]);
        }
    }
    kstar
}

/// Complex 2×2 matrix times a (y, z) phasor pair.
pub fn mul(a: &Complex2x2, x: &Phasor2<f64>) -> Phasor2<f64> {
    [
        a[0][0] * x[0] + a[0][1] * x[1],
        a[1][0] * x[0] + a[1][1] * x[1],
    ]
}
