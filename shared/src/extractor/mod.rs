//! Keyphasor-synchronous 1X phasor extraction, sample by sample, during a
//! run-down.
//!
//! # What a phasor is here
//!
//! For revolution j, between keyphasor edges at times τ_{j−1} and τ_j, the
//! extracted phasor of a channel x is its first Fourier coefficient with the
//! **shaft angle** θ as the independent variable:
//!
//! Q_j = (1/π) ∫₀^{2π} x(θ)·e^{−iθ} dθ,  θ = 0 at τ_{j−1}, θ = 2π at τ_j,
//!
//! so that x = Re{Q·e^{iθ}} + (DC and harmonics of θ) gives exactly Q, the
//! convention of `formats.md` (q(t) = Re{Q·e^{iΩt}}, t = 0 at the keyphasor)
//! with Ωt replaced by the shaft angle. It is attributed to the revolution's
//! mean speed 1/(τ_j − τ_{j−1}) [Hz]. At constant speed this is the usual
//! time-domain 1X phasor; while the speed changes (a revolution at 5 Hz
//! decelerating 5 Hz/s spans a 20 % speed change) DC, 2X, 3X, … still
//! integrate to zero, which they would not in the time domain. Velocity and
//! acceleration channels are converted to displacement with the revolution's
//! kinematics (see [`Conversion`]: exact for a displacement phasor constant
//! over the revolution, reducing to ÷iΩ and ÷(−Ω²) at constant speed).
//! During a run-down the displacement phasor itself changes from revolution
//! to revolution (by percents near a resonance); with the revolutions before
//! and after, [`mid_revolution`] removes what that change puts into the
//! revolution's coefficient (the −1X leaking through the one-revolution
//! window, and a seismic pick-up seeing dD/dt), so the output is the
//! displacement in the middle of the revolution: the response at the
//! revolution's speed. With
//! R revolutions per output the phasors of R consecutive valid revolutions
//! are averaged (the angle-domain coefficient over 2πR) and the speed is
//! R/(their total duration).
//!
//! # Noise
//!
//! Each output also carries the standard deviation of its noise per channel,
//! from the scatter between revolutions once the modelled trend (a cubic in
//! the revolution number) is removed by a fourth difference, pooled over the
//! last [`POOLED_REVOLUTIONS`] revolutions at the speed law of white noise
//! (one output's own revolutions are too few to weigh it by), and
//! propagated through the run-down correction and the average (module
//! `noise`: [`revolution_variance`], [`NoisePool`], [`average_noise_gain`]). A fit that treats
//! consecutive outputs as independent scales its parameter variances by
//! [`long_run_factor`], because neighbouring outputs share revolutions.
//!
//! # How
//!
//! The shaft angle within a revolution is modelled with constant angular
//! acceleration ([`ShaftModel`]), predicted from the two previous periods. A
//! chirp [`Rotator`] follows the predicted angle θ̂ with no trigonometric call
//! per sample; each sample adds x·θ̂'·e^{−iθ̂} to each channel's sum
//! ([`RevolutionIntegrator`]: one complex multiply-accumulate per channel),
//! with trapezoid weights split fractionally at the keyphasor edges (the
//! caller gives each edge's sub-sample position from the timer capture). At
//! the closing edge the true angle is known (quadratic through the last
//! three edges) and the 64 segment sums are rotated onto it. Memory is fixed and
//! independent of speed; nothing is buffered.
//!
//! # Faults
//!
//! An edge well before the predicted one (an extra pulse), no edge well after
//! it (a missing pulse), no edge at all within 1/`min_speed_hz` (timeout), or
//! an implausible speed change while acquiring emit a [`Fault`] event; the
//! revolutions that pulse could have corrupted (the open one and the one
//! before it, which is why every revolution is held back until the next one
//! closes cleanly, and once more until its successor, which its run-down
//! correction uses, is confirmed too) and any partial average are discarded,
//! and the extractor re-acquires from the next edges: 3 edges to predict,
//! then one revolution to integrate and two to confirm it.
//!
//! # Accuracy and cost (measured, see the tests)
//!
//! On clean synthetic signals at 51.2 kHz, constant speed (5.3, 37.3,
//! 199.7 Hz) and the 200 → 5 Hz run-down at 5 Hz/s: ≤ 5e-5 relative error for
//! a proximity probe riding on a −9 V gap voltage (36× its 1X) with 2X and
//! 3X, ≤ 4e-5 for velocity and acceleration channels. Through a resonance
//! (45 Hz, ζ = 2 %) against the response at each revolution's speed: ≤ 1e-5
//! of the peak for all three sensor kinds at 1 Hz/s, ≤ 6e-4 at 4 Hz/s
//! (10 % change per revolution). DC leaks at ~1.5e-6 of
//! its size (f32 rounding and the O(h²) edge quadrature), so a DC offset
//! 60× the 1X is the limit for 1e-4. The per-sample path compiles for
//! thumbv7em (opt-level 3, N = 8) to a loop of 114 instructions per two
//! samples — 7.1 per channel-sample, with the accumulators in FPU registers —
//! plus about one per channel-sample of per-chunk work.

