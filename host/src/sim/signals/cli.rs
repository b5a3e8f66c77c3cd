//! `plinth signals`: the command line over [`super::synthesise_to`].

use super::*;

/// Command-line arguments of `plinth signals`.
#[derive(clap::Args, Debug)]
pub struct SignalsArgs {
    /// Machine file (TOML, SI units; see the `plinth::sim::machine` docs).
    pub machine: PathBuf,
    /// Signal-set directory to write (created if needed).
    #[arg(long)]
    pub out: PathBuf,
    /// Speed ramp START:END:RATE [Hz:Hz:Hz/s] (linear; END < START is a run-down).
    #[arg(long, default_value = "200:5:5")]
    pub rundown: String,
    /// Sample rate per channel [Hz].
    #[arg(long, allow_negative_numbers = true, default_value = "51200", value_parser = crate::args::positive)]
    pub rate: f64,
    /// Proximity probe sensitivity [V/mm].
    #[arg(long, allow_negative_numbers = true, default_value = "7.87", value_parser = crate::args::positive)]
    pub probe_v_per_mm: f64,
    /// Proximity probe gap voltage [V].
    #[arg(long, default_value = "-9", allow_hyphen_values = true, value_parser = crate::args::finite)]
    pub probe_gap: f64,
    /// Probe channel noise [mV RMS].
    #[arg(long, allow_negative_numbers = true, default_value = "1", value_parser = crate::args::non_negative)]
    pub probe_noise_mv: f64,
    /// Transducer on the pedestals: displacement, velocity or acceleration.
    #[arg(long, value_parser = parse_sensor_kind, default_value = "acceleration")]
    pub seismic: SensorKind,
    /// Seismic sensitivity [V/(m/s²), V/(m/s) or V/m]; default by kind:
    /// 100 mV/g, 20 mV/(mm/s), 7.87 V/mm.
    #[arg(long, allow_negative_numbers = true, value_parser = crate::args::positive)]
    pub seismic_sensitivity: Option<f64>,
    /// Seismic channel noise [mV RMS].
    #[arg(long, allow_negative_numbers = true, default_value = "1", value_parser = crate::args::non_negative)]
    pub seismic_noise_mv: f64,
    /// ADC resolution [bits].
    #[arg(long, allow_negative_numbers = true, default_value_t = 16, value_parser = clap::value_parser!(u32).range(2..=16))]
    pub adc_bits: u32,
    /// ADC full scale [±V].
    #[arg(long, allow_negative_numbers = true, default_value = "10", value_parser = crate::args::positive)]
    pub adc_range: f64,
    /// Speed step of the precomputed response [Hz].
    #[arg(long, allow_negative_numbers = true, default_value = "0.01", value_parser = crate::args::positive)]
    pub grid_step: f64,
    /// Noise seed.
    #[arg(long, allow_negative_numbers = true, default_value_t = 1)]
    pub seed: u64,
    /// Effect to inject: NAME[:BEARING][=SIZE] (repeatable).
    #[arg(long = "effect")]
    pub effects: Vec<String>,
}

/// Runs `plinth signals`: the set is staged beside `args.out` and moved into
/// place only when complete (`force`: write into an `--out` that already
/// holds files). A file system without room for the samples alone is
/// refused before any work.
pub fn signals(args: &SignalsArgs, force: bool) -> anyhow::Result<()> {
    let machine = Machine::from_toml_path(&args.machine)?;
    let effects = EffectSet::from_options(&args.effects).map_err(anyhow::Error::msg)?;
    let opts = SignalOptions {
        rundown: RunDown::parse(&args.rundown)?,
        sample_rate_hz: args.rate,
        adc: Adc::new(args.adc_bits, args.adc_range)?,
        probe_sensitivity: args.probe_v_per_mm * 1e3,
        probe_gap_v: args.probe_gap,
        probe_noise_v: args.probe_noise_mv * 1e-3,
        seismic_kind: args.seismic,
        seismic_sensitivity: args
            .seismic_sensitivity
            .unwrap_or_else(|| default_seismic_sensitivity(args.seismic)),
        seismic_noise_v: args.seismic_noise_mv * 1e-3,
        grid_step_hz: args.grid_step,
        t0_sample_position: 0.5,
        seed: args.seed,
    };
    // `samples.i16` alone: samples × channels × 2 bytes [bytes].
    let channels = 4 * machine.bearings.len() as u64;
    let least = opts
        .sample_count()?
        .saturating_mul(channels)
        .saturating_mul(2);
    crate::output::check_room("--out", &args.out, least)?;
    let out = crate::output::OutputDir::create(&args.out, force)?;
    let set = synthesise_to(&machine, &effects, &opts, out.path())
        .with_context(|| format!("making signals of {}", args.machine.display()))?;
    out.commit()?;
    let h = &set.header;
    println!(
        "{}: {} samples x {} channels at {} Hz ({:.1} s), {} keyphasor pulses -> {}",
        h.machine,
        h.samples,
        h.channels.len(),
        h.sample_rate_hz,
        h.samples as f64 / h.sample_rate_hz,
        h.keyphasor_pulses,
        args.out.display()
    );
    println!(
        "response interpolation: {} Hz grid, largest error {:.2e} of channel peak",
        h.interpolation.grid_step_hz, h.interpolation.max_rel_error
    );
    // A 1X peak below the noise of the mean of every sample of the channel
    // (its noise and quantisation over √samples) cannot be resolved by any
    // averaging: the channel holds noise only.
    for c in &h.channels {
        let noise = c.noise_v_rms.hypot(h.adc.volts_per_code / 12f64.sqrt());
        let floor = noise / (h.samples.max(1) as f64).sqrt();
        if c.signal_peak_v < floor {
            eprintln!(
                "warning: {}: its 1X signal peaks at {} V, below what averaging all its samples resolves ({} V: noise and ADC step over √{} samples): the channel records noise only (check the sensitivity, --adc-range and --adc-bits)",
                c.name,
                crate::rundir::digits::format_number(c.signal_peak_v),
                crate::rundir::digits::format_number(floor),
                h.samples
            );
        }
    }
    for c in h.channels.iter().filter(|c| c.clipped_samples > 0) {
        eprintln!(
            "warning: {}: {} samples clipped at ±{} V (--adc-range)",
            c.name,
            c.clipped_samples,
            crate::rundir::digits::format_number(h.adc.full_scale_v)
        );
    }
    Ok(())
}
