//! The signal-set directory format (`plinth-signals` version 1): header,
//! raw ADC codes, keyphasor pulses and the truth run directory.

use super::*;

/// How the response is interpolated in speed (recorded in the header).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct Interpolation {
    /// Method name (`natural_cubic_spline`).
    pub method: InterpolationMethod,
    /// Grid step [Hz].
    pub grid_step_hz: f64,
    /// Largest error over all channels relative to each channel's largest |X|.
    pub max_rel_error: f64,
}

/// Interpolation method of the response in speed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum InterpolationMethod {
    /// Natural cubic spline through the grid in speed, per channel, complex.
    NaturalCubicSpline,
}

/// `signals.json`: everything about a signal set but the samples.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SignalHeader {
    /// Always [`FORMAT_NAME`].
    pub format: String,
    /// Format version ([`FORMAT_VERSION`]).
    pub version: u32,
    /// Machine name.
    pub machine: String,
    /// Sample rate per channel [Hz].
    pub sample_rate_hz: f64,
    /// Sample vectors (samples per channel).
    pub samples: u64,
    /// The converter.
    pub adc: Adc,
    /// The speed ramp.
    pub rundown: RunDown,
    /// Position of keyphasor pulse 0 (t = 0, θ = 0) in sample periods.
    pub t0_sample_position: f64,
    /// Keyphasor pulses in `keyphasor.csv`.
    pub keyphasor_pulses: u64,
    /// Channels in sample-vector order.
    pub channels: Vec<Channel>,
    /// How the response was interpolated in speed.
    pub interpolation: Interpolation,
    /// Seed of the noise (StdRng).
    pub seed: u64,
    /// Effects injected into the machine (formats.md names).
    #[serde(default)]
    pub effects: Vec<String>,
}

/// A whole signal set in memory.
#[derive(Clone, Debug, PartialEq)]
pub struct SignalSet {
    /// The header.
    pub header: SignalHeader,
    /// ADC codes interleaved by sample vector (k·N + n).
    pub codes: Vec<i16>,
    /// Keyphasor pulse positions [sample periods since sample 0], increasing;
    /// pulse j is at shaft angle 2πj.
    pub keyphasor: Vec<f64>,
}

impl SignalSet {
    /// Number of channels.
    pub fn channels(&self) -> usize {
        self.header.channels.len()
    }

    /// Sample vectors.
    pub fn len(&self) -> usize {
        self.header.samples as usize
    }

    /// True when there are no samples.
    pub fn is_empty(&self) -> bool {
        self.header.samples == 0
    }

    /// Sample k of channel n in volts [V].
    pub fn volts(&self, k: usize, n: usize) -> f64 {
        f64::from(self.codes[k * self.channels() + n]) * self.header.adc.volts_per_code
    }

    /// Time of sample k [s] (t = 0 at keyphasor pulse 0).
    pub fn time_s(&self, k: usize) -> f64 {
        (k as f64 - self.header.t0_sample_position) / self.header.sample_rate_hz
    }

    /// Writes the signal set to `dir` (created if needed); the truth run
    /// directory is written separately ([`write_truth`]) or by [`synthesise_to`].
    pub fn write(&self, dir: &Path) -> Result<(), SignalsError> {
        std::fs::create_dir_all(dir).map_err(io_err(dir))?;
        let hp = dir.join(HEADER_FILE);
        let text = serde_json::to_string_pretty(&self.header)
            .map_err(|e| SignalsError::Request(format!("serialising the header: {e}")))?;
        std::fs::write(&hp, text + "\n").map_err(io_err(&hp))?;

        let sp = dir.join(SAMPLES_FILE);
        let f = std::fs::File::create(&sp).map_err(io_err(&sp))?;
        let mut w = BufWriter::with_capacity(1 << 20, f);
        for c in &self.codes {
            w.write_all(&c.to_le_bytes()).map_err(io_err(&sp))?;
        }
        w.flush().map_err(io_err(&sp))?;

        let kp = dir.join(KEYPHASOR_FILE);
        let f = std::fs::File::create(&kp).map_err(io_err(&kp))?;
        let mut w = BufWriter::new(f);
        writeln!(w, "revolution,sample_position,time_s").map_err(io_err(&kp))?;
        let fs = self.header.sample_rate_hz;
        let p0 = self.header.t0_sample_position;
        for (j, p) in self.keyphasor.iter().enumerate() {
            writeln!(w, "{j},{p:.17e},{:.17e}", (p - p0) / fs).map_err(io_err(&kp))?;
        }
        w.flush().map_err(io_err(&kp))?;
        Ok(())
    }

