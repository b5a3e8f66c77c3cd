//! A speed column that is not the speed of the vectors: one offset Δ
//! [Hz] shared by every bearing of a run, estimated from the data, counted
//! in the pedestal ± where the data do not exclude it, and the speed
//! accuracy each bearing's values need, said with them.
//!
//! **What it is.** formats.md's `speed_hz` is the speed of the revolutions
//! a vector is made of. A speed channel that is filtered (or sampled at
//! another moment than the vector's revolutions) reads the speed of some
//! time earlier: on a run-down at rate r [Hz/s] a lag of T [s] stamps each
//! vector with a speed Δ = r·T too high (too low on a run-up). The vector
//! belongs to f − Δ, f the stamp, and the model at f is wrong twice: the
//! bearing force is read from the table at the wrong speed (a tilting-pad
//! table's stiffness rising 0.3-0.4 % per Hz) and the pedestal's Ω²m and
//! iΩc carry 2Δ/f and Δ/f too much. Both are smooth over the run and the
//! fit takes them into k and m (unseen-eight `kp-lag`, a 0.75 Hz lag:
//! identify printed `ok` with k 3-4 ± high in 7 of 10 runs, never flagged;
//! docs/unseen-eight.md, finding 2).
//!
//! **Its form: one Δ in Hz, the same at every speed and every bearing.**
//! The speed channel is one, so Δ is shared by every bearing. Without a
//! time column (formats.md has none) the rate is not known; over a
//! run-down whose deceleration changes slowly Δ = r·T is nearly constant,
//! and a constant offset is also what a speed reference of another
//! (calibration) origin gives. A Δ proportional to the local speed step
//! fits only a run logged at constant time intervals (the step is then
//! r·Δt); a run logged on a speed grid (a vector every so many rpm, the
//! common case and every ROSS run here) has a step that says nothing of
//! the rate, so the constant form is the one these data can carry.
//!
//! **The linearisation** ([`linearise`]): each bearing's one-mass
//! equations at f − Δ, to first order in Δ, through the table's
//! interpolation and Ω; Δ estimated from all bearings at once with each
//! bearing's θ free (one Gauss–Newton step from Δ = 0), σ_Δ from the
//! information scaled by each bearing's excess (or the speeds' scatter,
//! [`spread`], where larger), with θ̂'s own error in the column added
//! ([`regressor`]: 0.6 % of σ_Δ on a clean unseen-eight run; measured,
//! docs/trust-speed.md, Session 50 (speed50)). As for a delay
//! ([`crate::estimate::lack_of_fit::delay_unknown`], whose widening this
//! calls), each parameter's ρ = σ(Δ free)/σ(Δ held) follows from b (its
//! shift per Hz of Δ): ρ² = 1 + (b·σ_Δ/σ_held)².
//!
//! **The gate**: the likelihood ratio of Δ in the linearisation, (Δ̂/σ_Δ)²,
//! beyond [`Z_GATE`]² = 6.6 (|Δ̂| > 2.576σ_Δ two-sided: both a lag and a
//! lead are causal, depending on the run's direction; 1 % of runs under
//! the null, one test per run), with Δ̂ from the speeds whose pull is an
//! offset's and that pull spread over the run as an offset's is
//! ([`spread`]: a model error local in speed, such as phasors averaged
//! over more speed than a lightly damped resonance is wide, pulls on the
//! Δ column from a few speeds and is not an offset; docs/trust-speed.md,
//! Session 49 (kplag17b)). **Excluded**: Δ's interval
//! [min(0, Δ̂ − 1.96σ_Δ), max(0, Δ̂ + 1.96σ_Δ)] moves no value of a bearing
//! by more than its Δ-held ±. **Counted as unknown** (gate open, not
//! excluded, on a trusted bearing on rigid ground): every ± of the bearing
//! is multiplied by √(1 + (ρ² − 1)·(1 + (Δ̂/σ_Δ)²)), the RMS error of the
//! held value when the true Δ is as the data give it
//! ([`widening`]), with a warning that names Δ̂ ± σ_Δ and the factors; the
//! values and the trust verdict stay as they are.
//!
//! **Which bearings estimate Δ**: the trusted ones on rigid ground whose
//! noise is known from noise columns. A bearing untrusted for a model
//! error (a sub-base, a wrong table) leaves a residual smooth in speed
//! that the Δ column would take as a speed error and carry to the other
//! bearings; its own ± are already said to exclude model error. The
//! column ∂e/∂f is made of the measured phasors, so its product with the
//! residual has a mean under the noise (errors in variables): the
//! gradient of the fit's cost with its weights moving with Δ takes it
//! back only where the noise's split between the channels is known (the
//! columns); with the noise estimated from the scatter it is not, and
//! Δ̂/σ_Δ came out 2.7-4.8 in 5 of 6 clean unseen-eight runs without
//! columns (docs/trust-lack-of-fit.md, Session 48 (kplag17)). The same
//! restriction as the support-mode and sensor-delay tests
//! ([`crate::estimate::lack_of_fit`]). Without columns Δ is not estimated;
//! the speed accuracy the values need is still said.
//!
//! **The speed accuracy the values need** ([`BearingLag::tolerance_hz`]):
//! the smallest speed error that moves some value of the bearing by its
//! ± , min_i σ_i/|b_i| (f·σ_k/(k·s) for k, s its relative sensitivity to
//! the relative speed), said in the conditional block where it is below
//! [`TOLERANCE_SAID`] of the top speed.

