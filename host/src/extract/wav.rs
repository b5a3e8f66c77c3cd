//! The WAV container as recorders write it, read by hand so that what the
//! format allows is accepted: integer PCM (8, 16, 24, 32 bits), IEEE float
//! (32 and 64 bits), `WAVE_FORMAT_EXTENSIBLE` of either, chunks before
//! `data` of odd size with or without their pad byte, a streaming writer's
//! `data` size (0xFFFFFFFF, or 0 never patched) and RF64's 64-bit sizes.
//! What is not supported (big-endian `RIFX`, compressed formats such as
//! µ-law or ADPCM, other sample sizes) is named exactly.

use std::io::{Read, Seek, SeekFrom};

/// What a WAV header says.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WavFormat {
    /// Channels per frame.
    pub channels: u16,
    /// Frames per second [Hz].
    pub sample_rate: u32,
    /// Bits per sample.
    pub bits: u16,
    /// IEEE float samples (else integer PCM).
    pub float: bool,
    /// Byte offset of the first sample.
    pub data_start: u64,
    /// Whole frames in the data (the file's end bounds a size the header
    /// does not give).
    pub frames: u64,
}

impl WavFormat {
    /// Bytes per frame.
    pub fn frame_bytes(&self) -> usize {
        usize::from(self.channels) * usize::from(self.bits / 8)
    }

    /// A name for messages: `24-bit integer PCM WAV`, `64-bit float WAV`.
    pub fn describe(&self) -> String {
        let kind = if self.float { "float" } else { "integer PCM" };
        format!("{}-bit {kind} WAV", self.bits)
    }
}

const PCM: u16 = 1;
const IEEE_FLOAT: u16 = 3;
const EXTENSIBLE: u16 = 0xFFFE;

fn u16_at(b: &[u8], i: usize) -> u16 {
    u16::from_le_bytes([b[i], b[i + 1]])
}

fn u32_at(b: &[u8], i: usize) -> u32 {
    u32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]])
}

fn u64_at(b: &[u8], i: usize) -> u64 {
    let mut a = [0u8; 8];
    a.copy_from_slice(&b[i..i + 8]);
    u64::from_le_bytes(a)
}

/// A chunk id of four printable ASCII characters.
fn is_chunk_id(id: &[u8]) -> bool {
    id.len() == 4 && id.iter().all(|&c| (0x20..0x7F).contains(&c))
}

