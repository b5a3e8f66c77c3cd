//! The convention mistakes field data commonly carry, and how each is
//! undone on a run (its data, its bearing table, its noise).

use super::rotation::Angle;
use super::*;

/// A convention mistake that field data commonly carry (formats.md names
/// them; serialised in snake_case: `conjugated`, `swapped_yz`, ...).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Convention {
    /// Every phasor conjugated (phase lag read as lead).
    Conjugated,
    /// y and z of the readings exchanged.
    SwappedYz,
    /// `rel` written as pedestal minus rotor.
    RelNegated,
    /// Bearing matrices K_b, C_b transposed.
    BearingTransposed,
    /// The bearing's cross-coupling terms with the wrong sign.
    CrossCouplingSign,
    /// Speeds in rpm read as Hz.
    SpeedInRpm,
    /// Only the pedestal phasors conjugated.
    PedConjugated,
    /// Pedestal velocity written as displacement.
    PedVelocity,
    /// The proximity probes (`rel`) mounted at an angle and written as they
    /// read: the pair turned by the angle [deg] ([`super::rotation`]).
    RelRotated(Angle),
    /// The casing pick-ups (`ped`) mounted at an angle and written as they
    /// read: the pair turned by the angle [deg] ([`super::rotation`]).
    PedRotated(Angle),
}

impl Convention {
    /// Every mistake of fixed form tried, in report order (the turned
    /// pairs, whose angle the data give, are tried after them:
    /// [`super::rotation::candidates`]).
    pub const ALL: [Convention; 8] = [
        Convention::Conjugated,
        Convention::SwappedYz,
        Convention::RelNegated,
        Convention::BearingTransposed,
        Convention::CrossCouplingSign,
        Convention::SpeedInRpm,
        Convention::PedConjugated,
        Convention::PedVelocity,
    ];

    /// True for a mistake that, when made, is made for the whole run: the
    /// speeds are one column of measurements.csv, so their unit is the
    /// same at every bearing (the sign and phase conventions can differ
    /// from one transducer or bearing table to the next). Such a mistake is
    /// named only when the run as a whole prefers it
    /// ([`super::decide::run_prefers`]).
    pub fn run_wide(self) -> bool {
        matches!(self, Convention::SpeedInRpm)
    }