pub mod linearise;
pub mod regressor;
pub mod spread;

use super::{Identification, PedestalFit, Warning, WarningKind};
use crate::estimate::lack_of_fit::delay_unknown::{ratio, widening, Z_INTERVAL};
use crate::estimate::noise::NoiseSource;
use crate::rundir::RunDir;
use plinth_shared::regression::{Parameter, PARAMETERS};
use serde::{Deserialize, Serialize};

/// A bearing's speed tolerance is said with its values where it is below
/// this share of the run's top speed [-]: a speed filter of 0.1-1 s on a
/// run-down of 1-5 %/s of the speed per second reads 0.1-5 % high, and a
/// keyphasor's own speed is good to far better, so a tolerance of 1 % of
/// the speed is one a real speed channel can miss.
pub const TOLERANCE_SAID: f64 = 0.01;

/// The gate on Δ's likelihood ratio: |Δ̂| beyond this many of its ± [-],
/// the standard normal's two-sided 1 % quantile: widening every ± of a
/// run is a false alarm on a clean run, and a rule that marks values is
/// held to 1 % of clean runs (issue 17). (Session 48 used the delay
/// rule's 2, 4.6 % per run.)
pub const Z_GATE: f64 = 2.576;

/// What the run's data say of an offset of its speed column
/// (`speed_lag` in `plinth identify --json`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SpeedLag {
    /// Δ as the data give it, where estimated (`null`: no trusted
    /// bearing on rigid ground has its noise from noise columns).
    pub offset: Option<Offset>,
    /// The run's top speed [Hz].
    pub top_speed_hz: f64,
    /// Per bearing on rigid ground, what Δ does to its values.
    pub bearings: Vec<BearingLag>,
}

/// Δ estimated from the data ([`linearise::joint`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Offset {
    /// Δ̂: the speed column minus the speed of the revolutions the vectors
    /// are made of [Hz] (above zero: the column reads high, a lagging
    /// speed in a run-down), one step from Δ = 0.
    pub offset_hz: f64,
    /// Its ± [Hz].
    pub offset_std_hz: f64,
    /// The likelihood ratio (Δ̂/σ_Δ)² [-]; the gate needs it beyond [`Z_GATE`]² = 6.6.
    pub evidence: f64,
    /// The bearings Δ was estimated from (the trusted ones on rigid
    /// ground whose noise is known from noise columns).
    pub from_bearings: Vec<String>,
    /// σ_Δ from the information alone [Hz]; `offset_std_hz` is the
    /// larger of it and the speeds' own scatter ([`spread::scatter_std`]),
    /// with θ̂'s share ([`regressor`]) added in quadrature.
    pub information_std_hz: f64,
    /// Δ̂'s ± from the bearings' θ̂ errors alone [Hz] (the column is
    /// made at θ̂, [`regressor::theta_variance`]); 0 where not formed.
    #[serde(default)]
    pub theta_std_hz: f64,
    /// The speeds whose pull on Δ departs from an offset's beyond what
    /// the noise gives any speed of the run in 1 % of runs
    /// ([`spread::set_aside`]) [Hz]: said, not used by the gate.
    pub local_speeds_hz: Vec<f64>,
    /// Δ̂ and its ± (information) from the other speeds [Hz].
    pub without_local_hz: Option<[f64; 2]>,
    /// Whether the pull on Δ is spread over the run as an offset's is
    /// ([`spread`]); `null` where the bands could not be formed.
    pub spread: Option<spread::Spread>,
}

