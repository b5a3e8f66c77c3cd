//! Counting the significant digits of a number: from its text as written
//! (one pass over the bytes) or from its value (the shortest text that
//! reads back as it, Ryū's), and deciding from the text alone, with exact
//! integer arithmetic, when a text of more than 15 digits is itself that
//! shortest text (as every full-precision writer's is), so that the value
//! need not be printed.

/// The significant digits and decimal exponent of the first significant
/// digit of a number as written in `text` (e.g. `-1.230e-6` → (3, −6):
/// trailing zeros carry no digit, as for the value), counted from the text;
/// `None` for zero, text that is not a plain decimal number, or more than 15
/// significant digits (beyond 15 two decimals may read as the same f64, so
/// the value decides: [`written_digits`]). Up to 15 digits this is exactly
/// [`written_digits`] of the parsed value: a decimal of at most 15 digits is
/// the shortest text of its f64.
pub fn text_digits(text: &str) -> Option<(u32, i32)> {
    counted_digits(text)
        .map(|c| (c.digits, c.exponent))
        .filter(|&(d, _)| d <= 15)
}

/// [`written_digits`] of `value`, the number `text` reads as: counted from
/// the text when it is the shortest text of `value` (up to 15 digits
/// always; beyond, when no decimal of fewer digits reads as `value`:
/// [`Counted::is_shortest_of`]), else from the value.
pub fn digits_of_text(text: &str, value: f64) -> Option<(u32, i32)> {
    digits_of(counted_digits(text), value, false)
}

/// [`digits_of_text`] of a text counted as `counted` ([`counted_digits`]);
/// `nearest`: `value` is known to be the text's nearest double (the
/// standard parser's value of it), so that it need not be tested to read
/// as it.
fn digits_of(counted: Option<Counted>, value: f64, nearest: bool) -> Option<(u32, i32)> {
    let shortest = |c: &Counted| {
        if nearest {
            c.is_shortest_of_its_value(value)
        } else {
            c.is_shortest_of(value)
        }
    };
    match counted {
        Some(c) if c.digits <= 15 || shortest(&c) => Some((c.digits, c.exponent)),
        _ => written_digits(value),
    }
}

/// A plain decimal number's text as counted: `mantissa`·10^(`exponent` −
/// `digits` + 1) is its magnitude.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Counted {
    /// Significant digits (first to last non-zero digit).
    digits: u32,
    /// Decimal exponent of the first significant digit.
    exponent: i32,
    /// The significant digits as an integer (wrapped, meaningless, beyond
    /// 19 digits).
    mantissa: u64,
}

/// The significant digits, the decimal exponent of the first one and their
/// integer of a plain decimal number's text, however many digits it has
/// (`None` for zero and for text that is not a plain decimal number).
fn counted_digits(text: &str) -> Option<Counted> {
    counted_plain(trimmed(text))
}

