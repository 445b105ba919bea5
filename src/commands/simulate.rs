//! `aacmm simulate` (being written).

use anyhow::Result;

/// Simulate a calibration campaign.
#[derive(clap::Args)]
pub struct Args {}

pub fn run(_args: Args) -> Result<()> {
    anyhow::bail!("simulate is not implemented yet")
}
