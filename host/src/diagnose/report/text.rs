//! The diagnosis as the text report an engineer reads: what was found in
//! the data as given, the base model and its noise, the steps, where the
//! search stopped, the pedestals, the verdict.

use super::{Diagnosis, FoundationReport, ModalViews, Step, BASE_AS_IDENTIFY, BASE_AS_STEPS};
use crate::identify::trust::hz_list;
use std::collections::BTreeMap;
use std::fmt::Write;

impl FoundationReport {
    /// The bases and the test as text lines.
    pub fn write_text(&self, s: &mut String) {
        let t = &self.test;
        let _ = writeln!(
            s,
            "     test: {}: LR {:.1}, statistic LR − q·ln N {:.1}, {} of {} replicates reached it (95 % point {:.1}), p = {:.2e}",
            t.test, t.likelihood_ratio, t.statistic, t.exceedances, t.replicates, t.critical_value_95, t.p_calibrated
        );
        for g in &self.groups {
            let what: Vec<&str> = g.identifiability.iter().map(|i| i.name()).collect();
            let params: Vec<String> = g
                .parameters
                .iter()
                .map(|p| format!("{} = {:.4e} ± {:.2e}", p.name, p.value, p.std_err))
                .collect();
            let _ = writeln!(
                s,
                "     base under {}: determined y {}, z {}{}; {}",
                g.bearings.join(", "),
                what[0],
                what[1],
                if g.converged {
                    ""
                } else {
                    " (fit NOT converged)"
                },
                if params.is_empty() {
                    "no base motion detected".to_string()
                } else {
                    params.join(", ")
                }
            );
        }
    }
}

impl Diagnosis {
    /// The text report.
    pub fn to_text(&self) -> String {
        self.to_text_with(&ModalViews::default())
    }

    /// The text report with the pedestals' modal view (f_n, ζ with ±).
    pub fn to_text_with(&self, modal: &ModalViews) -> String {
        let mut s = String::new();
        self.write_data_as_found(&mut s);
        self.write_base_model(&mut s);
        self.write_steps(&mut s);
        self.write_search_end(&mut s);
        self.write_pedestals(&mut s, modal);
        self.write_verdict(&mut s);
        s
    }

    /// What the data carry as given: suspected convention mistakes,
    /// keyphasor flips, outlier speeds.
    fn write_data_as_found(&self, s: &mut String) {
        for c in &self.suspected_convention_errors {
            let _ = writeln!(
                s,
                "SUSPECTED CONVENTION ERROR at {}: {}\n  {}",
                c.bearing, c.convention, c.message
            );
        }
        if !self.suspected_convention_errors.is_empty() {
            let _ = writeln!(
                s,
                "  (the findings below are of the data as found: fix the data first)\n"
            );
        }
        if !self.flipped_speeds_hz.is_empty() {
            for (bearing, speeds) in &self.flipped_speeds_hz {
                let _ = writeln!(
                    s,
                    "KEYPHASOR FLIP at {bearing}: every channel (rel and ped, y and z) looks flipped by 180° at {} Hz (against its neighbouring speeds or the other bearings at the same speed): left out of the noise, the fits and the gaps below",
                    hz_list(speeds)
                );
            }
            let lists: Vec<Vec<f64>> = self.flipped_speeds_hz.values().cloned().collect();
            let every = crate::identify::flips::listed_by_every_bearing(&lists);
            if !every.is_empty() && lists.len() == self.pedestals_before.len() {
                let _ = writeln!(
                    s,
                    "  every bearing is flipped at {} Hz: the machine's keyphasor itself triggered half a revolution off",
                    hz_list(&every)
                );
            }
            let _ = writeln!(s);
        }
        for (bearing, speeds) in &self.outlier_speeds_hz {
            let _ = writeln!(
                s,
                "OUTLIER SPEEDS at {bearing}: {} Hz, down-weighted by the base model's robust fit and not explained by the effects below either: left out of the noise, the fits and the gaps below",
                hz_list(speeds)
            );
        }
        for (bearing, speeds) in &self.outliers_explained_hz {
            let _ = writeln!(
                s,
                "Outlier speeds of the base model at {bearing} ({} Hz) are explained by the effects below (chosen without them): kept in the data",
                hz_list(speeds)
            );
        }
        if !(self.outlier_speeds_hz.is_empty() && self.outliers_explained_hz.is_empty()) {
            let _ = writeln!(s);
        }
    }

