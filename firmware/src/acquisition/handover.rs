//! Hand-over of the ADC's DMA double buffer from the DMA (producer) to the
//! extractor task (consumer), with every lost buffer counted and no torn
//! buffer ever delivered.
//!
//! The SPI receive DMA runs in double-buffer mode: it fills one half while
//! the consumer reads the other, and switches halves by itself when one is
//! full, whether the consumer is done or not. The transfer-complete
//! interrupt counts finished halves ([`HalfCompletions::complete`]). When
//! `n` halves are complete, half `n − 1` is the only intact one: the DMA is
//! writing half `n` into the memory of half `n − 2`. The consumer therefore
//! takes only the newest complete half, counts the ones it skipped as lost,
//! and after copying checks that no further half completed meanwhile (the
//! DMA would then be overwriting what it copied): such a copy is thrown
//! away and counted as lost too.
//!
//! Timing argument for the check: the DMA switches halves at the last word
//! of a conversion and writes the new half's first word only after the next
//! conversion (one sample period, 19.5 µs at 51.2 kHz); the
//! transfer-complete interrupt preempts the consumer within a few cycles of
//! the switch, so the count is always raised before the DMA touches the
//! half it now writes.

use crate::source::CHANNELS;
use core::sync::atomic::{AtomicU32, Ordering};

/// Halves the DMA has completed since acquisition started (producer side:
/// the transfer-complete interrupt calls [`HalfCompletions::complete`]).
#[derive(Debug, Default)]
pub struct HalfCompletions(AtomicU32);

impl HalfCompletions {
    /// None completed.
    pub const fn new() -> Self {
        Self(AtomicU32::new(0))
    }

    /// One more half is full; returns the new count (wrapping).
    #[inline]
    pub fn complete(&self) -> u32 {
        // Only the one interrupt writes: a load and a store are enough
        // (Cortex-M has no atomic read-modify-write on every target).
        let n = self.0.load(Ordering::Relaxed).wrapping_add(1);
        self.0.store(n, Ordering::Release);
        n
    }

    /// Halves completed so far (wrapping).
    pub fn count(&self) -> u32 {
        self.0.load(Ordering::Acquire)
    }

    /// Back to zero (acquisition stopped; before the DMA restarts).
    pub fn reset(&self) {
        self.0.store(0, Ordering::Release);
    }
}

/// The DMA's double buffer as the consumer sees it.
pub trait DoubleBuffer {
    /// Halves completed since acquisition started (wrapping), e.g.
    /// [`HalfCompletions::count`].
    fn completed(&self) -> u32;
    /// The codes of sample vector `vector` in half `half` (0 or 1).
    fn read(&self, half: usize, vector: usize) -> [i16; CHANNELS];
}

/// What one [`HandOver::take`] got.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Taken {
    /// No half completed since the last take.
    Nothing,
    /// An intact half was copied: its first sample's count since start,
    /// and the sample vectors lost since the previous delivered half.
    Half {
        /// Sample count since acquisition start of the half's first vector.
        first_sample: u64,
        /// Vectors lost (overrun) just before this half.
        lost_before: u64,
    },
    /// The DMA overran the half while it was being copied: the copy is
    /// void; `lost` vectors (this half and any skipped) are gone.
    Torn {
        /// Vectors lost, this half included.
        lost: u64,
    },
}

/// The consumer's side of the hand-over.
#[derive(Clone, Debug)]
pub struct HandOver {
    /// Sample vectors per half.
    vectors_per_half: usize,
    /// Halves accounted for (taken or counted lost) since start.
    next: u64,
    /// Halves lost (overruns) since start.
    lost_halves: u64,
}

impl HandOver {
    /// A consumer of halves of `vectors_per_half` sample vectors (≥ 1).
    pub fn new(vectors_per_half: usize) -> Self {
        Self {
            vectors_per_half: vectors_per_half.max(1),
            next: 0,
            lost_halves: 0,
        }
    }

    /// Sample vectors per half.
    pub fn vectors_per_half(&self) -> usize {
        self.vectors_per_half
    }

    /// Halves lost to overruns since [`HandOver::reset`].
    pub fn lost_halves(&self) -> u64 {
        self.lost_halves
    }

    /// Starts counting from zero (the DMA restarts at half 0).
    pub fn reset(&mut self) {
        self.next = 0;
        self.lost_halves = 0;
    }

