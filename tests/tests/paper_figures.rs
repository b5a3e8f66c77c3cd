//! `plinth paper --plots`: every figure exists as a valid PNG and SVG, the
//! re-prediction behind Fig. 6 is exact when given the true pedestals, and
//! the re-prediction gap of the 2-digit pedestals is reported and located.

use num_complex::Complex;
use plinth::paper::{locate_gap, reprediction_text, reproduce, write_figures, PaperOptions};
use plinth::rundir::DigitsMode;
use plinth::sim::predict::{compare, predict_run};
use plinth::sim::{EffectSet, Machine};

fn coarse() -> PaperOptions {
    PaperOptions {
        speeds_hz: (5..=200).step_by(5).map(f64::from).collect(),
        ..PaperOptions::default()
    }
}

#[test]
fn figures_are_valid_png_and_svg() {
    let paper = reproduce(&coarse()).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let files = write_figures(&paper, dir.path()).unwrap();
    // Figs. 3-6 once, Figs. 7-9 for both damping cases; PNG and SVG each.
    assert_eq!(files.len(), 20);
    for fig in [
        "fig3_amplitudes",
        "fig4_phases",
        "fig5_phase_difference",
        "fig6_measured_vs_predicted",
        "fig7_amplitudes",
        "fig8_phases",
        "fig9_phase_difference",
        "fig7_amplitudes_heavy_damping",
        "fig8_phases_heavy_damping",
        "fig9_phase_difference_heavy_damping",
    ] {
        let png = std::fs::read(dir.path().join(format!("{fig}.png"))).unwrap();
        assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n", "{fig}.png signature");
        assert_eq!(&png[12..16], b"IHDR");
        let w = u32::from_be_bytes([png[16], png[17], png[18], png[19]]);
        let h = u32::from_be_bytes([png[20], png[21], png[22], png[23]]);
        assert!(w >= 800 && h >= 400, "{fig}.png is {w}x{h}");
        let svg = std::fs::read_to_string(dir.path().join(format!("{fig}.svg"))).unwrap();
        assert!(svg.starts_with("<svg"), "{fig}.svg");
        assert!(svg.trim_end().ends_with("</svg>"), "{fig}.svg is complete");
        assert!(
            svg.contains("Rotor speed [Hz]"),
            "{fig}.svg has its x label"
        );
        assert!(svg.contains("<text"), "{fig}.svg has text");
    }
    // Fig. 6 states its gap in the title; the heavy case names its factor.
    let svg = std::fs::read_to_string(dir.path().join("fig6_measured_vs_predicted.svg")).unwrap();
    assert!(svg.contains("gap RMS"), "Fig. 6 title states the gap");
    let svg = std::fs::read_to_string(dir.path().join("fig9_phase_difference_heavy_damping.svg"))
        .unwrap();
    assert!(
        svg.contains("×55"),
        "Fig. 9 (heavy) names the damping factor"
    );
}

#[test]
fn reprediction_with_true_pedestals_is_exact() {
    let paper = reproduce(&coarse()).unwrap();
    let machine =
        Machine::from_toml_str(plinth::paper::UNDAMPED_MACHINE, "feng-hahn-1997.toml").unwrap();
    let predicted = predict_run(&machine, &EffectSet::none(), &paper.undamped).unwrap();
    let c = compare(&predicted, &paper.undamped.measurements).unwrap();
    assert!(c.overall.rms_rel < 1e-12, "{:?}", c.overall);
    let g = locate_gap(&predicted, &paper.undamped.measurements, 2.0, 3, 0.95).unwrap();
    assert!(g.bands.is_empty() || g.rms_rel_outside < 1e-12);
    // The 2-digit identified pedestals do not reproduce it exactly.
    assert!(paper.reprediction.overall.rms_rel > 1e-4);
}

#[test]
fn reprediction_gap_sits_at_two_resonances() {
    // Measured on 5-200 Hz every 1 Hz: rounded, RMS 22 %, max 28 %, 84 % of
    // the squared gap at 43-47 Hz and 16 % at 26-30 Hz, 2.4 % RMS elsewhere;
    // truncated, RMS 44 %, max 65 %, the same two bands, 6.0 % elsewhere.
    // They are nearly undamped resonances of the rotor on its pedestals, so a
    // sub-percent error in k or m shifts them by a fraction of a hertz.
    for (mode, rms_max, outside_max) in [
        (DigitsMode::Round, 0.30, 0.04),
        (DigitsMode::Truncate, 0.55, 0.08),
    ] {
        let paper = reproduce(&PaperOptions {
            digits_mode: mode,
            ..PaperOptions::default()
        })
        .unwrap();
        let o = &paper.reprediction.overall;
        assert!(o.rms_rel < rms_max, "{mode:?}: RMS {}", o.rms_rel);
        let g = &paper.reprediction_gap;
        let mut at: Vec<f64> = g.bands.iter().map(|b| b.speed_hz).collect();
        at.sort_by(f64::total_cmp);
        assert_eq!(at.len(), 2, "{mode:?}: {:?}", g.bands);
        assert!((26.0..=30.0).contains(&at[0]), "{mode:?}: {at:?}");
        assert!((43.0..=47.0).contains(&at[1]), "{mode:?}: {at:?}");
        let share: f64 = g.bands.iter().map(|b| b.share).sum();
        assert!(share >= 0.95, "{mode:?}: bands hold {share}");
        assert!(
            g.rms_rel_outside < outside_max,
            "{mode:?}: {} elsewhere",
            g.rms_rel_outside
        );
        let text = reprediction_text(&paper);
        assert!(text.contains("RMS") && text.contains("max |dX|"), "{text}");
        assert!(text.contains("elsewhere"), "{text}");
    }
}

#[test]
fn locate_gap_finds_a_planted_error() {
    let paper = reproduce(&coarse()).unwrap();
    let measured = &paper.undamped.measurements;
    let mut predicted = measured.clone();
    for m in predicted.iter_mut().filter(|m| m.speed_hz == 100.0) {
        m.rel[0] += Complex::new(1e-6, 0.0);
    }
    let g = locate_gap(&predicted, measured, 2.0, 3, 0.95).unwrap();
    assert_eq!(g.bands.len(), 1, "{g:?}");
    assert_eq!(g.bands[0].speed_hz, 100.0);
    assert!((g.bands[0].share - 1.0).abs() < 1e-12);
    assert_eq!(g.rms_rel_outside, 0.0);
    // A measured row without a prediction is an error.
    let e = locate_gap(&predicted[1..], measured, 2.0, 3, 0.95).unwrap_err();
    assert!(e.to_string().contains("no prediction"), "{e}");
}