/// What an offset of the speed column does to one bearing's values.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BearingLag {
    /// Bearing name.
    pub bearing: String,
    /// b per θ = (k_y, k_z, m, c_y, c_z): the shift of the fitted value
    /// per Hz of Δ [SI per Hz] (0 for a parameter the model fixes).
    pub path_per_hz: [f64; PARAMETERS],
    /// σ_held per θ: its ± with Δ held at zero in the linearisation [SI].
    pub held_std_err: [f64; PARAMETERS],
    /// ρ = σ(Δ free)/σ(Δ held) per θ [-].
    pub ratio: [f64; PARAMETERS],
    /// The smallest speed error that moves some value by its ±,
    /// min σ_held/|b| [Hz] (∞, `null`, where Δ moves nothing).
    #[serde(deserialize_with = "crate::estimate::params::null_is_infinite")]
    pub tolerance_hz: f64,
    /// The parameter that sets `tolerance_hz`.
    pub tolerance_of: String,
    /// True where the ± were widened for Δ (gate open, not excluded).
    pub widened: bool,
}

impl Offset {
    /// Whether the data pull on Δ beyond the gate ((Δ̂/σ_Δ)² > [`Z_GATE`]²),
    /// whatever the pull's spread.
    pub fn pulled(&self) -> bool {
        self.evidence > Z_GATE * Z_GATE
    }

    /// Whether the pull comes from a few speeds only, not as an offset's
    /// would ([`spread`]).
    pub fn local(&self) -> bool {
        self.spread.as_ref().is_some_and(|s| !s.like_an_offset())
    }

    /// Whether the gate is open: pulled, and spread over the run as an
    /// offset's pull is.
    pub fn favoured(&self) -> bool {
        self.pulled() && !self.local()
    }

    /// The end of Δ's 95 % interval (holding zero) farthest from zero [Hz].
    pub fn reach_hz(&self) -> f64 {
        (self.offset_hz + Z_INTERVAL * self.offset_std_hz)
            .max(0.0)
            .max(-(self.offset_hz - Z_INTERVAL * self.offset_std_hz).min(0.0))
    }

    /// The widening factor of each of θ's ± for `b` [-].
    pub fn widening(&self, b: &BearingLag) -> [f64; PARAMETERS] {
        b.ratio
            .map(|r| widening(r, self.offset_hz, self.offset_std_hz))
    }

    /// ρ = σ(Δ free)/σ(Δ held) of a value whose Δ-held ± is `held` and
    /// shift per Hz `path` [-].
    pub fn ratio(&self, held: f64, path: f64) -> f64 {
        ratio(
            held,
            (held * held + (path * self.offset_std_hz).powi(2)).sqrt(),
        )
    }

    /// Whether Δ's interval moves some value of `b` by more than its ±.
    pub fn not_excluded(&self, b: &BearingLag) -> bool {
        let reach = self.reach_hz();
        (0..PARAMETERS)
            .any(|i| b.held_std_err[i] > 0.0 && b.path_per_hz[i].abs() * reach > b.held_std_err[i])
    }

    /// Δ̂ ± σ_Δ as a sentence's figure.
    pub fn figure(&self) -> String {
        let lead = if self.offset_hz >= 0.0 {
            "high (a speed that lags the vectors in a run-down, leads them in a run-up)"
        } else {
            "low (a speed that leads the vectors in a run-down, lags them in a run-up)"
        };
        format!(
            "the speed column reads {:.3} ± {:.3} Hz {lead}",
            self.offset_hz.abs(),
            self.offset_std_hz
        )
    }
}

fn estimated(p: &PedestalFit) -> Vec<Parameter> {
    Parameter::ALL
        .iter()
        .copied()
        .filter(|c| !p.fixed.iter().any(|f| f == c.name()))
        .collect()
}

