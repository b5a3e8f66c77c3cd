//! Step 4 of a session: the replay's sample blocks, paced by their
//! acknowledgements (go-back-N), and the journal of its position.

use super::*;

impl<'a> Session<'a> {
    /// Sends the replay from the first unacknowledged block (go-back-N).
    pub(super) fn replay_blocks(&mut self) -> Result<()> {
        let Some(replay) = self.replay.as_ref() else {
            return Ok(());
        };
        let total = replay.plan.len();
        let origin = self.journal.as_ref().map_or(0, |j| j.box_origin);
        let window = self.options.window.max(1);
        let mut next = self.acked_blocks;
        // Block sends by sequence number: (block, rewind round it was sent in).
        let mut sent: HashMap<u32, (usize, u32)> = HashMap::new();
        let mut round = 0u32;
        let mut last_progress = Instant::now();
        // A Ping sent when acknowledgements are late: (its seq, when, blocks
        // sent before it). The box answers in order, so once its Ack is in,
        // a block sent before it and still unacknowledged was really lost.
        let mut probe: Option<(u32, Instant, usize)> = None;
        let mut stalls = 0u32;
        self.replies.clear();
        while self.acked_blocks < total {
            while next < total && next < self.acked_blocks + window {
                let replay = self.replay.as_ref().ok_or_else(|| anyhow!("no replay"))?;
                let block = replay.plan.block(replay.source, next, origin);
                let seq = self.send(&HostMessage::Samples(block))?;
                sent.insert(seq, (next, round));
                next += 1;
            }
            self.pump()?;
            let mut rewind = false;
            while let Some((seq, reply)) = self.replies.pop_front() {
                if let Some((probe_seq, _, sent_before)) = probe {
                    if seq == probe_seq {
                        probe = None;
                        if self.acked_blocks < sent_before {
                            rewind = true;
                        } else {
                            last_progress = Instant::now();
                        }
                        continue;
                    }
                }
                let Some(&(block, sent_in)) = sent.get(&seq) else {
                    continue;
                };
                match reply {
                    // The box processes blocks in order: an Ack covers every
                    // block before it too.
                    Ok(()) => {
                        if block >= self.acked_blocks {
                            self.acked_blocks = block + 1;
                            stalls = 0;
                            last_progress = Instant::now();
                            next = next.max(self.acked_blocks);
                        }
                    }
                    Err(NackReason::WrongState) => return Err(anyhow::Error::new(NotRunning)),
                    // Go-back-N: the box refused this block (a block before
                    // it went missing, or its queue was full), so it refuses
                    // every later one too; one rewind resends them all.
                    // Refusals of sends from before the last rewind are of
                    // blocks already sent again.
                    Err(NackReason::QueueFull) | Err(NackReason::BadBlock) => {
                        if block >= self.acked_blocks && sent_in == round {
                            rewind = true;
                        }
                    }
                    Err(r) => {
                        let start = self
                            .replay
                            .as_ref()
                            .and_then(|p| p.plan.spans().get(block))
                            .map_or(0, |s| s.start);
                        bail!("the box refused the sample block at sample {start}: {r:?}");
                    }
                }
            }
            let waiting = next > self.acked_blocks;
            if waiting && !rewind && last_progress.elapsed() > self.options.block_timeout {
                match probe {
                    None => {
                        let seq = self.send(&HostMessage::Ping)?;
                        probe = Some((seq, Instant::now(), next));
                    }
                    // The Ping or its Ack was lost too: resend blindly.
                    Some((_, t, _)) if t.elapsed() > self.options.block_timeout * 2 => {
                        probe = None;
                        rewind = true;
                    }
                    Some(_) => {}
                }
            }
            if rewind {
                stalls += 1;
                if stalls > self.options.max_stalls {
                    return Err(lost(format!(
                        "the box acknowledged no sample block after {} resends",
                        self.options.max_stalls
                    )));
                }
                self.state.resent_blocks += (next - self.acked_blocks) as u64;
                next = self.acked_blocks;
                round = round.wrapping_add(1);
                sent.retain(|_, (b, _)| *b >= self.acked_blocks);
                last_progress = Instant::now();
                probe = None;
                // Give a full queue time to drain.
                let until = Instant::now() + Duration::from_millis(2);
                while Instant::now() < until {
                    self.pump()?;
                }
            }
            sent.retain(|_, (b, _)| *b >= self.acked_blocks.saturating_sub(window));
            self.state.replay = Some((self.acked_blocks as u64, total as u64));
            if let Some(j) = self.journal.as_mut() {
                let replay = self.replay.as_ref().map(|r| &r.plan);
                j.acknowledged = replay
                    .and_then(|p| p.spans().get(self.acked_blocks))
                    .map_or(replay.map_or(0, |p| p.sample_vectors()), |s| s.start);
            }
            self.save_journal(false)?;
        }
        self.save_journal(true)?;
        Ok(())
    }

    pub(super) fn save_journal(&mut self, now: bool) -> Result<()> {
        if !now && self.journal_written.elapsed() < Duration::from_millis(200) {
            return Ok(());
        }
        if let Some(j) = &self.journal {
            j.write(&self.out_dir)?;
            self.journal_written = Instant::now();
        }
        Ok(())
    }
}
