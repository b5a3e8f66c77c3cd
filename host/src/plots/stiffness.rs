//! A pedestal's measured dynamic stiffness against its model: what
//! `identify --plots` and `diagnose --plots` draw for each bearing.
//!
//! Eq. 3 of Feng & Hahn says (k − Ω²m + iΩc)·X_ped = F per direction, so the
//! measured ratio F/X_ped [N/m] at each speed is the pedestal's dynamic
//! stiffness: its real part the parabola k − Ω²m (crossing zero at the
//! pedestal's resonance), its imaginary part the line Ωc. The figure shows,
//! per bearing and with y and z in distinct colours:
//!
//! 1. Re F/X [MN/m]: measured points, the model as a smooth curve and its
//!    ±1σ band;
//! 2. Im F/X [MN/m]: the same;
//! 3. the residual |F − D_fit·X| [N] of eq. 3 at each speed (the quantity the
//!    fit's residual RMS summarises): where the misfit lives.
//!
//! The band is the standard deviation of the model's dynamic stiffness from
//! the parameter covariance (delta method, exact here: D is linear in θ):
//! var Re D = var k + Ω⁴ var m − 2Ω² cov(k, m), var Im D = Ω² var c. Given
//! only standard errors (no correlations), the band takes the parameters as
//! independent and says so in its legend: for a run-down k and m are
//! positively correlated, so that band is wider than the true one.
//!
//! The input ([`StiffnessInput`]) is plain numbers, independent of how the
//! fit was made.

use super::legend::LegendEntry;
use super::{
    colour, draw_cell, speed_axis, speed_range, titled_page, Axes, Band, Curve, Mark, Style,
};
use crate::estimate::Pedestal;
use anyhow::{anyhow, Result};
use num_complex::Complex;
use plotters::coord::Shift;
use plotters::prelude::*;

/// Direction names, index 0 = y (vertical), 1 = z (horizontal).
pub const DIRECTIONS: [&str; 2] = ["y", "z"];

/// Points of the smooth model curve across the speed range.
const CURVE_POINTS: usize = 400;

/// What is known of the parameters' uncertainty, θ = (k_y, k_z, m, c_y, c_z)
/// in N/m, kg, N·s/m.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Uncertainty {
    /// The full covariance matrix (θ units squared).
    Covariance([[f64; 5]; 5]),
    /// Standard errors only (θ units): the band treats them as independent.
    StdErrors([f64; 5]),
}

impl Uncertainty {
    /// The covariance, zero off the diagonal when only standard errors are
    /// known (non-finite standard errors give non-finite variances).
    pub fn matrix(&self) -> [[f64; 5]; 5] {
        match *self {
            Uncertainty::Covariance(c) => c,
            Uncertainty::StdErrors(s) => {
                let mut c = [[0.0; 5]; 5];
                for i in 0..5 {
                    c[i][i] = s[i] * s[i];
                }
                c
            }
        }
    }
}

/// A rigid pedestal k − Ω²m + iΩc per direction with its uncertainty.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidPedestal {
    /// Its parameters (k [N/m], m [kg], c [N·s/m]).
    pub pedestal: Pedestal,
    /// Of θ = (k_y, k_z, m, c_y, c_z).
    pub uncertainty: Uncertainty,
}

impl RigidPedestal {
    /// Dynamic stiffness k − Ω²m + iΩc [N/m] in direction `d` at `speed_hz`.
    pub fn dynamic_stiffness(&self, d: usize, speed_hz: f64) -> Complex<f64> {
        self.pedestal
            .dynamic_stiffness(d, std::f64::consts::TAU * speed_hz)
    }

    /// Standard deviations [N/m] of Re and Im of the dynamic stiffness in
    /// direction `d` at `speed_hz` (see the module's documentation).
    pub fn dynamic_stiffness_sd(&self, d: usize, speed_hz: f64) -> (f64, f64) {
        let w = std::f64::consts::TAU * speed_hz;
        let cov = self.uncertainty.matrix();
        let (k, m, c) = (d, 2, 3 + d);
        let w2 = w * w;
        let var_re = cov[k][k] + w2 * w2 * cov[m][m] - 2.0 * w2 * cov[k][m];
        let var_im = w2 * cov[c][c];
        (var_re.max(0.0).sqrt(), var_im.max(0.0).sqrt())
    }
}