/// Δ of `identification` (of `run`, whose bearings' observations are
/// `bearings`, [`super::data::Prepared`]) estimated from its trusted
/// pedestals on rigid ground whose noise is known from noise columns
/// (module docs), with what it does to every pedestal on rigid ground;
/// `None` where no pedestal is on rigid ground or the figures cannot be
/// formed.
pub fn estimate(
    run: &RunDir,
    bearings: &[super::data::BearingObservations],
    identification: &Identification,
) -> Option<SpeedLag> {
    let schedules = run.bearing_schedules();
    let mut all = Vec::new();
    for p in identification.pedestals.iter().filter(|p| p.base.is_none()) {
        let obs = bearings
            .iter()
            .find(|b| b.bearing == p.bearing)?
            .observations
            .as_ref()
            .ok()?;
        let schedule = schedules.get(&p.bearing)?;
        let columns = estimated(p);
        // The speeds the fit left out (outliers, flips) are left out here
        // too: the Δ step linearises the fit it was given.
        let left_out = identification
            .noise
            .get(&p.bearing)
            .map(|n| n.outlier_speeds_hz.as_slice())
            .unwrap_or_default();
        let obs: Vec<_> = obs
            .iter()
            .filter(|o| {
                !left_out
                    .iter()
                    .any(|f| (f - o.speed_hz).abs() <= 1e-9 * f.abs())
            })
            .copied()
            .collect();
        let t = linearise::terms(&obs, schedule, &p.pedestal.theta(), &columns)?;
        all.push((p, columns, t, obs, schedule));
    }
    if all.is_empty() {
        return None;
    }
    let columns_noise = |p: &PedestalFit| {
        identification
            .noise
            .get(&p.bearing)
            .is_some_and(|n| n.source == NoiseSource::Columns)
    };
    let from: Vec<_> = all
        .iter()
        .filter(|(p, _, _, _, _)| p.trusted && columns_noise(p))
        .collect();
    let offset = if from.is_empty() {
        None
    } else {
        let terms: Vec<linearise::Terms> = from.iter().map(|(_, _, t, _, _)| t.clone()).collect();
        let fitted: Vec<regressor::Fitted<'_>> = from
            .iter()
            .map(|(p, columns, t, obs, schedule)| regressor::Fitted {
                obs,
                schedule,
                theta: p.pedestal.theta(),
                columns,
                terms: t,
            })
            .collect();
        let theta_var = regressor::theta_variance(&fitted).unwrap_or(0.0);
        linearise::joint(&terms).map(|j| {
            let kept = spread::set_aside(&j.by_speed);
            let noise_std = spread::scatter_std(&j.by_speed, j.offset_hz)
                .map_or(j.offset_std_hz, |s| s.max(j.offset_std_hz));
            let offset_std_hz = (noise_std * noise_std + theta_var).sqrt();
            Offset {
                offset_hz: j.offset_hz,
                offset_std_hz,
                evidence: (j.offset_hz / offset_std_hz).powi(2),
                from_bearings: from
                    .iter()
                    .map(|(p, _, _, _, _)| p.bearing.clone())
                    .collect(),
                information_std_hz: j.offset_std_hz,
                theta_std_hz: theta_var.sqrt(),
                local_speeds_hz: kept
                    .as_ref()
                    .map(|k| k.local_speeds_hz.clone())
                    .unwrap_or_default(),
                without_local_hz: kept.as_ref().map(|k| [k.offset_hz, k.offset_std_hz]),
                spread: spread::spread(&j.by_speed),
            }
        })
    };
    // Every bearing's b and σ_held from its own fit, its ρ at σ_Δ.
    let mut out = Vec::new();
    for (p, columns, t, _, _) in &all {
        let share = linearise::joint(std::slice::from_ref(t))?
            .bearings
            .remove(0);
        let mut path_per_hz = [0.0; PARAMETERS];
        let mut held_std_err = [0.0; PARAMETERS];
        let mut rho = [1.0; PARAMETERS];
        for (k, &c) in columns.iter().enumerate() {
            let i = c as usize;
            path_per_hz[i] = share.path[k];
            held_std_err[i] = share.held[k];
            if let Some(o) = &offset {
                rho[i] = o.ratio(share.held[k], share.path[k]);
            }
        }
        let (tolerance_hz, tolerance_of) = columns
            .iter()
            .map(|&c| {
                let i = c as usize;
                (held_std_err[i] / path_per_hz[i].abs(), c.name())
            })
            .filter(|(v, _)| v.is_finite())
            .fold((f64::INFINITY, ""), |a, b| if b.0 < a.0 { b } else { a });
        out.push(BearingLag {
            bearing: p.bearing.clone(),
            path_per_hz,
            held_std_err,
            ratio: rho,
            tolerance_hz,
            tolerance_of: tolerance_of.to_string(),
            widened: false,
        });
    }
    let top_speed_hz = identification
        .pedestals
        .iter()
        .map(|p| p.speed_range_hz[1])
        .fold(0.0, f64::max);
    Some(SpeedLag {
        offset,
        top_speed_hz,
        bearings: out,
    })
}

