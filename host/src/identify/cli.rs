//! `plinth identify`.

/// Command-line arguments of `plinth identify`.
#[derive(clap::Args, Debug)]
pub struct Args {}

/// Runs `plinth identify`.
pub fn run(_args: &Args) -> anyhow::Result<()> {
    anyhow::bail!("`plinth identify` is not available in this build yet")
}