/// [`counted_digits`] of a text as it stands (no whitespace taken off):
/// an optional sign, digits with at most one point, at least one of them
/// non-zero, then an optional exponent (`e` or `E`, an optional sign,
/// digits, within i32).
fn counted_plain(t: &str) -> Option<Counted> {
    let t = t.strip_prefix(['-', '+']).unwrap_or(t);
    let bytes = t.as_bytes();
    // One pass over the digits and the point (this runs for every number
    // of a table), up to the exponent's 'e' ('e' and 'E' never occur
    // inside a multi-byte character). Positions count digits only.
    let mut running = 0u64; // the digits as an integer (wrapping)
    let whole = digit_run(bytes, &mut running);
    let (n, point, end) = match bytes.get(whole) {
        Some(b'.') => {
            let fraction = digit_run(&bytes[whole + 1..], &mut running);
            (whole + fraction, whole, whole + 1 + fraction)
        }
        _ => (whole, whole, whole),
    };
    let exponent = match bytes.get(end) {
        None => 0,
        Some(b'e' | b'E') => exponent_of(&bytes[end + 1..])?,
        Some(_) => return None,
    };
    // Leading zeros: up to 19 digits `running` is exact and has the
    // others; beyond, counted on the text (rare).
    let zeros = if n <= 19 {
        match running.checked_ilog10() {
            Some(log) => n - log as usize - 1,
            None => return None, // zero
        }
    } else {
        let zeros = bytes[..end]
            .iter()
            .filter(|&&b| b != b'.')
            .take_while(|&&b| b == b'0')
            .count();
        if zeros == n {
            return None;
        }
        zeros
    };
    let (n, point, zeros) = (n as i32, point as i32, zeros as i32);
    // Significant digits, the trailing zeros taken off.
    let mut digits = n - zeros;
    let mut mantissa = running;
    if digits <= 19 {
        // `running` is exact (leading zeros add nothing to it).
        while mantissa.is_multiple_of(10) {
            mantissa /= 10;
            digits -= 1;
        }
    } else {
        // Counted again from the text (more than 19 digits: rare).
        let text = &bytes[..end];
        let trailing = text
            .iter()
            .rev()
            .filter(|&&b| b != b'.')
            .take_while(|&&b| b == b'0')
            .count() as i32;
        digits -= trailing;
        mantissa = text
            .iter()
            .filter(|b| b.is_ascii_digit())
            .skip(zeros as usize)
            .take(digits as usize)
            .fold(0u64, |m, &b| {
                m.wrapping_mul(10).wrapping_add(u64::from(b - b'0'))
            });
    }
    Some(Counted {
        digits: digits as u32,
        // An exponent near i32's limits that would leave them: not a
        // plain number here (the standard parser reads it as 0 or ∞).
        exponent: exponent.checked_add(point - zeros - 1)?,
        mantissa,
    })
}

/// The number of ASCII digits `bytes` starts with, added to `running`
/// (times ten per digit, wrapping): a word of eight bytes at a time while
/// eight digits follow (as the standard library's parser does), then byte
/// by byte.
fn digit_run(bytes: &[u8], running: &mut u64) -> usize {
    let mut i = 0;
    while let Some(Ok(word)) = bytes.get(i..i + 8).map(<[u8; 8]>::try_from) {
        let v = u64::from_le_bytes(word);
        // A byte outside b'0'..=b'9' sets a top bit in v + 0x46.. or in
        // v − 0x30.. (the standard library's test).
        let above = v.wrapping_add(0x4646_4646_4646_4646);
        let below = v.wrapping_sub(0x3030_3030_3030_3030);
        if (above | below) & 0x8080_8080_8080_8080 != 0 {
            break;
        }
        *running = running
            .wrapping_mul(100_000_000)
            .wrapping_add(eight_digits(below));
        i += 8;
    }
    while let Some(&b) = bytes.get(i) {
        let digit = b.wrapping_sub(b'0');
        if digit >= 10 {
            break;
        }
        *running = running.wrapping_mul(10).wrapping_add(u64::from(digit));
        i += 1;
    }
    i
}

/// The integer of eight decimal digits, one per byte (values 0..=9, the
/// first digit in the lowest byte): pairs, then fours, then all eight.
fn eight_digits(v: u64) -> u64 {
    let v = v.wrapping_mul(10).wrapping_add(v >> 8);
    let mask = 0x0000_00ff_0000_00ff;
    let pairs_high = (v & mask).wrapping_mul(0x000f_4240_0000_0064);
    let pairs_low = ((v >> 16) & mask).wrapping_mul(0x0000_2710_0000_0001);
    u64::from((pairs_high.wrapping_add(pairs_low) >> 32) as u32)
}

mod exact;
mod number;

pub(crate) use number::{read_counted, read_number};

