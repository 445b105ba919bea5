//! `aacmm`: the command-line front end. Each subcommand lives in its own file
//! under `commands/`; this file only parses and dispatches.

mod commands;
mod output;
mod paths;

use std::io::Write;
use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

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

/// Negative numbers are values, not flags, in every subcommand: `--x -0.5`
/// works as `--x=-0.5` does (no option of aacmm is a digit).
#[derive(Subcommand)]
enum Command {
    /// Forward kinematics: the probe position of every pose of a poses or positions file (CSV point,x,y,z in mm).
    #[command(allow_negative_numbers = true)]
    Points(commands::points::Args),
    /// Simulate a calibration campaign with a known true arm.
    #[command(allow_negative_numbers = true)]
    Simulate(commands::simulate::Args),
    /// Evaluate an arm on measured poses (single-point and length metrics) or at reference positions (3-D errors).
    #[command(allow_negative_numbers = true)]
    Evaluate(commands::evaluate::Args),
    /// Qualify a probe on a reference sphere: its tip offset and effective ball diameter, the arm's geometry held.
    #[command(allow_negative_numbers = true)]
    Probe(commands::probe::Args),
    /// Identifiability: which parameters the data can determine, and which to fix.
    #[command(allow_negative_numbers = true)]
    Identify(commands::identify::Args),
    /// Calibrate an arm from touches, reference lengths and/or reference positions.
    #[command(
        allow_negative_numbers = true,
        after_help = "Exit status: 0 for a usable calibration; 1 for an error, or for a \
                      calibration that is not usable — the solver did not reach a confirmed \
                      minimum, the arm is not the nominal arm's geometry (a mirror image, a \
                      collapsed arm, a unit mistake), or (unless --accept-poor-fit) its χ² is \
                      far outside the stated noise or it is worse than the nominal on its own \
                      data; the files are then written for inspection and calibration.json's \
                      /verdict says why; 2 for a command line that cannot be parsed."
    )]
    Calibrate(Box<commands::calibrate::Args>),
    /// Import a robot's URDF: the chain from a base link to a tip link as an arm file.
    #[command(allow_negative_numbers = true)]
    Import(commands::import::Args),
    /// Export an arm (a calibrated one) as URDF or as a D-H table.
    Export(commands::export::Args),
    /// Experiment design: which poses to measure for the best calibration.
    #[command(
        allow_negative_numbers = true,
        after_help = "Exit status: 0 for a plan whose chosen rows determine every free \
                      parameter; 1 for an error, or for a plan whose chosen rows do not (its \
                      files are written all the same, and the message says how many rows do); \
                      2 for a command line that cannot be parsed."
    )]
    Plan(commands::plan::Args),
    /// Acceptance tests of a measuring arm (ISO 10360-12 / ASME B89.4.22): P_Size, P_Form, L_Dia, E_Uni, SPAT, decided against MPEs.
    #[command(
        allow_negative_numbers = true,
        after_help = "Exit status: 0 when every test with a stated MPE passes (|value| ≤ MPE − U, \
                      ISO 14253-1), or when no MPE is stated (the figures are printed and the \
                      output says that nothing was decided); 1 for an error, or when a test \
                      with a stated MPE fails or is inconclusive, or an MPE is stated for a test \
                      no data performs (each named); 2 for a command line that cannot be parsed."
    )]
    Verify(Box<commands::verify::Args>),
}

fn main() -> ExitCode {
    let matches = match Cli::command().try_get_matches() {
        Ok(m) => m,
        Err(e) => return usage(&e),
    };
    if let Err(e) = one_stdin(&Cli::command(), &matches) {
        return ExitCode::from(output::exit_code(&e));
    }
    let cli = match Cli::from_arg_matches(&matches) {
        Ok(cli) => cli,
        Err(e) => return usage(&e),
    };
    let result = match cli.command {
        Command::Points(args) => commands::points::run(args),
        Command::Simulate(args) => commands::simulate::run(args),
        Command::Evaluate(args) => commands::evaluate::run(args),
        Command::Probe(args) => commands::probe::run(args),
        Command::Identify(args) => commands::identify::run(args),
        Command::Calibrate(args) => commands::calibrate::run(*args),
        Command::Import(args) => commands::import::run(args),
        Command::Export(args) => commands::export::run(args),
        Command::Plan(args) => commands::plan::run(args),
        Command::Verify(args) => commands::verify::run(*args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => ExitCode::from(output::exit_code(&e)),
    }
}

/// Flags whose path is written, not read: `-` there is standard output.
const OUTPUT_FLAGS: [&str; 3] = ["out", "json", "report"];

/// Refuses `-` (standard input) for more than one input file, before any
/// is read: the second would otherwise find standard input used up and
/// report it as an empty file.
fn one_stdin(cli: &clap::Command, matches: &clap::ArgMatches) -> anyhow::Result<()> {
    let Some((name, sub)) = matches.subcommand() else {
        return Ok(());
    };
    let Some(command) = cli.find_subcommand(name) else {
        return Ok(());
    };
    let path = clap::builder::ValueParser::path_buf().type_id();
    let stdin: Vec<String> = command
        .get_arguments()
        .filter(|a| a.get_value_parser().type_id() == path)
        .filter(|a| !OUTPUT_FLAGS.contains(&a.get_id().as_str()))
        .filter(|a| {
            sub.get_raw(a.get_id().as_str())
                .is_some_and(|mut v| v.any(|v| v == "-"))
        })
        .map(|a| format!("--{}", a.get_long().unwrap_or(a.get_id().as_str())))
        .collect();
    if stdin.len() > 1 {
        anyhow::bail!(
            "{}: each is `-` (standard input), which can be read once; give all but one as a file",
            stdin.join(" and ")
        );
    }
    Ok(())
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
