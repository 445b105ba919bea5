//! `aacmm`: the command-line front end. Each subcommand lives in its own file
//! under `commands/`; this file only parses and dispatches.

mod commands;
mod output;
mod paths;

use std::io::Write;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Calibration toolkit for articulated arm coordinate measuring machines.
///
/// Units are explicit: arm files state theirs, poses are degrees unless
/// `--angle-unit rad`, every length written is mm.
#[derive(Parser)]
#[command(name = "aacmm", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Forward kinematics: the probe position of every pose (CSV point,x,y,z in mm).
    Points(commands::points::Args),
    /// Simulate a calibration campaign with a known true arm.
    Simulate(commands::simulate::Args),
    /// Evaluate an arm on measured poses: single-point and length metrics.
    Evaluate(commands::evaluate::Args),
    /// Identifiability: which parameters the data can determine, and which to fix.
    Identify(commands::identify::Args),
    /// Calibrate an arm from touches and reference lengths.
    Calibrate(commands::calibrate::Args),
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return usage(&e),
    };
    let result = match cli.command {
        Command::Points(args) => commands::points::run(args),
        Command::Simulate(args) => commands::simulate::run(args),
        Command::Evaluate(args) => commands::evaluate::run(args),
        Command::Identify(args) => commands::identify::run(args),
        Command::Calibrate(args) => commands::calibrate::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => ExitCode::from(output::exit_code(&e)),
    }
}

/// Help, version or a usage error, written (and checked) like any output:
/// help and version on stdout, usage errors on stderr.
fn usage(e: &clap::Error) -> ExitCode {
    let written = e.print().and_then(|()| {
        if e.use_stderr() {
            std::io::stderr().flush()
        } else {
            std::io::stdout().flush()
        }
    });
    match written {
        Ok(()) => ExitCode::from(u8::try_from(e.exit_code()).unwrap_or(1)),
        Err(_) if e.use_stderr() => ExitCode::FAILURE,
        Err(w) => ExitCode::from(output::exit_code(&output::stdout_error(w))),
    }
}
