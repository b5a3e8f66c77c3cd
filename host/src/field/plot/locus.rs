//! The loci a run's figures draw: one per bearing, quantity and direction
//! (or transducer), in speed order.

use super::PlotTransducer;
use crate::field::transducer::Quantity;
use crate::plots::Quantity as PlotQuantity;
use crate::rundir::RunDir;
use num_complex::Complex;

/// One locus to draw: name and (speed [Hz], phasor [m]) points.
#[derive(Clone, Debug)]
pub struct Locus {
    /// Title, e.g. `B1 rel y` or `B1 rel 45°`.
    pub name: String,
    /// File-name stem.
    pub stem: String,
    /// Points in speed order (displacement [m]).
    pub points: Vec<(f64, Complex<f64>)>,
    /// The transducer's axis [deg from +y towards +z] (y: 0, z: 90).
    pub angle_deg: f64,
    /// Unit the locus is drawn in.
    pub unit: PlotQuantity,
    /// True for a transducer's own reading, false for a resolved y or z.
    pub transducer: bool,
}

impl Locus {
    /// The points in the drawn unit's SI signal (displacement, velocity or
    /// acceleration).
    pub fn signal(&self) -> Vec<(f64, Complex<f64>)> {
        self.points
            .iter()
            .map(|&(f, x)| (f, self.unit.from_displacement(x, f)))
            .collect()
    }
}

/// The loci of a run: each bearing's y and z, and each extra transducer
/// reconstructed as cos α·Y + sin α·Z.
pub fn loci(run: &RunDir, transducers: &[PlotTransducer]) -> Vec<Locus> {
    let mut out = Vec::new();
    for b in run.measured_bearings() {
        let mut rows: Vec<_> = run.measurements.iter().filter(|m| m.bearing == b).collect();
        rows.sort_by(|x, y| x.speed_hz.total_cmp(&y.speed_hz));
        for q in [Quantity::Rel, Quantity::Ped] {
            let pick = |m: &crate::rundir::Measurement| match q {
                Quantity::Rel => m.rel,
                Quantity::Ped => m.ped,
            };
            let file_b = crate::names::file_name(b);
            for (i, axis) in ["y", "z"].iter().enumerate() {
                out.push(Locus {
                    name: format!("{b} {} {axis}", q.name()),
                    stem: format!("{file_b}_{}_{axis}", q.name()),
                    points: rows.iter().map(|m| (m.speed_hz, pick(m)[i])).collect(),
                    angle_deg: 90.0 * i as f64,
                    unit: PlotQuantity::DisplacementMicrons,
                    transducer: false,
                });
            }
            for t in transducers
                .iter()
                .filter(|t| t.bearing == b && t.quantity == q)
            {
                let a = t.angle_deg;
                let (s, c) = a.to_radians().sin_cos();
                out.push(Locus {
                    name: format!("{} {} {a}°", t.bearing, q.name()),
                    stem: format!("{file_b}_{}_{}deg", q.name(), a),
                    points: rows
                        .iter()
                        .map(|m| (m.speed_hz, pick(m)[0] * c + pick(m)[1] * s))
                        .collect(),
                    angle_deg: a,
                    unit: t.unit,
                    transducer: true,
                });
            }
        }
    }
    out
}
