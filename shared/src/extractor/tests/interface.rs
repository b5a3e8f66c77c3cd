//! The extractor's interface: any block size gives the same events, and
//! bad edges or a bad configuration are refused with their name before
//! anything happens.

use super::*;

#[test]
fn sample_by_sample_equals_block_feeding() {
    let channels = three_sensors();
    let shaft = RunDown {
        f0: 90.0,
        rate: 5.0,
        offset: 0.3,
    };
    let config = configured(&channels);
    let blocks = simulate(config, shaft, &channels, 0.4, 333, |_| {});
    let single = simulate(config, shaft, &channels, 0.4, 1, |_| {});
    assert!(blocks.phasors().count() > 20);
    assert_eq!(blocks.events, single.events);
}

#[test]
fn bad_edges_are_rejected_before_anything_happens() {
    let mut x =
        PhasorExtractor::new(ExtractorConfig::new(51_200.0, [Sensor::displacement(1.0)])).unwrap();
    let samples = [[0.0f32]; 4];
    let mut sink = |_e: Event<1>| panic!("no event expected");
    let edge = |index, fraction| KeyphasorEdge { index, fraction };
    assert_eq!(
        x.update_block(&samples, &[edge(4, 0.5)], &mut sink),
        Err(InputError::EdgeIndex { edge: 0 })
    );
    assert_eq!(
        x.update_block(&samples, &[edge(1, 0.5), edge(2, f32::NAN)], &mut sink),
        Err(InputError::EdgeFraction { edge: 1 })
    );
    assert_eq!(
        x.update_block(&samples, &[edge(1, 1.0)], &mut sink),
        Err(InputError::EdgeFraction { edge: 0 })
    );
    assert_eq!(
        x.update_block(&samples, &[edge(2, 0.5), edge(1, 0.5)], &mut sink),
        Err(InputError::EdgeOrder { edge: 1 })
    );
    assert_eq!(x.sample_index(), 0, "a rejected block is not consumed");
}

#[test]
fn bad_configurations_are_named() {
    let ok = ExtractorConfig::new(
        51_200.0,
        [Sensor::displacement(1.0), Sensor::velocity(20.0)],
    );
    assert!(PhasorExtractor::new(ok).is_ok());
    let mut c = ok;
    c.sensors[1].sensitivity = 0.0;
    assert_eq!(
        PhasorExtractor::new(c).err(),
        Some(ConfigError::Sensitivity { channel: 1 })
    );
    let mut c = ok;
    c.max_speed_hz = 1000.0;
    assert_eq!(PhasorExtractor::new(c).err(), Some(ConfigError::SpeedRange));
    let mut c = ok;
    c.sample_rate_hz = f32::NAN;
    assert_eq!(PhasorExtractor::new(c).err(), Some(ConfigError::SampleRate));
    let mut c = ok;
    c.revolutions_per_output = 0;
    assert_eq!(
        PhasorExtractor::new(c).err(),
        Some(ConfigError::Revolutions)
    );
    let mut c = ok;
    c.period_tolerance = 0.7;
    assert_eq!(
        PhasorExtractor::new(c).err(),
        Some(ConfigError::PeriodTolerance)
    );
}
