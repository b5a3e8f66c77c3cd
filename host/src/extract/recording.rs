//! Recordings read as a stream of sample frames in volts, a block at a time
//! (memory independent of the file's length): WAV (8- to 32-bit integer PCM,
//! 32- and 64-bit float, read by [`super::wav`]; integer codes scaled so
//! that full scale is `full_scale_v`) and CSV (a header row, `time_s`, then one column
//! per channel in channel order, in volts; the sample rate from the time
//! column).
//!
//! Every sample at the converter's rails (the most negative or most positive
//! integer code; |v| ≥ `full_scale_v` for float and CSV when it is given) is
//! reported per channel with the first frame it happened at, so that a
//! clipped channel is named with the time its clipping began.

use anyhow::{bail, Context, Result};
use std::fs::File;
use std::io::BufReader;
use std::path::Path;

/// Rows read ahead from a CSV recording to measure its sample rate (fewer
/// when its channels would make them more than [`CSV_AHEAD_BYTES`]).
const CSV_RATE_ROWS: usize = 65_536;

/// The most memory the rows read ahead may take [bytes]: 64 MiB.
const CSV_AHEAD_BYTES: usize = 64 << 20;

/// Rows read ahead from a CSV recording of `channels` channels: at most
/// [`CSV_RATE_ROWS`], at most [`CSV_AHEAD_BYTES`] of volts (f32), at least 16.
fn csv_rate_rows(channels: usize) -> usize {
    (CSV_AHEAD_BYTES / (4 * channels.max(1))).clamp(16, CSV_RATE_ROWS)
}

/// Clipping seen on one channel.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub struct Clipping {
    /// First frame at the rails.
    pub first_frame: Option<u64>,
    /// Frames at the rails.
    pub count: u64,
}

enum Source {
    Wav {
        reader: BufReader<File>,
        header: super::wav::WavFormat,
        /// Frames not yet read.
        left: u64,
        /// Bytes of the current block.
        bytes: Vec<u8>,
        /// Volts per integer code.
        scale: f64,
        /// Integer rails.
        rails: (i32, i32),
    },
    Csv {
        records: csv::StringRecordsIntoIter<BufReader<crate::input_file::BoundedLines<File>>>,
        /// Rows read ahead (interleaved volts), consumed first.
        ahead: std::collections::VecDeque<f32>,
        /// Time of the previous row and of row 0 [s].
        last_time: f64,
        first_time: f64,
    },
}

/// An open recording.
pub struct Recording {
    /// File name for messages.
    pub file: String,
    /// Sample rate per channel [Hz].
    pub sample_rate_hz: f64,
    /// Channels per frame.
    pub channels: usize,
    /// Frames in the file, when the header says (WAV).
    pub frames: Option<u64>,
    /// Size of the file [bytes] (for progress of CSV recordings).
    pub bytes: u64,
    /// What kind of samples, for messages (`16-bit PCM`, `CSV`, ...).
    pub format: String,
    /// Frames delivered so far.
    pub position: u64,
    /// Per channel clipping so far.
    pub clipping: Vec<Clipping>,
    /// Volts at |v| ≥ which a float/CSV sample counts as clipped.
    float_rail: Option<f64>,
    source: Source,
    /// Where it was opened from, and the full scale it was opened with.
    reopen: (std::path::PathBuf, Option<f64>),
}

impl Recording {
    /// Opens a WAV (by its `.wav` extension or RIFF header) or CSV recording.
    pub fn open(path: &Path, full_scale_v: Option<f64>) -> Result<Recording> {
        let mut r = Self::open_any(path, full_scale_v)?;
        r.reopen = (path.to_path_buf(), full_scale_v);
        Ok(r)
    }

    /// The same recording opened again at its start.
    pub fn reopen(&self) -> Result<Recording> {
        Self::open(&self.reopen.0, self.reopen.1)
    }

    fn open_any(path: &Path, full_scale_v: Option<f64>) -> Result<Recording> {
        let file = path.display().to_string();
        let mut head = [0u8; 4];
        crate::input_file::ensure_regular(path).with_context(|| file.clone())?;
        {
            use std::io::Read;
            let mut f = File::open(path).with_context(|| file.clone())?;
            let n = f.read(&mut head).with_context(|| file.clone())?;
            if n < 4 {
                head = [0; 4];
            }
        }
        let bytes = std::fs::metadata(path).map(|m| m.len()).unwrap_or(0);
        if &head == b"RIFF" || &head == b"RIFX" || &head == b"RF64" {
            Self::open_wav(path, file, bytes, full_scale_v)
        } else {
            Self::open_csv(path, file, bytes, full_scale_v)
        }
    }

