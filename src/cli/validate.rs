use anyhow::Result;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct ValidateArgs {}

pub fn run(_args: ValidateArgs) -> Result<ExitCode> {
    anyhow::bail!("'validate' is not implemented yet")
}
