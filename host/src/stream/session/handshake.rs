//! Steps 2, 3 and 5 of a session: the handshake, the configuration and
//! `Start`, then `Stop` and the drain.

use super::*;

impl<'a> Session<'a> {
    pub(super) fn handshake(&mut self, started: Instant) -> Result<HelloAck> {
        let began = Instant::now();
        let mut deadline = began + self.options.handshake_timeout;
        if let Some(d) = self.options.duration {
            deadline = deadline.min(started + d);
        }
        self.hellos.clear();
        // Nonces of this handshake's Hellos: any of them may be answered.
        let mut nonces: Vec<u32> = Vec::new();
        loop {
            // Every Hello opens a new session: it is sequence number 0, with
            // a fresh nonce so that the box does not take a repeat for a
            // duplicated frame.
            let nonce: u32 = rand::random();
            nonces.push(nonce);
            self.tx.restart();
            self.send(&HostMessage::Hello(Hello {
                protocol_version: PROTOCOL_VERSION,
                host_nonce: nonce,
            }))?;
            let resend = Instant::now() + self.options.hello_interval;
            while Instant::now() < resend {
                self.pump()?;
                while let Some(m) = self.hellos.pop_front() {
                    match m {
                        DeviceMessage::HelloAck(ack) if nonces.contains(&ack.host_nonce) => {
                            if ack.protocol_version != PROTOCOL_VERSION {
                                bail!(
                                    "the box acknowledged Hello with protocol version {} but this host speaks {}",
                                    ack.protocol_version,
                                    PROTOCOL_VERSION
                                );
                            }
                            let v = ack.firmware_version;
                            if self.device.is_none() {
                                self.progress.note(&format!(
                                    "connected: firmware {}.{}.{}, protocol {}, room for {} channels and {} bearings, {} Hz",
                                    v.major,
                                    v.minor,
                                    v.patch,
                                    ack.protocol_version,
                                    ack.capabilities.max_channels,
                                    ack.capabilities.max_bearings,
                                    ack.capabilities.sample_rate_hz
                                ));
                            }
                            if ack.health.needs_attention() {
                                self.progress
                                    .note(&super::super::report::render_health(&ack.health));
                            }
                            self.device = Some(ack);
                            self.replies.clear();
                            return Ok(ack);
                        }
                        DeviceMessage::VersionMismatch(m) if nonces.contains(&m.host_nonce) => {
                            bail!(
                                "the box speaks protocol version {} and this host {}: update one of them",
                                m.device_protocol_version,
                                m.host_protocol_version
                            );
                        }
                        _ => {} // an answer to an older Hello
                    }
                }
            }
            if Instant::now() >= deadline {
                if self.device.is_none() {
                    return Err(anyhow::Error::new(NoAnswer {
                        port: self.connector.describe(),
                        seconds: began.elapsed().as_secs_f64(),
                    }));
                }
                return Err(lost(format!(
                    "no answer to Hello within {:.1} s",
                    self.options.handshake_timeout.as_secs_f64()
                )));
            }
        }
    }

    pub(super) fn configure_and_start(&mut self) -> Result<()> {
        // No `Stop` up front: a box that is not running needs none, and some
        // images end on `Stop` (the QEMU image exits). A box still running
        // refuses the first configuration command with `WrongState`; it is
        // stopped then and the command sent again.
        let mut stopped_once = false;
        let commands = self.config.device_commands(self.tables)?;
        let mut i = 0;
        let mut table_restarts = 0;
        while i < commands.len() {
            let cmd = &commands[i];
            let (answer, attempts) = self.command_counted(cmd)?;
            match answer {
                Ok(()) => i += 1,
                Err(NackReason::WrongState) if i == 0 && !stopped_once => {
                    stopped_once = true;
                    match self.command(&HostMessage::Stop)? {
                        Ok(()) | Err(NackReason::WrongState) => {}
                        Err(r) => bail!("the box refused Stop: {r:?}"),
                    }
                }
                // A resent chunk the box had already taken (its Ack was lost):
                // send this bearing's table again from its first chunk.
                Err(NackReason::TableOutOfOrder) if attempts > 1 && table_restarts < 5 => {
                    table_restarts += 1;
                    let HostMessage::BearingTable(chunk) = cmd else {
                        bail!("the box refused {} as out of order", describe(cmd));
                    };
                    let bearing = chunk.bearing;
                    while i > 0 {
                        match &commands[i - 1] {
                            HostMessage::BearingTable(c) if c.bearing == bearing => i -= 1,
                            _ => break,
                        }
                    }
                }
                Err(r) => bail!(
                    "the box refused {}: {r:?} (check the stream configuration {})",
                    describe(cmd),
                    self.config.bearings_csv.display()
                ),
            }
        }
        let (answer, attempts) = self.command_counted(&HostMessage::Start)?;
        match answer {
            Ok(()) => {}
            // A resent Start after a lost Ack finds the box running.
            Err(NackReason::WrongState) if attempts > 1 => {}
            Err(NackReason::SamplingUnavailable) => bail!(
                "the box refused Start: it cannot sample at its clock ({})",
                self.device
                    .map(|d| super::super::report::render_health(&d.health))
                    .unwrap_or_default()
            ),
            Err(r) => bail!("the box refused Start: {r:?}"),
        }
        if let Some(j) = self.journal.as_mut() {
            let r = self.replay.as_ref().map(|r| &r.plan);
            j.box_origin = r
                .and_then(|p| p.spans().get(self.acked_blocks))
                .map_or(j.acknowledged, |s| s.start);
            j.acknowledged = j.box_origin;
            j.started = true;
        }
        self.save_journal(true)?;
        Ok(())
    }

    pub(super) fn stop_and_drain(&mut self) -> Result<()> {
        let (answer, attempts) = self.command_counted(&HostMessage::Stop)?;
        match answer {
            Ok(()) => {}
            Err(NackReason::WrongState) if attempts > 1 => {}
            Err(r) => bail!("the box refused Stop: {r:?}"),
        }
        // The last frames (final estimates, status) follow the Ack. A box
        // that ends its run on Stop may close the line meanwhile: that ends
        // the drain, it is not a lost link.
        let until = Instant::now() + self.options.drain;
        while Instant::now() < until {
            match self.pump() {
                Ok(()) => {}
                Err(e) if e.is::<LinkLost>() => break,
                Err(e) => return Err(e),
            }
        }
        Ok(())
    }
}
