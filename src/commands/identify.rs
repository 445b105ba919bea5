//! `aacmm identify`: which parameters the data can determine, how well, and
//! which to fix (see `aacmm_core::identify` for the method; the library's
//! `IdentifyReport` is what is printed and written).

use std::path::PathBuf;

use aacmm_core::calibrate::CalibrationError;
use aacmm_core::io::source_name;
use anyhow::Result;

use super::shared_flags::{FitInput, flag_error};
use crate::output::Stdout;
use crate::paths::check_output_file;

/// Identifiability of the arm's parameters from the data.
#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    fit: FitInput,
    /// Also write everything as JSON.
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Write over earlier results: an output file that exists, or an
    /// output directory holding results of an aacmm command (this command's
    /// files are overwritten; nothing is deleted).
    #[arg(long)]
    force: bool,
}

pub fn run(args: Args) -> Result<()> {
    if let Some(json) = &args.json {
        check_output_file("--json", json, &args.fit.paths(), args.force)?;
    }
    // Bad noise flags are refused before any file is read.
    args.fit.noise().check().map_err(flag_error)?;
    let report = args.fit.request()?.identify().map_err(|e| match e {
        CalibrationError::Option(_) => flag_error(e),
        // Each names the input at fault itself.
        e if e.names_its_input() => anyhow::Error::new(e),
        other => super::noise_flags(
            anyhow::Error::new(other).context(source_name(&args.fit.arm)),
            &args.fit,
        ),
    })?;
    let mut out = Stdout::new();
    out.print(report.summary())?;
    out.finish()?;
    if let Some(path) = &args.json {
        super::write_json(path, &report)?;
    }
    Ok(())
}