    /// The name used in `--json` and messages.
    pub fn name(self) -> &'static str {
        match self {
            Convention::Conjugated => "conjugated",
            Convention::SwappedYz => "swapped_yz",
            Convention::RelNegated => "rel_negated",
            Convention::BearingTransposed => "bearing_transposed",
            Convention::CrossCouplingSign => "cross_coupling_sign",
            Convention::SpeedInRpm => "speed_in_rpm",
            Convention::PedConjugated => "ped_conjugated",
            Convention::PedVelocity => "ped_velocity",
            Convention::RelRotated(_) => "rel_rotated",
            Convention::PedRotated(_) => "ped_rotated",
        }
    }

    /// What the mistake is, for people.
    pub fn describe(self) -> Cow<'static, str> {
        let turned = |what: &str, y: &str, z: &str, a: Angle| {
            let arrangement = if a.is_field_arrangement() {
                " (a field arrangement: the X-Y pair of API 670 is at ±45° from the vertical)"
            } else {
                ""
            };
            let d = a.deg();
            Cow::Owned(format!(
                "the {what} read as a pair turned by {a} from y (vertical) and z (horizontal){arrangement}: `{y}` reads along {}° and `{z}` along {}° from the vertical (towards +z). Were they written as they read? Resolve them to y and z: y = cos a·{y} + sin a·{z}, z = −sin a·{y} + cos a·{z} with a = {a} (docs/formats.md: y vertical, z horizontal; `plinth import` resolves probe angles)",
                Angle::from_deg(-d).deg(),
                Angle::from_deg(90.0 - d).deg(),
            ))
        };
        Cow::Borrowed(match self {
            Convention::RelRotated(a) => {
                return turned("proximity probes (rel)", "rel_y", "rel_z", a)
            }
            Convention::PedRotated(a) => {
                return turned("casing pick-ups (ped)", "ped_y", "ped_z", a)
            }
            Convention::Conjugated => {
                "the phasors are conjugated (phase lag read as lead: docs/formats.md wants q(t) = Re{Q·e^{iΩt}})"
            }
            Convention::SwappedYz => {
                "the y and z readings are swapped (docs/formats.md: y vertical, z horizontal)"
            }
            Convention::RelNegated => {
                "rel is pedestal minus rotor (docs/formats.md: rel = rotor − pedestal)"
            }
            Convention::BearingTransposed => {
                "the bearing matrices are transposed (kyz and kzy, cyz and czy exchanged)"
            }
            Convention::CrossCouplingSign => {
                "the bearing cross terms kyz, kzy, cyz, czy have the wrong sign"
            }
            Convention::SpeedInRpm => "the speeds are in rpm, not Hz",
            Convention::PedConjugated => {
                "only the pedestal phasors are conjugated (pick-ups read with phase lead, probes with lag: one phase convention for rel and ped)"
            }
            Convention::PedVelocity => {
                "the pedestal readings are velocities written as displacements (formats.md: ped in m; divide a velocity by iΩ)"
            }
        })
    }

    /// The run as it would be had the mistake not been made: the mistake
    /// undone on the raw data (module docs).
    pub fn correct(self, run: &RunDir) -> RunDir {
        let mut out = run.clone();
        if self == Convention::SpeedInRpm {
            let table_in_same_unit = rpm_table(run, &run.bearing_schedules());
            for m in &mut out.measurements {
                m.speed_hz = rpm_to_hz(m.speed_hz);
            }
            if table_in_same_unit {
                for b in &mut out.bearings {
                    b.speed_hz = rpm_to_hz(b.speed_hz);
                }
            }
            return out;
        }
        self.fix_measurements(&mut out.measurements);
        for b in &mut out.bearings {
            self.fix_coefficients(&mut b.coefficients);
        }
        out
    }

    /// Undoes the mistake on every row's phasors and noise columns (what
    /// [`Convention::correct`] does to the measurements, except for
    /// `speed_in_rpm`, which changes the speeds).
    pub(super) fn fix_measurements(self, measurements: &mut [crate::rundir::Measurement]) {
        for m in measurements {
            self.fix_phasors(m.speed_hz, &mut m.rel, &mut m.ped);
            if let Some(sd) = &mut m.noise_sd {
                self.fix_noise_sd(m.speed_hz, sd);
            }
        }
    }

    /// Whether undoing the mistake changes `run` at all
    /// (`self.correct(run) != *run`), without copying it.
    pub fn changes(self, run: &RunDir) -> bool {
        self.changes_with(run, &run.bearing_schedules())
    }

    /// [`Convention::changes`] of `run`, whose bearing schedules are
    /// `schedules`.
    #[allow(clippy::eq_op)]
    pub(super) fn changes_with(self, run: &RunDir, schedules: &Schedules) -> bool {
        let rpm = self == Convention::SpeedInRpm;
        let table_rpm = rpm && rpm_table(run, schedules);
        let same_row = |m: &crate::rundir::Measurement| {
            let (mut rel, mut ped, mut sd) = (m.rel, m.ped, m.noise_sd);
            self.fix_phasors(m.speed_hz, &mut rel, &mut ped);
            if let Some(sd) = &mut sd {
                self.fix_noise_sd(m.speed_hz, sd);
            }
            let speed = if rpm {
                rpm_to_hz(m.speed_hz)
            } else {
                m.speed_hz
            };
            // `Measurement`'s equality, field by field (a NaN is unequal
            // to itself there too).
            speed == m.speed_hz && rel == m.rel && ped == m.ped && sd == m.noise_sd
        };
        let same_table_row = |b: &crate::rundir::BearingRow| {
            let mut c = b.coefficients;
            self.fix_coefficients(&mut c);
            let speed = if table_rpm {
                rpm_to_hz(b.speed_hz)
            } else {
                b.speed_hz
            };
            speed == b.speed_hz && c == b.coefficients
        };
        !(run.measurements.iter().all(same_row)
            && run.bearings.iter().all(same_table_row)
            && run.truth == run.truth)
    }

    /// Undoes the mistake on one row's rotor-relative and pedestal phasors
    /// `rel`, `ped` [m] measured at `speed_hz` [Hz] (nothing for the
    /// mistakes of the bearing table and the speeds).
    pub fn fix_phasors(self, speed_hz: f64, rel: &mut Phasor2<f64>, ped: &mut Phasor2<f64>) {
        match self {
            Convention::Conjugated => {
                for z in rel.iter_mut().chain(ped.iter_mut()) {
                    *z = z.conj();
                }
            }
            Convention::SwappedYz => {
                rel.swap(0, 1);
                ped.swap(0, 1);
            }
            Convention::RelNegated => {
                for z in rel {
                    *z = -*z;
                }
            }
            Convention::PedConjugated => {
                for z in ped {
                    *z = z.conj();
                }
            }
            Convention::PedVelocity => {
                let omega = plinth_shared::phasor::omega_from_hz(speed_hz);
                for z in ped {
                    *z /= num_complex::Complex::new(0.0, omega);
                }
            }
            Convention::RelRotated(a) => super::rotation::resolve_turned(rel, a.deg()),
            Convention::PedRotated(a) => super::rotation::resolve_turned(ped, a.deg()),
            Convention::BearingTransposed
            | Convention::CrossCouplingSign
            | Convention::SpeedInRpm => {}
        }
    }

    /// Undoes the mistake on one row's noise columns `sd` [m] (rel y, rel z,
    /// ped y, ped z) measured at `speed_hz` [Hz].
    fn fix_noise_sd(self, speed_hz: f64, sd: &mut crate::rundir::NoiseSd) {
        match self {
            Convention::SwappedYz => {
                sd.swap(0, 1);
                sd.swap(2, 3);
            }
            Convention::PedVelocity => {
                let omega = plinth_shared::phasor::omega_from_hz(speed_hz);
                sd[2] /= omega;
                sd[3] /= omega;
            }
            Convention::RelRotated(a) => super::rotation::resolve_turned_sd(&mut sd[..2], a.deg()),
            Convention::PedRotated(a) => super::rotation::resolve_turned_sd(&mut sd[2..], a.deg()),
            _ => {}
        }
    }

    /// Undoes the mistake on one row of the bearing table (nothing for the
    /// mistakes of the measurements).
    pub fn fix_coefficients(self, c: &mut BearingCoefficients<f64>) {
        match self {
            Convention::BearingTransposed => {
                (c.k[0][1], c.k[1][0]) = (c.k[1][0], c.k[0][1]);
                (c.c[0][1], c.c[1][0]) = (c.c[1][0], c.c[0][1]);
            }
            Convention::CrossCouplingSign => {
                for (i, j) in [(0, 1), (1, 0)] {
                    c.k[i][j] = -c.k[i][j];
                    c.c[i][j] = -c.c[i][j];
                }
            }
            _ => {}
        }
    }
}

