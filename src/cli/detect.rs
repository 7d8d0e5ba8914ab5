use anyhow::Result;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct DetectArgs {}

pub fn run(_args: DetectArgs) -> Result<ExitCode> {
    anyhow::bail!("'detect' is not implemented yet")
}
