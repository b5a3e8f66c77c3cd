//! A base fit as report entries: the base's own parameters (what the data
//! determine per direction), the test, and the pedestals standing on it.

use super::FoundationFit;
use crate::diagnose::data::Prepared;
use crate::diagnose::report::{BaseGroupReport, Estimate, FoundationReport};
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
}