/// `text` without leading and trailing whitespace: `str::trim` (Unicode
/// White_Space), returning at once when both ends are printable ASCII (all
/// ASCII whitespace is at or below b' '), as every field of a plain CSV
/// table is: this runs for every number of a measurements file.
pub(crate) fn trimmed(text: &str) -> &str {
    let plain = |b: Option<&u8>| b.is_some_and(|&b| b > b' ' && b.is_ascii());
    let bytes = text.as_bytes();
    if plain(bytes.first()) && plain(bytes.last()) {
        text
    } else {
        text.trim()
    }
}

/// The exponent after a number's `e`: what `str::parse::<i32>` gives for
/// `bytes` (an optional sign, then one or more ASCII digits, within i32),
/// without its generic machinery; `None` where it fails.
fn exponent_of(bytes: &[u8]) -> Option<i32> {
    let (negative, digits) = match bytes.split_first() {
        Some((b'-', rest)) => (true, rest),
        Some((b'+', rest)) => (false, rest),
        _ => (false, bytes),
    };
    if digits.is_empty() {
        return None;
    }
    // Accumulated on the side of the sign, so that i32::MIN is reached.
    let mut value = 0i32;
    for &b in digits {
        let d = b.wrapping_sub(b'0');
        if d >= 10 {
            return None;
        }
        let d = i32::from(d);
        value = value.checked_mul(10).and_then(|v| {
            if negative {
                v.checked_sub(d)
            } else {
                v.checked_add(d)
            }
        })?;
    }
    Some(value)
}

/// The fewest significant digits (1..=17) that reproduce `v` exactly when
/// printed in scientific notation and parsed back, with the decimal exponent
/// of that printing; `None` for zero and non-finite values. Counted on the
/// shortest text that reads back as `v` (Ryū's, on the stack; the same
/// digits as Rust's `{:e}`, which is unique in length and, being the
/// closest of the shortest, in its leading digit's place).
pub fn written_digits(v: f64) -> Option<(u32, i32)> {
    if v == 0.0 || !v.is_finite() {
        return None;
    }
    let mut buf = ryu::Buffer::new();
    counted_digits(buf.format_finite(v.abs())).map(|c| (c.digits, c.exponent))
}

#[cfg(test)]
mod tests {
    use super::super::{round_to_digits, DigitsMode};
    use super::*;

    /// The digits counted from the text are the value's: every text a
    /// writer may produce, and random values at every digit count.
    #[test]
    fn text_digits_agree_with_the_value() {
        for text in [
            "1.23e-6",
            "-4.5e-9",
            "1",
            "1.0",
            "0.00012",
            "-0.000120",
            "120",
            "1.2E+3",
            "+7.25e2",
            "9.99999999999999e0",
            "123456789012345",
            "6.935303281509727e-9",
            "0.5",
            ".5",
            "5.",
        ] {
            let v: f64 = text.parse().unwrap();
            match text_digits(text) {
                Some(d) => assert_eq!(Some(d), written_digits(v), "{text}"),
                None => assert!(text.len() > 16, "{text}"),
            }
        }
        assert_eq!(text_digits("0"), None);
        assert_eq!(text_digits("0.000"), None);
        assert_eq!(text_digits("1e5x"), None);
        let mut x = 0.123_456_789_f64;
        for d in 1..=17u32 {
            for scale in [1e-12, 1e-3, 1.0, 7e5] {
                let v = round_to_digits(x * scale, d, DigitsMode::Round);
                let text = format!("{:.*e}", (d - 1) as usize, v);
                let parsed: f64 = text.parse().unwrap();
                if let Some(t) = text_digits(&text) {
                    assert_eq!(Some(t), written_digits(parsed), "{text}");
                }
            }
            x = x * 7.3 % 1.0 + 0.1;
        }
        assert_eq!(written_digits(1.23e-6), Some((3, -6)));
        assert_eq!(written_digits(-4.5e-9), Some((2, -9)));
        assert_eq!(written_digits(1.0), Some((1, 0)));
        assert_eq!(written_digits(0.0), None);
    }

