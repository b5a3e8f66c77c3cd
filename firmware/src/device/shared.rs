//! How the protocol task reaches what it shares with the extraction task:
//! the extraction state with the sample source, and the outbox. On the
//! board each access is an RTIC lock (a priority-ceiling critical section
//! that holds the extraction task off for its length only); in one thread
//! (QEMU, tests) the parts are plain borrows and the extraction runs
//! inline.

use super::extraction::Extraction;
use super::outbox::Outbox;
use crate::source::SampleSource;

/// Exclusive access to one shared part for the length of a closure.
pub trait Lock {
    /// What the lock guards.
    type Target;
    /// Runs `f` with the part held.
    fn lock<R>(&mut self, f: impl FnOnce(&mut Self::Target) -> R) -> R;
}

/// A part owned by the caller: no lock needed.
impl<T> Lock for &mut T {
    type Target = T;
    fn lock<R>(&mut self, f: impl FnOnce(&mut T) -> R) -> R {
        f(self)
    }
}

/// What the protocol task ([`super::Session::poll`]) shares.
pub trait Shared {
    /// The sample source.
    type Source: SampleSource;
    /// Runs `f` with the extraction state and the source held (keep it short:
    /// on the board the extraction task waits meanwhile).
    fn acquisition<R>(&mut self, f: impl FnOnce(&mut Extraction, &mut Self::Source) -> R) -> R;
    /// Runs `f` with the outbox held (one frame, or one chunk to the link).
    fn outbox<R>(&mut self, f: impl FnOnce(&mut Outbox) -> R) -> R;
    /// Runs the extraction here and returns the sample vectors taken, when
    /// it has no task of its own (one thread); 0 where a task runs it.
    fn extract_inline(&mut self) -> usize;
}

/// Every part in one thread: plain borrows, the extraction inline.
pub struct Inline<'a, S> {
    /// The extraction state.
    pub extraction: &'a mut Extraction,
    /// The sample source.
    pub source: &'a mut S,
    /// The outbox.
    pub outbox: &'a mut Outbox,
}

impl<S: SampleSource> Shared for Inline<'_, S> {
    type Source = S;
    fn acquisition<R>(&mut self, f: impl FnOnce(&mut Extraction, &mut S) -> R) -> R {
        f(self.extraction, self.source)
    }
    fn outbox<R>(&mut self, f: impl FnOnce(&mut Outbox) -> R) -> R {
        f(self.outbox)
    }
    fn extract_inline(&mut self) -> usize {
        self.extraction.run(self.source, &mut &mut *self.outbox)
    }
}