/// The model a bearing's measured dynamic stiffness is drawn against.
#[derive(Clone, Debug, PartialEq)]
pub enum StiffnessModel {
    /// A fitted rigid pedestal, drawn as a smooth curve with its ±1σ band.
    Rigid(RigidPedestal),
    /// The model's dynamic stiffness at given speeds (y, z): (speed [Hz],
    /// D [N/m]) — e.g. diagnose's model with effects, F/X_predicted.
    Points([Vec<(f64, Complex<f64>)>; 2]),
}

impl StiffnessModel {
    /// The model's dynamic stiffness [N/m] in direction `d` at a measured
    /// speed: the rigid formula, or the point at that speed (within 1e-9
    /// relative), `None` when it has none there.
    fn at(&self, d: usize, speed_hz: f64) -> Option<Complex<f64>> {
        match self {
            StiffnessModel::Rigid(p) => Some(p.dynamic_stiffness(d, speed_hz)),
            StiffnessModel::Points(pts) => pts[d]
                .iter()
                .find(|(s, _)| (s - speed_hz).abs() <= 1e-9 * speed_hz.abs().max(1.0))
                .map(|p| p.1),
        }
    }
}

/// One direction's measured points: (speed [Hz], force transmitted to the
/// pedestal F [N], absolute pedestal displacement X_ped [m]).
pub type MeasuredStiffness = Vec<(f64, Complex<f64>, Complex<f64>)>;

/// One bearing's data for the figure: plain numbers, independent of the
/// estimator's types.
#[derive(Clone, Debug, PartialEq)]
pub struct StiffnessInput {
    /// Bearing name (panel title).
    pub bearing: String,
    /// Per direction (y, z): (speed [Hz], force transmitted to the pedestal
    /// F [N], absolute pedestal displacement X_ped [m]).
    pub measured: [MeasuredStiffness; 2],
    /// The model drawn against them.
    pub model: StiffnessModel,
    /// The model's legend text, e.g. `fit` or `base model`.
    pub model_label: String,
    /// A remark under the bearing's name (e.g. `UNTRUSTED`), or empty.
    pub note: String,
}

/// A figure of measured-versus-model dynamic stiffness, one column per
/// bearing.
#[derive(Clone, Debug, PartialEq)]
pub struct StiffnessFigure {
    /// Figure title.
    pub title: String,
    /// The bearings, one column each.
    pub bearings: Vec<StiffnessInput>,
    /// Speed unit (amplitude scale does not apply).
    pub style: Style,
}

/// Colour of direction `d` (y blue, z vermillion).
fn direction_colour(d: usize) -> RGBColor {
    colour(d)
}

/// One row's curves, bands, legend and how many points were off scale.
struct RowData {
    curves: Vec<Curve>,
    bands: Vec<Band>,
    /// Per direction: its curves', then its band's entries.
    legend: Vec<LegendEntry>,
    y_range: (f64, f64),
    off_scale: usize,
}

/// Measured dynamic stiffness (speed [Hz], F/X [N/m]) of direction `d`,
/// finite points only, sorted by speed.
fn measured_ratio(input: &StiffnessInput, d: usize) -> Vec<(f64, Complex<f64>)> {
    let mut v: Vec<(f64, Complex<f64>)> = input.measured[d]
        .iter()
        .filter(|(s, f, x)| s.is_finite() && x.norm() > 0.0 && (f / x).is_finite())
        .map(|&(s, f, x)| (s, f / x))
        .collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    v
}

