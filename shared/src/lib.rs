//! Plinth's `no_std` core, shared by the field box firmware and the host tool.
#![no_std]
#![forbid(unsafe_code)]
