use anyhow::Result;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct IdsArgs {}

pub fn run(_args: IdsArgs) -> Result<ExitCode> {
    anyhow::bail!("'ids' is not implemented yet")
}