/// The residual |F − D_fit·X| [N] of direction `d` at every measured speed the
/// model covers.
pub fn residuals(input: &StiffnessInput, d: usize) -> Vec<(f64, f64)> {
    let mut v: Vec<(f64, f64)> = input.measured[d]
        .iter()
        .filter_map(|&(s, f, x)| {
            let dm = input.model.at(d, s)?;
            let r = (f - dm * x).norm();
            (s.is_finite() && r.is_finite()).then_some((s, r))
        })
        .collect();
    v.sort_by(|a, b| a.0.total_cmp(&b.0));
    v
}

/// A y range that holds the model (and its band) and the bulk of the
/// measured points: the 5th-95th percentile of the measured values, so that
/// a point where X_ped nearly vanishes (F/X huge) does not flatten the rest.
fn robust_range(model: &[f64], measured: &[f64]) -> (f64, f64) {
    let mut m: Vec<f64> = measured.iter().copied().filter(|v| v.is_finite()).collect();
    m.sort_by(f64::total_cmp);
    let pick = |q: f64| -> Option<f64> {
        if m.is_empty() {
            None
        } else {
            Some(m[((m.len() - 1) as f64 * q).round() as usize])
        }
    };
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for v in model
        .iter()
        .copied()
        .chain(pick(0.05))
        .chain(pick(0.95))
        .filter(|v| v.is_finite())
    {
        lo = lo.min(v);
        hi = hi.max(v);
    }
    if !lo.is_finite() {
        return (0.0, 1.0);
    }
    // Keep every measured point within 3 spans of the bulk.
    let span = (hi - lo).max(hi.abs().max(lo.abs()) * 1e-3).max(1e-12);
    for &v in &m {
        if v >= lo - span && v <= hi + span {
            lo = lo.min(v);
            hi = hi.max(v);
        }
    }
    let pad = 0.06 * (hi - lo).max(1e-12);
    (lo - pad, hi + pad)
}

