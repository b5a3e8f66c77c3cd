//! Progress on stderr for commands that can run over a second (`simulate`,
//! `diagnose`, `accuracy`, `paper`, `identify`, `import`, `extract`), drawn
//! with `indicatif`.
//!
//! Shown only when stderr is a terminal and neither the command (`enabled`
//! false) nor the global `--quiet` ([`set_quiet`]) silences it; it appears
//! once the work has run for a second (so quick commands never flash a
//! bar), redraws itself five times a second (a long single step still shows
//! its elapsed time) and is erased at the end, so that scripts, pipes and
//! `--json` on stdout never see it.
//!
//! Every display of the process draws through one `MultiProgress`, so a
//! command's own line (`diagnose`) and a step's line under it (the
//! candidate rounds) stack instead of overwriting each other.
//! `PLINTH_PROGRESS_AFTER_MS` sets the delay before a display appears
//! (default 1000; the tests use 0).

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::OnceLock;
use std::time::Duration;

/// Set once by `plinth --quiet`: no progress anywhere in the process.
static QUIET: AtomicBool = AtomicBool::new(false);

/// Silences every progress display of the process (the global `--quiet`).
pub fn set_quiet(quiet: bool) {
    QUIET.store(quiet, Ordering::Relaxed);
}

/// True when the global `--quiet` was given.
pub fn quiet() -> bool {
    QUIET.load(Ordering::Relaxed)
}

/// True when progress may be drawn: not `--quiet` and stderr is a terminal.
pub fn visible() -> bool {
    !quiet() && std::io::stderr().is_terminal()
}

/// Delay before a progress display appears: 1 s, or
/// `PLINTH_PROGRESS_AFTER_MS` milliseconds.
fn show_after() -> Duration {
    std::env::var("PLINTH_PROGRESS_AFTER_MS")
        .ok()
        .and_then(|v| v.trim().parse::<u64>().ok())
        .map_or(Duration::from_secs(1), Duration::from_millis)
}

/// The one stderr display every progress line of the process joins.
fn multi() -> &'static MultiProgress {
    static MULTI: OnceLock<MultiProgress> = OnceLock::new();
    MULTI.get_or_init(|| MultiProgress::with_draw_target(ProgressDrawTarget::stderr_with_hz(5)))
}

/// A `LABEL [bar] DONE/TOTAL (PCT %) ELAPSED<ETA` line on stderr.
#[derive(Debug)]
pub struct Ticker {
    bar: ProgressBar,
    live: bool,
}

impl Ticker {
    /// A ticker over `total` steps; `enabled` false never prints (a
    /// command's own `quiet`); the global `--quiet` or stderr not being a
    /// terminal disables it too.
    pub fn new(label: &str, total: usize, enabled: bool) -> Ticker {
        Ticker::with_template(
            label,
            Some(total as u64),
            "{msg} [{bar:30}] {pos}/{len} ({percent} %) {elapsed_precise}<{eta}",
            enabled,
        )
    }

    /// A ticker for work of unknown length (`LABEL ELAPSED` with a
    /// spinner), e.g. a whole command around steps that show their own.
    pub fn activity(label: &str, enabled: bool) -> Ticker {
        Ticker::with_template(label, None, "{spinner} {msg} {elapsed_precise}", enabled)
    }

    fn with_template(label: &str, total: Option<u64>, template: &str, enabled: bool) -> Ticker {
        let bar = ProgressBar::with_draw_target(total, ProgressDrawTarget::hidden());
        bar.set_style(
            ProgressStyle::with_template(template)
                .unwrap_or_else(|_| ProgressStyle::default_bar())
                .progress_chars("=> "),
        );
        bar.set_message(label.to_string());
        let live = enabled && visible();
        if live {
            // The steady tick redraws even when no step finishes; the bar
            // stays hidden until a small thread shows it after
            // [`show_after`], in the process's one display.
            bar.enable_steady_tick(Duration::from_millis(200));
            let after = show_after();
            if after.is_zero() {
                // Shown at once and drawn now (`tick` does nothing while a
                // steady tick runs, whose first tick may have fallen before
                // the bar joined the display), so even a command faster
                // than one tick shows its line.
                multi().add(bar.clone()).force_draw();
                return Ticker { bar, live };
            }
            let delayed = bar.downgrade();
            std::thread::spawn(move || {
                std::thread::sleep(after);
                if let Some(bar) = delayed.upgrade() {
                    if !bar.is_finished() {
                        multi().add(bar);
                    }
                }
            });
        }
        Ticker { bar, live }
    }

    /// `done` of the total steps are finished.
    pub fn tick(&mut self, done: usize) {
        self.bar.set_position(done as u64);
    }

    /// Stops and erases the line (if it was shown).
    pub fn finish(&mut self) {
        if !self.bar.is_finished() {
            self.bar.finish_and_clear();
            if self.live {
                multi().remove(&self.bar);
            }
        }
    }

    /// True when this ticker draws (enabled, not `--quiet`, a terminal).
    pub fn is_live(&self) -> bool {
        self.live
    }
}

impl Drop for Ticker {
    fn drop(&mut self) {
        self.finish();
    }
}

/// A progress bar over `len` units (frames, rows) for commands that drive
/// `indicatif` themselves, or a spinner when `len` is unknown; hidden
/// under `--quiet`, with `enabled` false or off a terminal.
pub fn bar(label: &str, len: Option<u64>, enabled: bool) -> ProgressBar {
    if !(enabled && visible()) {
        return ProgressBar::hidden();
    }
    let (bar, template) = match len {
        Some(n) => (
            ProgressBar::new(n),
            "{msg} [{bar:40}] {percent}% {elapsed}<{eta}",
        ),
        None => (
            ProgressBar::new_spinner(),
            "{spinner} {msg} {pos} {elapsed}",
        ),
    };
    bar.set_style(
        ProgressStyle::with_template(template).unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_message(label.to_string());
    multi().add(bar)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_disabled_ticker_never_draws_and_finishes_cleanly() {
        let mut t = Ticker::new("test", 10, false);
        assert!(!t.is_live());
        for i in 0..=10 {
            t.tick(i);
        }
        t.finish();
        t.finish();
        assert!(bar("x", Some(3), false).is_hidden());
    }

    #[test]
    fn global_quiet_hides_everything() {
        set_quiet(true);
        let t = Ticker::new("test", 3, true);
        assert!(!t.is_live());
        assert!(bar("x", None, true).is_hidden());
        set_quiet(false);
    }
}