mod config;
mod events;
mod integrator;
mod noise;
mod rotator;
mod sensor;
mod shaft;
mod variation;

#[cfg(test)]
mod tests;

pub use config::{ConfigError, ExtractorConfig};
pub use events::{Event, Fault, FaultKind, InputError, KeyphasorEdge, Phasors};
pub use integrator::{RevolutionIntegrator, CHUNK, SEGMENTS};
pub use noise::{
    average_noise_gain, long_run_factor, revolution_variance, white_noise_law, NoisePool,
    POOLED_REVOLUTIONS,
};
pub use rotator::{expi_neg, expi_neg_small, Rotator};
pub use sensor::{Conversion, Kinematics, Sensor, SensorKind};
pub use shaft::{EdgeTime, ShaftModel};
pub use variation::mid_revolution;

use crate::phasor::Phasor;

const ZERO: Phasor = Phasor::new(0.0, 0.0);

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum State {
    /// No edge since the start, a reset or a timeout.
    Idle,
    /// `edges` (1 or 2) consecutive plausible edges seen.
    Acquiring { edges: u8 },
    /// Integrating a revolution along a predicted angle.
    Tracking,
}

/// A closed revolution waiting for the next one to confirm its closing edge.
#[derive(Clone, Copy, Debug)]
struct Pending<const N: usize> {
    displacement: [Phasor; N],
    period: f32,
    revolution: u32,
    end: EdgeTime,
}

/// The keyphasor-synchronous 1X phasor extractor for N channels sampled
/// together.
#[derive(Clone, Debug)]
pub struct PhasorExtractor<const N: usize> {
    config: ExtractorConfig<N>,
    /// Shortest and longest accepted period [samples].
    min_period: f32,
    max_period: f32,
    state: State,
    /// Absolute index of the next sample.
    now: u64,
    /// The last sample of the previous block [V].
    last: [f32; N],
    /// Keyphasor edges received.
    edges: u32,
    /// The most recent accepted edge: the open revolution's start.
    last_edge: EdgeTime,
    /// Period of the revolution before the open one [samples].
    previous_period: f32,
    /// Predicted period of the open revolution [samples].
    predicted_period: f32,
    /// Time after the open revolution's start at which it times out [samples].
    timeout: f32,
    integrator: RevolutionIntegrator<N>,
    /// The last closed revolution, until the next edge confirms it.
    pending: Option<Pending<N>>,
    /// The confirmed revolution before it, until `pending` is confirmed too:
    /// its run-down correction needs a trustworthy next revolution.
    confirmed: Option<Pending<N>>,
    /// Constant-D phasors [m] of the three revolutions before `confirmed`
    /// (oldest first), each if contiguous: the last two for the run-down
    /// correction, all three for the noise.
    before: [Option<[Phasor; N]>; 3],
    /// Running average: Σ displacement [m], Σ period [samples], count.
    sum: [Phasor; N],
    sum_period: f32,
    count: u16,
    /// Each channel's per-revolution noise variance, pooled over the last
    /// revolutions (kept across faults).
    noise: NoisePool<N>,
    /// Noise gain G of an output per channel (see [`average_noise_gain`]).
    gain: [f32; N],
}