    /// The digits counted on Ryū's text are those of Rust's own shortest
    /// `{:e}` printing, at every magnitude and digit count.
    #[test]
    fn written_digits_are_those_of_the_shortest_printing() {
        let std_digits = |v: f64| {
            let text = format!("{:e}", v.abs());
            let (mantissa, exponent) = text.split_once('e').unwrap();
            let digits = mantissa.bytes().filter(u8::is_ascii_digit).count() as u32;
            (digits, exponent.parse::<i32>().unwrap())
        };
        let mut x = 0.123_456_789_012_345_67_f64;
        for k in 0..20_000 {
            let scale = 10f64.powi(k % 600 - 300);
            for v in [
                x * scale,
                -x * scale,
                round_to_digits(x * scale, 1 + k as u32 % 17, DigitsMode::Round),
            ] {
                if v != 0.0 && v.is_finite() {
                    assert_eq!(written_digits(v), Some(std_digits(v)), "{v:e}");
                }
            }
            x = (x * 7.389_056_098_930_65 + 0.377_123_456) % 1.0 + 1e-3;
        }
        for v in [
            1.0,
            9.999_999_999_999_999,
            1e16,
            123.0,
            5e-324,
            f64::MAX,
            0.1 + 0.2,
        ] {
            assert_eq!(written_digits(v), Some(std_digits(v)), "{v:e}");
        }
    }

    #[test]
    fn exponents_and_trimming_are_those_of_the_standard_library() {
        for text in [
            "",
            "+",
            "-",
            "0",
            "-0",
            "+0",
            "7",
            "-9",
            "+12",
            "007",
            "-300",
            "2147483647",
            "2147483648",
            "-2147483648",
            "-2147483649",
            "99999999999",
            "1x",
            "+-1",
            "--1",
            " 1",
            "1 ",
            "١",
            "1.5",
            "e5",
        ] {
            assert_eq!(
                exponent_of(text.as_bytes()),
                text.parse::<i32>().ok(),
                "{text:?}"
            );
        }
        for text in [
            "",
            " ",
            "1",
            " 1",
            "1 ",
            "\t1.5\r",
            "\u{b}2\u{b}",
            "\u{a0}3",
            "4\u{2003}",
            "a b",
            "\u{85}",
            "x",
            "\u{1c}5",
        ] {
            assert_eq!(trimmed(text), text.trim(), "{text:?}");
        }
    }

