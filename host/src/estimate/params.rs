//! The pedestal's parameters: the one type for the paper's pedestal (Feng &
//! Hahn eq. 3), whether identified, simulated or true, and for their
//! standard errors.
//!
//! [`Pedestal`] serialises with formats.md's flat keys `k_y, k_z, m, c_y,
//! c_z` (in that order); a struct with those keys at its top level
//! (`truth.json`'s and `identify --json`'s pedestals) holds it under
//! `#[serde(flatten)]`. JSON has no NaN or ∞: serde_json writes them as
//! `null`, and `null` reads back as NaN for a value ([`null_is_nan`]) and as
//! +∞ for a standard error ([`std_err`]: not estimable).

use num_complex::Complex;
use plinth_shared::regression::{Parameter, PARAMETERS};
use serde::{Deserialize, Deserializer, Serialize};

/// The paper's pedestal: one mass, direct stiffness and viscous damping in
/// y (vertical) and z (horizontal), eq. 3: (k − Ω²m + iΩc)·ped = F per
/// direction. Also the type of the standard errors of an estimate of it
/// (same units; 0 for a parameter fixed by the model, +∞ when not
/// estimable).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct Pedestal {
    /// Vertical stiffness to ground [N/m].
    #[serde(deserialize_with = "null_is_nan")]
    pub k_y: f64,
    /// Horizontal stiffness to ground [N/m].
    #[serde(deserialize_with = "null_is_nan")]
    pub k_z: f64,
    /// Mass [kg], the same in y and z.
    #[serde(deserialize_with = "null_is_nan")]
    pub m: f64,
    /// Vertical viscous damping to ground [N·s/m].
    #[serde(deserialize_with = "null_is_nan")]
    pub c_y: f64,
    /// Horizontal viscous damping to ground [N·s/m].
    #[serde(deserialize_with = "null_is_nan")]
    pub c_z: f64,
}

impl Pedestal {
    /// The pedestal of θ = (k_y [N/m], k_z [N/m], m [kg], c_y [N·s/m],
    /// c_z [N·s/m]), the order of [`Parameter`] and of every fit's vector.
    pub const fn from_theta(theta: [f64; PARAMETERS]) -> Self {
        let [k_y, k_z, m, c_y, c_z] = theta;
        Self {
            k_y,
            k_z,
            m,
            c_y,
            c_z,
        }
    }

    /// θ = (k_y [N/m], k_z [N/m], m [kg], c_y [N·s/m], c_z [N·s/m]).
    pub const fn theta(&self) -> [f64; PARAMETERS] {
        [self.k_y, self.k_z, self.m, self.c_y, self.c_z]
    }

    /// The value of one parameter (its unit: see [`Parameter`]).
    pub const fn get(&self, p: Parameter) -> f64 {
        self.theta()[p as usize]
    }

    /// Undamped natural frequencies (vertical, horizontal) [Hz] of the
    /// pedestal alone on its springs, √(k/m)/2π.
    pub fn natural_frequencies_hz(&self) -> (f64, f64) {
        let f = |k: f64| (k / self.m).sqrt() / std::f64::consts::TAU;
        (f(self.k_y), f(self.k_z))
    }

    /// Dynamic stiffness k − Ω²m + iΩc [N/m] in direction `d` (0 = y,
    /// 1 = z) at Ω = `omega` [rad/s]: eq. 3's (k − Ω²m + iΩc)·ped = F.
    pub fn dynamic_stiffness(&self, d: usize, omega: f64) -> Complex<f64> {
        let (k, c) = if d == 0 {
            (self.k_y, self.c_y)
        } else {
            (self.k_z, self.c_z)
        };
        Complex::new(k - omega * omega * self.m, omega * c)
    }

    /// True when every parameter is finite.
    pub fn is_finite(&self) -> bool {
        self.theta().iter().all(|v| v.is_finite())
    }
}

/// serde: reads standard errors (a [`Pedestal`] of them) with JSON `null`
/// as +∞ (not estimable), for `#[serde(deserialize_with = "std_err")]`.
pub fn std_err<'de, D: Deserializer<'de>>(d: D) -> Result<Pedestal, D::Error> {
    Pedestal::deserialize(d).map(null_std_errs_infinite)
}