impl<const N: usize> PhasorExtractor<N> {
    /// An extractor with `config`, waiting for the first keyphasor edge.
    pub fn new(config: ExtractorConfig<N>) -> Result<Self, ConfigError> {
        let fs = config.sample_rate_hz;
        if !(fs.is_finite() && fs > 0.0) {
            return Err(ConfigError::SampleRate);
        }
        if let Some(channel) = config.sensors.iter().position(|s| !s.is_valid()) {
            return Err(ConfigError::Sensitivity { channel });
        }
        if config.revolutions_per_output == 0 {
            return Err(ConfigError::Revolutions);
        }
        let (lo, hi) = (config.min_speed_hz, config.max_speed_hz);
        // The rotator's Taylor step needs ≤ 0.1 rad/sample; f32 sample counts
        // within a revolution must stay exact.
        if !(lo > 0.0 && lo < hi && hi <= fs / 64.0 && fs / lo < 4_194_304.0) {
            return Err(ConfigError::SpeedRange);
        }
        let tol = config.period_tolerance;
        if !(tol > 0.0 && tol < 0.5) {
            return Err(ConfigError::PeriodTolerance);
        }
        let a = config.max_acceleration_hz_per_s;
        if !(a.is_finite() && a > 0.0) {
            return Err(ConfigError::Acceleration);
        }
        Ok(Self {
            config,
            min_period: fs / hi,
            max_period: fs / lo,
            state: State::Idle,
            now: 0,
            last: [0.0; N],
            edges: 0,
            last_edge: EdgeTime {
                sample: 0,
                fraction: 0.0,
            },
            previous_period: 0.0,
            predicted_period: 0.0,
            timeout: 0.0,
            integrator: RevolutionIntegrator::default(),
            pending: None,
            confirmed: None,
            before: [None, None, None],
            sum: [ZERO; N],
            sum_period: 0.0,
            count: 0,
            noise: NoisePool::new(config.sensors.map(|s| s.kind)),
            gain: config
                .sensors
                .map(|s| average_noise_gain(s.kind, config.revolutions_per_output)),
        })
    }

    /// The settings.
    pub fn config(&self) -> &ExtractorConfig<N> {
        &self.config
    }

    /// φ of channel `channel` ([`long_run_factor`]): how much the parameter
    /// variances of a fit that takes consecutive outputs as independent must
    /// be scaled (they share revolutions). 1 for a channel out of range.
    pub fn long_run_factor(&self, channel: usize) -> f32 {
        self.gain.get(channel).map_or(1.0, |&g| {
            long_run_factor(self.config.revolutions_per_output, g)
        })
    }

    /// Whether a revolution is being integrated (synchronised to the keyphasor).
    pub fn is_tracking(&self) -> bool {
        self.state == State::Tracking
    }

    /// Absolute index of the next sample to be fed.
    pub fn sample_index(&self) -> u64 {
        self.now
    }

    /// Forget the keyphasor history, pending revolutions and partial average
    /// (the sample count keeps running).
    pub fn reset(&mut self) {
        self.state = State::Idle;
        self.discard();
    }

    /// Feed one sample vector [V]; `edge` is the position in [0, 1) of a
    /// keyphasor edge within the interval since the previous sample, if one
    /// occurred. Events go to `sink`.
    pub fn update(
        &mut self,
        sample: &[f32; N],
        edge: Option<f32>,
        sink: &mut impl FnMut(Event<N>),
    ) -> Result<(), InputError> {
        let edges = edge.map(|fraction| KeyphasorEdge { index: 0, fraction });
        self.update_block(core::slice::from_ref(sample), edges.as_slice(), sink)
    }

    /// Feed a block of consecutive sample vectors [V] with the keyphasor edges
    /// that occurred during it (sorted); events go to `sink` in time order.
    /// Between edges this runs the per-sample path only: one shared rotator
    /// step and one complex multiply-accumulate per channel.
    pub fn update_block(
        &mut self,
        samples: &[[f32; N]],
        edges: &[KeyphasorEdge],
        sink: &mut impl FnMut(Event<N>),
    ) -> Result<(), InputError> {
        let mut before: Option<&KeyphasorEdge> = None;
        for (edge, e) in edges.iter().enumerate() {
            if e.index >= samples.len() {
                return Err(InputError::EdgeIndex { edge });
            }
            if !(e.fraction >= 0.0 && e.fraction < 1.0) {
                return Err(InputError::EdgeFraction { edge });
            }
            if let Some(b) = before {
                if e.index < b.index || (e.index == b.index && e.fraction <= b.fraction) {
                    return Err(InputError::EdgeOrder { edge });
                }
            }
            before = Some(e);
        }
        let mut start = 0;
        for e in edges {
            self.run(&samples[start..e.index], sink);
            let previous = if e.index == 0 {
                self.last
            } else {
                samples[e.index - 1]
            };
            self.edge(&previous, &samples[e.index], e.fraction, sink);
            start = e.index;
        }
        self.run(&samples[start..], sink);
        if let Some(last) = samples.last() {
            self.last = *last;
        }
        Ok(())
    }

