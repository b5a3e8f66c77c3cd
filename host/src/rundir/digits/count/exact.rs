//! Exact decisions about a decimal text c·10^k and a double, in integer
//! arithmetic: whether the text reads as the double (the double's rounding
//! limits) and whether a shorter decimal does (the text is then not the
//! double's shortest).

use super::Counted;

/// 5^k for k in 0..32: 5^31 < 2^72.
const POW5: [u128; 32] = {
    let mut table = [1u128; 32];
    let mut k = 1;
    while k < 32 {
        table[k] = table[k - 1] * 5;
        k += 1;
    }
    table
};

/// The powers 10^k the exact comparisons below take, k in
/// `POW10_RANGE`: every product they form fits in 128 bits (a mantissa of
/// ≤ 19 digits times 5^27 < 2^63, or a rounding limit < 2^56 times 5^31 <
/// 2^72).
const POW10_RANGE: std::ops::RangeInclusive<i32> = -31..=27;

impl Counted {
    /// Whether this text (read as a positive number) is the shortest text
    /// of `value` ([`written_digits`]'s): it reads as `|value|` and no
    /// decimal of one digit fewer does. Such a decimal, when there is one,
    /// lies between the text and `value`'s rounding limits; the nearest ones
    /// on either side of the text (its mantissa without the last digit,
    /// rounded down and up) then do, as does 10^(first digit's exponent),
    /// the only shorter decimal of another first exponent that could. The
    /// shortest text of `value` then has as many digits as this one and the
    /// same first exponent (a different one would put a one-digit power of
    /// ten between them). Decided with exact integer arithmetic; `false`
    /// (the value decides) for more than 19 digits, a subnormal, infinite
    /// or zero value, or powers of ten outside [`POW10_RANGE`].
    pub(super) fn is_shortest_of(&self, value: f64) -> bool {
        let Some(limits) = RoundingLimits::of(value.abs()) else {
            return false;
        };
        let reads = self
            .limits_at(&limits, 0)
            .is_some_and(|own| own.reads(u128::from(self.mantissa)));
        reads && self.none_shorter_reads(&limits)
    }

    /// [`Counted::is_shortest_of`] for a text known to read as `value`
    /// (`value` is the text's nearest double): the same decision without
    /// testing that again.
    pub(super) fn is_shortest_of_its_value(&self, value: f64) -> bool {
        let Some(limits) = RoundingLimits::of(value.abs()) else {
            return false;
        };
        self.limits_at(&limits, 0).is_some() && self.none_shorter_reads(&limits)
    }

    /// The second half of [`Counted::is_shortest_of`], for a text known to
    /// read as the value of `limits`: no decimal of one digit fewer does
    /// (`false` outside 2..=19 digits or [`POW10_RANGE`]).
    fn none_shorter_reads(&self, limits: &RoundingLimits) -> bool {
        if !(2..=19).contains(&self.digits) {
            return false;
        }
        let Some(shorter) = self.limits_at(limits, 1) else {
            return false;
        };
        let c = u128::from(self.mantissa / 10);
        !shorter.reads(c) && !shorter.reads(c + 1)
    }

    /// `limits` for the decimals whose last digit is `more` places left of
    /// this text's (10^k: the unit of its last digit).
    fn limits_at(&self, limits: &RoundingLimits, more: i32) -> Option<DecimalLimits> {
        limits.at(self.exponent - self.digits as i32 + 1 + more)
    }
}

/// The decimals that read as a positive normal f64 v = m·2^e: those
/// strictly between its rounding limits (the midpoints to its neighbours,
/// `low`·2^`shift` and `high`·2^`shift`), and the limits themselves when m
/// is even (round half to even).
#[derive(Clone, Copy)]
struct RoundingLimits {
    low: u128,
    high: u128,
    shift: i32,
    inclusive: bool,
}

