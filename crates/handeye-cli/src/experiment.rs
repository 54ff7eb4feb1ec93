//! `handeye experiment`: the paper's simulated experiments (SPEC sec. 6) and the tracking and
//! advice studies, with tables and figures.

use std::io::IsTerminal;
use std::path::{Path, PathBuf};

use anyhow::{Context, Result};
use clap::Args as ClapArgs;
use clap::builder::PossibleValuesParser;
use handeye::experiment::{Experiment, ExperimentConfig, ExperimentReport, run_experiment};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

use crate::figures::{write_figures, write_text};
use crate::values;

/// Options of `handeye experiment`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Which experiment: one of the paper's, the tracking or the advice study, or all of them.
    #[arg(value_parser = which())]
    which: String,
    /// Number of series (default: the paper's, 20 / 100 / 50; 20 for tracking and advice).
    #[arg(long, value_parser = values::count(1, values::MAX_SERIES))]
    series: Option<usize>,
    /// Seed of the run.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Directory for the tables (Markdown, JSON) and figures (SVG, PNG).
    #[arg(long, default_value = "results")]
    out: PathBuf,
}

/// `which` beyond the experiments themselves: all of them.
const ALL: &str = "all";

/// The names of `which`: the experiments (the paper's, then the studies), then `all`.
fn which() -> PossibleValuesParser {
    PossibleValuesParser::new(Experiment::ALL.iter().map(|e| e.name()).chain([ALL]))
}

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    let experiments: Vec<Experiment> = if args.which == ALL {
        Experiment::ALL.to_vec()
    } else {
        vec![args.which.parse()?]
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
        crate::tell!("wrote {}", path.display());
    }
    Ok(())
}

/// The report as Markdown: the experiment's table(s).
fn markdown_table(report: &ExperimentReport) -> String {
    match report {
        ExperimentReport::Accuracy(report)
        | ExperimentReport::Adaptability(report)
        | ExperimentReport::Realtime(report) => {
            let mut out = format!(
                "### {} ({} series × {} poses, seed {})\n\n| method | series with calibration | calibrations (mean / median) | ‖ΔR‖_F | rotation (°) | t_rel | time per calibration (µs) |\n|---|---|---|---|---|---|---|\n",
                report.experiment,
                report.config.series,
                report.config.sim.poses,
                report.config.seed
            );
            for m in &report.methods {
                let name = if m.batch {
                    format!("batch `{}` (all poses)", m.method)
                } else {
                    format!("**{}**", m.method)
                };
                out += &format!(
                    "| {name} | {}/{} | {:.2} / {:.1} | {:.4} | {:.3} | {:.4} | {:.2} |\n",
                    m.series_with_calibration,
                    m.series,
                    m.calibrations_mean,
                    m.calibrations_median,
                    m.rot_fro_mean,
                    m.rot_deg_mean,
                    m.trans_rel_mean,
                    m.time_per_calibration_s * 1e6
                );
            }
            out
        }
        ExperimentReport::Tracking(report) => {
            let mut out = format!(
                "### tracking ({} series × {} poses, seed {})\n\n| poses |",
                report.config.series, report.config.poses, report.config.seed
            );
            for c in &report.curves {
                out += &format!(" {} ‖ΔR‖_F / t_rel |", c.method);
            }
            out += "\n|---|";
            out += &"---|".repeat(report.curves.len());
            out += "\n";
            let n = report.curves.first().map_or(0, |c| c.poses.len());
            for k in (0..n).filter(|k| (k + 1) % 2 == 0 || *k == 0) {
                out += &format!("| {} |", report.curves[0].poses[k]);
                for c in &report.curves {
                    out += &format!(" {:.4} / {:.3} |", c.rot_fro[k], c.trans_rel[k]);
                }
                out += "\n";
            }
            out += &format!(
                "\n### change detection ({} series × {} poses, jump at pose {})\n\n| jump | detected within 30 poses | median delay (poses) | false alarms / stationary poses | final error vs new X (°) |\n|---|---|---|---|---|\n",
                report.config.series,
                report.config.jump_poses,
                report.config.jump_poses / 2
            );
            for d in &report.detection {
                out += &format!(
                    "| {}° / {} mm | {:.0}% | {} | {} / {} | {:.3} |\n",
                    d.rotation_deg,
                    d.translation,
                    100.0 * d.detected_within_30,
                    d.median_delay.map_or("–".to_string(), |m| m.to_string()),
                    d.false_alarms,
                    d.stationary_poses,
                    d.final_rot_deg
                );
            }
            out
        }
        ExperimentReport::Advice(r) => {
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
    }
}
