//! Bearing coefficients and the force a bearing transmits to its pedestal.
//!
//! F = (K_b + iΩ·C_b) · rel  (Feng & Hahn eq. 2; formats.md), where `rel` is the
//! rotor displacement relative to the pedestal at the bearing.

use crate::phasor::{Complex, Phasor2};
use num_traits::Float;
use serde::{Deserialize, Serialize};

/// The eight linearised coefficients of one bearing at one speed.
///
/// `k` in N/m and `c` in N·s/m, indexed `[row][col]` over (y, z):
/// `k = [[kyy, kyz], [kzy, kzz]]`.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct BearingCoefficients<T = f32> {
    /// Stiffness matrix [N/m].
    pub k: [[T; 2]; 2],
    /// Damping matrix [N·s/m].
    pub c: [[T; 2]; 2],
}

impl<T: Float> BearingCoefficients<T> {
    /// Isotropic, uncoupled coefficients: k [N/m] and c [N·s/m] on the diagonal.
    pub fn isotropic(k: T, c: T) -> Self {
        let z = T::zero();
        Self {
            k: [[k, z], [z, k]],
            c: [[c, z], [z, c]],
        }
    }

    /// Force [N] the bearing exerts on its pedestal at Ω [rad/s] for the
    /// rotor-relative 1X displacement `rel` [m]: F = (K + iΩC)·rel.
    #[inline]
    pub fn force(&self, omega: T, rel: &Phasor2<T>) -> Phasor2<T> {
        let mut f = [Complex::new(T::zero(), T::zero()); 2];
        for (i, fi) in f.iter_mut().enumerate() {
            for (j, r) in rel.iter().enumerate() {
                *fi = *fi + Complex::new(self.k[i][j], omega * self.c[i][j]) * *r;
            }
        }
        f
    }

    /// Linear interpolation between `self` (t = 0) and `other` (t = 1).
    #[inline]
    pub fn lerp(&self, other: &Self, t: T) -> Self {
        let mut out = *self;
        for i in 0..2 {
            for j in 0..2 {
                out.k[i][j] = self.k[i][j] + (other.k[i][j] - self.k[i][j]) * t;
                out.c[i][j] = self.c[i][j] + (other.c[i][j] - self.c[i][j]) * t;
            }
        }
        out
    }

    /// Converts the scalar type (f64 on the host, f32 on the box).
    pub fn cast<U: Float>(&self) -> BearingCoefficients<U> {
        let cv = |x: T| U::from(x).unwrap_or_else(U::nan);
        BearingCoefficients {
            k: [
                [cv(self.k[0][0]), cv(self.k[0][1])],
                [cv(self.k[1][0]), cv(self.k[1][1])],
            ],
            c: [
                [cv(self.c[0][0]), cv(self.c[0][1])],
                [cv(self.c[1][0]), cv(self.c[1][1])],
            ],
        }
    }
}

/// Why a bearing table could not give coefficients.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum BearingTableError {
    /// The table holds no speeds.
    Empty,
    /// The table is full (capacity N).
    Full,
    /// Speeds must be added in strictly increasing order.
    NotIncreasing,
    /// The requested speed lies outside the table (no extrapolation).
    OutOfRange,
}

/// A fixed-capacity speed table of bearing coefficients for one bearing,
/// interpolated linearly in speed and never extrapolated (formats.md).
#[derive(Clone, Debug)]
pub struct BearingTable<const N: usize, T = f32> {
    speeds_hz: heapless::Vec<T, N>,
    coefficients: heapless::Vec<BearingCoefficients<T>, N>,
}

impl<const N: usize, T: Float> Default for BearingTable<N, T> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const N: usize, T: Float> BearingTable<N, T> {
    /// An empty table.
    pub const fn new() -> Self {
        Self {
            speeds_hz: heapless::Vec::new(),
            coefficients: heapless::Vec::new(),
        }
    }

    /// Number of speeds in the table.
    pub fn len(&self) -> usize {
        self.speeds_hz.len()
    }

    /// True when the table holds no speeds.
    pub fn is_empty(&self) -> bool {
        self.speeds_hz.is_empty()
    }

    /// Removes every entry.
    pub fn clear(&mut self) {
        self.speeds_hz.clear();
        self.coefficients.clear();
    }

    /// Appends the coefficients at `speed_hz` [Hz]; speeds must increase.
    pub fn push(
        &mut self,
        speed_hz: T,
        coefficients: BearingCoefficients<T>,
    ) -> Result<(), BearingTableError> {
        let increasing = match self.speeds_hz.last() {
            Some(&last) => speed_hz > last,
            None => true,
        };
        if !increasing || !speed_hz.is_finite() {
            return Err(BearingTableError::NotIncreasing);
        }
        self.speeds_hz
            .push(speed_hz)
            .map_err(|_| BearingTableError::Full)?;
        if self.coefficients.push(coefficients).is_err() {
            self.speeds_hz.pop();
            return Err(BearingTableError::Full);
        }
        Ok(())
    }