impl RoundingLimits {
    /// The limits of positive normal `v`; `None` otherwise.
    fn of(v: f64) -> Option<Self> {
        if !v.is_normal() || v < 0.0 {
            return None;
        }
        let bits = v.to_bits();
        let biased = ((bits >> 52) & 0x7ff) as i32;
        let fraction = bits & ((1 << 52) - 1);
        let m = u128::from(fraction | (1 << 52));
        // v = m·2^e = 4m·2^(e−2); the neighbour above is (m+1)·2^e, the one
        // below (m−1)·2^e, or (2m−1)·2^(e−1) when m is the binade's first
        // (v a power of two above the smallest normal).
        let e = biased - 1075;
        let low = if fraction == 0 && biased > 1 {
            4 * m - 1
        } else {
            4 * m - 2
        };
        Some(Self {
            low,
            high: 4 * m + 2,
            shift: e - 2,
            inclusive: m % 2 == 0,
        })
    }

    /// The limits for decimals c·10^k (c < 10^19); `None` when k is
    /// outside [`POW10_RANGE`] (the products would not fit).
    fn at(&self, k: i32) -> Option<DecimalLimits> {
        if !POW10_RANGE.contains(&k) {
            return None;
        }
        let five = POW5[k.unsigned_abs() as usize];
        // c·10^k = c·5^k·2^k against n·2^shift: c·5^k·2^(k−shift) against
        // n, or c·2^(k−shift) against n·5^−k.
        let (scale, low, high) = if k >= 0 {
            (five, self.low, self.high)
        } else {
            (1, self.low * five, self.high * five)
        };
        Some(DecimalLimits {
            scale,
            shift: k - self.shift,
            low,
            high,
            inclusive: self.inclusive,
        })
    }
}

/// [`RoundingLimits`] for the decimals c·10^k of one k: c reads as the
/// value when c·`scale`·2^`shift` is strictly between `low` and `high`,
/// or equal to either and `inclusive`.
struct DecimalLimits {
    scale: u128,
    shift: i32,
    low: u128,
    high: u128,
    inclusive: bool,
}

impl DecimalLimits {
    /// Whether c·10^k reads as the value.
    #[inline]
    fn reads(&self, c: u128) -> bool {
        use std::cmp::Ordering::{Equal, Greater, Less};
        let a = if self.scale == 1 { c } else { c * self.scale };
        let above_low = match compare_shifted(a, self.shift, self.low) {
            Greater => true,
            Equal => self.inclusive,
            Less => false,
        };
        above_low
            && match compare_shifted(a, self.shift, self.high) {
                Less => true,
                Equal => self.inclusive,
                Greater => false,
            }
    }
}

/// a·2^s compared with b, exactly (s of either sign).
#[inline(always)]
fn compare_shifted(a: u128, s: i32, b: u128) -> std::cmp::Ordering {
    if s < 0 {
        shifted_above(b, s.unsigned_abs(), a).reverse()
    } else {
        shifted_above(a, s.unsigned_abs(), b)
    }
}

/// a·2^s compared with b, exactly.
#[inline(always)]
fn shifted_above(a: u128, s: u32, b: u128) -> std::cmp::Ordering {
    if a == 0 {
        return 0.cmp(&b);
    }
    if s > a.leading_zeros() {
        // a·2^s ≥ 2^128 > b.
        return std::cmp::Ordering::Greater;
    }
    (a << s).cmp(&b)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The exact comparison of a·2^s with b, against floating point on
    /// small numbers and at the edges of the 128 bits.
    #[test]
    fn shifted_comparisons_are_exact() {
        use std::cmp::Ordering::{Equal, Greater, Less};
        assert_eq!(compare_shifted(3, 1, 6), Equal);
        assert_eq!(compare_shifted(3, 1, 7), Less);
        assert_eq!(compare_shifted(6, -1, 3), Equal);
        assert_eq!(compare_shifted(7, -1, 3), Greater);
        assert_eq!(compare_shifted(0, 500, 0), Equal);
        assert_eq!(compare_shifted(0, 500, 1), Less);
        assert_eq!(compare_shifted(1, 127, u128::MAX), Less);
        assert_eq!(compare_shifted(1, 128, u128::MAX), Greater);
        assert_eq!(compare_shifted(u128::MAX, -200, 0), Greater);
        assert_eq!(compare_shifted(u128::MAX, -200, 1), Less);
    }
}
