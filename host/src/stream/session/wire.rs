//! Commands to the box with their acknowledgements (resent on timeout),
//! and the receive pump that logs and dispatches every frame.

use super::*;

impl<'a> Session<'a> {
    /// Sends a command and waits for its answer, resending on timeout.
    pub(super) fn command(&mut self, msg: &HostMessage) -> Result<Reply> {
        Ok(self.command_counted(msg)?.0)
    }

    /// Like [`Session::command`], also saying how many sends it took.
    pub(super) fn command_counted(&mut self, msg: &HostMessage) -> Result<(Reply, u32)> {
        for attempt in 1..=self.options.command_attempts {
            let seq = self.send(msg)?;
            let until = Instant::now() + self.options.command_timeout;
            while Instant::now() < until {
                self.pump()?;
                while let Some((s, reply)) = self.replies.pop_front() {
                    if s == seq {
                        return Ok((reply, attempt));
                    }
                }
            }
        }
        Err(lost(format!(
            "no answer to {} after {} attempts",
            describe(msg),
            self.options.command_attempts
        )))
    }

    /// Encodes and writes one frame; returns its sequence number.
    pub(super) fn send(&mut self, msg: &HostMessage) -> Result<u32> {
        let mut wire = [0u8; MAX_FRAME_SIZE];
        let (seq, bytes) = self
            .tx
            .encode(msg, &mut wire)
            .map_err(|e| anyhow!("cannot encode {}: {e:?}", describe(msg)))?;
        let link = self.link.as_mut().ok_or_else(|| lost("not connected"))?;
        write_all_patiently(link.as_mut(), bytes, self.options.write_patience)
            .map_err(|e| lost(format!("cannot write {}: {e}", describe(msg))))?;
        Ok(seq)
    }

    /// One read: log the bytes, decode, dispatch, redraw the progress line.
    pub(super) fn pump(&mut self) -> Result<()> {
        let link = self.link.as_mut().ok_or_else(|| lost("not connected"))?;
        let n = match link.read(&mut self.read_buf) {
            Ok(0) => return Err(lost("the port reached end of file")),
            Ok(n) => n,
            Err(e) if is_quiet(&e) => 0,
            Err(e) => return Err(lost(format!("read error: {e}"))),
        };
        if n > 0 {
            self.log.append(&self.read_buf[..n])?;
            self.state.bytes += n as u64;
            let mut messages = Vec::new();
            for frame in self.rx.feed(&self.read_buf[..n]).flatten() {
                messages.push(frame.message);
            }
            for m in messages {
                self.dispatch(m);
            }
            let s = self.rx.stats();
            self.state.frames = s.frames_ok as u64;
            self.state.frames_lost = s.sequence_gaps as u64;
            self.state.bad_frames = s.failures() as u64;
            self.state.resyncs = s.resyncs as u64;
        }
        self.progress.tick(&self.state);
        Ok(())
    }

    pub(super) fn dispatch(&mut self, m: DeviceMessage) {
        match m {
            DeviceMessage::HelloAck(_) | DeviceMessage::VersionMismatch(_) => {
                self.hellos.push_back(m)
            }
            DeviceMessage::Ack(a) => self.replies.push_back((a.command_seq, Ok(()))),
            DeviceMessage::Nack(n) => self.replies.push_back((n.command_seq, Err(n.reason))),
            DeviceMessage::Phasors(p) => {
                self.state.phasor_frames += 1;
                self.state.speed_hz = Some(p.speed_hz as f64);
                self.state.revolutions = p.revolution as u64 + p.revolutions as u64;
            }
            DeviceMessage::Estimates(e) => {
                self.state.estimate_frames += 1;
                self.last_estimates = Some(e);
            }
            DeviceMessage::Status(s) => {
                // A change in the box's health is shown when it happens.
                let before = self.last_status.as_ref().map(|p| p.health);
                if s.health.needs_attention() && before != Some(s.health) {
                    self.progress
                        .note(&super::super::report::render_health(&s.health));
                }
                self.last_status = Some(s);
            }
        }
    }
}
