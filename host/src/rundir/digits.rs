//! Significant-digit reduction (instrument accuracy, the paper's truncated
//! data) and the shortest decimal text of a number.

/// How numbers are reduced to a number of significant digits on writing,
/// imitating instrument accuracy (the paper truncated its data).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DigitsMode {
    /// Round half away from zero.
    Round,
    /// Drop the digits beyond the last kept one (towards zero), as the paper did.
    Truncate,
}

/// Options for [`RunDir::write_with`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct WriteOptions {
    /// Significant digits of the measured phasors (`rel_*`, `ped_*`); `None`
    /// writes every value with full round-trip precision. Speeds, bearing
    /// coefficients and the truth are always written in full.
    pub digits: Option<u32>,
    /// How the digits are reduced.
    pub digits_mode: DigitsMode,
}

impl Default for WriteOptions {
    fn default() -> Self {
        Self {
            digits: None,
            digits_mode: DigitsMode::Round,
        }
    }
}

/// The shortest decimal text that reads back as exactly `x` (finite `x`),
/// in plain notation for moderate magnitudes and exponent notation otherwise.
pub fn format_number(x: f64) -> String {
    let a = x.abs();
    if a == 0.0 || (1e-4..1e9).contains(&a) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// `x` reduced to `digits` significant decimal digits (at least one), working
/// on the shortest decimal text of `x` so that e.g. 0.29 truncates to 0.29,
/// not 0.28. Non-finite values are returned unchanged.
pub fn round_to_digits(x: f64, digits: u32, mode: DigitsMode) -> f64 {
    if !x.is_finite() || x == 0.0 {
        return x;
    }
    let digits = digits.max(1) as usize;
    // `{:e}` is the shortest round-trip text: "-1.2345e-7".
    let text = format!("{:e}", x.abs());
    let (mantissa, exponent) = text.split_once('e').unwrap_or((text.as_str(), "0"));
    let exponent: i32 = exponent.parse().unwrap_or(0);
    let mut ds: Vec<u8> = mantissa
        .bytes()
        .filter(u8::is_ascii_digit)
        .map(|b| b - b'0')
        .collect();
    if ds.len() <= digits {
        return x;
    }
    let round_up = mode == DigitsMode::Round && ds[digits] >= 5;
    ds.truncate(digits);
    let mut exponent = exponent;
    if round_up {
        let mut i = digits;
        loop {
            if i == 0 {
                // 9.99 → 10.0: a carry out of the leading digit.
                ds.insert(0, 1);
                ds.truncate(digits);
                exponent += 1;
                break;
            }
            i -= 1;
            if ds[i] == 9 {
                ds[i] = 0;
            } else {
                ds[i] += 1;
                break;
            }
        }
    }
    let mut s = String::with_capacity(digits + 8);
    if x < 0.0 {
        s.push('-');
    }
    for (i, d) in ds.iter().enumerate() {
        if i == 1 {
            s.push('.');
        }
        s.push(char::from(b'0' + d));
    }
    s.push('e');
    s.push_str(&exponent.to_string());
    s.parse().unwrap_or(x)
}

pub(crate) use count::{read_counted, read_number, trimmed};
pub use count::{text_digits, written_digits};

mod count;
mod nearest;

/// How the eight real numbers of a `measurements.csv` row (formats.md
/// order: rel y re, rel y im, rel z re, rel z im, ped y re, …) were written:
/// their digits counted once from the text as it was read. Each entry
/// remembers the magnitude it describes, so a value changed since (a
/// slow-roll subtraction) is not taken for its text, while a sign change or
/// a swap of channels (convention corrections) still finds its digits.
///
/// It also carries the rounding the numbers had before they were written
/// here, when a run directory says it (`resolution.csv`,
/// [`super::resolution`]: a vector table's amplitude digits and phase
/// steps, propagated by `plinth import`), as a variance per number, found
/// the same way: by the magnitude it describes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WrittenDigits {
    abs_bits: [u64; 8],
    digits: [u8; 8],
    exponent: [i16; 8],
    /// Variance [m²] of each number's rounding before it was written here
    /// (0: none known).
    floor_var: [f64; 8],
}

impl WrittenDigits {
    /// The digits of `values` parsed from `texts` (same order):
    /// [`written_digits`] of each value, counted from its text where that
    /// is the value's shortest text.
    pub fn from_text(texts: [&str; 8], values: [f64; 8]) -> Self {
        Self::from_counted(
            values,
            std::array::from_fn(|k| count::digits_of_text(texts[k], values[k])),
        )
    }

    /// `values` with the digits already counted for each
    /// ([`written_digits`] of the value, or `None`: see [`Self::from_text`]).
    pub(crate) fn from_counted(values: [f64; 8], counted: [Option<(u32, i32)>; 8]) -> Self {
        let mut out = Self {
            abs_bits: [0; 8],
            digits: [0; 8],
            exponent: [0; 8],
            floor_var: [0.0; 8],
        };
        for k in 0..8 {
            let (d, e) = counted[k].unwrap_or((0, 0));
            out.abs_bits[k] = values[k].abs().to_bits();
            out.digits[k] = d as u8;
            out.exponent[k] = e.clamp(i16::MIN as i32, i16::MAX as i32) as i16;
        }
        out
    }