    fn open_wav(
        path: &Path,
        file: String,
        bytes: u64,
        full_scale_v: Option<f64>,
    ) -> Result<Recording> {
        let mut handle = File::open(path).with_context(|| file.clone())?;
        let header = super::wav::read_header(&mut handle, bytes)
            .map_err(|e| anyhow::anyhow!("{file}: WAV: {e}"))?;
        std::io::Seek::seek(&mut handle, std::io::SeekFrom::Start(header.data_start))
            .with_context(|| file.clone())?;
        let reader = BufReader::new(handle);
        let channels = usize::from(header.channels);
        let float = header.float;
        let format = header.describe();
        let bits = u32::from(header.bits);
        let scale = if float {
            1.0
        } else {
            let fs = full_scale_v.ok_or_else(|| {
                anyhow::anyhow!("{file}: {format}: the channels file must give `full_scale_v` (the voltage of full scale) to turn codes into volts")
            })?;
            fs / 2f64.powi(bits as i32 - 1)
        };
        let half = 1i64 << (bits - 1);
        let rails = ((-half) as i32, (half - 1) as i32);
        Ok(Recording {
            sample_rate_hz: f64::from(header.sample_rate),
            channels,
            frames: Some(header.frames),
            bytes,
            format,
            position: 0,
            clipping: vec![Clipping::default(); channels],
            reopen: (std::path::PathBuf::new(), None),
            float_rail: if float { full_scale_v } else { None },
            source: Source::Wav {
                reader,
                header,
                left: header.frames,
                bytes: Vec::new(),
                scale,
                rails,
            },
            file,
        })
    }

    fn open_csv(
        path: &Path,
        file: String,
        bytes: u64,
        full_scale_v: Option<f64>,
    ) -> Result<Recording> {
        let handle = crate::csv_layout::open_stream(path, "time_s").map_err(|e| match e {
            crate::csv_layout::LayoutError::NotAFile(m) => anyhow::anyhow!("{file}: {m}"),
            crate::csv_layout::LayoutError::At(line, m) => anyhow::anyhow!("{file}:{line}: {m}"),
        })?;
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(false)
            .trim(csv::Trim::All)
            .from_reader(handle);
        let mut header = csv::StringRecord::new();
        if !reader
            .read_record(&mut header)
            .with_context(|| format!("{file}:1"))?
        {
            bail!("{file}:1: empty file: expected a header row `time_s,<channel 0>,<channel 1>,...` (or a WAV file)");
        }
        let first = header.get(0).unwrap_or("").trim_start_matches('\u{feff}');
        if first != "time_s" {
            bail!("{file}:1:1: the first column must be `time_s` (found `{first}`); a CSV recording is `time_s` then one column per channel, in volts");
        }
        let channels = header.len() - 1;
        if channels == 0 {
            bail!("{file}:1: no channel columns after `time_s`");
        }
        let mut records = reader.into_records();
        let mut ahead = std::collections::VecDeque::new();
        let mut times = Vec::new();
        for record in records.by_ref().take(csv_rate_rows(channels)) {
            let record = record.with_context(|| file.clone())?;
            let (t, _) = parse_csv_row(&file, &record, channels, &mut ahead)?;
            times.push(t);
        }
        if times.len() < 2 {
            bail!("{file}: fewer than two data rows: no sample rate");
        }
        let n = times.len();
        let span = times[n - 1] - times[0];
        if span.is_nan() || span <= 0.0 {
            bail!("{file}: `time_s` does not increase over the first {n} rows");
        }
        let rate = (n - 1) as f64 / span;
        for (k, w) in times.windows(2).enumerate() {
            check_step(&file, k as u64 + 3, w[1] - w[0], rate)?;
        }
        let (first_time, last_time) = (times[0], times[n - 1]);
        Ok(Recording {
            sample_rate_hz: rate,
            channels,
            frames: None,
            bytes,
            format: "CSV".into(),
            position: 0,
            clipping: vec![Clipping::default(); channels],
            reopen: (std::path::PathBuf::new(), None),
            float_rail: full_scale_v,
            source: Source::Csv {
                records,
                ahead,
                last_time,
                first_time,
            },
            file,
        })
    }

    /// Bytes one sample takes in the file (WAV), 0 for CSV (parsed a row
    /// at a time).
    pub fn sample_bytes(&self) -> usize {
        match &self.source {
            Source::Wav { header, .. } => usize::from(header.bits / 8),
            Source::Csv { .. } => 0,
        }
    }

