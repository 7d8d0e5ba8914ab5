use anyhow::Result;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct SimulateArgs {}

pub fn run(_args: SimulateArgs) -> Result<ExitCode> {
    anyhow::bail!("'simulate' is not implemented yet")
}
