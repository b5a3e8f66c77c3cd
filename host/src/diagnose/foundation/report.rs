//! A base fit as report entries: the base's own parameters (what the data
//! determine per direction), the test, and the pedestals standing on it.

use super::{FoundationFit, Kind};
use crate::diagnose::data::Prepared;
use crate::diagnose::report::{BaseGroupReport, Diagnosis, Estimate, FoundationReport};
use crate::estimate::base::BaseIdentifiability;

impl FoundationFit {
    /// The base's own parameters as report entries: k, c, m of y and z
    /// (`base_k_y`, ...), then the quasi-static compliance or mass where
    /// only that is determined.
    pub fn parameters(&self, prep: &Prepared) -> Vec<Estimate> {
        let mut out = Vec::new();
        for r in self.report(prep).groups {
            out.extend(r.parameters);
        }
        out
    }

    /// The report entry: the bases, what the data determine, and the test.
    pub fn report(&self, prep: &Prepared) -> FoundationReport {
        let groups = self
            .grouping
            .groups
            .iter()
            .zip(&self.grouping.fits)
            .enumerate()
            .map(|(gi, (g, f))| {
                let stem = self.kind.prefix();
                let prefix = if self.grouping.groups.len() > 1 {
                    format!("{stem}{}_", gi + 1)
                } else {
                    format!("{stem}_")
                };
                let mut parameters = Vec::new();
                for (d, dir) in ["y", "z"].iter().enumerate() {
                    match f.identifiability[d] {
                        BaseIdentifiability::Full => {
                            for (name, v, se) in [
                                ("k", f.base.k[d], f.base_std_err.k[d]),
                                ("c", f.base.c[d], f.base_std_err.c[d]),
                                ("m", f.base.m[d], f.base_std_err.m[d]),
                            ] {
                                parameters.push(Estimate {
                                    name: format!("{prefix}{name}_{dir}"),
                                    value: v,
                                    std_err: se,
                                });
                            }
                        }
                        BaseIdentifiability::QuasiStatic {
                            compliance_m_per_n,
                            std_err,
                        } => parameters.push(Estimate {
                            name: format!("{prefix}compliance_{dir}"),
                            value: compliance_m_per_n,
                            std_err,
                        }),
                        BaseIdentifiability::MassLine { mass_kg, std_err } => {
                            parameters.push(Estimate {
                                name: format!("{prefix}m_{dir}"),
                                value: mass_kg,
                                std_err,
                            })
                        }
                        BaseIdentifiability::NotDetected => {}
                    }
                }
                BaseGroupReport {
                    bearings: g.iter().map(|&b| prep.bearings[b].clone()).collect(),
                    identifiability: f.identifiability,
                    base: f.base,
                    base_std_err: f.base_std_err,
                    base_frequency_hz: f.base_frequency_hz,
                    converged: f.converged,
                    parameters,
                }
            })
            .collect();
        FoundationReport {
            groups,
            test: self.test.clone(),
        }
    }

    /// The pedestal θ and its standard errors of bearing `b` when it stands
    /// on one of the bases.
    pub fn pedestal(&self, b: usize) -> Option<([f64; 5], [f64; 5])> {
        for (g, f) in self.grouping.groups.iter().zip(&self.grouping.fits) {
            if let Some(i) = g.iter().position(|&x| x == b) {
                return Some((f.pedestals[i], f.pedestal_std_err[i]));
            }
        }
        None
    }

    /// The parameters of this fit whose profile likelihood stayed open
    /// (`split_unresolved`, `base_unresolved` of
    /// [`crate::estimate::base::BaseFitResult`], set by
    /// [`FoundationFit::with_profile_errors`]): each as (the bearing of a
    /// pedestal or `None` for a base's own, the parameter's report name).
    pub fn unbounded(&self, prep: &Prepared) -> Vec<(Option<String>, String)> {
        let mut out = Vec::new();
        let report = self.report(prep);
        for ((g, f), r) in self
            .grouping
            .groups
            .iter()
            .zip(&self.grouping.fits)
            .zip(&report.groups)
        {
            for (i, &b) in g.iter().enumerate() {
                let open = f.split_unresolved.get(i).copied().unwrap_or_default();
                for (name, _) in ["k_y", "k_z", "m"].iter().zip(open).filter(|(_, o)| *o) {
                    out.push((prep.bearings.get(b).cloned(), name.to_string()));
                }
            }
            for (d, dir) in ["y", "z"].iter().enumerate() {
                for (w, q) in ["k", "m", "c"].iter().enumerate() {
                    // Named as the report names it; a parameter the report
                    // does not give (not determined in that direction) is
                    // not said.
                    let name = format!("{q}_{dir}");
                    let shown = r.parameters.iter().find(|e| {
                        e.name.ends_with(&name)
                            || (w == 0 && e.name.ends_with(&format!("compliance_{dir}")))
                    });
                    if let (true, Some(e)) = (f.base_unresolved[d][w], shown) {
                        out.push((None, e.name.clone()));
                    }
                }
            }
        }
        out
    }

