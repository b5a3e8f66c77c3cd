//! Run-directory reader and writer (formats.md): round trips, number
//! formats, interpolation, and an error naming file, line and column for
//! every way a file can break the contract.

use num_complex::Complex;
use plinth::identify::synthetic::SyntheticRun;
use plinth::rundir::{round_to_digits, DigitsMode, RunDir, WriteOptions};
use std::fs;
use tempfile::TempDir;

const M_HEADER: &str =
    "speed_hz,bearing,rel_y_re,rel_y_im,rel_z_re,rel_z_im,ped_y_re,ped_y_im,ped_z_re,ped_z_im";
const B_HEADER: &str = "speed_hz,bearing,kyy,kyz,kzy,kzz,cyy,cyz,czy,czz";
const B_ROWS: &str = "0,left,1e7,0,0,1e7,1e3,0,0,1e3\n200,left,3e7,2e6,-2e6,2e7,2e3,0,0,3e3\n";

fn dir_with(measurements: &str, bearings: &str) -> TempDir {
    let dir = tempfile::tempdir().unwrap();
    fs::write(dir.path().join("measurements.csv"), measurements).unwrap();
    fs::write(dir.path().join("bearings.csv"), bearings).unwrap();
    dir
}

fn bearings() -> String {
    format!("{B_HEADER}\n{B_ROWS}")
}

/// The error message of reading a run whose measurements.csv has `rows`
/// after the header.
fn measurement_error(rows: &str) -> String {
    let dir = dir_with(&format!("{M_HEADER}\n{rows}"), &bearings());
    match RunDir::read(dir.path()) {
        Ok(_) => panic!("accepted:\n{rows}"),
        Err(e) => e.to_string(),
    }
}

fn assert_contains(message: &str, parts: &[&str]) {
    for p in parts {
        assert!(message.contains(p), "`{p}` not in: {message}");
    }
}

const GOOD: &str = "10,left,1e-6,0,0,1e-6,1e-7,0,0,1e-7";

#[test]
fn reads_unsorted_rows_any_number_format_and_column_order() {
    let m = "bearing,speed_hz,rel_y_re,rel_y_im,rel_z_re,rel_z_im,ped_y_re,ped_y_im,ped_z_re,ped_z_im,note\n\
             left , 50 , 1.2e-05, 12E-6, -0.3E+0, 0.5e-6,1e-6,2e-6,3e-6,4e-6,first\n\
             left,10.25,+1e-6,-0,1E-3,7e-6,1e-6,2e-6,3e-6,4e-6,\n";
    let dir = dir_with(m, &bearings());
    let run = RunDir::read(dir.path()).unwrap();
    assert_eq!(run.measurements.len(), 2);
    let first = &run.measurements[0];
    assert_eq!(first.speed_hz, 50.0);
    assert_eq!(first.bearing, "left");
    assert_eq!(first.rel[0], Complex::new(1.2e-5, 12e-6));
    assert_eq!(first.rel[1], Complex::new(-0.3, 0.5e-6));
    assert_eq!(
        first.ped,
        [Complex::new(1e-6, 2e-6), Complex::new(3e-6, 4e-6)]
    );
    assert_eq!(run.measurements[1].speed_hz, 10.25);
    assert_eq!(run.measurements[1].rel[1].re, 1e-3);
    assert!(run.truth.is_none());
}

#[test]
fn bearing_coefficients_are_interpolated_linearly_in_speed() {
    let dir = dir_with(&format!("{M_HEADER}\n{GOOD}\n"), &bearings());
    let run = RunDir::read(dir.path()).unwrap();
    let schedules = run.bearing_schedules();
    let left = &schedules["left"];
    let c = left.at(50.0).unwrap();
    assert!((c.k[0][0] - 1.5e7).abs() < 1e-6);
    assert!((c.k[0][1] - 0.5e6).abs() < 1e-6);
    assert!((c.k[1][0] + 0.5e6).abs() < 1e-6);
    assert!((c.c[1][1] - 1.5e3).abs() < 1e-9);
    assert_eq!(left.at(200.0).unwrap().k[1][1], 2e7);
    let out = left.at(200.5).unwrap_err();
    assert_eq!((out.min_hz, out.max_hz), (0.0, 200.0));
}

#[test]
fn full_precision_round_trip_is_exact() {
    let run = SyntheticRun::paper_like(true, 37).build().unwrap();
    let dir = tempfile::tempdir().unwrap();
    run.write(dir.path()).unwrap();
    let back = RunDir::read(dir.path()).unwrap();
    assert_eq!(back, run);
}