/// serde: [`std_err`] for standard errors a file may leave out (absent or
/// `null`: `None`), for `#[serde(default, deserialize_with =
/// "optional_std_err")]`.
pub fn optional_std_err<'de, D: Deserializer<'de>>(d: D) -> Result<Option<Pedestal>, D::Error> {
    Ok(Option::<Pedestal>::deserialize(d)?.map(null_std_errs_infinite))
}

/// Standard errors read with [`null_is_nan`]: JSON carries no NaN, so a NaN
/// read is a `null`, an unbounded standard error (+∞).
fn null_std_errs_infinite(read: Pedestal) -> Pedestal {
    Pedestal::from_theta(
        read.theta()
            .map(|v| if v.is_nan() { f64::INFINITY } else { v }),
    )
}

/// serde: JSON `null` (how serde_json writes a non-finite number) reads as NaN.
pub fn null_is_nan<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::NAN))
}

/// serde: JSON `null` reads as +∞ (an unbounded standard error or condition number).
pub fn null_is_infinite<'de, D: Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::INFINITY))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A value and its standard errors, as a fit's JSON holds them.
    #[derive(Debug, PartialEq, Serialize, Deserialize)]
    struct Fit {
        bearing: String,
        #[serde(flatten)]
        pedestal: Pedestal,
        #[serde(deserialize_with = "std_err")]
        std_err: Pedestal,
    }

    #[test]
    fn theta_order_is_the_parameters_order() {
        let p = Pedestal::from_theta([1.0, 2.0, 3.0, 4.0, 5.0]);
        assert_eq!(p.theta(), [1.0, 2.0, 3.0, 4.0, 5.0]);
        for q in Parameter::ALL {
            let by_name = match q.name() {
                "k_y" => p.k_y,
                "k_z" => p.k_z,
                "m" => p.m,
                "c_y" => p.c_y,
                "c_z" => p.c_z,
                other => panic!("unknown parameter {other}"),
            };
            assert_eq!(p.get(q), by_name);
        }
    }

    #[test]
    fn serialises_with_flat_keys_in_theta_order() {
        let fit = Fit {
            bearing: "left".into(),
            pedestal: Pedestal::from_theta([1.0e7, 1.5e7, 100.0, 0.0, 250.5]),
            std_err: Pedestal::from_theta([1.0e4, f64::INFINITY, 0.5, 0.0, 3.0]),
        };
        let text = serde_json::to_string(&fit).unwrap();
        assert_eq!(
            text,
            r#"{"bearing":"left","k_y":10000000.0,"k_z":15000000.0,"m":100.0,"c_y":0.0,"c_z":250.5,"std_err":{"k_y":10000.0,"k_z":null,"m":0.5,"c_y":0.0,"c_z":3.0}}"#
        );
        let back: Fit = serde_json::from_str(&text).unwrap();
        assert_eq!(back, fit);
    }

    #[test]
    fn null_reads_as_nan_for_values_and_infinite_for_standard_errors() {
        let text = r#"{"bearing":"b","k_y":null,"k_z":1,"m":2,"c_y":3,"c_z":4,
            "std_err":{"k_y":null,"k_z":0,"m":null,"c_y":1,"c_z":2}}"#;
        let fit: Fit = serde_json::from_str(text).unwrap();
        assert!(fit.pedestal.k_y.is_nan());
        assert_eq!(fit.pedestal.theta()[1..], [1.0, 2.0, 3.0, 4.0]);
        assert_eq!(
            fit.std_err.theta(),
            [f64::INFINITY, 0.0, f64::INFINITY, 1.0, 2.0]
        );
    }

    #[test]
    fn a_missing_key_is_refused() {
        let text = r#"{"bearing":"b","k_y":0,"k_z":1,"m":2,"c_y":3,
            "std_err":{"k_y":0,"k_z":0,"m":0,"c_y":1,"c_z":2}}"#;
        let err = serde_json::from_str::<Fit>(text).unwrap_err();
        assert!(err.to_string().contains("c_z"), "{err}");
    }

    #[test]
    fn natural_frequencies_are_sqrt_k_over_m() {
        let tau = std::f64::consts::TAU;
        let p = Pedestal::from_theta([
            (10.0 * tau).powi(2) * 4.0,
            (20.0 * tau).powi(2) * 4.0,
            4.0,
            1.0,
            1.0,
        ]);
        let (fy, fz) = p.natural_frequencies_hz();
        assert!((fy - 10.0).abs() < 1e-12 && (fz - 20.0).abs() < 1e-12);
    }

    /// The files that carry a pedestal, each written, read back and written
    /// again byte for byte (with a NaN value and an infinite standard error
    /// where the file can hold them).
    mod files {
        use crate::identify::synthetic::SyntheticRun;
        use crate::identify::{identify_run, Identification, Options};
        use crate::rundir::{RunDir, Truth};

        fn run() -> RunDir {
            SyntheticRun::paper_like(true, 30).build().unwrap()
        }

        #[test]
        fn truth_json_round_trips() {
            let run = run();
            let truth = run.truth.clone().unwrap();
            let dir = tempfile::tempdir().unwrap();
            run.write(dir.path()).unwrap();
            let text = std::fs::read_to_string(dir.path().join("truth.json")).unwrap();
            // formats.md's keys, flat, in order.
            assert!(
                text.contains("\"bearing\": \"left\",\n      \"k_y\": 10000000.0,\n      \"k_z\": 8000000.0,\n      \"m\": 150.0,\n      \"c_y\": 100.0,\n      \"c_z\": 80.0\n"),
                "{text}"
            );
            let back = RunDir::read(dir.path()).unwrap().truth.unwrap();
            assert_eq!(back, truth);
            assert_eq!(serde_json::to_string_pretty(&back).unwrap() + "\n", text);
            let direct: Truth = serde_json::from_str(&text).unwrap();
            assert_eq!(direct.pedestals[1].pedestal, truth.pedestals[1].pedestal);
        }

        #[test]
        fn identify_json_round_trips_with_null_values_and_standard_errors() {
            let mut id = identify_run(&run(), &Options::default()).unwrap();
            id.pedestals[0].pedestal.c_y = f64::NAN;
            id.pedestals[0].std_err.m = f64::INFINITY;
            let text = serde_json::to_string_pretty(&id).unwrap();
            let back: Identification = serde_json::from_str(&text).unwrap();
            assert_eq!(serde_json::to_string_pretty(&back).unwrap(), text);
            let p = &back.pedestals[0];
            assert!(p.pedestal.c_y.is_nan());
            assert_eq!(p.std_err.m, f64::INFINITY);
            assert_eq!(back.pedestals[1], id.pedestals[1]);
            // The pedestal's keys sit at the top level, in order, before
            // `std_err`.
            let second = &text[text.find("\"bearing\": \"right\"").unwrap()..];
            let at: Vec<usize> = ["k_y", "k_z", "m", "c_y", "c_z", "std_err", "residual_rms"]
                .map(|k| second.find(&format!("\n      \"{k}\": ")).unwrap())
                .to_vec();
            assert!(at.windows(2).all(|w| w[0] < w[1]), "{at:?}");
            let value: serde_json::Value = serde_json::from_str(&text).unwrap();
            assert!(value["pedestals"][0]["c_y"].is_null());
            assert!(value["pedestals"][0]["std_err"]["m"].is_null());
        }

        #[test]
        fn predict_reads_what_identify_writes() {
            let mut id = identify_run(&run(), &Options::default()).unwrap();
            id.pedestals[1].std_err.c_z = f64::INFINITY;
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join("id.json");
            std::fs::write(&path, serde_json::to_string_pretty(&id).unwrap()).unwrap();
            let read = crate::sim::predict::read_identified(&path).unwrap();
            for (r, fit) in read.iter().zip(&id.pedestals) {
                assert_eq!(r.bearing, fit.bearing);
                assert_eq!(r.pedestal, fit.pedestal);
                assert_eq!(r.std_err, Some(fit.std_err));
            }
            assert_eq!(read[1].std_err.unwrap().c_z, f64::INFINITY);
        }
    }
}
