//! AD7606-class 8-channel simultaneous-sampling ADC on SPI (serial
//! interface, DOUTA only), with its CONVST and BUSY pins, written against the
//! embedded-hal 1.0 traits.
//!
//! One conversion: a rising CONVST edge samples all eight inputs at once;
//! BUSY goes high for the conversion (≈ 4 µs) and falls when the results are
//! ready; then eight 16-bit two's-complement words, channel 1 first, are
//! clocked out MSB first in one SPI transaction (CS framed by the
//! [`SpiDevice`]).

use embedded_hal::digital::{InputPin, OutputPin};
use embedded_hal::spi::SpiDevice;

/// Channels of one AD7606.
pub const ADC_CHANNELS: usize = 8;

/// The analog input range, set by the RANGE pin.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Range {
    /// ±5 V full scale.
    PlusMinus5V,
    /// ±10 V full scale.
    PlusMinus10V,
}

impl Range {
    /// Volts per code [V]: full scale / 32768.
    pub const fn volts_per_code(self) -> f32 {
        match self {
            Range::PlusMinus5V => 5.0 / 32768.0,
            Range::PlusMinus10V => 10.0 / 32768.0,
        }
    }
}

/// What went wrong talking to the ADC.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Error<S, P> {
    /// The SPI transfer failed.
    Spi(S),
    /// A CONVST or BUSY pin operation failed.
    Pin(P),
    /// BUSY stayed high for more than the allowed polls (no conversion
    /// result: ADC unpowered, in reset, or BUSY not connected).
    BusyTimeout,
}

/// An AD7606 on `spi` with its CONVST output and BUSY input.
#[derive(Debug)]
pub struct Ad7606<SPI, CONVST, BUSY> {
    spi: SPI,
    convst: CONVST,
    busy: BUSY,
    range: Range,
    /// Most BUSY polls before [`Error::BusyTimeout`].
    max_busy_polls: u32,
}

impl<SPI, CONVST, BUSY, P> Ad7606<SPI, CONVST, BUSY>
where
    SPI: SpiDevice,
    CONVST: OutputPin<Error = P>,
    BUSY: InputPin<Error = P>,
{
    /// Takes the bus and pins; drives CONVST low (idle). `max_busy_polls`
    /// bounds the wait for BUSY to fall (a few hundred at 168 MHz cover the
    /// 4.15 µs conversion of the AD7606 with margin).
    pub fn new(
        spi: SPI,
        mut convst: CONVST,
        busy: BUSY,
        range: Range,
        max_busy_polls: u32,
    ) -> Result<Self, Error<SPI::Error, P>> {
        convst.set_low().map_err(Error::Pin)?;
        Ok(Self {
            spi,
            convst,
            busy,
            range,
            max_busy_polls,
        })
    }

    /// The configured input range.
    pub fn range(&self) -> Range {
        self.range
    }

    /// Starts a conversion: a rising edge on CONVST, left high until
    /// [`Ad7606::read`] (the AD7606 needs CONVST high for ≥ 25 ns and
    /// samples on the edge).
    pub fn start(&mut self) -> Result<(), Error<SPI::Error, P>> {
        self.convst.set_low().map_err(Error::Pin)?;
        self.convst.set_high().map_err(Error::Pin)
    }

    /// Whether the conversion is still running (BUSY high).
    pub fn is_busy(&mut self) -> Result<bool, Error<SPI::Error, P>> {
        self.busy.is_high().map_err(Error::Pin)
    }

    /// Reads the eight results of a finished conversion as codes and
    /// returns CONVST low.
    pub fn read(&mut self) -> Result<[i16; ADC_CHANNELS], Error<SPI::Error, P>> {
        let mut raw = [0u8; 2 * ADC_CHANNELS];
        self.spi.read(&mut raw).map_err(Error::Spi)?;
        self.convst.set_low().map_err(Error::Pin)?;
        let mut codes = [0i16; ADC_CHANNELS];
        for (c, pair) in codes.iter_mut().zip(raw.chunks_exact(2)) {
            *c = i16::from_be_bytes([pair[0], pair[1]]);
        }
        Ok(codes)
    }

    /// One complete conversion: CONVST edge, wait (bounded) for BUSY to fall,
    /// read the eight codes.
    pub fn convert(&mut self) -> Result<[i16; ADC_CHANNELS], Error<SPI::Error, P>> {
        self.start()?;
        let mut polls = 0;
        while self.is_busy()? {
            polls += 1;
            if polls >= self.max_busy_polls {
                // Leave CONVST low so that the next start makes an edge.
                self.convst.set_low().map_err(Error::Pin)?;
                return Err(Error::BusyTimeout);
            }
        }
        self.read()
    }

    /// Codes to volts [V] for this range.
    pub fn to_volts(&self, codes: &[i16; ADC_CHANNELS]) -> [f32; ADC_CHANNELS] {
        let step = self.range.volts_per_code();
        codes.map(|c| f32::from(c) * step)
    }

    /// Gives back the bus and pins.
    pub fn release(self) -> (SPI, CONVST, BUSY) {
        (self.spi, self.convst, self.busy)
    }
}

