use anyhow::Result;
use std::process::ExitCode;

#[derive(Debug, clap::Args)]
pub struct SheetArgs {}

pub fn run(_args: SheetArgs) -> Result<ExitCode> {
    anyhow::bail!("'sheet' is not implemented yet")
}