#[test]
fn digits_round_the_phasors_only() {
    let run = SyntheticRun::paper_like(true, 30).build().unwrap();
    let dir = tempfile::tempdir().unwrap();
    run.write_with(
        dir.path(),
        &WriteOptions {
            digits: Some(2),
            digits_mode: DigitsMode::Round,
        },
    )
    .unwrap();
    let back = RunDir::read(dir.path()).unwrap();
    assert_eq!(back.bearings, run.bearings);
    assert_eq!(back.truth, run.truth);
    let mut changed = 0;
    for (a, b) in back.measurements.iter().zip(&run.measurements) {
        assert_eq!(a.speed_hz, b.speed_hz);
        let values = |m: &plinth::rundir::Measurement| {
            m.rel
                .iter()
                .chain(&m.ped)
                .flat_map(|c| [c.re, c.im])
                .collect::<Vec<_>>()
        };
        for (x, y) in values(a).into_iter().zip(values(b)) {
            // Rounding to 2 digits: at most half a unit in the 2nd digit.
            assert!((x - y).abs() <= 0.05 * y.abs() + 1e-300, "{x} vs {y}");
            assert_eq!(round_to_digits(x, 2, DigitsMode::Round), x);
            changed += usize::from(x != y);
        }
    }
    assert!(changed > 100);
    let text = fs::read_to_string(dir.path().join("measurements.csv")).unwrap();
    let row = text.lines().nth(1).unwrap();
    for field in row.split(',').skip(2) {
        let digits = field
            .split(['e', 'E'])
            .next()
            .unwrap()
            .chars()
            .filter(char::is_ascii_digit)
            .collect::<String>();
        assert!(
            digits.trim_start_matches('0').len() <= 2,
            "{field} in {row}"
        );
    }
}

#[test]
fn significant_digits_work_on_the_decimal_text() {
    use DigitsMode::{Round, Truncate};
    assert_eq!(round_to_digits(0.29, 2, Truncate), 0.29);
    assert_eq!(round_to_digits(0.299, 2, Truncate), 0.29);
    assert_eq!(round_to_digits(1234.5, 2, Truncate), 1200.0);
    assert_eq!(round_to_digits(-1234.5, 2, Round), -1200.0);
    assert_eq!(round_to_digits(1250.0, 2, Round), 1300.0);
    assert_eq!(round_to_digits(9.96, 2, Round), 10.0);
    assert_eq!(round_to_digits(-0.0123456, 3, Round), -0.0123);
    assert_eq!(round_to_digits(9.99e-7, 1, Round), 1e-6);
    assert_eq!(round_to_digits(0.0, 2, Round), 0.0);
    assert_eq!(round_to_digits(12.0, 5, Round), 12.0);
}

#[test]
fn bad_number_names_file_line_column_and_text() {
    let e = measurement_error(&format!("{GOOD}\n20,left,1e-6,abc,0,1e-6,1e-7,0,0,1e-7\n"));
    assert_contains(
        &e,
        &[
            "measurements.csv:3:4:",
            "`rel_y_im`",
            "`abc` is not a number",
        ],
    );
}

#[test]
fn non_finite_numbers_are_rejected() {
    let e = measurement_error("10,left,1e-6,0,inf,1e-6,1e-7,0,0,1e-7\n");
    assert_contains(&e, &["measurements.csv:2:5:", "`rel_z_re`", "not finite"]);
    let e = measurement_error("10,left,1e-6,0,0,1e-6,1e-7,0,0,NaN\n");
    assert_contains(&e, &["measurements.csv:2:10:", "`ped_z_im`", "not finite"]);
}

#[test]
fn missing_and_extra_columns() {
    let e = measurement_error("10,left,1e-6,0,0,1e-6,1e-7,0,0\n");
    assert_contains(&e, &["measurements.csv:2:10:", "missing column `ped_z_im`"]);
    let e = measurement_error(&format!("{GOOD}\n{GOOD},7\n"));
    assert_contains(&e, &["measurements.csv:3:11:", "extra column"]);
}

#[test]
fn wrong_or_missing_header() {
    let dir = dir_with(&format!("{GOOD}\n"), &bearings());
    let e = RunDir::read(dir.path()).unwrap_err().to_string();
    assert_contains(&e, &["measurements.csv:1:", "missing header"]);

    let dir = dir_with("", &bearings());
    let e = RunDir::read(dir.path()).unwrap_err().to_string();
    assert_contains(&e, &["measurements.csv:1:", "missing header"]);

    let wrong = M_HEADER.replace("rel_z_im", "rel_zim");
    let dir = dir_with(&format!("{wrong}\n{GOOD}\n"), &bearings());
    let e = RunDir::read(dir.path()).unwrap_err().to_string();
    assert_contains(&e, &["measurements.csv:1:", "no column `rel_z_im`"]);

    let twice = format!("{M_HEADER},bearing");
    let dir = dir_with(&format!("{twice}\n{GOOD},x\n"), &bearings());
    let e = RunDir::read(dir.path()).unwrap_err().to_string();
    assert_contains(&e, &["measurements.csv:1:11:", "`bearing`", "twice"]);

    let dir = dir_with(
        &format!("{M_HEADER}\n{GOOD}\n"),
        &format!("{}\n{B_ROWS}", B_HEADER.replace("czy", "czx")),
    );
    let e = RunDir::read(dir.path()).unwrap_err().to_string();
    assert_contains(&e, &["bearings.csv:1:", "no column `czy`"]);
}