    /// Samples between edges: integrate, or count, until a timeout.
    fn run(&mut self, mut samples: &[[f32; N]], sink: &mut impl FnMut(Event<N>)) {
        while !samples.is_empty() {
            let (next, limit) = match self.state {
                State::Idle => {
                    self.now += samples.len() as u64;
                    return;
                }
                State::Acquiring { .. } => {
                    let since = self.now.wrapping_sub(self.last_edge.sample) as f32;
                    (since + 1.0 - self.last_edge.fraction, self.max_period)
                }
                State::Tracking => (self.integrator.next_time(), self.timeout),
            };
            let allowed = if next > limit {
                0
            } else {
                (limit - next) as usize + 1
            };
            let take = allowed.min(samples.len());
            let (now, rest) = samples.split_at(take);
            if self.state == State::Tracking {
                self.integrator.accumulate(now);
            }
            self.now += take as u64;
            samples = rest;
            if !samples.is_empty() {
                let kind = if self.state == State::Tracking && self.timeout < self.max_period {
                    FaultKind::MissingPulse
                } else {
                    FaultKind::Timeout
                };
                self.fault(kind, sink);
                self.state = State::Idle;
            }
        }
    }

    /// A keyphasor edge at `fraction` of the interval between `previous` and
    /// `current`, which is sample number `self.now`.
    fn edge(
        &mut self,
        previous: &[f32; N],
        current: &[f32; N],
        fraction: f32,
        sink: &mut impl FnMut(Event<N>),
    ) {
        let edge = EdgeTime {
            sample: self.now,
            fraction,
        };
        self.edges = self.edges.wrapping_add(1);
        let period = edge.since(self.last_edge);
        match self.state {
            State::Idle => self.restart(edge),
            State::Acquiring { edges } => {
                if period < self.min_period {
                    self.fault(FaultKind::ExtraPulse, sink);
                    self.restart(edge);
                } else if period > self.max_period {
                    self.fault(FaultKind::Timeout, sink);
                    self.restart(edge);
                } else if edges == 1 {
                    self.previous_period = period;
                    self.last_edge = edge;
                    self.state = State::Acquiring { edges: 2 };
                } else if !self.plausible(self.previous_period, period) {
                    self.fault(FaultKind::IrregularPulses, sink);
                    self.restart(edge);
                } else {
                    let model = ShaftModel::fit(self.previous_period, period).advance(period);
                    self.begin(model, edge, period, previous, current);
                }
            }
            State::Tracking => {
                let tol = self.config.period_tolerance;
                if period < (1.0 - tol) * self.predicted_period || period < self.min_period {
                    self.fault(FaultKind::ExtraPulse, sink);
                    self.restart(edge);
                } else if period > (1.0 + tol) * self.predicted_period || period > self.max_period {
                    self.fault(FaultKind::MissingPulse, sink);
                    self.restart(edge);
                } else {
                    let actual = ShaftModel::fit(self.previous_period, period);
                    self.close(&actual, period, edge, previous, current, sink);
                    self.begin(actual.advance(period), edge, period, previous, current);
                }
            }
        }
    }

    /// Whether the speed change from a period of `first` to `second` samples
    /// is within `max_acceleration_hz_per_s` (plus the period tolerance).
    fn plausible(&self, first: f32, second: f32) -> bool {
        let fs = self.config.sample_rate_hz;
        let change_hz = fs * libm::fabsf(1.0 / second - 1.0 / first);
        let elapsed_s = 0.5 * (first + second) / fs;
        let allowed_hz = self.config.max_acceleration_hz_per_s * elapsed_s
            + self.config.period_tolerance * fs / first;
        change_hz <= allowed_hz
    }

    /// Open a revolution at `edge` along the predicted angle `model`.
    fn begin(
        &mut self,
        model: ShaftModel,
        edge: EdgeTime,
        period: f32,
        previous: &[f32; N],
        current: &[f32; N],
    ) {
        self.predicted_period = match model.period() {
            Some(p) if p < self.max_period => p,
            _ => self.max_period,
        };
        self.timeout =
            ((1.0 + self.config.period_tolerance) * self.predicted_period).min(self.max_period);
        self.previous_period = period;
        self.last_edge = edge;
        self.state = State::Tracking;
        let reach = model.angle(self.timeout);
        self.integrator
            .start(model, reach, edge.fraction, previous, current);
    }