/// Reads the header of a WAV file of `len` bytes from `r` (at its start);
/// `Err` says what is wrong or unsupported, with the byte offset.
pub fn read_header<R: Read + Seek>(r: &mut R, len: u64) -> Result<WavFormat, String> {
    let io = |e: std::io::Error| format!("cannot read the header: {e}");
    let mut head = [0u8; 12];
    r.read_exact(&mut head)
        .map_err(|_| format!("{len} bytes: too short for a WAV header (12 bytes of RIFF/WAVE)"))?;
    match &head[0..4] {
        b"RIFF" | b"RF64" => {}
        b"RIFX" => {
            return Err("a big-endian WAV (RIFX): not supported; convert it to little-endian (sox in.wav out.wav)".into())
        }
        _ => return Err("not a WAV file: it does not start with `RIFF`".into()),
    }
    if &head[8..12] != b"WAVE" {
        return Err("a RIFF file but not WAVE (bytes 8..12)".into());
    }
    let mut pos: u64 = 12;
    let mut fmt: Option<(u16, u16, u32, u16, u16)> = None;
    let mut ds64_data: Option<u64> = None;
    loop {
        let mut ch = [0u8; 8];
        r.seek(SeekFrom::Start(pos)).map_err(io)?;
        if r.read_exact(&mut ch).is_err() {
            return Err(format!(
                "no `data` chunk before the end of the file (at byte {pos})"
            ));
        }
        if !is_chunk_id(&ch[0..4]) {
            return Err(format!(
                "byte {pos}: not a chunk header (bytes {:02X?}): the file is damaged",
                &ch[0..4]
            ));
        }
        let id = [ch[0], ch[1], ch[2], ch[3]];
        let size = u64::from(u32_at(&ch, 4));
        let body = pos + 8;
        match &id {
            b"fmt " => {
                if !(16..=1024).contains(&size) {
                    return Err(format!(
                        "byte {pos}: a `fmt ` chunk of {size} bytes (16 to 40 expected)"
                    ));
                }
                let mut b = vec![0u8; size as usize];
                r.read_exact(&mut b)
                    .map_err(|_| format!("byte {pos}: the `fmt ` chunk is cut short"))?;
                let mut tag = u16_at(&b, 0);
                if tag == EXTENSIBLE {
                    if b.len() < 26 {
                        return Err(format!(
                            "byte {pos}: WAVE_FORMAT_EXTENSIBLE without its sub-format"
                        ));
                    }
                    tag = u16_at(&b, 24);
                }
                fmt = Some((
                    tag,
                    u16_at(&b, 2),
                    u32_at(&b, 4),
                    u16_at(&b, 12),
                    u16_at(&b, 14),
                ));
            }
            b"ds64" => {
                let mut b = [0u8; 16];
                r.read_exact(&mut b)
                    .map_err(|_| format!("byte {pos}: the RF64 `ds64` chunk is cut short"))?;
                ds64_data = Some(u64_at(&b, 8));
            }
            b"data" => {
                let (tag, channels, sample_rate, block_align, bits) = fmt.ok_or_else(|| {
                    format!("byte {pos}: the `data` chunk comes before any `fmt ` chunk")
                })?;
                let float = match (tag, bits) {
                    (PCM, 8 | 16 | 24 | 32) => false,
                    (IEEE_FLOAT, 32 | 64) => true,
                    (PCM, b) => return Err(format!("{b}-bit integer PCM: Plinth reads 8-, 16-, 24- and 32-bit integer PCM and 32- and 64-bit float")),
                    (IEEE_FLOAT, b) => return Err(format!("{b}-bit float: Plinth reads 32- and 64-bit float and 8- to 32-bit integer PCM")),
                    (t, _) => return Err(format!("format tag {t:#06X} (compressed: µ-law, A-law, ADPCM or similar): Plinth reads uncompressed integer PCM (tag 1) and IEEE float (tag 3); convert it (sox in.wav -e signed -b 24 out.wav)")),
                };
                if channels == 0 || sample_rate == 0 {
                    return Err(format!("`fmt `: {channels} channels at {sample_rate} Hz"));
                }
                let frame = u64::from(channels) * u64::from(bits / 8);
                if u64::from(block_align) != frame {
                    return Err(format!("`fmt `: block align {block_align} bytes, but {channels} channels of {bits} bits make {frame}"));
                }
                let available = len.saturating_sub(body);
                let declared = match (size, ds64_data) {
                    (0xFFFF_FFFF, Some(d)) => d,
                    (0xFFFF_FFFF | 0, _) => available, // streaming: to the end of the file
                    (s, _) => s,
                };
                return Ok(WavFormat {
                    channels,
                    sample_rate,
                    bits,
                    float,
                    data_start: body,
                    frames: declared.min(available) / frame,
                });
            }
            _ => {}
        }
        pos = body + size;
        if size & 1 == 1 {
            // The pad byte after an odd-sized chunk is 0; some writers
            // leave it out, and then the next chunk's id starts here.
            let mut pad = [0u8; 1];
            r.seek(SeekFrom::Start(pos)).map_err(io)?;
            if r.read_exact(&mut pad).is_ok() && pad[0] == 0 {
                pos += 1;
            }
        }
        if pos > len {
            return Err(format!(
                "the `{}` chunk at byte {} claims {size} bytes, beyond the end of the file ({len} bytes), and no `data` chunk came before it",
                String::from_utf8_lossy(&id),
                body - 8
            ));
        }
    }
}

/// One sample as the file stores it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Sample {
    /// An integer PCM code (8-bit samples centred on 0).
    Code(i32),
    /// An IEEE float value.
    Float(f64),
}

