//! The double nearest to a decimal w·10^q (w < 10^19), as `str::parse`
//! rounds it (to nearest, ties to even), by the Eisel–Lemire algorithm:
//! w times a 128-bit truncation of 5^q, decided from the product's top
//! bits unless it lies too near a halfway point (then `None`, and the
//! caller parses the text with the standard library, which decides those
//! exactly). The standard library's parser runs the same algorithm after
//! its own scan of the digits; here it runs on the integer that the digit
//! count already scanned (D. Lemire, "Number parsing at a gigabyte per
//! second", Software: Practice and Experience 51(8), 2021, sections 5-6).

/// Smallest and largest q of [`POWERS_OF_FIVE`]: below, w·10^q < 2^−1075
/// rounds to 0 for every w < 10^19; above, w·10^q > 1e308·(1 + 2^−53)
/// rounds to infinity.
const SMALLEST_Q: i32 = -342;
const LARGEST_Q: i32 = 308;

/// 64-bit words of the integers the table is built with: 2^1728 needs 1729
/// bits.
const LIMBS: usize = 28;

/// The power of two whose quotients by 5^k give the negative-q entries:
/// at least the largest b of [`powers_of_five`] (2·795 + 128 = 1718).
const TOP: u32 = 1728;

/// An unsigned integer of [`LIMBS`] words, least significant first.
type Wide = [u64; LIMBS];

/// 5^q for q in `SMALLEST_Q..=LARGEST_Q` as the 128 bits (high word,
/// low word) the algorithm multiplies by: for q ≥ 0 the top 128 bits of
/// 5^q, truncated; for q < 0 the top 128 bits of ⌊2^b / 5^−q⌋ + 1 with
/// b = z + 127 (q ≥ −27) or 2z + 128 (z = the bit length of 5^−q),
/// truncated: the table of the algorithm's reference implementation
/// (and of the standard library), computed here when compiling.
static POWERS_OF_FIVE: [(u64, u64); (LARGEST_Q - SMALLEST_Q + 1) as usize] = powers_of_five();

/// Builds [`POWERS_OF_FIVE`]: 5^k by repeated multiplication by 5, and
/// ⌊2^TOP / 5^k⌋ by repeated exact division by 5 (⌊⌊x⌋ / 5⌋ = ⌊x / 5⌋),
/// from which ⌊2^b / 5^k⌋ is a right shift.
const fn powers_of_five() -> [(u64, u64); (LARGEST_Q - SMALLEST_Q + 1) as usize] {
    let mut table = [(0u64, 0u64); (LARGEST_Q - SMALLEST_Q + 1) as usize];
    let mut five: Wide = [0; LIMBS];
    five[0] = 1;
    let mut quotient: Wide = [0; LIMBS];
    quotient[(TOP / 64) as usize] = 1 << (TOP % 64);
    let mut k = 1;
    while k <= -SMALLEST_Q {
        times_five(&mut five);
        over_five(&mut quotient);
        let z = bit_length(&five);
        let b = if k <= 27 { z + 127 } else { 2 * z + 128 };
        let mut c = shifted_right(&quotient, TOP - b);
        plus_one(&mut c);
        table[(-k - SMALLEST_Q) as usize] = top_128(&c);
        k += 1;
    }
    let mut five: Wide = [0; LIMBS];
    five[0] = 1;
    let mut q = 0;
    while q <= LARGEST_Q {
        if q > 0 {
            times_five(&mut five);
        }
        table[(q - SMALLEST_Q) as usize] = top_128(&five);
        q += 1;
    }
    table
}

/// x ← 5x (x stays below 2^(64·LIMBS)).
const fn times_five(x: &mut Wide) {
    let mut carry = 0u128;
    let mut i = 0;
    while i < LIMBS {
        let v = x[i] as u128 * 5 + carry;
        x[i] = v as u64;
        carry = v >> 64;
        i += 1;
    }
}

/// x ← ⌊x / 5⌋.
const fn over_five(x: &mut Wide) {
    let mut rest = 0u128;
    let mut i = LIMBS;
    while i > 0 {
        i -= 1;
        let v = (rest << 64) | x[i] as u128;
        x[i] = (v / 5) as u64;
        rest = v % 5;
    }
}

/// x + 1 (x below 2^(64·LIMBS) − 1).
const fn plus_one(x: &mut Wide) {
    let mut i = 0;
    while i < LIMBS {
        let (v, carry) = x[i].overflowing_add(1);
        x[i] = v;
        if !carry {
            return;
        }
        i += 1;
    }
}

