//! A raw log of one valid phasor frame, as a box sends it: the smallest
//! log `stream --offline` rebuilds a run from (an empty one is refused).
//! Shared by `link_faults` and the host's `robustness_cli` (by `#[path]`).

use plinth_shared::protocol::framing::{Transmitter, MAX_FRAME_SIZE};
use plinth_shared::protocol::{BearingPhasors, DeviceMessage, PhasorFrame, WirePhasor};

/// One frame at `speed_hz` [Hz] with phasors of a few µm at bearings
/// 0..`bearings` (noise not measured).
pub fn one_frame_log(speed_hz: f32, bearings: u8) -> Vec<u8> {
    let p = |re: f32| WirePhasor { re, im: -re };
    let mut frame = PhasorFrame {
        revolution: 0,
        revolutions: 4,
        speed_hz,
        bearings: Default::default(),
    };
    for bearing in 0..bearings {
        frame
            .bearings
            .push(BearingPhasors {
                bearing,
                rel: [p(1e-6), p(2e-6)],
                ped: [p(3e-7), p(4e-7)],
                rel_sd: [f32::NAN; 2],
                ped_sd: [f32::NAN; 2],
            })
            .expect("at most MAX_BEARINGS bearings");
    }
    let mut buf = [0u8; MAX_FRAME_SIZE];
    Transmitter::new()
        .encode(&DeviceMessage::Phasors(frame), &mut buf)
        .expect("a one-frame log fits a frame buffer")
        .1
        .to_vec()
}