/// Estimates Δ ([`estimate`]), widens the ± of every trusted pedestal on
/// rigid ground whose values Δ is not excluded from moving (module docs),
/// with a [`WarningKind::SpeedLagNotExcluded`] warning, and keeps the
/// figures in `identification.speed_lag`.
pub fn mark(
    run: &RunDir,
    bearings: &[super::data::BearingObservations],
    identification: &mut Identification,
) {
    let Some(mut lag) = estimate(run, bearings, identification) else {
        return;
    };
    if let Some(offset) = lag.offset.clone().filter(Offset::favoured) {
        for k in 0..lag.bearings.len() {
            let b = &lag.bearings[k];
            let Some(p) = identification
                .pedestals
                .iter_mut()
                .find(|p| p.bearing == b.bearing && p.trusted)
            else {
                continue;
            };
            if offset.not_excluded(b) {
                widen(p, &offset, b);
                lag.bearings[k].widened = true;
            }
        }
    }
    identification.speed_lag = Some(lag);
}

/// Multiplies `p`'s ± and covariance by `lag`'s widening for `b` and says
/// so.
fn widen(p: &mut PedestalFit, lag: &Offset, b: &BearingLag) {
    let w = lag.widening(b);
    p.widen_by(w);
    let widened: Vec<String> = estimated(p)
        .iter()
        .filter(|&&c| w[c as usize] >= 1.05)
        .map(|&c| format!("{} ±×{:.2}", c.name(), w[c as usize]))
        .collect();
    p.warnings.push(Warning {
        kind: WarningKind::SpeedLagNotExcluded,
        message: format!(
            "the speed column may be off by up to {:.3} Hz (the fit's 95 % range; {}, likelihood ratio {:.1} > 6.6, spread over the run as an offset's pull is, from every trusted bearing at once): a vector read at the wrong speed moves k and m through the table and Ω²m, so the values are conditional on it and their ± count it as unknown, multiplied by √(1 + (ρ² − 1)·(1 + (Δ̂/σ_Δ)²)) ({}); the values are the fit's",
            lag.reach_hz(),
            lag.figure(),
            lag.evidence,
            if widened.is_empty() {
                "each by less than 5 %".to_string()
            } else {
                widened.join(", ")
            }
        ),
    });
}