/// The number of bits of x (0 for 0).
const fn bit_length(x: &Wide) -> u32 {
    let mut i = LIMBS;
    while i > 0 {
        i -= 1;
        if x[i] != 0 {
            return i as u32 * 64 + 64 - x[i].leading_zeros();
        }
    }
    0
}

/// ⌊x / 2^s⌋.
const fn shifted_right(x: &Wide, s: u32) -> Wide {
    let mut out: Wide = [0; LIMBS];
    let mut i = 0;
    while i < LIMBS {
        out[i] = bits_at(x, (i * 64) as i64 + s as i64);
        i += 1;
    }
    out
}

/// The 64 bits of x from bit `p` up (bits below 0 are 0).
const fn bits_at(x: &Wide, p: i64) -> u64 {
    if p <= -64 {
        return 0;
    }
    if p < 0 {
        return x[0] << (-p);
    }
    let (i, s) = ((p / 64) as usize, (p % 64) as u32);
    let low = if i < LIMBS { x[i] >> s } else { 0 };
    let high = if s > 0 && i + 1 < LIMBS {
        x[i + 1] << (64 - s)
    } else {
        0
    };
    low | high
}

/// The 128 bits of non-zero x from its leading bit down, as (high word,
/// low word): truncated when x is longer, shifted left when shorter.
const fn top_128(x: &Wide) -> (u64, u64) {
    let from = bit_length(x) as i64 - 128;
    (bits_at(x, from + 64), bits_at(x, from))
}

/// The double nearest to w·10^q, rounded as the standard library rounds
/// (to nearest, ties to even; 0 below the smallest subnormal's half,
/// infinity above the largest finite), for w < 10^19 (more digits are the
/// caller's: they are not exact in w); `None` when the 128-bit product
/// cannot decide (within one unit of its low word of a halfway point).
pub(super) fn nearest(w: u64, q: i64) -> Option<f64> {
    if w == 0 || q < i64::from(SMALLEST_Q) {
        return Some(0.0);
    }
    if q > i64::from(LARGEST_Q) {
        return Some(f64::INFINITY);
    }
    let q = q as i32;
    // w normalised: its top bit set.
    let lz = w.leading_zeros();
    let w = w << lz;
    let (low, high) = product(q, w);
    // A low word of all ones may be an approximation that a carry from
    // below would change; exact (so decidable) only for q in −27..=55.
    if low == u64::MAX && !(-27..=55).contains(&q) {
        return None;
    }
    // 54 bits: the 53 of the significand and one to round with.
    let upper = (high >> 63) as i32;
    let shift = upper + 64 - 52 - 3;
    let mut m = high >> shift;
    let mut biased = binary_exponent(q) + upper - lz as i32 + 1022 + 1;
    if biased <= 0 {
        // Subnormal (or 0): shifted to the subnormals' exponent and
        // rounded; a rounding up to 2^52 is the smallest normal.
        if -biased + 1 >= 64 {
            return Some(0.0);
        }
        m >>= -biased + 1;
        m += m & 1;
        m >>= 1;
        biased = i32::from(m >= 1 << 52);
        return Some(f64::from_bits(m | (biased as u64) << 52));
    }
    // Exactly halfway (possible only where 5^q is exact in 64 bits and w
    // ends in the dropped bits' zeros): round to even, down.
    if low <= 1 && (-4..=23).contains(&q) && m & 3 == 1 && (m << shift) == high {
        m &= !1;
    }
    m += m & 1;
    m >>= 1;
    if m >= 2 << 52 {
        // The rounding carried into a new binade.
        m = 1 << 52;
        biased += 1;
    }
    if biased >= 0x7ff {
        return Some(f64::INFINITY);
    }
    Some(f64::from_bits((m & !(1 << 52)) | (biased as u64) << 52))
}

/// ⌊log2(10^q)⌋ + 63 for |q| ≤ 342: 217706/2^16 approximates log2(10)
/// closely enough over that range.
fn binary_exponent(q: i32) -> i32 {
    (q.wrapping_mul(152_170 + 65_536) >> 16) + 63
}