    /// Puts this fit, the one the diagnosis `d` reports (its ± the profile
    /// likelihood's, [`FoundationFit::with_profile_errors`]), into `d`'s
    /// entries of its bases: the step that chose it and, for a shared base,
    /// the foundation entry take its values and ± (they were written
    /// before its profile ran). A parameter whose profile stayed open
    /// ([`FoundationFit::unbounded`]) is said in the verdict: the data do
    /// not bound it, its ± is a lower bound; a pedestal's makes the
    /// diagnosis untrusted (its values are what the diagnosis reports).
    pub fn report_into(&self, d: &mut Diagnosis, prep: &Prepared) {
        let report = self.report(prep);
        let same = |r: &FoundationReport| {
            r.groups.len() == report.groups.len()
                && r.groups
                    .iter()
                    .zip(&report.groups)
                    .all(|(a, b)| a.bearings == b.bearings)
        };
        for s in d
            .steps
            .iter_mut()
            .filter(|s| s.effect == self.kind.effect())
        {
            if let Some(f) = s.foundation.as_mut().filter(|f| same(f)) {
                f.groups.clone_from(&report.groups);
                s.parameters = self.parameters(prep);
            }
        }
        if self.kind == Kind::Shared {
            if let Some(f) = d.foundation.as_mut().filter(|f| same(f)) {
                f.groups.clone_from(&report.groups);
            }
        }
        let (note, why) = open_profiles(&self.unbounded(prep));
        d.verdict += &note;
        if let Some(why) = why {
            d.trust_reasons.push(why);
            d.trusted = false;
        }
    }
}

/// What the verdict says of the parameters whose profile stayed open
/// (`open` as [`FoundationFit::unbounded`] gives them): the sentences to
/// add, and the reason not to trust the diagnosis when a pedestal's is
/// among them (its values are what the diagnosis reports; the base's own
/// only get their ± called a lower bound).
fn open_profiles(open: &[(Option<String>, String)]) -> (String, Option<String>) {
    const OPEN: &str =
        "its profile likelihood stays within 1 of its minimum past 16 of its Fisher ± or to zero";
    let pedestal: Vec<String> = open
        .iter()
        .filter_map(|(b, q)| Some(format!("{q} of {}", b.as_ref()?)))
        .collect();
    let base: Vec<&str> = open
        .iter()
        .filter(|(b, _)| b.is_none())
        .map(|(_, q)| q.as_str())
        .collect();
    let mut note = String::new();
    if !base.is_empty() {
        note += &format!(
            " The data do not bound the base's {} ({OPEN}): the ± printed is a lower bound.",
            base.join(", ")
        );
    }
    let why = (!pedestal.is_empty()).then(|| {
        format!(
            "the data do not bound the pedestal's {} on the base ({OPEN}): the value and ± printed are not determined",
            pedestal.join(", ")
        )
    });
    if let Some(why) = &why {
        note += &format!(" But {why}; the identified parameters are not to be trusted.");
    }
    (note, why)
}

#[cfg(test)]
mod tests {
    use super::open_profiles;

    #[test]
    fn an_open_profile_is_said_and_a_pedestals_untrusts() {
        assert_eq!(open_profiles(&[]), (String::new(), None));
        let (note, why) = open_profiles(&[(None, "base_m_y".into())]);
        assert!(
            note.contains("base's base_m_y") && note.contains("lower bound"),
            "{note}"
        );
        assert_eq!(why, None);
        let (note, why) =
            open_profiles(&[(Some("B1".into()), "m".into()), (None, "base_k_z".into())]);
        let why = why.expect("a pedestal's open profile is a reason");
        assert!(why.contains("m of B1"), "{why}");
        assert!(note.contains("base_k_z") && note.contains(&why), "{note}");
    }
}