    /// Reads and checks a signal set (not the truth; see [`read_truth`]).
    pub fn read(dir: &Path) -> Result<SignalSet, SignalsError> {
        let hp = dir.join(HEADER_FILE);
        let text = crate::input_file::read_to_string(&hp).map_err(io_err(&hp))?;
        let header: SignalHeader = serde_json::from_str(&text).map_err(|e| SignalsError::Json {
            file: hp.clone(),
            line: e.line(),
            column: e.column(),
            message: e.to_string(),
        })?;
        check_header(&header, &hp)?;

        let sp = dir.join(SAMPLES_FILE);
        let n = header.channels.len() as u64;
        let expected = header
            .samples
            .checked_mul(n)
            .and_then(|v| v.checked_mul(2))
            .ok_or_else(|| SignalsError::Header {
                file: hp.clone(),
                message: "samples × channels overflows".into(),
            })?;
        crate::input_file::ensure_regular(&sp).map_err(io_err(&sp))?;
        let mut f = std::fs::File::open(&sp).map_err(io_err(&sp))?;
        let len = f.metadata().map_err(io_err(&sp))?.len();
        if len != expected {
            return Err(SignalsError::Samples {
                file: sp,
                offset: len.min(expected),
                message: format!(
                    "file is {len} bytes, the header describes {} samples × {n} channels × 2 bytes = {expected}",
                    header.samples
                ),
            });
        }
        let mut bytes = Vec::with_capacity(expected as usize);
        f.read_to_end(&mut bytes).map_err(io_err(&sp))?;
        if bytes.len() as u64 != expected {
            return Err(SignalsError::Samples {
                file: sp,
                offset: bytes.len() as u64,
                message: "file changed size while being read".into(),
            });
        }
        let codes: Vec<i16> = bytes
            .chunks_exact(2)
            .map(|b| i16::from_le_bytes([b[0], b[1]]))
            .collect();
        let (lo, hi) = header.adc.code_range();
        if let Some(i) = codes
            .iter()
            .position(|&c| i32::from(c) < lo || i32::from(c) > hi)
        {
            return Err(SignalsError::Samples {
                file: sp,
                offset: 2 * i as u64,
                message: format!(
                    "code {} is outside the {}-bit ADC range {lo}..={hi}",
                    codes[i], header.adc.bits
                ),
            });
        }

        let kp = dir.join(KEYPHASOR_FILE);
        let keyphasor = read_keyphasor(&kp, header.samples)?;
        if keyphasor.len() as u64 != header.keyphasor_pulses {
            return Err(SignalsError::Keyphasor {
                file: kp,
                line: keyphasor.len() + 1,
                message: format!(
                    "{} pulses, the header says {}",
                    keyphasor.len(),
                    header.keyphasor_pulses
                ),
            });
        }
        Ok(SignalSet {
            header,
            codes,
            keyphasor,
        })
    }
}

