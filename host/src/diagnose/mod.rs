//! `plinth diagnose` (not yet implemented).

/// Command-line arguments of `plinth diagnose`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs `plinth diagnose`.
pub fn run(_args: &Args) -> anyhow::Result<()> {
    anyhow::bail!("`plinth diagnose` is not available in this build yet")
}