    /// Reads up to `max_frames` frames into `out` (interleaved volts,
    /// cleared first); returns the frames read, 0 at the end.
    pub fn read(&mut self, out: &mut Vec<f32>, max_frames: usize) -> Result<usize> {
        out.clear();
        let n = self.channels;
        match &mut self.source {
            Source::Wav {
                reader,
                header,
                left,
                bytes,
                scale,
                rails,
            } => {
                use std::io::Read;
                let frames = (*left).min(max_frames as u64) as usize;
                bytes.resize(frames * header.frame_bytes(), 0);
                reader.read_exact(bytes).map_err(|e| {
                    anyhow::anyhow!(
                        "{}: frame {}: {e} (the file is shorter than its header says)",
                        self.file,
                        self.position
                    )
                })?;
                *left -= frames as u64;
                let position = self.position;
                let clipping = &mut self.clipping;
                super::wav::decode(header, bytes, |sample, i| match sample {
                    super::wav::Sample::Code(code) => {
                        if code <= rails.0 || code >= rails.1 {
                            let c = &mut clipping[i % n];
                            c.first_frame.get_or_insert(position + (i / n) as u64);
                            c.count += 1;
                        }
                        out.push((f64::from(code) * *scale) as f32);
                    }
                    super::wav::Sample::Float(v) => out.push(v as f32),
                });
            }
            Source::Csv {
                records,
                ahead,
                last_time,
                first_time: _,
            } => {
                while out.len() < max_frames * n && !ahead.is_empty() {
                    out.extend(ahead.drain(..n));
                }
                while out.len() < max_frames * n {
                    let Some(record) = records.next() else { break };
                    let record = record.with_context(|| self.file.clone())?;
                    let line = record.position().map_or(0, |p| p.line());
                    let mut row = std::collections::VecDeque::new();
                    let (t, _) = parse_csv_row(&self.file, &record, n, &mut row)?;
                    check_step(&self.file, line, t - *last_time, self.sample_rate_hz)?;
                    *last_time = t;
                    out.extend(row);
                }
            }
        }
        let frames = out.len() / n;
        if let Some(rail) = self.float_rail {
            for (i, v) in out.iter().enumerate() {
                if f64::from(v.abs()) >= rail {
                    let c = &mut self.clipping[i % n];
                    c.first_frame.get_or_insert(self.position + (i / n) as u64);
                    c.count += 1;
                }
            }
        }
        self.position += frames as u64;
        Ok(frames)
    }

    /// The sample rate over the whole CSV file read so far [Hz] (WAV: the header's).
    pub fn measured_rate_hz(&self) -> f64 {
        match &self.source {
            Source::Csv {
                last_time,
                first_time,
                ..
            } if self.position > 1 => (self.position - 1) as f64 / (last_time - first_time),
            _ => self.sample_rate_hz,
        }
    }
}

/// Parses one CSV data row: its time and channel volts (appended to `out`).
fn parse_csv_row(
    file: &str,
    record: &csv::StringRecord,
    channels: usize,
    out: &mut std::collections::VecDeque<f32>,
) -> Result<(f64, usize)> {
    let line = record.position().map_or(0, |p| p.line());
    if record.len() != channels + 1 {
        bail!(
            "{file}:{line}: {} fields, but the header has `time_s` and {channels} channels",
            record.len()
        );
    }
    let mut t = 0.0;
    for (c, text) in record.iter().enumerate() {
        let v: f64 = text
            .parse()
            .ok()
            .filter(|v: &f64| v.is_finite())
            .ok_or_else(|| {
                anyhow::anyhow!("{file}:{line}:{}: `{text}` is not a finite number", c + 1)
            })?;
        if c == 0 {
            t = v;
        } else {
            out.push_back(v as f32);
        }
    }
    Ok((t, line as usize))
}

/// A time step between consecutive rows must be one sample period (within
/// half a period): no gaps, no reversals.
fn check_step(file: &str, line: u64, dt: f64, rate: f64) -> Result<()> {
    let period = 1.0 / rate;
    if dt.is_nan() || (dt - period).abs() > 0.5 * period {
        bail!(
            "{file}:{line}:1: `time_s` steps by {dt:e} s, but the recording's sample period is {period:e} s ({rate:.6} Hz): the samples must be uniformly spaced (a gap or a jump in time?)"
        );
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    #[test]
    fn rows_read_ahead_stay_within_their_memory_whatever_the_channels() {
        assert_eq!(super::csv_rate_rows(9), super::CSV_RATE_ROWS);
        for channels in [1000, 100_000, 524_288] {
            let rows = super::csv_rate_rows(channels);
            assert!(
                rows >= 16 && rows * channels * 4 <= super::CSV_AHEAD_BYTES,
                "{channels}: {rows}"
            );
        }
    }
}
