//! `plinth simulate`, `plinth signals`, `plinth predict`.

/// Command-line arguments of `plinth simulate`.
#[derive(clap::Args, Debug)]
pub struct SimulateArgs {}
/// Command-line arguments of `plinth signals`.
#[derive(clap::Args, Debug)]
pub struct SignalsArgs {}
/// Command-line arguments of `plinth predict`.
#[derive(clap::Args, Debug)]
pub struct PredictArgs {}

/// Runs `plinth simulate`.
pub fn simulate(_args: &SimulateArgs) -> anyhow::Result<()> {
    anyhow::bail!("`plinth simulate` is not available in this build yet")
}
/// Runs `plinth signals`.
pub fn signals(_args: &SignalsArgs) -> anyhow::Result<()> {
    anyhow::bail!("`plinth signals` is not available in this build yet")
}
/// Runs `plinth predict`.
pub fn predict(_args: &PredictArgs) -> anyhow::Result<()> {
    anyhow::bail!("`plinth predict` is not available in this build yet")
}
