//! The number a table's text reads as, from the one scan that counts its
//! digits: the counted integer and exponent made into the nearest double
//! ([`super::super::nearest`], the standard library's own algorithm),
//! the standard parser only where that cannot decide (more than 19
//! digits, a near-halfway product) or the text is not a plain decimal
//! (zero, `inf`, `nan`, an exponent beyond i32, anything refused).

use super::super::nearest::nearest;
use super::{counted_plain, digits_of, Counted};

/// `text.parse::<f64>().ok()`, bit for bit (whitespace is refused as the
/// standard parser refuses it).
pub(crate) fn read_number(text: &str) -> Option<f64> {
    match counted_plain(text).and_then(|c| value_of(&c, text)) {
        Some(v) => Some(v),
        None => text.parse().ok(),
    }
}

/// The value of `text` ([`read_number`]) and its digits as
/// [`super::digits_of_text`] counts them for that value, from one scan.
pub(crate) fn read_counted(text: &str) -> Option<(f64, Option<(u32, i32)>)> {
    let counted = counted_plain(text);
    let value = match counted.as_ref().and_then(|c| value_of(c, text)) {
        Some(v) => v,
        None => text.parse().ok()?,
    };
    // Either way `value` is the text's nearest double.
    Some((value, digits_of(counted, value, true)))
}

/// The signed value of a plain decimal text counted as `c`, when its
/// digits are exact in the counted integer (at most 19) and the nearest
/// double is decided.
fn value_of(c: &Counted, text: &str) -> Option<f64> {
    if c.digits > 19 {
        return None;
    }
    let v = nearest(c.mantissa, i64::from(c.exponent) - i64::from(c.digits) + 1)?;
    Some(if text.starts_with('-') { -v } else { v })
}

#[cfg(test)]
mod tests {
    use super::super::digits_of_text;
    use super::*;

    /// What the table read before: the standard parser, then the digits of
    /// the text for that value.
    fn before(text: &str) -> Option<(u64, Option<(u32, i32)>)> {
        let v: f64 = text.parse().ok()?;
        Some((v.to_bits(), digits_of_text(text, v)))
    }

    fn check(text: &str) {
        let counted = read_counted(text).map(|(v, d)| (v.to_bits(), d));
        assert_eq!(counted, before(text), "{text:?}");
        assert_eq!(
            read_number(text).map(f64::to_bits),
            text.parse::<f64>().ok().map(f64::to_bits),
            "{text:?}"
        );
    }

    /// Edge texts: signs, points, exponents of every size, zeros, 17-20
    /// digits, subnormals, the largest double and beyond, halfway points,
    /// and every text the standard parser refuses or reads as a special
    /// value.
    #[test]
    fn edge_texts_read_as_the_standard_parser_reads_them() {
        for text in [
            "",
            " ",
            "+",
            "-",
            ".",
            "-.",
            "+.e1",
            "e5",
            "1e",
            "1e+",
            "1e-",
            "1.2.3",
            "0x10",
            "1_000",
            " 1",
            "1 ",
            "\t1",
            "1,5",
            "١",
            "inf",
            "-inf",
            "+infinity",
            "Infinity",
            "nan",
            "NaN",
            "-nan",
            "0",
            "-0",
            "+0",
            "0.0",
            "-0.000e-5",
            "0e999999999999",
            "1",
            "-1",
            "+1",
            "1.",
            ".5",
            "-.5",
            "5.e3",
            "1e5",
            "1E5",
            "1e+5",
            "1e-5",
            "1.5E-07",
            "6.935303281509643e-9",
            "-2.4282161458489725e-9",
            "1.7752256612730702e-9",
            "12345678901234567890",
            "1234567890123456789",
            "9999999999999999999",
            "18446744073709551615",
            "18446744073709551616",
            "0.1",
            "0.30000000000000004",
            "4.9406564584124654e-324",
            "5e-324",
            "2.4703282292062327e-324",
            "2.4703282292062328e-324",
            "2e-324",
            "1e-400",
            "-1e-400",
            "2.2250738585072014e-308",
            "2.2250738585072011e-308",
            "2.225073858507201e-308",
            "1.7976931348623157e308",
            "1.7976931348623158e308",
            "1.7976931348623159e308",
            "1.8e308",
            "-1.8e308",
            "1e308",
            "1e309",
            "9007199254740993",
            "9007199254740995",
            "9007199254740992.5",
            "1e2147483647",
            "1e-2147483648",
            "10e2147483647",
            "0.001e-2147483648",
            "1e2147483648",
            "1e99999999999",
            "1e-99999999999",
            "00000000000000000000001.5",
            "1.00000000000000000000000000",
            "123456789012345678901234567890e-20",
        ] {
            check(text);
        }
        check(&"1".repeat(1000));
        check(&format!("{}1.25", "0".repeat(500)));
    }

    /// Random texts over the characters of numbers (most are refused),
    /// random plain decimals of 1-22 digits at every exponent, and the
    /// shortest and the 17-digit texts of random doubles, subnormals
    /// included.
    #[test]
    fn random_texts_read_as_the_standard_parser_reads_them() {
        let mut x = 0x9e37_79b9_7f4a_7c15u64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        let alphabet = b"0123456789.eE+-";
        for _ in 0..200_000 {
            let len = 1 + next() % 12;
            let text: String = (0..len)
                .map(|_| char::from(alphabet[(next() % alphabet.len() as u64) as usize]))
                .collect();
            check(&text);
        }
        for _ in 0..300_000 {
            let digits = 1 + next() % 22;
            let mut text: String = (0..digits)
                .map(|_| char::from(b'0' + (next() % 10) as u8))
                .collect();
            let point = (next() % (digits + 1)) as usize;
            text.insert(point, '.');
            if next() % 2 == 0 {
                text.insert(0, '-');
            }
            let exponent = (next() % 700) as i64 - 360;
            check(&format!("{text}e{exponent}"));
            check(&text);
        }
        for _ in 0..300_000 {
            let any = f64::from_bits(next() & !(1 << 63));
            let measured = (next() >> 11) as f64 * 2f64.powi(-53) * 1e-8;
            for v in [any, measured] {
                check(&format!("{v:e}"));
                check(&format!("{v:.16e}"));
                check(&format!("-{v:.20e}"));
                check(&format!("{v}"));
            }
        }
    }
}
