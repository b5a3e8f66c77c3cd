//! Natural cubic splines of complex phasors in speed: the response between
//! grid speeds, and the truth phasors at any speed.

use super::*;

/// A natural cubic spline of complex values on a sorted grid.
#[derive(Clone, Debug, PartialEq)]
pub struct ComplexSpline {
    x: Vec<f64>,
    y: Vec<C64>,
    /// Second derivatives at the knots.
    m: Vec<C64>,
}

impl ComplexSpline {
    /// Natural cubic spline through (x, y); x strictly increasing, ≥ 2 points.
    pub fn new(x: Vec<f64>, y: Vec<C64>) -> Result<ComplexSpline, String> {
        let n = x.len();
        if n < 2 || y.len() != n {
            return Err(format!(
                "spline needs ≥ 2 points and as many values (got {n}, {})",
                y.len()
            ));
        }
        if x.iter().any(|v| !v.is_finite()) || x.windows(2).any(|w| w[1] <= w[0]) {
            return Err("spline abscissae must be finite and strictly increasing".into());
        }
        let mut m = vec![C64::new(0.0, 0.0); n];
        if n > 2 {
            // Tridiagonal system for interior second derivatives (Thomas).
            let k = n - 2;
            let mut diag = vec![0.0; k];
            let mut rhs = vec![C64::new(0.0, 0.0); k];
            let mut upper = vec![0.0; k];
            let mut lower = vec![0.0; k];
            for i in 1..n - 1 {
                let h0 = x[i] - x[i - 1];
                let h1 = x[i + 1] - x[i];
                lower[i - 1] = h0;
                diag[i - 1] = 2.0 * (h0 + h1);
                upper[i - 1] = h1;
                rhs[i - 1] = 6.0 * ((y[i + 1] - y[i]) / h1 - (y[i] - y[i - 1]) / h0);
            }
            for i in 1..k {
                let w = lower[i] / diag[i - 1];
                diag[i] -= w * upper[i - 1];
                let r = rhs[i - 1] * w;
                rhs[i] -= r;
            }
            m[k] = rhs[k - 1] / diag[k - 1];
            for i in (0..k - 1).rev() {
                m[i + 1] = (rhs[i] - m[i + 2] * upper[i]) / diag[i];
            }
        }
        Ok(ComplexSpline { x, y, m })
    }

    /// Range of the abscissae.
    pub fn range(&self) -> (f64, f64) {
        (self.x[0], self.x[self.x.len() - 1])
    }

    /// Interval index containing x (clamped to the ends).
    fn interval(&self, x: f64) -> usize {
        let n = self.x.len();
        match self.x.partition_point(|&k| k <= x) {
            0 => 0,
            i if i >= n => n - 2,
            i => i - 1,
        }
    }

    /// Value, first and second derivative at `x` (cubic extension beyond the
    /// ends: callers keep x inside [`ComplexSpline::range`]).
    pub fn eval(&self, x: f64) -> (C64, C64, C64) {
        let i = self.interval(x);
        let h = self.x[i + 1] - self.x[i];
        let a = (self.x[i + 1] - x) / h;
        let b = (x - self.x[i]) / h;
        let (y0, y1, m0, m1) = (self.y[i], self.y[i + 1], self.m[i], self.m[i + 1]);
        let v = y0 * a + y1 * b + (m0 * (a * a * a - a) + m1 * (b * b * b - b)) * (h * h / 6.0);
        let d = (y1 - y0) / h + (m1 * (3.0 * b * b - 1.0) - m0 * (3.0 * a * a - 1.0)) * (h / 6.0);
        let dd = m0 * a + m1 * b;
        (v, d, dd)
    }
}

/// The truth phasors of a run directory interpolated in speed: one spline
/// per (bearing, quantity).
#[derive(Clone, Debug, PartialEq)]
pub struct PhasorSpline {
    splines: BTreeMap<(String, ChannelQuantity), ComplexSpline>,
}

impl PhasorSpline {
    /// Builds splines from measurement rows (each bearing's speeds strictly
    /// increasing after sorting, ≥ 2 of them).
    pub fn from_measurements(rows: &[Measurement]) -> Result<PhasorSpline, String> {
        let mut by_bearing: BTreeMap<&str, Vec<&Measurement>> = BTreeMap::new();
        for r in rows {
            by_bearing.entry(r.bearing.as_str()).or_default().push(r);
        }
        let mut splines = BTreeMap::new();
        for (b, mut rs) in by_bearing {
            rs.sort_by(|p, q| p.speed_hz.total_cmp(&q.speed_hz));
            let x: Vec<f64> = rs.iter().map(|r| r.speed_hz).collect();
            for q in ChannelQuantity::ALL {
                let y: Vec<C64> = rs.iter().map(|r| q.of(r)).collect();
                let s =
                    ComplexSpline::new(x.clone(), y).map_err(|e| format!("bearing {b}: {e}"))?;
                splines.insert((b.to_string(), q), s);
            }
        }
        Ok(PhasorSpline { splines })
    }

    /// The spline of one channel.
    pub fn get(&self, bearing: &str, quantity: ChannelQuantity) -> Option<&ComplexSpline> {
        self.splines.get(&(bearing.to_string(), quantity))
    }

    /// Displacement phasor [m] of (bearing, quantity) at `speed_hz`, `None`
    /// for an unknown channel or a speed outside the grid.
    pub fn at(&self, bearing: &str, quantity: ChannelQuantity, speed_hz: f64) -> Option<C64> {
        let s = self.get(bearing, quantity)?;
        let (lo, hi) = s.range();
        (speed_hz >= lo && speed_hz <= hi).then(|| s.eval(speed_hz).0)
    }
}