impl StiffnessFigure {
    /// Row `row` (0 = Re, 1 = Im, 2 = residual) of bearing `b`.
    fn row(&self, input: &StiffnessInput, row: usize) -> RowData {
        let unit = self.style.speed_unit.factor();
        let scale = if row < 2 { 1e-6 } else { 1.0 };
        let part = |z: Complex<f64>| if row == 0 { z.re } else { z.im };
        let mut curves = Vec::new();
        let mut bands = Vec::new();
        let mut legend = Vec::new();
        let mut model_values = Vec::new();
        let mut measured_values = Vec::new();
        let speeds = input.measured.iter().flatten().map(|p| &p.0);
        let (lo, hi) = speed_range(speeds);
        for d in 0..2 {
            let c = direction_colour(d);
            if row == 2 {
                let r = residuals(input, d);
                measured_values.extend(r.iter().map(|p| p.1));
                let line = Curve {
                    name: format!("{} |F − D_fit·X|", DIRECTIONS[d]),
                    mark: Mark::Line,
                    colour: c,
                    segments: vec![r.iter().map(|&(s, v)| (s * unit, v)).collect()],
                };
                legend.push(line.entry());
                curves.push(line);
                curves.push(Curve {
                    name: String::new(),
                    mark: Mark::Markers,
                    colour: c,
                    segments: vec![r.iter().map(|&(s, v)| (s * unit, v)).collect()],
                });
                continue;
            }
            let meas: Vec<(f64, f64)> = measured_ratio(input, d)
                .into_iter()
                .map(|(s, z)| (s * unit, part(z) * scale))
                .collect();
            measured_values.extend(meas.iter().map(|p| p.1));
            let model: Vec<(f64, f64)> = match &input.model {
                StiffnessModel::Rigid(p) => {
                    let mut band = Vec::with_capacity(CURVE_POINTS);
                    let mut line = Vec::with_capacity(CURVE_POINTS);
                    for i in 0..CURVE_POINTS {
                        let s = lo + (hi - lo) * i as f64 / (CURVE_POINTS - 1) as f64;
                        let v = part(p.dynamic_stiffness(d, s)) * scale;
                        let (sd_re, sd_im) = p.dynamic_stiffness_sd(d, s);
                        let sd = if row == 0 { sd_re } else { sd_im } * scale;
                        line.push((s * unit, v));
                        if sd.is_finite() {
                            band.push((s * unit, v - sd, v + sd));
                        }
                    }
                    model_values.extend(band.iter().flat_map(|b| [b.1, b.2]));
                    bands.push(Band {
                        colour: c,
                        points: band,
                    });
                    line
                }
                StiffnessModel::Points(pts) => {
                    let mut v: Vec<(f64, f64)> = pts[d]
                        .iter()
                        .filter(|(s, z)| s.is_finite() && z.re.is_finite() && z.im.is_finite())
                        .map(|&(s, z)| (s * unit, part(z) * scale))
                        .collect();
                    v.sort_by(|a, b| a.0.total_cmp(&b.0));
                    v
                }
            };
            model_values.extend(model.iter().map(|p| p.1));
            curves.push(Curve {
                name: format!("{} measured F/X", DIRECTIONS[d]),
                mark: Mark::Markers,
                colour: c,
                segments: vec![meas],
            });
            curves.push(Curve {
                name: format!("{} {}", DIRECTIONS[d], input.model_label),
                mark: Mark::Line,
                colour: c,
                segments: vec![model],
            });
            legend.extend(curves[curves.len() - 2..].iter().map(Curve::entry));
            if let StiffnessModel::Rigid(p) = &input.model {
                let name = match p.uncertainty {
                    Uncertainty::Covariance(_) => format!("{} ±1σ", DIRECTIONS[d]),
                    Uncertainty::StdErrors(_) => format!("{} ±1σ (θ indep.)", DIRECTIONS[d]),
                };
                legend.extend(bands.last().map(|b| b.entry(name)));
            }
        }
        let y_range = if row == 2 {
            let hi = measured_values
                .iter()
                .copied()
                .filter(|v| v.is_finite())
                .fold(0.0, f64::max);
            (0.0, if hi > 0.0 { hi * 1.08 } else { 1.0 })
        } else {
            robust_range(&model_values, &measured_values)
        };
        // Points off scale are left out (and counted in the caption).
        let mut off_scale = 0;
        for c in curves.iter_mut().filter(|c| c.mark == Mark::Markers) {
            for seg in &mut c.segments {
                let before = seg.len();
                seg.retain(|p| p.1 >= y_range.0 && p.1 <= y_range.1);
                off_scale += before - seg.len();
            }
        }
        RowData {
            curves,
            bands,
            legend,
            y_range,
            off_scale,
        }
    }

    /// Draws the figure into a drawing area of any plotters backend.
    pub fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()>
    where
        DB::ErrorType: 'static,
    {
        if self.bearings.is_empty() {
            return Err(anyhow!("figure '{}' has no bearings", self.title));
        }
        let body = titled_page(root, &self.title)?;
        let cols = self.bearings.len();
        let cells = body.split_evenly((3, cols));
        let x_label = self.style.speed_unit.axis_label();
        for (b, input) in self.bearings.iter().enumerate() {
            for row in 0..3 {
                let data = self.row(input, row);
                let caption = match row {
                    0 if input.note.is_empty() => format!("Pedestal {}", input.bearing),
                    0 => format!("Pedestal {} ({})", input.bearing, input.note),
                    _ => String::new(),
                };
                let y_label = match row {
                    0 => "Re F/X  [MN/m]".to_string(),
                    1 => "Im F/X  [MN/m]".to_string(),
                    _ => "Residual of eq. 3 [N]".to_string(),
                };
                let y_label = if data.off_scale > 0 {
                    format!("{y_label} ({} off scale)", data.off_scale)
                } else {
                    y_label
                };
                let x_range = speed_axis(
                    input.measured.iter().flatten().map(|p| &p.0),
                    self.style.speed_unit,
                );
                draw_cell(
                    &cells[row * cols + b],
                    &Axes {
                        caption: &caption,
                        x_range,
                        x_label: &x_label,
                        y_range: data.y_range,
                        y_step: None,
                        y_label: &y_label,
                        log_y: false,
                    },
                    &data.bands,
                    &data.curves,
                    &data.legend,
                    true,
                )?;
            }
        }
        Ok(())
    }