    /// The digits counted from a text of any length are those of its value,
    /// at every magnitude: shortest texts of 16 and 17 digits, longer
    /// texts of the same values, their neighbours one unit of the last
    /// digit away, and decimals of up to 19 digits at and around the
    /// rounding limits of large integers (exact midpoints: ties).
    #[test]
    fn digits_from_long_texts_are_those_of_the_value() {
        let check = |text: &str| {
            let v: f64 = text.parse().unwrap();
            assert_eq!(digits_of_text(text, v), written_digits(v), "{text}");
        };
        let mut x = 0.123_456_789_012_345_67_f64;
        let mut fast = 0;
        for k in 0..40_000 {
            let scale = 10f64.powi(k % 80 - 40);
            let v = x * scale;
            let shortest = format!("{v:e}");
            check(&shortest);
            if counted_digits(&shortest).is_some_and(|c| c.is_shortest_of(v)) {
                fast += 1;
            }
            for d in 15..=20usize {
                let long = format!("{:.*e}", d - 1, v);
                check(&long);
                let c = counted_digits(&long).unwrap();
                if c.digits <= 19 {
                    // One unit of the last digit either way.
                    for m in [c.mantissa - 1, c.mantissa + 1] {
                        let text = format!("{m}e{}", c.exponent - c.digits as i32 + 1);
                        check(&text);
                    }
                }
            }
            x = (x * 7.389_056_098_930_65 + 0.377_123_456) % 1.0 + 1e-3;
        }
        // Most shortest texts are decided without the value's printing.
        assert!(fast > 22_000, "{fast}");
        // Large integers: their rounding limits are integers of ≤ 19 digits.
        let mut n = 0x0012_3456_789a_bcdfu64;
        for _ in 0..20_000 {
            for shift in [1u32, 2, 5, 9] {
                let v = ((n << shift) as f64).max(1.0);
                let ulp = (v.to_bits() >> 52).saturating_sub(1075).min(60);
                let base = v as u64;
                for delta in [-3i64, -2, -1, 0, 1, 2, 3] {
                    for half in [0u64, 1u64 << ulp.saturating_sub(1)] {
                        let m = (base as i128 + delta as i128 + half as i128) as u64;
                        check(&m.to_string());
                        check(&format!("{m}0"));
                    }
                }
            }
            n = n.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1) >> 11;
        }
        for text in [
            "1.0000000000000001",
            "0.30000000000000004",
            "0.3000000000000000444",
            "9.9999999999999999e-1",
            "9007199254740993",
            "9007199254740995",
            "18014398509481986",
            "4503599627370496.5",
            "1.7976931348623157e308",
            "2.2250738585072014e-308",
            "4.9406564584124654e-324",
            "123456789012345678901234",
            "18446744073709551616",
            "0.000018446744073709551616",
            "1e-9",
            "5.000000000000000e-9",
        ] {
            check(text);
        }
    }

    /// The digits counted from any text are its value's: random texts
    /// over the characters of a number (most of them malformed: no count),
    /// long digit strings (the word-at-a-time scan, more than 19 digits),
    /// exact midpoints between doubles, and hostile fields.
    #[test]
    fn digits_of_random_texts_are_those_of_their_value() {
        let same = |text: &str| {
            if let Ok(v) = text.parse::<f64>() {
                if v != 0.0 && v.is_finite() {
                    assert_eq!(digits_of_text(text, v), written_digits(v), "{text:?}");
                    if let Some(d) = text_digits(text) {
                        assert_eq!(Some(d), written_digits(v), "{text:?}");
                    }
                }
            } else if text.trim() == text {
                // What the parser refuses is not counted as a plain decimal
                // (whitespace aside: the count trims it, the parser not).
                assert_eq!(counted_digits(text), None, "{text:?}");
            }
        };
        let mut state = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            state
        };
        let alphabet = b"0123456789.eE+-";
        for _ in 0..200_000 {
            let len = next() % 24;
            let text: String = (0..len)
                .map(|_| char::from(alphabet[(next() % alphabet.len() as u64) as usize]))
                .collect();
            same(&text);
        }
        let mut n = 0x0020_0000_0000_0001u64;
        for _ in 0..20_000 {
            for m in [n, n + 1, n + 2, n << 1 | 1, (n << 3) + 4, (n << 3) + 3] {
                same(&m.to_string());
                same(&format!("{m}e-30"));
                same(&format!("0.000{m}"));
                same(&format!("{m}.{m}e10"));
            }
            n = (n.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1) >> 11) | (1 << 53);
        }
        for text in [
            "",
            ".",
            "-",
            "+",
            "e5",
            ".e5",
            "1e",
            "1e+",
            "1.2.3",
            "--1",
            "+-1",
            "0x10",
            "1_000",
            " 1",
            "1 ",
            "\u{feff}1",
            "1\r",
            "inf",
            "NaN",
            "1e308",
            "5e-324",
            "1e-400",
            "1e99999999999",
            "0",
            "-0",
            "0.000",
            "5.",
            ".5",
            "5.e3",
            "+.5e-3",
            "00000000000000000000001",
            "12345678901234567890",
            "18446744073709551616",
            "0.00000000018446744073709551616",
            "1000000000000000000000000000000000000000001",
            "0.30000000000000004",
            "12345678.12345678e-9",
            "1234567812345678",
        ] {
            same(text);
        }
    }
}
