//! Run directories the diagnose unit tests share.

use crate::rundir::RunDir;

/// Sets the noise columns of every bearing of `run` to `fraction` of each
/// channel's RMS over the run [-]: the sd the fits weight with, no noise
/// added (exact data said to carry that noise).
pub fn with_noise_columns(run: &mut RunDir, fraction: f64) {
    let mut names: Vec<String> = run.measurements.iter().map(|m| m.bearing.clone()).collect();
    names.sort();
    names.dedup();
    for name in names {
        let rows: Vec<usize> = (0..run.measurements.len())
            .filter(|&i| run.measurements[i].bearing == name)
            .collect();
        let sd: [f64; 4] = std::array::from_fn(|ch| {
            let ms: f64 = rows
                .iter()
                .map(|&i| {
                    let m = &run.measurements[i];
                    if ch < 2 { m.rel[ch] } else { m.ped[ch - 2] }.norm_sqr()
                })
                .sum::<f64>()
                / rows.len() as f64;
            fraction * ms.sqrt()
        });
        for &i in &rows {
            run.measurements[i].noise_sd = Some(sd);
        }
    }
}

/// The stored run `case` of tests/data (a path under it, e.g.
/// "ross-unseen-3/delay-55"), arranged for the fits.
pub fn stored(case: &str) -> crate::diagnose::data::Prepared {
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../tests/data")
        .join(case);
    let run = RunDir::read(&dir).expect("stored run directory");
    crate::diagnose::data::Prepared::from_run(&run).expect("prepared")
}
