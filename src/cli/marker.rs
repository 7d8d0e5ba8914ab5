use anyhow::Result;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct MarkerArgs {}

pub fn run(_args: MarkerArgs) -> Result<ExitCode> {
    anyhow::bail!("'marker' is not implemented yet")
}