/// A speed written in rpm, in Hz (what `speed_in_rpm` makes of every speed).
pub(super) fn rpm_to_hz(speed: f64) -> f64 {
    speed / crate::present::table::RPM_PER_HZ
}

/// Whether `speed_in_rpm` converts the bearing table too: the table (its
/// schedules `schedules`) covers every measured speed as written, so it is
/// in the measurements' unit.
fn rpm_table(run: &RunDir, schedules: &Schedules) -> bool {
    run.measurements.iter().all(|m| {
        schedules
            .get(&m.bearing)
            .is_some_and(|s| s.at(m.speed_hz).is_ok())
    })
}

/// The bearing schedules of `run` (whose own are `schedules`) with the
/// speeds in rpm read as Hz: the schedules of `SpeedInRpm.correct(run)`,
/// made from its table's rows in the same way, without copying the run.
pub(super) fn rpm_schedules(run: &RunDir, schedules: &Schedules) -> Schedules {
    if rpm_table(run, schedules) {
        run.bearing_schedules_with(rpm_to_hz)
    } else {
        schedules.clone()
    }
}

impl fmt::Display for Convention {
    /// The name, and a turned pair's angle after it (`rel_rotated 45°`).
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Convention::RelRotated(a) | Convention::PedRotated(a) => {
                write!(f, "{} {a}", self.name())
            }
            _ => f.write_str(self.name()),
        }
    }
}

/// What the convention check's ML refit of the run with `rel` negated gives
/// for each pedestal, from the fits as `found`: k, m and c negated, every
/// other figure (standard errors, speed range, fixed parameters) as found.
/// Negating `rel` negates every bearing force F = K*·rel; the dynamic
/// stiffness is linear in θ, so Z(−θ) = −Z(θ) negates every residual
/// e = Z·ped − F and leaves every residual covariance Z·Σ·Zᴴ + B·Σ·Bᴴ as
/// it is, and IEEE arithmetic is sign-symmetric (−a·b = (−a)·b, and a sum
/// of negated terms is the negated sum, exactly): every step of the fit
/// (the OLS start, the ML iteration, the noise level, the variance law,
/// the outliers, the equation error) is the negation of the step as found.
/// Measured (docs/engine-instructions.md, session 28): on 57 runs the ML fit of the
/// data with `rel` negated is the fit as found with k, m, c negated and the
/// same standard errors, bit for bit. A reading reads the parameters, the
/// standard errors, the speed range and the fixed parameters only; a named
/// `rel_negated` finding carries the refit itself. (A parameter fixed at
/// zero becomes −0 here and stays +0 in the refit: no reading tells them
/// apart, as x + (±0)·y = x.)
pub(super) fn rel_negated_fits(found: &[PedestalFit]) -> Vec<PedestalFit> {
    found
        .iter()
        .map(|p| {
            let mut q = p.clone();
            q.pedestal = crate::estimate::Pedestal::from_theta(p.pedestal.theta().map(|v| -v));
            q
        })
        .collect()
}