/// Under the table: the estimate where the gate is open (one line), then
/// one line per pedestal widened for it; empty when the gate is shut.
pub fn describe(identification: &Identification) -> String {
    let Some(lag) = identification
        .speed_lag
        .as_ref()
        .and_then(|l| l.offset.as_ref())
    else {
        return String::new();
    };
    let by_information = lag.offset_hz / lag.information_std_hz;
    if !lag.pulled() && by_information.abs() > Z_GATE {
        let local = match lag.without_local_hz {
            Some([d, s]) if !lag.local_speeds_hz.is_empty() => {
                let speeds: Vec<String> = lag
                    .local_speeds_hz
                    .iter()
                    .map(|f| format!("{f:.2}"))
                    .collect();
                format!(
                    "; the speeds {} Hz pull beyond what an offset and the noise allow, and without them it is {d:+.3} ± {s:.3} Hz",
                    speeds.join(", ")
                )
            }
            _ => String::new(),
        };
        return format!(
            "\nSpeed column: the speeds pull it {:+.3} ± {:.3} Hz by the noise's information (from {}), but they scatter about it {:.1} times more than the noise allows{local}: a model error local in speed (phasors averaged over more speed than a lightly damped resonance is wide read so), not an offset; with the scatter's ± ({:.3} Hz) it is within the gate and nothing is widened for it.\n",
            lag.offset_hz,
            lag.information_std_hz,
            lag.from_bearings.join(", "),
            lag.offset_std_hz / lag.information_std_hz,
            lag.offset_std_hz
        );
    }
    if !lag.pulled() {
        return String::new();
    }
    if let Some(s) = lag.spread.as_ref().filter(|_| lag.local()) {
        let band = s
            .most_local(lag.offset_hz)
            .map(|b| {
                format!(
                    "; the {:.1}-{:.1} Hz band alone gives {:+.3} ± {:.3} Hz",
                    b.from_hz, b.to_hz, b.offset_hz, b.offset_std_hz
                )
            })
            .unwrap_or_default();
        return format!(
            "\nSpeed column: the data pull it {:+.3} ± {:.3} Hz (likelihood ratio {:.1}, from {}), but not as an offset of the speed column would: the {} speed bands of equal information disagree (χ² {:.1} on {} degrees of freedom, p = {:.1e} < {}{band}). That is a model error local in speed (a sweep through a lightly damped resonance faster than the phasors follow reads so), not an offset: nothing is widened for it.\n",
            lag.offset_hz,
            lag.offset_std_hz,
            lag.evidence,
            lag.from_bearings.join(", "),
            s.bands.len(),
            s.heterogeneity,
            s.bands.len() - 1,
            s.p_value,
            spread::SPREAD_P,
        );
    }
    let mut out = format!(
        "\nSpeed column: {} (likelihood ratio {:.1} > 6.6, from {}).\n",
        lag.figure(),
        lag.evidence,
        lag.from_bearings.join(", ")
    );
    for (bearing, w) in identification.warnings_of(WarningKind::SpeedLagNotExcluded) {
        out.push_str(&format!("{bearing}: {}\n", w.message));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lag(offset: f64, std: f64) -> Offset {
        Offset {
            offset_hz: offset,
            offset_std_hz: std,
            evidence: (offset / std).powi(2),
            from_bearings: vec!["B1".into()],
            information_std_hz: std,
            theta_std_hz: 0.0,
            local_speeds_hz: Vec::new(),
            without_local_hz: None,
            spread: None,
        }
    }

    fn bearing(path: f64, held: f64) -> BearingLag {
        BearingLag {
            bearing: "B1".into(),
            path_per_hz: [path, 0.0, 0.0, 0.0, 0.0],
            held_std_err: [held, 1.0, 1.0, 1.0, 1.0],
            ratio: [1.0; PARAMETERS],
            tolerance_hz: held / path,
            tolerance_of: "k_y".into(),
            widened: false,
        }
    }

    /// The gate, the interval's reach on Δ̂'s side holding zero, the
    /// exclusion and the figure's sign.
    #[test]
    fn the_gate_the_reach_and_the_exclusion() {
        assert!(!lag(0.25, 0.1).favoured());
        assert!(lag(0.26, 0.1).favoured());
        assert!(lag(-0.26, 0.1).favoured());
        assert!((lag(0.3, 0.1).reach_hz() - 0.496).abs() < 1e-12);
        assert!((lag(-0.3, 0.1).reach_hz() - 0.496).abs() < 1e-12);
        assert!((lag(0.0, 0.1).reach_hz() - 0.196).abs() < 1e-12);
        // b = 2e6 N/m per Hz, σ 1e6 N/m: reach 0.496 Hz moves it 0.99 σ.
        assert!(!lag(0.3, 0.1).not_excluded(&bearing(2.0e6, 1.0e6)));
        assert!(lag(0.3, 0.1).not_excluded(&bearing(2.1e6, 1.0e6)));
        assert!(lag(0.25, 0.05)
            .figure()
            .contains("reads 0.250 ± 0.050 Hz high"));
        assert!(lag(-0.25, 0.05)
            .figure()
            .contains("reads 0.250 ± 0.050 Hz low"));
    }
}
