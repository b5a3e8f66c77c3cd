//! `plinth paper` (not yet implemented).

/// Command-line arguments of `plinth paper`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs `plinth paper`.
pub fn run(_args: &Args) -> anyhow::Result<()> {
    anyhow::bail!("`plinth paper` is not available in this build yet")
}
