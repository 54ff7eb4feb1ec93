//! `handeye`: hand–eye calibration from the command line. See `handeye --help`.
//!
//! Results go to stdout as JSON (JSON Lines for streams); messages and progress to stderr.
//! Exit codes: 0 success, 2 bad input (file, line and field named), 3 valid input from which X
//! cannot be determined.

mod advise;
mod bench;
mod calibrate;
mod demo;
mod experiment;
mod figures;
mod input;
mod inspect;
mod online;
mod output;
mod simulate;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Hand–eye calibration (AX = XB): batch solvers and online calibration with adaptive motion
/// selection.
#[derive(Parser)]
#[command(name = "handeye", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Solve X from a recording with one of the batch solvers.
    Calibrate(calibrate::Args),
    /// Calibrate online, one pose pair at a time, printing each calibration as it happens.
    Online(online::Args),
    /// List the topics, types, counts and tf tree of a ROS 2 recording, to choose its frames.
    Inspect(inspect::Args),
    /// Say what to record next: the least determined directions of X and the motions that
    /// would shrink its uncertainty most.
    Advise(advise::Args),
    /// Write a simulated series (the paper's protocol) and its truth.
    Simulate(simulate::Args),
    /// Run the paper's simulated experiments and write tables and figures.
    Experiment(experiment::Args),
    /// Simulate a stream, calibrate it online three ways and compare with the true X.
    Demo(demo::Args),
    /// Time every solver and the online calibrator in-process.
    Bench(bench::Args),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Calibrate(a) => calibrate::run(a),
        Command::Online(a) => online::run(a),
        Command::Inspect(a) => inspect::run(a),
        Command::Advise(a) => advise::run(a),
        Command::Simulate(a) => simulate::run(a),
        Command::Experiment(a) => experiment::run(a),
        Command::Demo(a) => demo::run(a),
        Command::Bench(a) => bench::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", output::error_message(&e));
            ExitCode::from(output::exit_code(&e))
        }
    }
}
