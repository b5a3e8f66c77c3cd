//! What `plinth identify`'s values and ± are conditional on, said where they
//! are read (text and JSON), and the bearing table's own doubt carried into
//! the ± when the user gives it (`--table-uncertainty PCT`).
//!
//! Two things no reading of the data can check, both honest fits of the
//! model (docs/unseen-train.md, third machine, items 1 and 2):
//!
//! - The values are the support's **apparent** (equivalent) k, c, m over
//!   the measured speeds. A support with more inside it (a sub-base, a
//!   frame) whose own resonances lie outside the range moves as one
//!   mass-spring-damper there: below them the pedestal and its sub-base
//!   are one mass on the series stiffness, and that is what is printed.
//! - The ± is **conditional on the bearing table**. Eq. 3,
//!   Z(θ)·ped = (K_b + iΩC_b)·rel with Z linear in θ, is homogeneous in the
//!   bearing force: if the machine's bearing is s times the table (K and C
//!   alike), the data fit θ/s exactly as the true machine fits θ, so the
//!   truth is θ = s·θ̂ and no fit can see s. A stiffness error alone is such
//!   a common scale wherever the bearing force is almost all stiffness
//!   (ΩC_b ≪ K_b, [`SCALES_WITH_TABLE_RATIO`]): that bearing's pedestal
//!   values scale with its table.
//!
//! Carrying the table's doubt: let s be the table's common scale with mean
//! 1 and relative standard uncertainty σ_s, independent of the noise, and
//! θ̂ the fit with covariance Σ (the noise alone). The truth s·θ̂ has
//! covariance E[s²]·E[θ̂θ̂ᵀ] − θθᵀ = (1 + σ_s²)·Σ + σ_s²·θθᵀ, so each
//! variance gains (σ_s·θ_i)² (and the small (1 + σ_s²) factor), and the
//! correlation of k, c, m tends to +1 as the table's share grows: they all
//! move together with s. Natural frequency √(k/m) and damping ratio
//! c/(2√(km)) are homogeneous of degree 0 in θ, their gradient g satisfies
//! g·θ = 0, so the σ_s²·θθᵀ term adds nothing to their ± (first order): the
//! modal values are not conditional on the table's scale. The combined ±
//! is measured by `tests/tests/identify_conditional.rs` on runs whose
//! tables were drawn from N(1, σ_s²).

use super::{Identification, PedestalFit};
use crate::rundir::RunDir;
use serde::Serialize;
use sub_base::SubBaseBound;

pub mod drift;
pub mod sensor;
pub mod speed;
pub mod sub_base;

/// The first promise of every value printed as a support's k, c, m
/// (`plinth identify`'s and `plinth diagnose`'s "Conditional on"): they
/// are the support's apparent values, and where the support-mode test was
/// made what the data exclude of a sub-base above the run ([`sub_base`]).
pub const APPARENT: &str = "k, c, m are each support's apparent (equivalent) values over the speeds it was measured at: a support with more inside it (a sub-base, a frame) whose own resonances lie outside that range moves as one mass-spring-damper there, and that is what is fitted (below its modes a pedestal on a sub-base is one mass on the series stiffness of the two springs, so the pedestal's own k can be well above the printed one). Where the support-mode test was made (noise columns), the lines below say how far the pedestal's own k and m could lie from the printed ones if a sub-base whose own mode lies above the run exists (what the run's Ω⁴ term excludes).";

/// Largest ratio ‖ΩC_b‖/‖K_b‖ (Frobenius norms, over the measured speeds)
/// of a bearing whose pedestal values "scale with its table" [-]: a
/// relative error δ in the table's stiffness alone is a common scale δ plus
/// a damping error −δ, which changes the bearing force's shape by only
/// δ·ΩC_b/|K_b + iΩC_b|; at 5 % that is 1 % of the force for a 20 %
/// stiffness error, under the 1-2 % noise of field data, so the fit cannot
/// tell it from a common scale.
pub const SCALES_WITH_TABLE_RATIO: f64 = 0.05;

/// Largest `--table-uncertainty` [%]: a relative standard uncertainty of
/// 100 % or more leaves no scale at all.
pub const MAX_TABLE_UNCERTAINTY_PCT: f64 = 100.0;

