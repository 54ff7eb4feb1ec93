//! The experiments with few series: the paper's (the report's fields and the direction of each
//! claim of SPEC sec. 6 / issue 4), the tracking study, and the settings no study runs with.

use handeye::experiment::{Experiment, ExperimentConfig, ExperimentReport, run_experiment};
use serde_json::Value;

fn run(experiment: Experiment, series: usize) -> Value {
    let config = ExperimentConfig {
        series,
        ..ExperimentConfig::for_experiment(experiment)
    };
    let report = run_experiment(experiment, &config, || {}).expect("experiment");
    serde_json::to_value(&report).expect("serialisable")
}

fn method<'a>(report: &'a Value, name: &str) -> &'a Value {
    report["methods"]
        .as_array()
        .unwrap()
        .iter()
        .find(|m| m["method"] == name)
        .unwrap_or_else(|| panic!("{name}"))
}

fn num(m: &Value, key: &str) -> f64 {
    m[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} in {}", m["method"]))
}

#[test]
fn every_method_reports_the_documented_fields() {
    let report = run(Experiment::Accuracy, 4);
    let fields = [
        "series",
        "series_with_calibration",
        "calibrations_mean",
        "calibrations_median",
        "rot_fro_mean",
        "rot_deg_mean",
        "trans_rel_mean",
        "time_per_calibration_s",
    ];
    let methods = report["methods"].as_array().unwrap();
    // The three online methods and the seven batch solvers.
    assert_eq!(methods.len(), 10);
    for m in methods {
        for f in fields {
            assert!(m[f].is_number(), "{} lacks {f}", m["method"]);
        }
        assert_eq!(num(m, "series"), 4.0);
    }
}

#[test]
fn accuracy_adaptive_halves_the_conventional_errors() {
    let report = run(Experiment::Accuracy, 8);
    let (c, a) = (method(&report, "conventional"), method(&report, "adaptive"));
    assert!(num(a, "rot_fro_mean") <= 0.5 * num(c, "rot_fro_mean"));
    assert!(num(a, "trans_rel_mean") <= 0.5 * num(c, "trans_rel_mean"));
    // A batch solve over all poses is far better than either (the reference rows).
    assert!(num(method(&report, "andreff"), "rot_fro_mean") < num(a, "rot_fro_mean"));
}

#[test]
fn adaptability_adaptive_calibrates_five_times_as_often_as_fixed() {
    let report = run(Experiment::Adaptability, 16);
    let (a, f) = (method(&report, "adaptive"), method(&report, "fixed"));
    assert!(num(a, "calibrations_mean") >= 5.0 * num(f, "calibrations_mean"));
}

#[test]
fn realtime_adaptive_is_fast_and_optimal_is_at_least_as_accurate() {
    let report = run(Experiment::Realtime, 16);
    let (a, o) = (method(&report, "adaptive"), method(&report, "optimal"));
    assert!(num(a, "time_per_calibration_s") < num(o, "time_per_calibration_s"));
    assert!(num(o, "rot_fro_mean") <= num(a, "rot_fro_mean"));
    assert!(num(o, "trans_rel_mean") <= num(a, "trans_rel_mean"));
}

#[test]
fn results_do_not_depend_on_the_number_of_threads() {
    let config = ExperimentConfig {
        series: 6,
        ..ExperimentConfig::for_experiment(Experiment::Accuracy)
    };
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .unwrap();
    let three = rayon::ThreadPoolBuilder::new()
        .num_threads(3)
        .build()
        .unwrap();
    let strip = |v: Value| {
        // Times differ from run to run; everything else must be identical.
        let mut v = v;
        for m in v["methods"].as_array_mut().unwrap() {
            m["time_per_calibration_s"] = Value::Null;
            for s in m["per_series"].as_array_mut().unwrap() {
                s["seconds"] = Value::Null;
            }
        }
        v
    };
    let a = one.install(|| {
        serde_json::to_value(run_experiment(Experiment::Accuracy, &config, || {}).unwrap()).unwrap()
    });
    let b = three.install(|| {
        serde_json::to_value(run_experiment(Experiment::Accuracy, &config, || {}).unwrap()).unwrap()
    });
    assert_eq!(strip(a), strip(b));
}

#[test]
fn tracking_the_running_estimate_improves_and_jumps_are_caught() {
    let config = ExperimentConfig {
        series: 8,
        ..ExperimentConfig::for_experiment(Experiment::Tracking)
    };
    let ExperimentReport::Tracking(report) =
        run_experiment(Experiment::Tracking, &config, || {}).unwrap()
    else {
        panic!("a tracking report")
    };
    let curve = |name: &str| report.curves.iter().find(|c| c.method == name).unwrap();
    let (acc, adaptive) = (curve("accumulate"), curve("adaptive"));
    let last = acc.rot_fro.len() - 1;
    // The running estimate keeps improving, and ends ten times better than the paper's.
    assert!(acc.rot_fro[last] < 0.5 * acc.rot_fro[1]);
    assert!(10.0 * acc.rot_fro[last] <= adaptive.rot_fro[last]);
    assert!(10.0 * acc.trans_rel[last] <= adaptive.trans_rel[last]);
    let one_degree = report
        .detection
        .iter()
        .find(|d| d.rotation_deg == 1.0)
        .unwrap();
    assert!(one_degree.detected_within_30 >= 0.95);
    assert!(report.detection.iter().all(|d| d.false_alarms == 0));
}

#[test]
fn settings_no_study_can_run_with_are_refused_by_name() {
    for (name, config) in [
        (
            "series",
            ExperimentConfig {
                series: 0,
                ..ExperimentConfig::for_experiment(Experiment::Tracking)
            },
        ),
        (
            "every",
            ExperimentConfig {
                every: 0,
                ..ExperimentConfig::for_experiment(Experiment::Tracking)
            },
        ),
        (
            "jump_poses",
            ExperimentConfig {
                jump_poses: 1,
                ..ExperimentConfig::for_experiment(Experiment::Tracking)
            },
        ),
    ] {
        let e = run_experiment(Experiment::Tracking, &config, || {}).unwrap_err();
        assert!(e.to_string().contains(name), "{name}: {e}");
    }
}