fn check_header(h: &SignalHeader, file: &Path) -> Result<(), SignalsError> {
    let bad = |message: String| SignalsError::Header {
        file: file.to_path_buf(),
        message,
    };
    if h.format != FORMAT_NAME {
        return Err(bad(format!(
            "format: expected {FORMAT_NAME:?}, got {:?}",
            h.format
        )));
    }
    if h.version != FORMAT_VERSION {
        return Err(bad(format!(
            "version: this build reads version {FORMAT_VERSION}, the file is version {}",
            h.version
        )));
    }
    if !(h.sample_rate_hz.is_finite() && h.sample_rate_hz > 0.0) {
        return Err(bad(format!(
            "sample_rate_hz: must be finite and > 0 (got {})",
            h.sample_rate_hz
        )));
    }
    let adc = Adc::new(h.adc.bits, h.adc.full_scale_v).map_err(|e| bad(format!("adc: {e}")))?;
    if (adc.volts_per_code - h.adc.volts_per_code).abs() > 1e-12 * adc.volts_per_code {
        return Err(bad(format!(
            "adc.volts_per_code: {} does not match {} bits over ±{} V ({})",
            h.adc.volts_per_code, h.adc.bits, h.adc.full_scale_v, adc.volts_per_code
        )));
    }
    h.rundown
        .validate()
        .map_err(|m| bad(format!("rundown: {m}")))?;
    if h.channels.is_empty() {
        return Err(bad("channels: none".into()));
    }
    if !h.t0_sample_position.is_finite() {
        return Err(bad("t0_sample_position: not finite".into()));
    }
    for (i, c) in h.channels.iter().enumerate() {
        if !(c.sensitivity.is_finite() && c.sensitivity > 0.0) {
            return Err(bad(format!(
                "channels[{i}].sensitivity: must be finite and > 0 (got {})",
                c.sensitivity
            )));
        }
        if !(c.offset_v.is_finite() && c.noise_v_rms.is_finite() && c.noise_v_rms >= 0.0) {
            return Err(bad(format!(
                "channels[{i}]: offset_v and noise_v_rms must be finite, noise >= 0"
            )));
        }
    }
    Ok(())
}

fn read_keyphasor(file: &Path, samples: u64) -> Result<Vec<f64>, SignalsError> {
    let text = crate::input_file::read_to_string(file).map_err(io_err(file))?;
    let bad = |line: usize, message: String| SignalsError::Keyphasor {
        file: file.to_path_buf(),
        line,
        message,
    };
    let mut lines = text.lines().enumerate();
    match lines.next() {
        Some((_, h)) if h.trim() == "revolution,sample_position,time_s" => {}
        _ => {
            return Err(bad(
                1,
                "header must be `revolution,sample_position,time_s`".into(),
            ))
        }
    }
    let mut out: Vec<f64> = Vec::new();
    for (i, line) in lines {
        let ln = i + 1;
        if line.trim().is_empty() {
            continue;
        }
        let cols: Vec<&str> = line.split(',').collect();
        if cols.len() != 3 {
            return Err(bad(ln, format!("expected 3 columns, got {}", cols.len())));
        }
        let rev: u64 = cols[0].trim().parse().map_err(|_| {
            bad(
                ln,
                format!("column 1 (revolution): {:?} is not an integer", cols[0]),
            )
        })?;
        if rev != out.len() as u64 {
            return Err(bad(
                ln,
                format!("column 1 (revolution): expected {}, got {rev}", out.len()),
            ));
        }
        let p: f64 = cols[1].trim().parse().map_err(|_| {
            bad(
                ln,
                format!("column 2 (sample_position): {:?} is not a number", cols[1]),
            )
        })?;
        if !p.is_finite() || p < 0.0 || p >= samples as f64 {
            return Err(bad(
                ln,
                format!("column 2 (sample_position): {p} is outside the samples 0..{samples}"),
            ));
        }
        if let Some(&prev) = out.last() {
            if p <= prev {
                return Err(bad(
                    ln,
                    format!(
                        "column 2 (sample_position): {p} is not after the previous pulse {prev}"
                    ),
                ));
            }
        }
        out.push(p);
    }
    Ok(out)
}

/// Reads the truth run directory of a signal set.
pub fn read_truth(dir: &Path) -> Result<RunDir, SignalsError> {
    Ok(RunDir::read(dir.join(TRUTH_DIR))?)
}

/// Writes the truth run directory of a signal set (full precision).
pub fn write_truth(dir: &Path, truth: &RunDir) -> Result<(), SignalsError> {
    Ok(truth.write(dir.join(TRUTH_DIR))?)
}