/// What the values and ± of an identification are conditional on
/// (`conditional_on` in `plinth identify --json`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Conditional {
    /// The promise in one paragraph, as the text report prints it.
    pub statement: String,
    /// Relative standard uncertainty σ_s of the bearing table's common
    /// scale folded into `std_err` and `covariance` [-] (`null`: the ± is
    /// the noise's alone, the table taken as exact).
    pub table_uncertainty: Option<f64>,
    /// Per bearing, how its pedestal values depend on its table.
    pub bearings: Vec<TableDependence>,
    /// Per bearing with a support-mode test, what the data exclude of a
    /// sub-base above the run ([`sub_base`]).
    pub sub_base: Vec<SubBaseBound>,
    /// Per pedestal on rigid ground, how far a drift of its support's
    /// stiffness over the run would move its values ([`drift`]).
    pub support_drift: Vec<drift::DriftSensitivity>,
    /// Per bearing, how right the speed column must be for its values to
    /// hold ([`speed`]).
    pub speed_column: Vec<speed::SpeedBound>,
    /// Standard uncertainty of the speed column folded into `std_err` and
    /// `covariance` [Hz] (`--speed-uncertainty`; `null`: the ± take the
    /// speed column as right).
    pub speed_uncertainty_hz: Option<f64>,
    /// Per bearing judged, how far a 1 % error in each channel's
    /// sensitivity moves each value ([`sensor`]).
    pub sensor_sensitivity: Vec<sensor::BearingSensitivity>,
    /// `--sensor-uncertainty` folded into the ± (`null`: the channels'
    /// sensitivities taken as exact) ([`sensor`]).
    pub sensor_uncertainty: Option<sensor::SensorUncertainty>,
}

impl Conditional {
    /// The paragraph under the text report's table: the statement, then
    /// one line per bearing whose values scale with its table.
    pub fn to_text(&self) -> String {
        let mut out = format!("\nConditional on: {}\n", self.statement);
        for b in &self.bearings {
            if let Some(m) = b.message() {
                out.push_str(&format!("  {m}\n"));
            }
        }
        for b in &self.sub_base {
            out.push_str(&format!("  {}\n", b.message()));
        }
        for d in self.support_drift.iter().filter(|d| d.matters()) {
            out.push_str(&format!("  {}\n", d.message()));
        }
        if let Some(sd) = self.speed_uncertainty_hz {
            out.push_str(&format!("  The ± include a {sd} Hz standard uncertainty of the speed column (--speed-uncertainty): σ² = σ_noise² + (b·σ_f)², b each value's shift per Hz of speed error.\n"));
        }
        for b in self.speed_column.iter().filter(|b| b.said) {
            out.push_str(&format!("  {}\n", b.message()));
        }
        for b in &self.sensor_sensitivity {
            out.push_str(&format!("  {}\n", b.message()));
        }
        out
    }
}

/// How one pedestal's values depend on its bearing's table.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TableDependence {
    /// Bearing name.
    pub bearing: String,
    /// Largest ‖ΩC_b‖/‖K_b‖ over the measured speeds [-] (NaN, `null`,
    /// when the table cannot be read there).
    pub damping_to_stiffness: f64,
    /// True when `damping_to_stiffness` is below [`SCALES_WITH_TABLE_RATIO`]:
    /// an error in the table's stiffness scales k, c, m alike, unseen.
    pub scales_with_table: bool,
    /// Lowest and highest speed fitted [Hz]: the range over which the
    /// values are the support's apparent ones.
    pub speed_range_hz: [f64; 2],
}

impl TableDependence {
    /// One sentence for people, or `None` when the values do not scale
    /// with the table more than the statement says.
    pub fn message(&self) -> Option<String> {
        self.scales_with_table.then(|| {
            format!(
                "{}: its bearing force is almost all stiffness (ΩC_b at most {:.1} % of K_b over {:.1}-{:.1} Hz): an error in the table's stiffness alone also scales k, c, m alike here, with a perfect fit; only the table (or `plinth diagnose --machine`) can say which",
                self.bearing,
                100.0 * self.damping_to_stiffness,
                self.speed_range_hz[0],
                self.speed_range_hz[1]
            )
        })
    }
}

/// `--table-uncertainty PCT`: a percentage greater than 0 and below
/// [`MAX_TABLE_UNCERTAINTY_PCT`].
pub fn parse_table_uncertainty(text: &str) -> Result<f64, String> {
    let v = crate::args::positive(text)?;
    if v >= MAX_TABLE_UNCERTAINTY_PCT {
        return Err(format!(
            "{v} %: the table's relative standard uncertainty must be below {MAX_TABLE_UNCERTAINTY_PCT} %"
        ));
    }
    Ok(v)
}

/// Largest ‖ΩC_b‖/‖K_b‖ of `bearing`'s table over the speeds `bearing`
/// was measured at in `run` [-] (NaN when no speed can be read).
fn damping_to_stiffness(
    run: &RunDir,
    schedules: &std::collections::BTreeMap<String, crate::rundir::BearingSchedule>,
    bearing: &str,
) -> f64 {
    let Some(schedule) = schedules.get(bearing) else {
        return f64::NAN;
    };
    let norm = |a: &[[f64; 2]; 2]| a.iter().flatten().map(|v| v * v).sum::<f64>().sqrt();
    run.measurements
        .iter()
        .filter(|m| m.bearing == bearing)
        .filter_map(|m| {
            let c = schedule.at(m.speed_hz).ok()?;
            let omega = plinth_shared::phasor::omega_from_hz(m.speed_hz);
            let r = omega * norm(&c.c) / norm(&c.k);
            r.is_finite().then_some(r)
        })
        .fold(f64::NAN, f64::max)
}

