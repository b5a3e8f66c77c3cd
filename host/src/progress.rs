//! A progress line on stderr for long batch commands (`simulate`,
//! `diagnose`).
//!
//! Shown only when stderr is a terminal and the work has run for more than a
//! second, redrawn five times a second by a small thread (so a long single
//! step still shows its elapsed time), and erased at the end, so that
//! scripts, pipes and `--json` on stdout never see it.

use std::io::{IsTerminal, Write};
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// A `LABEL: DONE/TOTAL (PCT %), ELAPSED s` line on stderr.
#[derive(Debug)]
pub struct Ticker {
    done: Arc<AtomicUsize>,
    stop: Arc<AtomicBool>,
    thread: Option<std::thread::JoinHandle<()>>,
}

impl Ticker {
    /// A ticker over `total` steps; `enabled` false never prints (e.g.
    /// `--quiet`); stderr not being a terminal disables it too.
    pub fn new(label: &str, total: usize, enabled: bool) -> Ticker {
        let done = Arc::new(AtomicUsize::new(0));
        let stop = Arc::new(AtomicBool::new(false));
        let thread = (enabled && std::io::stderr().is_terminal()).then(|| {
            let (done, stop, label) = (done.clone(), stop.clone(), label.to_string());
            std::thread::spawn(move || draw(&label, total, &done, &stop))
        });
        Ticker { done, stop, thread }
    }

    /// `done` of the total steps are finished.
    pub fn tick(&mut self, done: usize) {
        self.done.store(done, Ordering::Relaxed);
    }

    /// Stops and erases the line (if it was shown).
    pub fn finish(&mut self) {
        self.stop.store(true, Ordering::Relaxed);
        if let Some(t) = self.thread.take() {
            let _ = t.join();
        }
    }
}

fn draw(label: &str, total: usize, done: &AtomicUsize, stop: &AtomicBool) {
    let started = Instant::now();
    let mut shown = false;
    while !stop.load(Ordering::Relaxed) {
        std::thread::sleep(Duration::from_millis(200));
        if started.elapsed() < Duration::from_secs(1) || stop.load(Ordering::Relaxed) {
            continue;
        }
        let d = done.load(Ordering::Relaxed);
        let pct = 100.0 * d as f64 / total.max(1) as f64;
        let mut err = std::io::stderr().lock();
        let _ = write!(
            err,
            "\r{label}: {d}/{total} ({pct:.0} %), {:.1} s\x1b[K",
            started.elapsed().as_secs_f64()
        );
        let _ = err.flush();
        shown = true;
    }
    if shown {
        let mut err = std::io::stderr().lock();
        let _ = write!(err, "\r\x1b[K");
        let _ = err.flush();
    }
}

impl Drop for Ticker {
    fn drop(&mut self) {
        self.finish();
    }
}