    /// The base model: its gaps, the digits and noise, where it disagrees.
    fn write_base_model(&self, s: &mut String) {
        let _ = writeln!(s, "Base model: {}", self.base_model.join(", "));
        let _ = writeln!(
            s,
            "Pedestal-level gap {:.4} (noise floor {:.4}){}",
            self.gap_before,
            self.noise.gap_floor_before,
            self.machine_gap_before.map_or(String::new(), |g| format!(
                "; machine-level gap {g:.4} ({BASE_AS_IDENTIFY}; noise floor {:.4}, the final model's)",
                self.machine_gap_floor.unwrap_or(0.0)
            ))
        );
        let list = |d: &BTreeMap<String, u32>| -> String {
            let d: Vec<String> = d.iter().map(|(k, v)| format!("{k} {v}")).collect();
            d.join(", ")
        };
        if self
            .noise
            .bearings
            .values()
            .all(|n| n.digits == self.noise.digits)
        {
            let _ = writeln!(s, "Digits written: {}", list(&self.noise.digits));
        } else {
            // Each bearing written with its own digits: say them per bearing.
            for (bearing, n) in &self.noise.bearings {
                let _ = writeln!(s, "Digits written at {bearing}: {}", list(&n.digits));
            }
        }
        for (bearing, n) in &self.noise.bearings {
            let sd: Vec<String> = n.sd.iter().map(|(k, v)| format!("{k} {v:.2e}")).collect();
            let _ = writeln!(
                s,
                "Noise at {bearing}: from the {}, sd [m] {}",
                n.source.name(),
                sd.join(", ")
            );
        }
        let _ = writeln!(s, "\nWhere the disagreement lives (base model):");
        for l in self.where_before.iter().take(4) {
            let _ = writeln!(s, "  {}", l.summary);
        }
    }

    /// The steps (or that there are none), then the steps the
    /// machine-level check dropped (`crate::diagnose::refute`).
    fn write_steps(&self, s: &mut String) {
        if self.steps.is_empty() {
            let _ = writeln!(s, "\nNo significant missing effect.");
        } else {
            let _ = writeln!(
                s,
                "\n{:<4} {:<26} {:<10} {:>10} {:>10}  parameters (± std err)",
                "step", "effect", "bearing", "gap before", "gap after"
            );
            for (i, st) in self.steps.iter().enumerate() {
                write_step(s, i, st);
            }
        }
        if !self.refuted_steps.is_empty() {
            let _ = writeln!(
                s,
                "Dropped by the machine-level check (the search ended before the first step it refutes):"
            );
            for r in &self.refuted_steps {
                let _ = writeln!(s, "  {}", r.line());
            }
        }
    }

    /// Where the search stopped: the shared base not chosen, the best
    /// remaining candidate, those passed over.
    fn write_search_end(&self, s: &mut String) {
        if let (Some(f), false) = (
            &self.foundation,
            self.steps.iter().any(|st| st.foundation.is_some()),
        ) {
            let t = &f.test;
            let _ = writeln!(
                s,
                "foundation_coupling (pedestals on a shared base) not chosen: {}: LR {:.1}, statistic {:.1}, {} of {} replicates reached it, p = {:.2e}",
                t.test, t.likelihood_ratio, t.statistic, t.exceedances, t.replicates, t.p_calibrated
            );
        }
        if let Some(r) = &self.best_rejected {
            // Said as its own evidence says: a candidate that passed its
            // test can still be left out (its joint refit rejected, or on a
            // base its correction not significant there).
            let e = &r.evidence;
            let why = if e.delta_bic > 0.0 && e.p_adjusted < self.significance_level {
                "not added (its test passed, its joint refit was rejected)"
            } else {
                "not significant"
            };
            let _ = writeln!(
                s,
                "Best remaining candidate, {why}: {} at {} (ΔBIC {:.1}, adjusted p {:.2e}, level {})",
                r.effect, r.bearing, e.delta_bic, e.p_adjusted, self.significance_level
            );
        }
        for p in &self.passed_over_at_stop {
            let _ = writeln!(
                s,
                "  passed over (significant, not added): {} at {}: {}",
                p.effect, p.bearing, p.reason
            );
        }
    }

