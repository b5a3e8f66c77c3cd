//! `plinth demo` (not yet implemented).

/// Command-line arguments of `plinth demo`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs `plinth demo`.
pub fn run(_args: &Args) -> anyhow::Result<()> {
    anyhow::bail!("`plinth demo` is not available in this build yet")
}
