//! Keyphasor-synchronous 1X phasor extraction (not yet implemented).