#[test]
fn empty_or_quoted_bearing_names() {
    let e = measurement_error("10, ,1e-6,0,0,1e-6,1e-7,0,0,1e-7\n");
    assert_contains(&e, &["measurements.csv:2:2:", "empty bearing name"]);
    let e = measurement_error("10,\"left\",1e-6,0,0,1e-6,1e-7,0,0,1e-7\n");
    assert_contains(&e, &["measurements.csv:2:2:", "`\"left\"`", "quote"]);
}

#[test]
fn duplicate_speed_and_bearing_gives_both_lines() {
    let e = measurement_error(&format!(
        "{GOOD}\n20,left,1,0,0,1,1,0,0,1\n10.0,left,1,0,0,1,1,0,0,1\n"
    ));
    assert_contains(
        &e,
        &[
            "measurements.csv:4:",
            "duplicate",
            "`left`",
            "first at line 2",
        ],
    );
    // The same speed at another bearing is fine when that bearing is known.
    let b = format!(
        "{}0,right,1,0,0,1,0,0,0,0\n200,right,1,0,0,1,0,0,0,0\n",
        bearings()
    );
    let m = format!("{M_HEADER}\n{GOOD}\n10,right,1,0,0,1,1,0,0,1\n");
    let dir = dir_with(&m, &b);
    assert_eq!(RunDir::read(dir.path()).unwrap().measurements.len(), 2);
    // Duplicates in bearings.csv too.
    let dir = dir_with(
        &format!("{M_HEADER}\n{GOOD}\n"),
        &format!("{}200,left,1,0,0,1,0,0,0,0\n", bearings()),
    );
    let e = RunDir::read(dir.path()).unwrap_err().to_string();
    assert_contains(&e, &["bearings.csv:4:", "first at line 3"]);
}

#[test]
fn speed_outside_the_bearing_table_is_not_extrapolated() {
    let e = measurement_error(&format!("{GOOD}\n250,left,1,0,0,1,1,0,0,1\n"));
    assert_contains(
        &e,
        &[
            "measurements.csv:3:1:",
            "250 Hz",
            "0..=200 Hz",
            "`left`",
            "not extrapolated",
        ],
    );
    let e = measurement_error("-5,left,1,0,0,1,1,0,0,1\n");
    assert_contains(&e, &["measurements.csv:2:1:", "must be positive"]);
}

#[test]
fn measured_bearing_without_coefficients() {
    let e = measurement_error(&format!("{GOOD}\n10,middle,1,0,0,1,1,0,0,1\n"));
    assert_contains(
        &e,
        &[
            "measurements.csv:3:2:",
            "`middle`",
            "no rows in",
            "bearings.csv",
        ],
    );
}

#[test]
fn bearings_csv_errors_name_their_file() {
    let b = format!("{B_HEADER}\n0,left,1e7,x7,0,1e7,1e3,0,0,1e3\n");
    let dir = dir_with(&format!("{M_HEADER}\n{GOOD}\n"), &b);
    let e = RunDir::read(dir.path()).unwrap_err().to_string();
    assert_contains(&e, &["bearings.csv:2:4:", "`kyz`", "`x7`"]);
}

#[test]
fn missing_files() {
    let dir = tempfile::tempdir().unwrap();
    fs::write(
        dir.path().join("measurements.csv"),
        format!("{M_HEADER}\n{GOOD}\n"),
    )
    .unwrap();
    let e = RunDir::read(dir.path()).unwrap_err().to_string();
    assert_contains(&e, &["bearings.csv"]);
    let e = RunDir::read(dir.path().join("nowhere"))
        .unwrap_err()
        .to_string();
    assert_contains(&e, &["nowhere", "measurements.csv"]);
}

#[test]
fn truth_json_errors_give_line_and_column() {
    let dir = dir_with(&format!("{M_HEADER}\n{GOOD}\n"), &bearings());
    let truth = "{\"pedestals\": [\n  {\"bearing\": \"left\", \"k_y\": 1e7,\n   \"k_z\": oops}]}\n";
    fs::write(dir.path().join("truth.json"), truth).unwrap();
    let e = RunDir::read(dir.path()).unwrap_err().to_string();
    assert_contains(&e, &["truth.json:3:"]);

    let truth = "{\"pedestals\": [{\"bearing\": \"left\", \"k_y\": 1e7}]}";
    fs::write(dir.path().join("truth.json"), truth).unwrap();
    let e = RunDir::read(dir.path()).unwrap_err().to_string();
    assert_contains(&e, &["truth.json:1:", "missing field"]);
}

#[test]
fn writer_refuses_what_the_reader_would_refuse() {
    let mut run = SyntheticRun::paper_like(false, 5).build().unwrap();
    run.measurements[2].ped[1].im = f64::NAN;
    let dir = tempfile::tempdir().unwrap();
    let e = run.write(dir.path()).unwrap_err().to_string();
    assert_contains(
        &e,
        &["measurements.csv", "row 3", "`ped_z_im`", "not finite"],
    );

    let mut run = SyntheticRun::paper_like(false, 5).build().unwrap();
    run.measurements[0].bearing = "a,b".into();
    let e = run.write(dir.path()).unwrap_err().to_string();
    assert_contains(&e, &["`a,b`"]);
}