/// Turns `bytes` (whole frames of `format`) into samples, each given to
/// `each` with its index in `bytes`.
pub fn decode(format: &WavFormat, bytes: &[u8], mut each: impl FnMut(Sample, usize)) {
    let width = usize::from(format.bits / 8);
    for (i, s) in bytes.chunks_exact(width).enumerate() {
        let sample = match (format.float, width) {
            (false, 1) => Sample::Code(i32::from(s[0]) - 128),
            (false, 2) => Sample::Code(i32::from(i16::from_le_bytes([s[0], s[1]]))),
            (false, 3) => Sample::Code(i32::from_le_bytes([0, s[0], s[1], s[2]]) >> 8),
            (false, _) => Sample::Code(i32::from_le_bytes([s[0], s[1], s[2], s[3]])),
            (true, 4) => Sample::Float(f64::from(f32::from_le_bytes([s[0], s[1], s[2], s[3]]))),
            (true, _) => {
                let mut a = [0u8; 8];
                a.copy_from_slice(s);
                Sample::Float(f64::from_le_bytes(a))
            }
        };
        each(sample, i);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A WAV file: `fmt ` (tag, bits), an optional `LIST` chunk of `extra`
    /// bytes (padded when `pad`), and `data` of `body` with size field `size`.
    fn wav(
        tag: u16,
        channels: u16,
        bits: u16,
        extra: Option<(usize, bool)>,
        size: Option<u32>,
        body: &[u8],
    ) -> Vec<u8> {
        let mut b = b"RIFF\0\0\0\0WAVEfmt ".to_vec();
        b.extend_from_slice(&16u32.to_le_bytes());
        b.extend_from_slice(&tag.to_le_bytes());
        b.extend_from_slice(&channels.to_le_bytes());
        b.extend_from_slice(&1000u32.to_le_bytes());
        b.extend_from_slice(&(1000 * u32::from(channels * bits / 8)).to_le_bytes());
        b.extend_from_slice(&(channels * bits / 8).to_le_bytes());
        b.extend_from_slice(&bits.to_le_bytes());
        if let Some((n, pad)) = extra {
            b.extend_from_slice(b"LIST");
            b.extend_from_slice(&(n as u32).to_le_bytes());
            b.extend(std::iter::repeat_n(b'x', n));
            if pad && n % 2 == 1 {
                b.push(0);
            }
        }
        b.extend_from_slice(b"data");
        b.extend_from_slice(&size.unwrap_or(body.len() as u32).to_le_bytes());
        b.extend_from_slice(body);
        b
    }

    fn header(bytes: &[u8]) -> Result<WavFormat, String> {
        read_header(&mut std::io::Cursor::new(bytes), bytes.len() as u64)
    }

    #[test]
    fn float64_streaming_sizes_and_odd_chunks_are_read() {
        let body: Vec<u8> = [0.5f64, -0.25, 1.0, 2.0]
            .iter()
            .flat_map(|v| v.to_le_bytes())
            .collect();
        for size in [None, Some(0xFFFF_FFFF), Some(0)] {
            for extra in [None, Some((3, true)), Some((3, false)), Some((4, true))] {
                let f = header(&wav(3, 2, 64, extra, size, &body)).unwrap();
                assert_eq!(
                    (f.frames, f.float, f.bits, f.channels),
                    (2, true, 64, 2),
                    "{size:?} {extra:?}"
                );
                let bytes = wav(3, 2, 64, extra, size, &body);
                let mut got = Vec::new();
                decode(&f, &bytes[f.data_start as usize..], |v, _| got.push(v));
                assert_eq!(got, [0.5, -0.25, 1.0, 2.0].map(Sample::Float));
            }
        }
    }

    #[test]
    fn integer_codes_are_sign_extended() {
        let body = [0x00, 0x00, 0x80, 0xFF, 0xFF, 0x7F, 0x01, 0x00, 0x00];
        let bytes = wav(1, 1, 24, None, None, &body);
        let f = header(&bytes).unwrap();
        let mut got = Vec::new();
        decode(&f, &bytes[f.data_start as usize..], |c, _| got.push(c));
        assert_eq!(got, [-(1 << 23), (1 << 23) - 1, 1].map(Sample::Code));
    }

    #[test]
    fn what_is_not_supported_is_named() {
        let e = header(&wav(7, 1, 8, None, None, &[0; 4])).unwrap_err();
        assert!(e.contains("format tag 0x0007 (compressed"), "{e}");
        let e = header(&wav(3, 1, 16, None, None, &[0; 4])).unwrap_err();
        assert!(e.contains("16-bit float"), "{e}");
        let mut rifx = wav(1, 1, 16, None, None, &[0; 4]);
        rifx[3] = b'X';
        assert!(header(&rifx).unwrap_err().contains("big-endian"));
        let cut = wav(1, 1, 16, Some((100, true)), None, &[]);
        let e = header(&cut[..60]).unwrap_err();
        assert!(e.contains("beyond the end of the file"), "{e}");
    }
}