#[cfg(test)]
mod tests {
    extern crate std;
    use super::*;
    use embedded_hal_mock::eh1::digital::{
        Mock as PinMock, State as PinState, Transaction as PinTransaction,
    };
    use embedded_hal_mock::eh1::spi::{Mock as SpiMock, Transaction as SpiTransaction};
    use std::vec::Vec;

    /// The 16 bytes an AD7606 shifts out for these codes (MSB first).
    fn wire(codes: [i16; 8]) -> Vec<u8> {
        codes.iter().flat_map(|c| c.to_be_bytes()).collect()
    }

    #[test]
    fn one_conversion_pulses_convst_waits_for_busy_and_reads_eight_words() {
        let codes = [0, 1, -1, 32767, -32768, 12345, -12345, 256];
        let mut spi = SpiMock::new(&[
            SpiTransaction::transaction_start(),
            SpiTransaction::read_vec(wire(codes)),
            SpiTransaction::transaction_end(),
        ]);
        let mut convst = PinMock::new(&[
            PinTransaction::set(PinState::Low), // new(): idle low
            PinTransaction::set(PinState::Low), // start(): edge from low
            PinTransaction::set(PinState::High),
            PinTransaction::set(PinState::Low), // after the read
        ]);
        // BUSY high twice (converting), then low.
        let mut busy = PinMock::new(&[
            PinTransaction::get(PinState::High),
            PinTransaction::get(PinState::High),
            PinTransaction::get(PinState::Low),
        ]);
        let mut adc = Ad7606::new(
            spi.clone(),
            convst.clone(),
            busy.clone(),
            Range::PlusMinus10V,
            100,
        )
        .unwrap();
        assert_eq!(adc.convert().unwrap(), codes);
        spi.done();
        convst.done();
        busy.done();
    }

    #[test]
    fn busy_stuck_high_is_a_timeout_not_a_hang() {
        let mut spi = SpiMock::<u8>::new(&[]);
        let mut convst = PinMock::new(&[
            PinTransaction::set(PinState::Low),
            PinTransaction::set(PinState::Low),
            PinTransaction::set(PinState::High),
            PinTransaction::set(PinState::Low), // left low for the next edge
        ]);
        let mut busy = PinMock::new(&[
            PinTransaction::get(PinState::High),
            PinTransaction::get(PinState::High),
            PinTransaction::get(PinState::High),
        ]);
        let mut adc = Ad7606::new(
            spi.clone(),
            convst.clone(),
            busy.clone(),
            Range::PlusMinus5V,
            3,
        )
        .unwrap();
        assert_eq!(adc.convert(), Err(Error::BusyTimeout));
        spi.done();
        convst.done();
        busy.done();
    }

    #[test]
    fn codes_scale_to_the_selected_range() {
        let spi = SpiMock::<u8>::new(&[]);
        let convst = PinMock::new(&[PinTransaction::set(PinState::Low)]);
        let busy = PinMock::new(&[]);
        let adc = Ad7606::new(spi, convst, busy, Range::PlusMinus5V, 1).unwrap();
        let v = adc.to_volts(&[16384, -32768, 0, 1, 0, 0, 0, 0]);
        assert_eq!(v[0], 2.5);
        assert_eq!(v[1], -5.0);
        assert_eq!(v[2], 0.0);
        assert_eq!(v[3], 5.0 / 32768.0);
        assert_eq!(Range::PlusMinus10V.volts_per_code(), 10.0 / 32768.0);
        let (mut spi, mut convst, mut busy) = adc.release();
        spi.done();
        convst.done();
        busy.done();
    }
}