/// The top 128 bits (low word, high word) of normalised w times 5^q's
/// table entry, the second word of the entry added in when the first
/// product's bits below the 55 kept ones are all ones (a carry from below
/// may reach them).
fn product(q: i32, w: u64) -> (u64, u64) {
    let mask = u64::MAX >> 55;
    let (high5, low5) = POWERS_OF_FIVE[(q - SMALLEST_Q) as usize];
    let first = u128::from(w) * u128::from(high5);
    let (mut low, mut high) = (first as u64, (first >> 64) as u64);
    if high & mask == mask {
        let second = ((u128::from(w) * u128::from(low5)) >> 64) as u64;
        low = low.wrapping_add(second);
        if second > low {
            high += 1;
        }
    }
    (low, high)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Entries of the table as the reference implementation has them.
    #[test]
    fn the_table_is_the_reference_one() {
        let at = |q: i32| POWERS_OF_FIVE[(q - SMALLEST_Q) as usize];
        assert_eq!(at(-342), (0xeef4_53d6_923b_d65a, 0x113f_aa29_06a1_3b3f));
        assert_eq!(at(-341), (0x9558_b466_1b65_65f8, 0x4ac7_ca59_a424_c507));
        assert_eq!(at(-1), (0xcccc_cccc_cccc_cccc, 0xcccc_cccc_cccc_cccd));
        assert_eq!(at(0), (0x8000_0000_0000_0000, 0));
        assert_eq!(at(27), (0xcecb_8f27_f420_0f3a, 0));
        assert_eq!(at(55), (0xd0cf_4b50_cfe2_0765, 0xfff4_b4e3_f741_cf6d));
        assert_eq!(at(308), (0x8e67_9c2f_5e44_ff8f, 0x570f_09ea_a7ea_7648));
        // Every entry has its top bit set; the exact ones are 5^q shifted.
        for q in SMALLEST_Q..=LARGEST_Q {
            assert!(at(q).0 >> 63 == 1, "{q}");
        }
        for q in 0..=27u32 {
            let five = 5u128.pow(q);
            let v = five << five.leading_zeros();
            assert_eq!(at(q as i32), ((v >> 64) as u64, v as u64), "{q}");
        }
    }

    /// `nearest` gives `str::parse`'s double wherever it decides, on
    /// random integers at every decimal exponent, at the edges of the
    /// subnormals and of the largest double, and on exact halfway points.
    #[test]
    fn nearest_is_the_standard_parse() {
        let parsed = |w: u64, q: i64| format!("{w}e{q}").parse::<f64>().unwrap();
        let mut undecided = 0;
        let mut check = |w: u64, q: i64| match nearest(w, q) {
            Some(v) => assert_eq!(v.to_bits(), parsed(w, q).to_bits(), "{w}e{q}"),
            None => undecided += 1,
        };
        let mut x = 0x2545_f491_4f6c_dd1du64;
        let mut next = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x
        };
        for q in -360..=320i64 {
            for _ in 0..300 {
                let r = next();
                let digits = 1 + (r % 19) as u32;
                let w = next() % 10u64.pow(digits);
                check(w, q);
            }
        }
        // Halfway points between neighbouring doubles m·2^e and (m+1)·2^e
        // (m of 53 bits), exact in decimal: (2m+1)·2^(e−1) for e ≥ 1, and
        // (2m+1)·5^k·10^−k for e = 1 − k; with their neighbours ±1.
        for _ in 0..20_000 {
            let m = (next() >> 11) | 1 << 52;
            let e = 1 + (next() % 10) as u32;
            let half = (2 * m + 1) << (e - 1);
            for w in [half - 1, half, half + 1] {
                check(w, 0);
            }
            let k = 1 + (next() % 4) as u32;
            let half = (2 * m + 1) * 5u64.pow(k);
            for w in [half - 1, half, half + 1] {
                check(w, -i64::from(k));
            }
        }
        for (w, q) in [
            (49_406_564_584_124_654, -340), // the smallest subnormal
            (24_703_282_292_062_327, -340), // its half (rounds to 0)
            (24_703_282_292_062_328, -340),
            (22_250_738_585_072_014, -324), // the smallest normal
            (22_250_738_585_072_011, -324),
            (17_976_931_348_623_157, 292), // the largest double
            (17_976_931_348_623_158, 292),
            (17_976_931_348_623_159, 292), // rounds to infinity
            (9_999_999_999_999_999_999, 288),
            (9_999_999_999_999_999_999, -343),
            (1, -343),
            (1, 309),
            (0, 5),
            (9_007_199_254_740_993, 0), // 2^53 + 1: a tie, to even
            (9_007_199_254_740_995, 0),
        ] {
            check(w, q);
        }
        assert!(undecided < 50, "{undecided}");
    }
}