    /// Coefficients at `speed_hz` [Hz], interpolated linearly between the two
    /// nearest listed speeds; outside the listed range is an error.
    pub fn at(&self, speed_hz: T) -> Result<BearingCoefficients<T>, BearingTableError> {
        let n = self.speeds_hz.len();
        if n == 0 {
            return Err(BearingTableError::Empty);
        }
        let first = self.speeds_hz[0];
        let last = self.speeds_hz[n - 1];
        let inside = speed_hz >= first && speed_hz <= last;
        if !inside {
            return Err(BearingTableError::OutOfRange);
        }
        interpolate(&self.speeds_hz, &self.coefficients, speed_hz)
            .ok_or(BearingTableError::OutOfRange)
    }
}

/// Bearing coefficients at `speed_hz` [Hz] from a table listed at strictly
/// increasing `speeds_hz` [Hz] (`coefficients[i]` at `speeds_hz[i]`):
/// linear in speed between the two nearest listed speeds, `None` outside
/// the listed range (no extrapolation, formats.md), for an empty table or
/// slices of different lengths. The one speed-table interpolation of the
/// workspace (the box's [`BearingTable`], the host's run-directory schedule
/// and the simulator's tables all call it).
pub fn interpolate<T: Float>(
    speeds_hz: &[T],
    coefficients: &[BearingCoefficients<T>],
    speed_hz: T,
) -> Option<BearingCoefficients<T>> {
    if speeds_hz.len() != coefficients.len() {
        return None;
    }
    let (first, last) = (*speeds_hz.first()?, *speeds_hz.last()?);
    if !(speed_hz >= first && speed_hz <= last) {
        return None;
    }
    // First index whose speed is >= speed_hz.
    let hi = speeds_hz.partition_point(|&s| s < speed_hz);
    let (s_hi, c_hi) = (*speeds_hz.get(hi)?, coefficients.get(hi)?);
    if hi == 0 || s_hi == speed_hz {
        return Some(*c_hi);
    }
    let (s_lo, c_lo) = (*speeds_hz.get(hi - 1)?, coefficients.get(hi - 1)?);
    Some(c_lo.lerp(c_hi, (speed_hz - s_lo) / (s_hi - s_lo)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn force_of_pure_stiffness_is_in_phase() {
        let b = BearingCoefficients::<f64>::isotropic(2.0e7, 0.0);
        let rel = [Complex::new(1e-6, 0.0), Complex::new(0.0, 1e-6)];
        let f = b.force(100.0, &rel);
        assert!((f[0] - Complex::new(20.0, 0.0)).norm() < 1e-12);
        assert!((f[1] - Complex::new(0.0, 20.0)).norm() < 1e-12);
    }

    #[test]
    fn damping_force_leads_displacement_by_90_degrees() {
        let b = BearingCoefficients::<f64>::isotropic(0.0, 1.0e3);
        let rel = [Complex::new(1e-6, 0.0), Complex::new(0.0, 0.0)];
        let f = b.force(200.0, &rel);
        // iΩc·x = i·200·1e3·1e-6 = 0.2i
        assert!((f[0] - Complex::new(0.0, 0.2)).norm() < 1e-12);
    }

    #[test]
    fn cross_coupled_stiffness_moves_the_other_direction() {
        let mut b = BearingCoefficients::<f64>::isotropic(1.0e7, 0.0);
        b.k[1][0] = -3.0e6; // kzy
        let rel = [Complex::new(1e-6, 0.0), Complex::new(0.0, 0.0)];
        let f = b.force(10.0, &rel);
        assert!((f[1].re + 3.0).abs() < 1e-12);
    }

    #[test]
    fn table_interpolates_and_refuses_to_extrapolate() {
        let mut t: BearingTable<4, f64> = BearingTable::new();
        t.push(10.0, BearingCoefficients::isotropic(1.0e7, 1.0e3))
            .unwrap();
        t.push(20.0, BearingCoefficients::isotropic(2.0e7, 3.0e3))
            .unwrap();
        let c = t.at(12.5).unwrap();
        assert!((c.k[0][0] - 1.25e7).abs() < 1e-6);
        assert!((c.c[1][1] - 1.5e3).abs() < 1e-9);
        assert_eq!(t.at(20.0).unwrap().k[0][0], 2.0e7);
        assert_eq!(t.at(10.0).unwrap().k[0][0], 1.0e7);
        assert_eq!(t.at(9.99), Err(BearingTableError::OutOfRange));
        assert_eq!(t.at(f64::NAN), Err(BearingTableError::OutOfRange));
        assert_eq!(
            t.push(15.0, BearingCoefficients::isotropic(0.0, 0.0)),
            Err(BearingTableError::NotIncreasing)
        );
    }
}