/// What `identification` (of `run`) is conditional on, with the table
/// uncertainty `table_uncertainty` [-] when it was folded in ([`widen`]).
pub fn of(
    run: &RunDir,
    identification: &Identification,
    table_uncertainty: Option<f64>,
) -> Conditional {
    let schedules = run.bearing_schedules();
    let bearings = identification
        .pedestals
        .iter()
        .map(|p| {
            let r = damping_to_stiffness(run, &schedules, &p.bearing);
            TableDependence {
                bearing: p.bearing.clone(),
                damping_to_stiffness: r,
                scales_with_table: r < SCALES_WITH_TABLE_RATIO,
                speed_range_hz: p.speed_range_hz,
            }
        })
        .collect();
    let doubt = match table_uncertainty {
        Some(s) => format!(
            "The ± include a {:.3} % standard uncertainty of each bearing table's common scale (--table-uncertainty): σ² = (1 + σ_s²)·σ_noise² + (σ_s·θ)², which moves the correlations of k, c, m towards +1 and leaves f_n and ζ as they are.",
            100.0 * s
        ),
        None => "The ± are the noise's alone, the bearing table (bearings.csv) taken as exact: every pedestal value is proportional to the table's common scale (a table 10 % too stiff and too damped gives k, c, m all 10 % high, with the same fit), so give the table's own uncertainty with --table-uncertainty PCT to carry it into the ±; f_n and ζ do not depend on it.".to_string(),
    };
    let sub_base = identification
        .pedestals
        .iter()
        .filter_map(|p| {
            let t = identification
                .noise
                .get(&p.bearing)?
                .lack_of_fit
                .as_ref()?
                .support_mode?;
            let q = &p.pedestal;
            sub_base::bound(
                &p.bearing,
                [q.k_y, q.k_z],
                [q.m, q.m],
                p.speed_range_hz[1],
                &t,
            )
        })
        .collect();
    Conditional {
        statement: format!(
            "{APPARENT} {doubt} The transducers' units and sensitivities are taken as given too: one scale on every rel reading (or every ped reading), say mil pp read as µm pp, scales k, c, m alike with the same fit; only `plinth diagnose --machine` (the rotor and its unbalance) can see it. {}",
            drift::STATEMENT
        ),
        table_uncertainty,
        bearings,
        sub_base,
        support_drift: drift::of(run, identification),
        speed_column: speed::of(identification),
        speed_uncertainty_hz: None,
        sensor_sensitivity: Vec::new(),
        sensor_uncertainty: None,
    }
}

/// Folds a relative standard uncertainty `sd` [-] of every bearing table's
/// common scale into each pedestal's `std_err` and `covariance` (module
/// docs): Σ' = (1 + sd²)·Σ + sd²·θθᵀ, and into the ± of every unmeasured
/// base's own values ([`widen_base`]). Returns each pedestal's standard
/// errors from the noise alone, in the pedestals' order. Parameters fixed
/// by the model (θ = 0, σ = 0) stay 0; a standard error that is not finite
/// stays as it is.
pub fn widen(identification: &mut Identification, sd: f64) -> Vec<crate::estimate::Pedestal> {
    for b in &mut identification.bases {
        widen_base(b, sd);
    }
    identification
        .pedestals
        .iter_mut()
        .map(|p| widen_one(p, sd))
        .collect()
}

/// The standard error [unit of `value`] of a value homogeneous of degree
/// ±1 in the bearing tables' common scale s (its truth is s^±1 times the
/// fit), noise standard error `se`, under a relative standard uncertainty
/// `sd` [-] of s: sqrt((1 + sd²)·se² + (sd·value)²), to first order in sd²
/// for degree −1 (1/s has mean 1 + O(sd²) and sd sd + O(sd³)).
fn widened(value: f64, se: f64, sd: f64) -> f64 {
    if se.is_finite() {
        ((1.0 + sd * sd) * se * se + (sd * value).powi(2)).sqrt()
    } else {
        se
    }
}

