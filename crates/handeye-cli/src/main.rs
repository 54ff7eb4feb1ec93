//! `handeye`: hand–eye calibration from the command line. See `handeye --help`.
//!
//! Results go to stdout as JSON (JSON Lines for streams); messages and progress to stderr.
//! Exit codes: 0 success, 2 bad input (file, line and field named), 3 valid input from which X
//! cannot be determined.

mod advise;
mod bench;
mod calibrate;
mod demo;
mod detect;
mod experiment;
mod faces;
mod figures;
mod input;
mod inspect;
#[cfg(feature = "ros2")]
mod node;
mod online;
mod output;
mod publish;
mod report;
mod simulate;
mod values;
mod verify;

use std::process::ExitCode;

use clap::{Parser, Subcommand};

/// Hand–eye calibration (AX = XB): batch solvers and online calibration with adaptive motion
/// selection.
#[derive(Parser)]
#[command(name = "handeye", version, about, long_about = None, after_help = EXIT_CODES)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

/// The exit codes, in every command's `--help`.
const EXIT_CODES: &str = "Exit codes: 0 success (also when the reader of a pipe closes it early); 1 an unexpected failure (a file that cannot be written); 2 bad input or an out-of-range option (the file, line and field, or the flag, named); 3 valid input from which X cannot be determined (degenerate motions, or data that fit far better read another way: the message says what to do; `verify`: the recording cannot tell); 4 `verify`: the saved X does not fit the recording; 5 with `calibrate --strict` or `verify --strict`, an X whose verdict is questionable (printed, with its cautions).";

#[derive(Subcommand)]
enum Command {
    /// Solve X from a recording with one of the batch solvers.
    #[command(after_help = EXIT_CODES, allow_negative_numbers = true)]
    Calibrate(calibrate::Args),
    /// Calibrate online, one pose pair at a time, printing each calibration as it happens.
    #[command(after_help = EXIT_CODES, allow_negative_numbers = true)]
    Online(online::Args),
    /// List the topics, types, counts and tf tree of a ROS 2 recording, to choose its frames.
    #[command(after_help = EXIT_CODES, allow_negative_numbers = true)]
    Inspect(inspect::Args),
    /// Find a chessboard's or an AprilTag's corners in a recording's images and write the
    /// records with `detections` (JSON Lines) that `calibrate` reads.
    #[command(after_help = EXIT_CODES, allow_negative_numbers = true)]
    Detect(detect::Args),
    /// Say what to record next: the least determined directions of X and the motions that
    /// would shrink its uncertainty most.
    #[command(after_help = EXIT_CODES, allow_negative_numbers = true)]
    Advise(advise::Args),
    /// Check a saved X against a new recording: exit 0 when it fits (consistent), 4 when it does
    /// not (the camera moved, another rig, or the saved X was wrong), 3 when the recording cannot
    /// tell.
    #[command(after_help = EXIT_CODES, allow_negative_numbers = true)]
    Verify(verify::Args),
    /// Write a simulated series (the paper's protocol) and its truth.
    #[command(after_help = EXIT_CODES, allow_negative_numbers = true)]
    Simulate(simulate::Args),
    /// Run the paper's simulated experiments and write tables and figures.
    #[command(after_help = EXIT_CODES, allow_negative_numbers = true)]
    Experiment(experiment::Args),
    /// Simulate a stream, calibrate it online three ways and compare with the true X.
    #[command(after_help = EXIT_CODES, allow_negative_numbers = true)]
    Demo(demo::Args),
    /// Time every solver and the online calibrator in-process.
    #[command(after_help = EXIT_CODES, allow_negative_numbers = true)]
    Bench(bench::Args),
    /// A live ROS 2 node: calibrate online from /tf and the target's pose topic, publish X on
    /// /tf_static and every estimate on /handeye/status.
    #[cfg(feature = "ros2")]
    #[command(after_help = EXIT_CODES, allow_negative_numbers = true)]
    Node(node::Args),
}

impl Command {
    /// The command's name, as typed (a remedy is worded in its flags).
    fn name(&self) -> &'static str {
        match self {
            Self::Calibrate(_) => "calibrate",
            Self::Online(_) => "online",
            Self::Inspect(_) => "inspect",
            Self::Detect(_) => "detect",
            Self::Advise(_) => "advise",
            Self::Verify(_) => "verify",
            Self::Simulate(_) => "simulate",
            Self::Experiment(_) => "experiment",
            Self::Demo(_) => "demo",
            Self::Bench(_) => "bench",
            #[cfg(feature = "ros2")]
            Self::Node(_) => "node",
        }
    }
}

fn main() -> ExitCode {
    output::quiet_on_closed_pipe();
    let cli = Cli::parse();
    let command = cli.command.name();
    let result = match cli.command {
        Command::Calibrate(a) => calibrate::run(a),
        Command::Online(a) => online::run(a),
        Command::Inspect(a) => inspect::run(a),
        Command::Detect(a) => detect::run(a),
        Command::Advise(a) => advise::run(a),
        Command::Verify(a) => verify::run(a),
        Command::Simulate(a) => simulate::run(a),
        Command::Experiment(a) => experiment::run(a),
        Command::Demo(a) => demo::run(a),
        Command::Bench(a) => bench::run(a),
        #[cfg(feature = "ros2")]
        Command::Node(a) => node::run(a),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) if output::is_closed_pipe(&e) => ExitCode::SUCCESS,
        Err(e) => {
            crate::tell!("error: {}", faces::error(&e, command));
            ExitCode::from(output::exit_code(&e))
        }
    }
}