    /// The digits of `values` counted from the values themselves (rows made
    /// in memory, whose text is their shortest round-trip one).
    pub fn of_values(values: [f64; 8]) -> Self {
        Self::from_text([""; 8], values)
    }

    /// [`written_digits`] of `v` from the text when `v` is (up to its sign)
    /// one of the row's numbers as read, else from the value.
    pub fn of(&self, v: f64) -> Option<(u32, i32)> {
        if v == 0.0 || !v.is_finite() {
            return None;
        }
        let bits = v.abs().to_bits();
        match self.abs_bits.iter().position(|&b| b == bits) {
            Some(k) if self.digits[k] > 0 => {
                Some((u32::from(self.digits[k]), i32::from(self.exponent[k])))
            }
            _ => written_digits(v),
        }
    }

    /// The same row with the rounding of its complex channels before they
    /// were written here: `sd` [m] per channel (rel y, rel z, ped y, ped z),
    /// sqrt(E|n|²) of the complex rounding error, split equally between the
    /// real and the imaginary part (as the noise columns are).
    pub fn with_resolution(mut self, sd: super::NoiseSd) -> Self {
        self.floor_var = std::array::from_fn(|k| 0.5 * sd[k / 2] * sd[k / 2]);
        self
    }

    /// Variance [m²] of the earlier rounding of `v`, now the row's number
    /// `k` (formats.md order), when `v` is (up to its sign) one of the row's
    /// numbers as read (number `k` first: equal magnitudes, such as two
    /// zeros, keep their own), else 0: a value changed since (a unit
    /// conversion) is not taken for it.
    pub fn floor_var_of(&self, k: usize, v: f64) -> f64 {
        // Rows without one (every row not from a table): one test, no search.
        if self.floor_var == [0.0; 8] {
            return 0.0;
        }
        let bits = v.abs().to_bits();
        if self.abs_bits.get(k) == Some(&bits) {
            return self.floor_var[k];
        }
        self.abs_bits
            .iter()
            .position(|&b| b == bits)
            .map_or(0.0, |j| self.floor_var[j])
    }
}

impl super::Measurement {
    /// The eight real numbers of the row, formats.md order (rel y re, rel y
    /// im, rel z re, …, ped z im) [m].
    pub fn reals(&self) -> [f64; 8] {
        let [ry, rz] = self.rel;
        let [py, pz] = self.ped;
        [ry.re, ry.im, rz.re, rz.im, py.re, py.im, pz.re, pz.im]
    }

    /// Sets the rounding sd [m] of the row's phasors as they stand now
    /// ([`WrittenDigits::with_resolution`]; per complex channel, rel y, rel
    /// z, ped y, ped z), keeping the digits counted from its text when
    /// they describe these numbers.
    pub fn set_resolution(&mut self, sd: super::NoiseSd) {
        let values = self.reals();
        let written = match self.written {
            Some(w) if (0..8).all(|k| w.abs_bits[k] == values[k].abs().to_bits()) => w,
            _ => WrittenDigits::of_values(values),
        };
        self.written = Some(written.with_resolution(sd));
    }

    /// The rounding sd [m] (sqrt(E|n|²), per complex channel: rel y, rel z,
    /// ped y, ped z) this row's phasors carry from before they were written
    /// ([`WrittenDigits::with_resolution`]) as they stand now; `None` when
    /// none is known for any of them.
    pub fn resolution_sd(&self) -> Option<super::NoiseSd> {
        let w = self.written.as_ref()?;
        let values = [self.rel[0], self.rel[1], self.ped[0], self.ped[1]];
        if w.floor_var.iter().all(|&v| v == 0.0) {
            return None;
        }
        let sd: super::NoiseSd = std::array::from_fn(|ch| {
            (w.floor_var_of(2 * ch, values[ch].re) + w.floor_var_of(2 * ch + 1, values[ch].im))
                .sqrt()
        });
        sd.iter().any(|&s| s > 0.0).then_some(sd)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn written_digits_follow_their_values() {
        let texts = [
            "1.5e-6", "-2.25e-7", "3", "0", "4.1e-9", "5e-9", "6.02e-8", "7.1e-9",
        ];
        let values = texts.map(|t| t.parse::<f64>().unwrap());
        let w = WrittenDigits::from_text(texts, values);
        assert_eq!(w.of(1.5e-6), Some((2, -6)));
        // A sign change and a value moved to another channel still match.
        assert_eq!(w.of(2.25e-7), Some((3, -7)));
        assert_eq!(w.of(-4.1e-9), Some((2, -9)));
        // A changed value is counted from its own shortest text.
        assert_eq!(w.of(1.5e-6 + 1e-9), written_digits(1.5e-6 + 1e-9));
        assert_eq!(w.of(0.0), None);
    }
}
