//! ADC codes to volts, with the saturation count per channel.
//!
//! The AD7606 shifts out 16-bit two's-complement codes; read as 16-bit SPI
//! frames by the DMA they land in memory as `i16` already (no byte swap).
//! One code is full scale / 32768 ([`Range::volts_per_code`]); a code at
//! either end of the scale is counted as saturated.

use crate::ad7606::Range;
use crate::source::CHANNELS;

/// The codes of one sample vector as volts [V], counting saturated codes
/// into `saturated` (per ADC channel).
pub fn to_volts(
    range: Range,
    codes: &[i16; CHANNELS],
    saturated: &mut [u32; CHANNELS],
) -> [f32; CHANNELS] {
    let step = range.volts_per_code();
    for (count, &c) in saturated.iter_mut().zip(codes) {
        if c == i16::MAX || c == i16::MIN {
            *count = count.saturating_add(1);
        }
    }
    codes.map(|c| f32::from(c) * step)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scales_and_counts_the_ends_of_the_scale() {
        let mut sat = [0; CHANNELS];
        let v = to_volts(
            Range::PlusMinus5V,
            &[16384, -32768, 0, 1, 32767, -1, 0, 0],
            &mut sat,
        );
        assert_eq!(v[0], 2.5);
        assert_eq!(v[1], -5.0);
        assert_eq!(v[3], 5.0 / 32768.0);
        assert_eq!(v[4], 32767.0 * 5.0 / 32768.0);
        assert_eq!(sat, [0, 1, 0, 0, 1, 0, 0, 0]);
    }
}