    /// The pedestal tables of the base and the final model.
    fn write_pedestals(&self, s: &mut String, modal: &ModalViews) {
        // The shared printer (present::table): base model, then final model.
        for (title, list, modal) in [
            ("base model", &self.pedestals_before, &modal.before),
            ("final model", &self.pedestals_after, &modal.after),
        ] {
            let rows: Vec<_> = list
                .iter()
                .map(|p| crate::present::table::PedestalRow {
                    modal: modal.get(&p.bearing).copied(),
                    ..crate::present::table::PedestalRow::from_named(
                        &p.bearing, &p.values, &p.std_err,
                    )
                })
                .collect();
            let _ = write!(
                s,
                "\nPedestals, {title}:\n{}",
                crate::present::table::render(&rows)
            );
        }
    }

    /// The verdict, where the unexplained disagreement lies, and why not
    /// to trust.
    fn write_verdict(&self, s: &mut String) {
        let _ = writeln!(s, "\n{}", self.verdict);
        if !self.unexplained.is_empty() {
            let _ = writeln!(s, "The unexplained disagreement lies at:");
            for u in &self.unexplained {
                let _ = writeln!(s, "  {}", u.summary());
            }
        }
        if !self.trusted {
            let _ = writeln!(s, "The identified parameters are NOT to be trusted:");
            for r in &self.trust_reasons {
                let _ = writeln!(s, "  - {r}");
            }
        }
    }
}

/// Step `i` (0-based) of the table: its line, evidence, what it passed
/// over, its notes and machine-level gaps.
fn write_step(s: &mut String, i: usize, st: &Step) {
    let params: Vec<String> = st
        .parameters
        .iter()
        .map(|p| {
            format!(
                "{} = {}",
                p.name,
                crate::present::table::parameter_text(&p.name, p.value, p.std_err)
            )
        })
        .collect();
    let where_ = st.bearing.clone();
    let mut effect = st.effect.clone();
    if let Some(c) = &st.channels {
        effect += &format!(" ({c})");
    }
    let _ = writeln!(
        s,
        "{:<4} {:<26} {:<10} {:>10.4} {:>10.4}  {}",
        i + 1,
        effect,
        where_,
        st.gap_before,
        st.gap_after,
        params.join(", ")
    );
    let e = &st.evidence;
    let mut ev = format!(
            "     evidence ({}): statistic {:.3e} (floor {:.3e}, robust {:.3e}), q = {}, ΔBIC {:.1}, p = {:.2e} (adjusted {:.2e})",
            st.test, e.wald, e.wald_floor, e.wald_robust, e.extra_parameters, e.delta_bic, e.p_value, e.p_adjusted
        );
    if let Some(r) = &st.runner_up {
        ev += &format!(
            "; runner-up {} at {}: ΔBIC {:.1}",
            r.effect, r.bearing, r.evidence.delta_bic
        );
    }
    let _ = writeln!(s, "{ev}");
    for p in &st.passed_over {
        let _ = writeln!(
            s,
            "     passed over: {} at {} (ranked above it): {}",
            p.effect, p.bearing, p.reason
        );
    }
    if st.parameters.iter().any(|p| p.name == "k_scale") {
        let _ = writeln!(
                s,
                "     k_scale: the table's stiffness relative to its damping (c_scale held at 1: pedestal data see only the ratio; the pedestal values assume the damping as written)"
            );
    }
    if let Some(n) = crate::diagnose::bearing_table::viscosity::note(&st.parameters) {
        let _ = writeln!(s, "{n}");
    }
    if let Some(g) = st.machine_gap_before {
        let after = st
            .machine_gap_after
            .map_or("not simulated".to_string(), |a| format!("{a:.4}"));
        // Step 1's "before" is not the figure above: it is the
        // base model refitted as the steps fit it.
        let whose = if i == 0 {
            format!(" (before: {BASE_AS_STEPS})")
        } else {
            String::new()
        };
        let _ = writeln!(s, "     machine-level gap {g:.4} -> {after}{whose}");
    }
    if let Some(h) = &st.held {
        h.write_text(s, &st.bearing);
    }
    if let Some(why) = &st.dropped {
        let _ = writeln!(s, "     REMOVED again: {why}");
    }
    if let Some(f) = &st.foundation {
        f.write_text(s);
    }
}
