//! `handeye experiment`: the paper's simulated experiments (SPEC sec. 6), with tables and figures.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Args as ClapArgs;
use handeye::experiment::{
    Experiment, ExperimentConfig, TrackingConfig, markdown_table, run_experiment, run_tracking,
    tracking_table,
};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::figures::{write_figures, write_text, write_tracking_figures};
use crate::values;

/// Options of `handeye experiment`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Which experiment.
    #[arg(value_parser = ["accuracy", "adaptability", "realtime", "tracking", "advice", "all"])]
    which: String,
    /// Number of series (default: the paper's, 20 / 100 / 50).
    #[arg(long, value_parser = values::count(1, values::MAX_SERIES))]
    series: Option<usize>,
    /// Seed of the run.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Directory for the tables (Markdown, JSON) and figures (SVG, PNG).
    #[arg(long, default_value = "results")]
    out: PathBuf,
}

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    let experiments: Vec<Experiment> = match args.which.as_str() {
        "all" => Experiment::ALL.to_vec(),
        "tracking" | "advice" => Vec::new(),
        other => vec![other.parse()?],
    };
    std::fs::create_dir_all(&args.out)
        .with_context(|| format!("cannot create {}", args.out.display()))?;
    for experiment in experiments {
        let mut config = ExperimentConfig::for_experiment(experiment);
        config.seed = args.seed;
        if let Some(n) = args.series {
            config.series = n;
        }
        let bar = series_bar(config.series, experiment.name());
        let report = run_experiment(experiment, &config, || bar.inc(1))?;
        bar.finish_and_clear();
        let table = markdown_table(&report);
        let figures = write_figures(&report, &args.out)?;
        publish(&args.out, experiment.name(), &table, &report, &figures)?;
    }
    if args.which == "all" || args.which == "tracking" {
        let mut config = TrackingConfig {
            seed: args.seed,
            ..TrackingConfig::default()
        };
        if let Some(n) = args.series {
            config.series = n;
        }
        let bar = series_bar(config.series, "tracking");
        let report = run_tracking(&config, || bar.inc(1))?;
        bar.finish_and_clear();
        let table = tracking_table(&report);
        let figures = write_tracking_figures(&report, &args.out)?;
        publish(&args.out, "tracking", &table, &report, &figures)?;
    }
    if args.which == "all" || args.which == "advice" {
        let report = handeye::advice::closed_loop(args.series.unwrap_or(20), args.seed);
        publish(&args.out, "advice", &advice_table(&report), &report, &[])?;
    }
    Ok(())
}

/// A progress bar over the series on stderr (hidden when stderr is not a terminal).
fn series_bar(series: usize, name: &str) -> ProgressBar {
    let bar = ProgressBar::new(series as u64);
    if !std::io::stderr().is_terminal() {
        bar.set_draw_target(ProgressDrawTarget::hidden());
    }
    bar.set_style(
        ProgressStyle::with_template("{msg:>12} [{bar:40}] {pos}/{len} series")
            .unwrap_or_else(|_| ProgressStyle::default_bar()),
    );
    bar.set_message(name.to_string());
    bar
}

/// The closed loop of the advice as Markdown.
fn advice_table(r: &handeye::advice::ClosedLoop) -> String {
    let cell = |n: Option<usize>| n.map_or(format!("> {}", r.most), |n| n.to_string());
    format!(
        "### advice ({} series of the paper's protocol, from its first 3 poses)\n\nPoses needed to reach a rotation one-sigma of {:.4}° (what the paper's walk reaches after {} poses), median over the series:\n\n| the paper's walk | turns about random axes | the advice |\n|---|---|---|\n| {} | {} | {} |\n",
        r.series,
        r.target_rotation_deg,
        r.walk_poses,
        cell(r.median_poses[0]),
        cell(r.median_poses[1]),
        cell(r.median_poses[2]),
    )
}

/// Prints the table and writes `<name>.md` and `<name>.json` beside the figures already written.
fn publish(
    out: &Path,
    name: &str,
    table: &str,
    report: &impl serde::Serialize,
    figures: &[PathBuf],
) -> Result<()> {
    crate::outln!("{table}")?;
    let stem = out.join(name);
    write_text(&stem.with_extension("md"), table)?;
    write_text(
        &stem.with_extension("json"),
        &(serde_json::to_string_pretty(report)? + "\n"),
    )?;
    for path in figures {
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}
