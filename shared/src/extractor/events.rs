//! What goes into the extractor (keyphasor edges, input errors) and what
//! comes out (phasors of a revolution, keyphasor faults).

use super::EdgeTime;
use crate::phasor::Phasor;

/// A keyphasor edge inside a block of samples, from the timer capture.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct KeyphasorEdge {
    /// Index in the block of the first sample after the edge; 0 means the
    /// edge came after the previous block's last sample.
    pub index: usize,
    /// Where in the sample interval before `index` the edge happened, [0, 1):
    /// 0 at the previous sample, → 1 at sample `index`.
    pub fraction: f32,
}

/// A bad [`KeyphasorEdge`] list; nothing of the block was processed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum InputError {
    /// Edge number `edge` points at or past the end of the block.
    EdgeIndex {
        /// Position in the edge list.
        edge: usize,
    },
    /// Edge number `edge` has a fraction outside [0, 1) or NaN.
    EdgeFraction {
        /// Position in the edge list.
        edge: usize,
    },
    /// Edge number `edge` is not after the one before it.
    EdgeOrder {
        /// Position in the edge list.
        edge: usize,
    },
}

/// 1X displacement phasors of all channels over one revolution, or the
/// average over R consecutive revolutions.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Phasors<const N: usize> {
    /// Displacement phasor of each channel [m], q(θ) = Re{Q·e^{iθ}} with θ
    /// the shaft angle, 0 at the keyphasor edge.
    pub displacement: [Phasor; N],
    /// Standard deviation of each displacement phasor's noise [m],
    /// sqrt(E|n|²) of the complex noise n (formats.md's noise columns), from
    /// the scatter between the revolutions it is made of and those just
    /// before (see [`noise`](self#noise)).
    pub noise_sd: [f32; N],
    /// Mean speed over the revolution(s): revolutions / duration [Hz].
    pub speed_hz: f32,
    /// Number of keyphasor edges received up to and including the one that
    /// closed the (last) revolution: a monotonic revolution id.
    pub revolution: u32,
    /// How many revolutions were averaged (R).
    pub revolutions: u16,
    /// When the (last) revolution closed.
    pub end: EdgeTime,
}

/// What went wrong with the keyphasor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FaultKind {
    /// No edge by (1 + tolerance) × the predicted period.
    MissingPulse,
    /// An edge before (1 − tolerance) × the predicted period, or faster than
    /// `max_speed_hz`.
    ExtraPulse,
    /// While acquiring, two consecutive periods differ by more than
    /// `max_acceleration_hz_per_s` allows.
    IrregularPulses,
    /// No edge within 1/`min_speed_hz`: keyphasor lost or machine too slow.
    Timeout,
    /// A phasor came out NaN or infinite (a non-finite sample).
    NonFinite,
}

/// A keyphasor fault; the affected revolutions were discarded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Fault {
    /// What happened.
    pub kind: FaultKind,
    /// Absolute index of the sample at which it was detected.
    pub sample: u64,
    /// Keyphasor edges received so far.
    pub edges: u32,
}

/// What the extractor reports.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Event<const N: usize> {
    /// A revolution (or R of them) completed and validated.
    Phasors(Phasors<N>),
    /// A keyphasor fault.
    Fault(Fault),
}