/// Folds the tables' scale doubt `sd` [-] into an unmeasured base's ±.
/// The base is as homogeneous in the bearing force as its pedestals: with
/// the bearings s times their tables, Z_i(θ_i)(ped_i − x_B) = s·K_b,i·rel_i
/// at each pedestal and Z_B(θ_B)·x_B = Σ_i Z_i(θ_i)(ped_i − x_B) at the
/// base, both linear in (θ_i, θ_B), so θ_i/s and θ_B/s fit the data with
/// the tables as written exactly as the machine does, with the same base
/// motion x_B. K_B, C_B, M_B (and a mass line's mass) are of degree 1 in
/// s, the quasi-static compliance 1/K_B of degree −1, the base frequency
/// √(K_B/M_B) of degree 0 (unchanged). A measured base has no values of
/// its own (its pedestals are widened as on rigid ground).
pub fn widen_base(report: &mut super::on_base::BaseReport, sd: f64) {
    for d in [&mut report.y, &mut report.z].into_iter().flatten() {
        for v in [&mut d.k, &mut d.c, &mut d.m, &mut d.compliance_m_per_n]
            .into_iter()
            .flatten()
        {
            v[1] = widened(v[0], v[1], sd);
        }
    }
}

fn widen_one(p: &mut PedestalFit, sd: f64) -> crate::estimate::Pedestal {
    let noise = p.std_err;
    let theta = p.pedestal.theta();
    let se = noise.theta();
    let grow = 1.0 + sd * sd;
    let wide: [f64; 5] = std::array::from_fn(|i| widened(theta[i], se[i], sd));
    p.std_err = crate::estimate::Pedestal::from_theta(wide);
    if let Some(cov) = &mut p.covariance {
        for (i, row) in cov.iter_mut().enumerate() {
            for (j, v) in row.iter_mut().enumerate() {
                *v = grow * *v + sd * sd * theta[i] * theta[j];
            }
        }
    }
    noise
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimate::Pedestal;

    fn fit() -> PedestalFit {
        let theta = [2.0e7, 1.0e7, 100.0, 500.0, 300.0];
        let se = [2.0e5, 1.0e5, 1.0, 50.0, 30.0];
        let mut cov = [[0.0; 5]; 5];
        for i in 0..5 {
            cov[i][i] = se[i] * se[i];
        }
        // k_y and m correlated (a resonance in range).
        cov[0][2] = 0.9 * se[0] * se[2];
        cov[2][0] = cov[0][2];
        PedestalFit {
            bearing: "B".into(),
            pedestal: Pedestal::from_theta(theta),
            std_err: Pedestal::from_theta(se),
            residual_rms: 0.0,
            condition_number: 2.0,
            fixed: Vec::new(),
            trusted: true,
            speeds: 50,
            equations: 200,
            speed_range_hz: [5.0, 85.0],
            warnings: Vec::new(),
            ols: None,
            suspected_convention_error: None,
            base: None,
            base_measured: None,
            covariance: Some(cov),
            modal: None,
        }
    }

    #[test]
    fn a_table_scale_adds_its_share_of_every_value_and_leaves_f_n_and_zeta() {
        let mut p = fit();
        let before = crate::present::modal::pedestal(&p.pedestal.theta(), p.covariance.as_ref());
        let noise = widen_one(&mut p, 0.1);
        assert_eq!(noise, fit().std_err);
        // k_y: sqrt(1.01·(2e5)² + (2e6)²).
        let want = (1.01f64 * 4e10 + 4e12).sqrt();
        assert!(
            (p.std_err.k_y - want).abs() < 1e-9 * want,
            "{}",
            p.std_err.k_y
        );
        let cov = p.covariance.unwrap();
        assert!((cov[0][0].sqrt() - want).abs() < 1e-9 * want);
        // k_y and c_z were uncorrelated; with the table they move together.
        let rho = cov[0][4] / (cov[0][0] * cov[4][4]).sqrt();
        assert!(rho > 0.5, "{rho}");
        let after = crate::present::modal::pedestal(&p.pedestal.theta(), Some(&cov));
        for (b, a) in [(before.y, after.y), (before.z, after.z)] {
            assert!((a.f_n_std_err / b.f_n_std_err - 1.005).abs() < 1e-3);
            assert!((a.zeta_std_err / b.zeta_std_err - 1.005).abs() < 1e-3);
        }
    }

    #[test]
    fn a_fixed_parameter_stays_fixed_and_the_option_is_checked() {
        let mut p = fit();
        p.pedestal.c_z = 0.0;
        p.std_err.c_z = 0.0;
        p.std_err.m = f64::INFINITY;
        widen_one(&mut p, 0.2);
        assert_eq!(p.std_err.c_z, 0.0);
        assert!(p.std_err.m.is_infinite());
        assert_eq!(parse_table_uncertainty("5"), Ok(5.0));
        assert!(parse_table_uncertainty("0").is_err());
        assert!(parse_table_uncertainty("100").is_err());
        assert!(parse_table_uncertainty("x").is_err());
    }
}
