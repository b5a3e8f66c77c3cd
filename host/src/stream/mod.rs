//! `plinth stream` (not yet implemented).

/// Command-line arguments of `plinth stream`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs `plinth stream`.
pub fn run(_args: &Args) -> anyhow::Result<()> {
    anyhow::bail!("`plinth stream` is not available in this build yet")
}
