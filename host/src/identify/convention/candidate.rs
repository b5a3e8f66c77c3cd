//! One correction of a run under examination by [`super::diagnose`], and
//! the noise of the run with the mistake undone.

use super::*;

/// One correction of a run under examination by [`super::diagnose`].
pub struct Candidate<'a> {
    /// The mistake undone.
    pub convention: Convention,
    /// The bearings it is read at (`None`: every bearing). A turned pair's
    /// angle is found bearing by bearing ([`super::rotation`]): it is read
    /// only where it was found, so that two bearings' estimates of one
    /// arrangement (45.0° and 45.1°) do not stand as rival readings.
    pub only: Option<Vec<String>>,
    /// The run with the mistake undone, once a reading needed it (its
    /// noise re-estimated, its ML refit).
    pub fixed: Option<RunDir>,
    /// Its noise (the quantisation of the options; the run's own where the
    /// correction leaves it as it is).
    pub noise: Cow<'a, RunNoise>,
    /// Its noise floor ([`super::misfit::noise_floor`]).
    pub sigma: Vec<[f64; 4]>,
    /// Its OLS fits.
    pub screen: Vec<PedestalFit>,
    /// Its fits with the estimator of the options: `None` until refitted,
    /// `Some(None)` when the refit failed (kept once made).
    pub fit: Option<Option<Vec<PedestalFit>>>,
    /// Per pedestal of the identification (same order), the reading of
    /// `fit` and the fit read: empty until fitted.
    pub readings: Vec<Option<(Reading, PedestalFit)>>,
    /// Whether its readings are among those judged (with OLS from the
    /// start; with another estimator once [`super::diagnose`]'s refit rule
    /// asked for its fit).
    pub shown: bool,
    /// Per pedestal, the screen's lower bound on the relative residual of
    /// `fit` (`None`: no bound); empty with OLS, where the screen is the fit.
    pub bounds: Vec<Option<f64>>,
}

impl Candidate<'_> {
    /// Whether the correction is read at `bearing` ([`Candidate::only`]).
    pub fn reads_at(&self, bearing: &str) -> bool {
        self.only
            .as_ref()
            .is_none_or(|at| at.iter().any(|b| b == bearing))
    }
}

/// The noise of `run` with mistake `c` undone (`fixed`), from the noise
/// of the run as found: the same where the correction changes only signs
/// (each channel's scatter and each column's digits are blind to them),
/// only the bearing table, or only the unit of the speeds (`speed_in_rpm`:
/// the values, their digits and noise columns are unchanged, and the local
/// fits that give the scatter see each speed relative to its window's span,
/// which a change of unit leaves as it is); y and z exchanged for
/// `swapped_yz`; estimated anew where it changes the pedestal phasors
/// (only what that changes: [`RunNoise::with_pedestal_of`]).
pub(super) fn corrected_noise<'a>(
    c: Convention,
    noise: &'a RunNoise,
    run: &RunDir,
) -> Cow<'a, RunNoise> {
    Cow::Owned(match c {
        Convention::Conjugated
        | Convention::RelNegated
        | Convention::PedConjugated
        | Convention::BearingTransposed
        | Convention::CrossCouplingSign
        | Convention::SpeedInRpm => return Cow::Borrowed(noise),
        Convention::SwappedYz => noise.swapped_yz(),
        // A turned pair's channels are each a mix of the pair's written
        // channels: the noise as found stands for it (the floor of y and z
        // alike within the factor [`super::FLOOR_CHI2_PER_DOF`] allows;
        // the noise columns, where present, are turned with the data).
        Convention::RelRotated(_) | Convention::PedRotated(_) => return Cow::Borrowed(noise),
        Convention::PedVelocity => {
            // The noise reads the values of the measurements only: their
            // corrected copies without the bearing names are enough, and
            // cheaper to make than the corrected run.
            let mut measured: Vec<crate::rundir::Measurement> = run
                .measurements
                .iter()
                .map(|m| crate::rundir::Measurement {
                    speed_hz: m.speed_hz,
                    bearing: String::new(),
                    rel: m.rel,
                    ped: m.ped,
                    noise_sd: m.noise_sd,
                    written: m.written,
                })
                .collect();
            c.fix_measurements(&mut measured);
            noise.with_pedestal_of(&measured)
        }
    })
}