    /// Close the open revolution along its true angle `actual`, convert to
    /// displacement, and hold it until the next edge confirms it; emit the
    /// revolution before it, corrected for the run-down, once that one's
    /// successor is confirmed.
    fn close(
        &mut self,
        actual: &ShaftModel,
        period: f32,
        edge: EdgeTime,
        previous: &[f32; N],
        current: &[f32; N],
        sink: &mut impl FnMut(Event<N>),
    ) {
        let mut phasors = [ZERO; N];
        self.integrator.close(
            actual,
            period,
            edge.fraction,
            previous,
            current,
            &mut phasors,
        );
        let fs = self.config.sample_rate_hz;
        let kinematics = Kinematics {
            omega_start: actual.speed * fs,
            omega_end: actual.rate(period) * fs,
            alpha: actual.accel * fs * fs,
        };
        let conversions = [
            SensorKind::Displacement,
            SensorKind::Velocity,
            SensorKind::Acceleration,
        ]
        .map(|kind| Conversion::new(kind, &kinematics));
        let mut finite = true;
        for (q, sensor) in phasors.iter_mut().zip(&self.config.sensors) {
            let conversion = &conversions[match sensor.kind {
                SensorKind::Displacement => 0,
                SensorKind::Velocity => 1,
                SensorKind::Acceleration => 2,
            }];
            *q = conversion.to_displacement(*q / sensor.sensitivity);
            finite &= q.re.is_finite() && q.im.is_finite();
        }
        if !finite {
            self.fault(FaultKind::NonFinite, sink);
            return;
        }
        let closed = Pending {
            displacement: phasors,
            period,
            revolution: self.edges,
            end: edge,
        };
        // `closed` confirms the pending revolution, which in turn is the
        // trustworthy successor that the one confirmed before needs.
        if let Some(newly) = self.pending.replace(closed) {
            if let Some(ready) = self.confirmed.replace(newly) {
                // The displacement in the middle of the revolution, from its
                // neighbours (see [`mid_revolution`]).
                let mut mid = ready;
                let mut variance = [0.0; N];
                let mut order = 0;
                for (c, d) in mid.displacement.iter_mut().enumerate() {
                    let [_, two, one] = self.before.map(|b| b.map(|b| b[c]));
                    *d = mid_revolution(
                        self.config.sensors[c].kind,
                        [two, one],
                        ready.displacement[c],
                        newly.displacement[c],
                    );
                    (variance[c], order) = revolution_variance(
                        self.before.map(|b| b.map(|b| b[c])),
                        ready.displacement[c],
                        newly.displacement[c],
                    );
                }
                self.before = [self.before[1], self.before[2], Some(ready.displacement)];
                // The difference spans revolutions j + 1 − order … j + 1:
                // its variance is the noise's at their middle speed.
                let fs = self.config.sample_rate_hz;
                let (this_hz, next_hz) = (fs / ready.period, fs / newly.period);
                let middle_hz = next_hz + 0.5 * order as f32 * (this_hz - next_hz);
                self.noise.add(&variance, order, middle_hz);
                self.average(mid, sink);
            }
        }
    }

    /// Add a confirmed, run-down-corrected revolution to the average; emit
    /// it when R are in, with its noise from the pooled per-revolution
    /// variance at its speed times the gain G.
    fn average(&mut self, revolution: Pending<N>, sink: &mut impl FnMut(Event<N>)) {
        for (s, d) in self.sum.iter_mut().zip(&revolution.displacement) {
            *s += *d;
        }
        self.sum_period += revolution.period;
        self.count += 1;
        let r = self.config.revolutions_per_output;
        if self.count >= r {
            let scale = 1.0 / r as f32;
            let speed_hz = self.config.sample_rate_hz * r as f32 / self.sum_period;
            let mut noise_sd = [0.0; N];
            for (c, sd) in noise_sd.iter_mut().enumerate() {
                *sd = libm::sqrtf(self.gain[c] * self.noise.variance(c, speed_hz));
            }
            sink(Event::Phasors(Phasors {
                displacement: self.sum.map(|s| s * scale),
                noise_sd,
                speed_hz,
                revolution: revolution.revolution,
                revolutions: r,
                end: revolution.end,
            }));
            self.clear_average();
        }
    }

    /// Empty the running average.
    fn clear_average(&mut self) {
        self.sum = [ZERO; N];
        self.sum_period = 0.0;
        self.count = 0;
    }

    /// Start acquiring afresh with `edge` as the first edge.
    fn restart(&mut self, edge: EdgeTime) {
        self.last_edge = edge;
        self.state = State::Acquiring { edges: 1 };
    }

    /// Drop the held revolutions and the partial average.
    fn discard(&mut self) {
        self.pending = None;
        self.confirmed = None;
        self.before = [None, None, None];
        self.clear_average();
    }

    /// Report a fault and drop everything it may have corrupted.
    fn fault(&mut self, kind: FaultKind, sink: &mut impl FnMut(Event<N>)) {
        self.discard();
        sink(Event::Fault(Fault {
            kind,
            sample: self.now,
            edges: self.edges,
        }));
    }
}
