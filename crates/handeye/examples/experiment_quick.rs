//! Runs the paper's three simulated experiments with few series and prints their tables.
//!
//! `cargo run --release -p handeye --example experiment_quick`

use handeye::online::experiment::{Experiment, ExperimentConfig, markdown_table, run_experiment};

fn main() -> Result<(), handeye::Error> {
    for experiment in Experiment::ALL {
        let mut config = ExperimentConfig::for_experiment(experiment);
        config.series = std::env::args()
            .nth(1)
            .and_then(|s| s.parse().ok())
            .unwrap_or(config.series);
        config.batch = std::env::var("NO_BATCH").is_err();
        let report = run_experiment(experiment, &config, || {})?;
        println!("{}", markdown_table(&report));
    }
    Ok(())
}
