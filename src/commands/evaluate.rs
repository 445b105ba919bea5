//! `aacmm evaluate` (being written).

use anyhow::Result;

/// Evaluate an arm.
#[derive(clap::Args)]
pub struct Args {}

pub fn run(_args: Args) -> Result<()> {
    anyhow::bail!("evaluate is not implemented yet")
}