    /// Pixel size: 760 px per bearing column, three rows.
    pub fn size(&self) -> (u32, u32) {
        (
            (760 * self.bearings.len().max(1) as u32).max(900),
            60 + 3 * 330,
        )
    }
}

figure_output!(StiffnessFigure);

#[cfg(test)]
mod tests {
    use super::*;

    fn pedestal(uncertainty: Uncertainty) -> RigidPedestal {
        RigidPedestal {
            pedestal: Pedestal::from_theta([1.2e7, 0.8e7, 150.0, 2000.0, 1500.0]),
            uncertainty,
        }
    }

    #[test]
    fn band_follows_the_delta_method() {
        // var Re D = var k + Ω⁴ var m − 2Ω² cov(k, m): with a perfect
        // positive correlation chosen so that k − Ω₀²m is exact at Ω₀, the
        // band vanishes there.
        let (sk, sm): (f64, f64) = (1e5, 2.0);
        let w0 = (sk / sm).sqrt();
        let mut cov = [[0.0; 5]; 5];
        cov[0][0] = sk * sk;
        cov[2][2] = sm * sm;
        cov[0][2] = sk * sm;
        cov[2][0] = sk * sm;
        cov[3][3] = 40.0 * 40.0;
        let p = pedestal(Uncertainty::Covariance(cov));
        let f0 = w0 / std::f64::consts::TAU;
        let (re, im) = p.dynamic_stiffness_sd(0, f0);
        assert!(re < 1e-6 * sk, "{re}");
        assert!((im - w0 * 40.0).abs() < 1e-9 * w0 * 40.0);
        // Independent: the variances add.
        let q = pedestal(Uncertainty::StdErrors([sk, 0.0, sm, 40.0, 0.0]));
        let (re, _) = q.dynamic_stiffness_sd(0, f0);
        let expect = (sk * sk + w0.powi(4) * sm * sm).sqrt();
        assert!((re - expect).abs() < 1e-9 * expect);
    }

    #[test]
    fn residual_is_zero_on_the_model_and_the_misfit_elsewhere() {
        let p = pedestal(Uncertainty::StdErrors([1e4, 1e4, 0.1, 10.0, 10.0]));
        let mut measured = [Vec::new(), Vec::new()];
        for i in 1..=40 {
            let s = i as f64;
            for (d, m) in measured.iter_mut().enumerate() {
                let x = Complex::new(1e-5, -2e-6 * s);
                let mut f = p.dynamic_stiffness(d, s) * x;
                if d == 1 && i == 20 {
                    f += Complex::new(50.0, 0.0);
                }
                m.push((s, f, x));
            }
        }
        let input = StiffnessInput {
            bearing: "B1".into(),
            measured,
            model: StiffnessModel::Rigid(p),
            model_label: "fit".into(),
            note: String::new(),
        };
        let ry = residuals(&input, 0);
        assert_eq!(ry.len(), 40);
        assert!(ry.iter().all(|r| r.1 < 1e-9));
        let rz = residuals(&input, 1);
        let worst = rz
            .iter()
            .copied()
            .fold((0.0, 0.0), |a, b| if b.1 > a.1 { b } else { a });
        assert_eq!(worst.0, 20.0);
        assert!((worst.1 - 50.0).abs() < 1e-6);
        let fig = StiffnessFigure {
            title: "test".into(),
            bearings: vec![input],
            style: Style::default(),
        };
        let svg = fig.to_svg().unwrap();
        assert!(svg.contains("Re F/X") && svg.contains("Pedestal B1"));
        assert!(svg.contains("±1σ (θ indep.)"));
    }

    #[test]
    fn range_ignores_a_point_where_the_pedestal_barely_moves() {
        let model = [0.0, 10.0];
        let mut measured: Vec<f64> = (0..100).map(|i| i as f64 / 10.0).collect();
        measured.push(1e6);
        let (lo, hi) = robust_range(&model, &measured);
        assert!(lo < 0.0 && hi < 20.0, "{lo} {hi}");
    }
}
