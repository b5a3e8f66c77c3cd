//! The live progress line of `plinth stream`: one stderr line, rewritten in
//! place with a carriage return, showing speed, revolutions, frames,
//! estimates and every link loss as it happens.

use std::io::Write;
use std::time::{Duration, Instant};

/// What the progress line shows; the session fills it in as frames arrive.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ProgressState {
    /// Latest rotor speed reported by the box [Hz].
    pub speed_hz: Option<f64>,
    /// Keyphasor revolutions the box has processed.
    pub revolutions: u64,
    /// Phasor frames accepted.
    pub phasor_frames: u64,
    /// Estimate frames accepted.
    pub estimate_frames: u64,
    /// Frames of every kind accepted.
    pub frames: u64,
    /// Frames missing according to the sequence numbers.
    pub frames_lost: u64,
    /// Frames rejected by the CRC or the decoder.
    pub bad_frames: u64,
    /// Times the decoder had to resynchronise on a frame delimiter.
    pub resyncs: u64,
    /// Bytes received this session.
    pub bytes: u64,
    /// Times the port was lost and reopened.
    pub reconnects: u64,
    /// Replay sample blocks acknowledged by the box, and the total to send.
    pub replay: Option<(u64, u64)>,
    /// Replay sample blocks sent again after a loss.
    pub resent_blocks: u64,
}

/// Renders [`ProgressState`] at most every `interval` to a writer (stderr).
pub struct Progress {
    out: Box<dyn Write + Send>,
    started: Instant,
    last_draw: Option<Instant>,
    interval: Duration,
    last_width: usize,
    enabled: bool,
}

impl Progress {
    /// A progress line on stderr, redrawn at most 5 times a second.
    pub fn stderr() -> Self {
        Self::new(Box::new(std::io::stderr()), Duration::from_millis(200))
    }

    /// A progress line on `out`, redrawn at most every `interval`.
    pub fn new(out: Box<dyn Write + Send>, interval: Duration) -> Self {
        Self {
            out,
            started: Instant::now(),
            last_draw: None,
            interval,
            last_width: 0,
            enabled: true,
        }
    }

    /// A progress line that draws nothing (for `--quiet` and tests).
    pub fn hidden() -> Self {
        let mut p = Self::new(Box::new(std::io::sink()), Duration::from_secs(3600));
        p.enabled = false;
        p
    }

    /// Redraws the line if `interval` has passed since the last redraw.
    pub fn tick(&mut self, state: &ProgressState) {
        let due = self.last_draw.is_none_or(|t| t.elapsed() >= self.interval);
        if due {
            self.draw(state);
        }
    }

    /// Redraws the line now.
    pub fn draw(&mut self, state: &ProgressState) {
        if !self.enabled {
            return;
        }
        self.last_draw = Some(Instant::now());
        let line = render(state, self.started.elapsed());
        let pad = self.last_width.saturating_sub(line.chars().count());
        self.last_width = line.chars().count();
        // A broken stderr must not stop the acquisition.
        let _ = write!(self.out, "\r{line}{:pad$}", "");
        let _ = self.out.flush();
    }

    /// Prints a message on its own line without losing the progress line.
    pub fn note(&mut self, message: &str) {
        if !self.enabled {
            return;
        }
        let _ = write!(self.out, "\r{:w$}\r{message}\n", "", w = self.last_width);
        self.last_width = 0;
        self.last_draw = None;
        let _ = self.out.flush();
    }

    /// Draws the final state and ends the line.
    pub fn finish(&mut self, state: &ProgressState) {
        if !self.enabled {
            return;
        }
        self.draw(state);
        let _ = writeln!(self.out);
        let _ = self.out.flush();
    }
}

/// The text of the progress line for `state` after `elapsed`.
pub fn render(state: &ProgressState, elapsed: Duration) -> String {
    let speed = match state.speed_hz {
        Some(s) => format!("{s:7.2} Hz"),
        None => "     -- Hz".to_string(),
    };
    let mut line = format!(
        "{:6.1} s  speed {speed}  rev {}  frames {} (phasors {}, estimates {})  lost {}  bad {}  resync {}  {}",
        elapsed.as_secs_f64(),
        state.revolutions,
        state.frames,
        state.phasor_frames,
        state.estimate_frames,
        state.frames_lost,
        state.bad_frames,
        state.resyncs,
        human_bytes(state.bytes),
    );
    if let Some((done, total)) = state.replay {
        let pct = if total > 0 {
            100.0 * done as f64 / total as f64
        } else {
            100.0
        };
        line.push_str(&format!("  replay {done}/{total} ({pct:.0}%)"));
        if state.resent_blocks > 0 {
            line.push_str(&format!(" resent {}", state.resent_blocks));
        }
    }
    if state.reconnects > 0 {
        line.push_str(&format!("  reconnects {}", state.reconnects));
    }
    line
}

fn human_bytes(n: u64) -> String {
    if n < 10_000 {
        format!("{n} B")
    } else if n < 10_000_000 {
        format!("{:.1} kB", n as f64 / 1e3)
    } else {
        format!("{:.1} MB", n as f64 / 1e6)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::sync::{Arc, Mutex};

    #[derive(Clone, Default)]
    struct Shared(Arc<Mutex<Vec<u8>>>);
    impl Write for Shared {
        fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
            self.0.lock().unwrap().extend_from_slice(b);
            Ok(b.len())
        }
        fn flush(&mut self) -> std::io::Result<()> {
            Ok(())
        }
    }

    #[test]
    fn the_line_shows_every_counter() {
        let s = ProgressState {
            speed_hz: Some(123.456),
            revolutions: 42,
            phasor_frames: 80,
            estimate_frames: 4,
            frames: 90,
            frames_lost: 3,
            bad_frames: 2,
            resyncs: 5,
            bytes: 12_345,
            reconnects: 1,
            replay: Some((5, 10)),
            resent_blocks: 2,
        };
        let line = render(&s, Duration::from_millis(1500));
        for part in [
            "1.5 s",
            "123.46 Hz",
            "rev 42",
            "frames 90",
            "phasors 80",
            "estimates 4",
            "lost 3",
            "bad 2",
            "resync 5",
            "12.3 kB",
            "replay 5/10 (50%)",
            "reconnects 1",
        ] {
            assert!(line.contains(part), "{part:?} missing from {line:?}");
        }
    }

    #[test]
    fn redraws_overwrite_the_line_in_place() {
        let buf = Shared::default();
        let mut p = Progress::new(Box::new(buf.clone()), Duration::ZERO);
        let mut s = ProgressState::default();
        p.tick(&s);
        s.frames = 1;
        p.tick(&s);
        p.finish(&s);
        let text = String::from_utf8(buf.0.lock().unwrap().clone()).unwrap();
        assert_eq!(text.matches('\r').count(), 3);
        assert_eq!(text.matches('\n').count(), 1);
        assert!(text.ends_with('\n'));
    }
}
