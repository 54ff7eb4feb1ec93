//! Runs the paper's three simulated experiments with few series and prints each method's mean
//! errors (`handeye experiment` prints the full tables).
//!
//! `cargo run --release -p handeye --example experiment_quick`

use handeye::experiment::{Experiment, ExperimentConfig, ExperimentReport, run_experiment};

fn main() -> Result<(), handeye::Error> {
    for experiment in [
        Experiment::Accuracy,
        Experiment::Adaptability,
        Experiment::Realtime,
    ] {
        let mut config = ExperimentConfig::for_experiment(experiment);
        config.series = std::env::args()
            .nth(1)
            .and_then(|s| s.parse().ok())
            .unwrap_or(config.series);
        config.batch = std::env::var("NO_BATCH").is_err();
        let (ExperimentReport::Accuracy(report)
        | ExperimentReport::Adaptability(report)
        | ExperimentReport::Realtime(report)) = run_experiment(experiment, &config, || {})?
        else {
            unreachable!("the paper's experiments report one summary per method")
        };
        println!("{experiment} ({} series):", config.series);
        for m in &report.methods {
            println!(
                "  {:<14} calibrations {:6.1}  rotation {:.3}°  t_rel {:.4}",
                m.method.to_string() + if m.batch { " (batch)" } else { "" },
                m.calibrations_mean,
                m.rot_deg_mean,
                m.trans_rel_mean
            );
        }
    }
    Ok(())
}
