//! Links the image for the MCU: puts the workspace's `memory.x` where
//! cortex-m-rt's `link.x` finds it and passes the linker scripts to the bins.
//!
//! The link arguments live here rather than in `.cargo/config.toml` so that
//! `cargo build -p plinth-firmware --target thumbv7em-none-eabihf` works from
//! the workspace root as well as from `firmware/`.

use std::{env, fs, path::PathBuf};

fn main() {
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rerun-if-changed=../../memory.x");
    // Only the bare-metal target links against memory.x; the host build of
    // the library (simulated-hardware tests) needs nothing.
    if env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    let out = PathBuf::from(env::var_os("OUT_DIR").expect("cargo sets OUT_DIR"));
    let manifest =
        PathBuf::from(env::var_os("CARGO_MANIFEST_DIR").expect("cargo sets CARGO_MANIFEST_DIR"));
    let memory = manifest.join("..").join("..").join("memory.x");
    if let Err(e) = fs::copy(&memory, out.join("memory.x")) {
        panic!("cannot copy {} to OUT_DIR: {e}", memory.display());
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rustc-link-arg-bins=--nmagic");
    println!("cargo:rustc-link-arg-bins=-Tlink.x");
    println!("cargo:rustc-link-arg-bins=-Tdefmt.x");
}
