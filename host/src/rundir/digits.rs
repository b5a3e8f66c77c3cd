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