    /// Halves completed since start, unwrapped against what was taken.
    pub fn completed<B: DoubleBuffer>(&self, dma: &B) -> u64 {
        self.next + u64::from(dma.completed().wrapping_sub(self.next as u32))
    }

    /// An upper bound of the sample vectors converted since start: the
    /// complete halves and all of the one being filled.
    pub fn now_bound<B: DoubleBuffer>(&self, dma: &B) -> u64 {
        (self.completed(dma) + 1) * self.vectors_per_half as u64
    }

    /// Copies the newest complete half, vector by vector, into `sink`
    /// (`sink(index, codes)`), and says whether the copy stands.
    pub fn take<B: DoubleBuffer>(
        &mut self,
        dma: &B,
        mut sink: impl FnMut(usize, [i16; CHANNELS]),
    ) -> Taken {
        let done = self.completed(dma);
        if done == self.next {
            return Taken::Nothing;
        }
        let newest = done - 1;
        let skipped = newest - self.next;
        self.next = done;
        self.lost_halves += skipped;
        let half = (newest % 2) as usize;
        for v in 0..self.vectors_per_half {
            sink(v, dma.read(half, v));
        }
        let n = self.vectors_per_half as u64;
        // The copy's reads complete before the count is read again (on the
        // MCU a DMB: the DMA is another bus master).
        core::sync::atomic::fence(Ordering::SeqCst);
        if self.completed(dma) != done {
            // A further half completed during the copy: the DMA is now
            // writing into the half that was being copied.
            self.lost_halves += 1;
            return Taken::Torn {
                lost: (skipped + 1) * n,
            };
        }
        Taken::Half {
            first_sample: newest * n,
            lost_before: skipped * n,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use core::cell::Cell;

    /// Two halves of 2 vectors; `read` can advance the DMA (a preempting
    /// transfer-complete) after a given number of reads.
    struct Fake {
        done: HalfCompletions,
        reads: Cell<u32>,
        complete_after_reads: Option<u32>,
    }

    impl DoubleBuffer for Fake {
        fn completed(&self) -> u32 {
            self.done.count()
        }
        fn read(&self, half: usize, vector: usize) -> [i16; CHANNELS] {
            self.reads.set(self.reads.get() + 1);
            if Some(self.reads.get()) == self.complete_after_reads {
                self.done.complete();
            }
            [(half * 10 + vector) as i16; CHANNELS]
        }
    }

    #[test]
    fn newest_half_only_and_skipped_halves_counted() {
        let dma = Fake {
            done: HalfCompletions::new(),
            reads: Cell::new(0),
            complete_after_reads: None,
        };
        let mut h = HandOver::new(2);
        assert_eq!(
            h.take(&dma, |_, _| panic!("nothing to copy")),
            Taken::Nothing
        );
        dma.done.complete();
        let mut got = [0i16; 2];
        assert_eq!(
            h.take(&dma, |i, c| got[i] = c[0]),
            Taken::Half {
                first_sample: 0,
                lost_before: 0
            }
        );
        assert_eq!(got, [0, 1]);
        // Three more complete (halves 1, 2, 3): 1 and 2 are lost, 3 (in
        // memory half 1) is taken.
        for _ in 0..3 {
            dma.done.complete();
        }
        assert_eq!(
            h.take(&dma, |i, c| got[i] = c[0]),
            Taken::Half {
                first_sample: 6,
                lost_before: 4
            }
        );
        assert_eq!(got, [10, 11]);
        assert_eq!(h.lost_halves(), 2);
        assert_eq!(h.now_bound(&dma), 10);
    }

    #[test]
    fn a_half_overrun_during_the_copy_is_void() {
        let dma = Fake {
            done: HalfCompletions::new(),
            reads: Cell::new(0),
            complete_after_reads: Some(1),
        };
        dma.done.complete();
        let mut h = HandOver::new(2);
        assert_eq!(h.take(&dma, |_, _| {}), Taken::Torn { lost: 2 });
        assert_eq!(h.lost_halves(), 1);
        // The half completed during the copy is intact and comes next.
        assert_eq!(
            h.take(&dma, |_, _| {}),
            Taken::Half {
                first_sample: 2,
                lost_before: 0
            }
        );
    }
}
