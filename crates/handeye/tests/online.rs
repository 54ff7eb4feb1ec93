//! The online calibrator through its public API: save/restore, constant memory, the relaxation
//! rule, lock-in, and the paper's claim on simulated data.

use handeye::check::quality::errors_against_truth;
use handeye::online::select::{AdaptiveParams, Record, Selection, Thresholds, predict};
use handeye::online::{ErrorSource, Estimator, Event, OnlineCalibrator, OnlineConfig, run_series};
use handeye::sim::{SimConfig, simulate};
use handeye::{PosePair, Transform};
use nalgebra::Vector3;

fn config(selection: Selection, truth: Transform, optimal: bool) -> OnlineConfig {
    OnlineConfig {
        selection,
        params: AdaptiveParams {
            d_max: 100.0,
            ..AdaptiveParams::default()
        },
        error_source: ErrorSource::Truth,
        truth: Some(truth),
        optimal,
        ..OnlineConfig::default()
    }
}

/// Events without their wall-clock times, which differ between runs.
fn timeless(events: &[Event]) -> Vec<Event> {
    events
        .iter()
        .map(|e| {
            let mut e = *e;
            e.seconds = 0.0;
            if let Some(o) = e.optimal.as_mut() {
                o.seconds = 0.0;
            }
            e
        })
        .collect()
}

#[test]
fn a_restored_calibrator_continues_exactly() {
    let s = simulate(
        &SimConfig {
            poses: 300,
            ..SimConfig::default()
        },
        11,
        0,
    );
    for selection in [Selection::None, Selection::Fixed, Selection::Adaptive] {
        let cfg = config(selection, s.gripper_from_camera, true);
        let all = timeless(&run_series(cfg, &s.poses).unwrap());
        assert!(!all.is_empty() || selection == Selection::Fixed);
        for k in [1, 3, 6, 7, 50, 151, 299] {
            let mut first = OnlineCalibrator::new(cfg).unwrap();
            let mut events = Vec::new();
            for p in &s.poses[..k] {
                events.extend(first.push(p).unwrap().events);
            }
            let snapshot = serde_json::to_string(&first).unwrap();
            let mut restored: OnlineCalibrator = serde_json::from_str(&snapshot).unwrap();
            assert_eq!(restored, first);
            for p in &s.poses[k..] {
                events.extend(restored.push(p).unwrap().events);
            }
            assert_eq!(
                timeless(&events),
                all,
                "{selection} restored after pose {k}"
            );
        }
    }
}

/// A gripper that keeps moving, cheaply, for long streams.
fn endless_walk(n: usize) -> impl Iterator<Item = PosePair> {
    let x = Transform::new(
        Vector3::new(20.0, -30.0, 40.0),
        Vector3::new(0.3, -0.2, 0.5),
    );
    let target = Transform::new(Vector3::new(0.0, 0.0, 500.0), Vector3::new(3.0, 0.0, 0.0));
    (0..n).map(move |k| {
        let t = k as f64;
        let q = Transform::new(
            Vector3::new(
                (t * 0.37).sin() * 20.0,
                (t * 0.23).cos() * 20.0,
                (t * 0.11).sin() * 10.0,
            ),
            Vector3::new(
                (t * 0.71).sin() * 0.4,
                (t * 0.53).cos() * 0.4,
                (t * 0.29).sin() * 0.4,
            ),
        );
        PosePair {
            base_from_gripper: q,
            camera_from_target: (target.inverse() * q * x).inverse(),
        }
    })
}

/// Number of numeric values in a JSON document.
fn numbers_in(v: &serde_json::Value) -> usize {
    match v {
        serde_json::Value::Number(_) => 1,
        serde_json::Value::Array(a) => a.iter().map(numbers_in).sum(),
        serde_json::Value::Object(o) => o.values().map(numbers_in).sum(),
        _ => 0,
    }
}

#[test]
fn memory_stays_constant_over_a_million_poses() {
    for selection in [Selection::None, Selection::Fixed, Selection::Adaptive] {
        let cfg = OnlineConfig {
            selection,
            optimal: true,
            ..config(selection, Transform::identity(), true)
        };
        // The adaptive run also carries the accumulating estimator (its all-pairs sums and the
        // change detector's window are of fixed size too).
        let estimator = if selection == Selection::Adaptive {
            Estimator::Accumulate
        } else {
            Estimator::Paper
        };
        let cfg = OnlineConfig {
            error_source: ErrorSource::Residual,
            truth: None,
            estimator,
            ..cfg
        };
        let mut c = OnlineCalibrator::new(cfg).unwrap();
        let mut sizes = Vec::new();
        for (k, p) in endless_walk(1_000_000).enumerate() {
            c.push(&p).unwrap();
            if k + 1 == 1_000 || k + 1 == 1_000_000 {
                sizes.push(numbers_in(&serde_json::to_value(&c).unwrap()));
            }
        }
        // The paper's selection calibrates; the accumulating estimator, its own entry, reports
        // (the selection does not run beside it).
        if estimator == Estimator::Accumulate {
            assert_eq!(c.calibrations(), 0, "{selection}: the selection ran");
            assert!(c.last_report().is_some(), "{selection}: no report");
        } else {
            assert!(
                c.calibrations() > 100,
                "{selection}: {} calibrations",
                c.calibrations()
            );
        }
        // The state holds only fixed-size records and the accumulating estimator's sample of the
        // poses for the check of the readings, which holds 64 to 127 poses (thinned by half each
        // time it fills; 24 numbers a pose): the number of values it serialises does not grow
        // with the stream beyond that sample's swing.
        let swing = if estimator == Estimator::Accumulate {
            64 * 24
        } else {
            0
        };
        assert!(
            sizes[1] <= sizes[0] + swing,
            "{selection}: state grew from {} to {} numbers",
            sizes[0],
            sizes[1]
        );
    }
}

#[test]
fn thresholds_relax_after_interval_failed_candidates() {
    let pose = |axis_angle: Vector3<f64>, x: f64| {
        let q = Transform::new(Vector3::new(x, 0.0, 0.0), axis_angle);
        PosePair {
            base_from_gripper: q,
            camera_from_target: q.inverse(),
        }
    };
    let params = AdaptiveParams {
        d_max: 100.0,
        ..AdaptiveParams::default()
    };
    let mut c = OnlineCalibrator::new(OnlineConfig {
        params,
        ..OnlineConfig::default()
    })
    .unwrap();
    // Poses 1–5 rotate about alternating axes (so Eq. (1) gives positive thresholds); pose 5 is
    // unrotated, and so is every later pose, at the same place: every A' candidate has θ' = 0
    // (fails β₀) and d' = 0 (passes d₀).
    for k in 0..4 {
        let a = if k % 2 == 0 {
            Vector3::new(0.2, 0.0, 0.0)
        } else {
            Vector3::new(0.0, 0.2, 0.0)
        };
        c.push(&pose(a, k as f64)).unwrap();
    }
    c.push(&pose(Vector3::zeros(), 4.0)).unwrap();
    let mut trace = Vec::new();
    for _ in 0..4 * params.interval {
        c.push(&pose(Vector3::zeros(), 4.0)).unwrap();
        trace.push(c.summary().thresholds.unwrap());
    }
    let beta0 = trace[0].beta
        / if params.interval == 1 {
            params.relax_down
        } else {
            1.0
        };
    for (n, t) in trace.iter().enumerate() {
        // Candidate i = 6 + n; start = 6, so after candidates 10, 15, 20 and 25 (i − start + 1 =
        // interval) β₀ is relaxed once more, and d₀ never is.
        let relaxations = (n + 1) / params.interval;
        let expected = beta0 * params.relax_down.powi(relaxations as i32);
        assert!(
            (t.beta - expected).abs() <= 1e-12 * beta0,
            "candidate {}: β₀ {} expected {expected}",
            n + 6,
            t.beta
        );
        assert_eq!(
            t.d, trace[0].d,
            "d₀ must not move: every translation passes"
        );
        assert_eq!(
            t.sin_alpha, trace[0].sin_alpha,
            "sin α₀ is not tested while searching A'"
        );
    }
    assert_eq!(c.calibrations(), 0);
}

#[test]
fn equal_records_lock_a_threshold_unless_unfrozen() {
    let t = Thresholds {
        sin_alpha: 0.5,
        beta: 0.1,
        d: 10.0,
    };
    let records: [Record; 4] = std::array::from_fn(|n| Record {
        thresholds: t,
        rms_r: 0.001 * (n + 1) as f64,
        rms_t: 0.01 * (n + 2) as f64,
    });
    let faithful = AdaptiveParams {
        d_max: 100.0,
        ..AdaptiveParams::default()
    };
    let locked = predict(&records, t, &faithful);
    assert!((locked.sin_alpha - t.sin_alpha).abs() < 1e-12);
    assert!((locked.beta - t.beta).abs() < 1e-12);
    assert!((locked.d - t.d).abs() < 1e-9);
    let remedy = AdaptiveParams {
        unfreeze: true,
        ..faithful
    };
    let moved = predict(&records, t, &remedy);
    assert!((moved.sin_alpha - t.sin_alpha * 1.1).abs() < 1e-12);
    assert!((moved.beta - t.beta * 1.1).abs() < 1e-12);
    assert!((moved.d - t.d / 1.1).abs() < 1e-9);
}

#[test]
fn adaptive_selection_beats_the_conventional_method() {
    let (mut conv, mut adapt) = ((0.0, 0.0), (0.0, 0.0));
    let mut series = 0;
    for s in 0..6 {
        let sim = simulate(&SimConfig::default(), 2024, s);
        let mean = |events: &[Event]| {
            let n = events.len().max(1) as f64;
            events.iter().fold((0.0, 0.0), |acc, e| {
                let err = errors_against_truth(&e.x, &sim.gripper_from_camera);
                (acc.0 + err.rot_fro / n, acc.1 + err.trans_rel / n)
            })
        };
        let c = run_series(
            config(Selection::None, sim.gripper_from_camera, false),
            &sim.poses,
        )
        .unwrap();
        let a = run_series(
            config(Selection::Adaptive, sim.gripper_from_camera, false),
            &sim.poses,
        )
        .unwrap();
        if a.is_empty() {
            continue;
        }
        series += 1;
        let (cr, ct) = mean(&c);
        let (ar, at) = mean(&a);
        conv = (conv.0 + cr, conv.1 + ct);
        adapt = (adapt.0 + ar, adapt.1 + at);
    }
    assert!(series >= 4);
    println!("conventional {conv:?}, adaptive {adapt:?} over {series} series");
    assert!(
        adapt.0 < 0.5 * conv.0,
        "rotation: adaptive {} vs conventional {}",
        adapt.0,
        conv.0
    );
    assert!(
        adapt.1 < 0.5 * conv.1,
        "translation: adaptive {} vs conventional {}",
        adapt.1,
        conv.1
    );
}

#[test]
fn truth_error_source_needs_a_truth() {
    let cfg = OnlineConfig {
        error_source: ErrorSource::Truth,
        truth: None,
        ..OnlineConfig::default()
    };
    assert!(OnlineCalibrator::new(cfg).is_err());
}

#[test]
fn a_non_finite_pose_is_refused_and_changes_nothing() {
    let s = simulate(&SimConfig::default(), 5, 0);
    let cfg = config(Selection::Adaptive, s.gripper_from_camera, false);
    let mut c = OnlineCalibrator::new(cfg).unwrap();
    for p in &s.poses[..50] {
        c.push(p).unwrap();
    }
    let before = c.clone();
    let mut bad = s.poses[50];
    bad.base_from_gripper.translation.vector.x = f64::NAN;
    assert!(c.push(&bad).is_err());
    assert_eq!(c, before);
}

#[test]
fn estimators_and_error_sources_parse_from_their_names() {
    for e in [Estimator::Paper, Estimator::Accumulate] {
        assert_eq!(e.name().parse::<Estimator>().unwrap(), e);
    }
    for e in [ErrorSource::Residual, ErrorSource::Truth] {
        assert_eq!(e.name().parse::<ErrorSource>().unwrap(), e);
    }
    let unknown = "selected".parse::<Estimator>().unwrap_err().to_string();
    assert!(unknown.contains("paper or accumulate"), "{unknown}");
    assert!("exact".parse::<ErrorSource>().is_err());
}

#[test]
fn an_absurd_n_init_is_refused_before_anything_is_allocated() {
    for selection in [Selection::Fixed, Selection::Adaptive, Selection::None] {
        for n_init in [
            handeye::online::select::MAX_N_INIT + 1,
            1 << 62,
            1_000_000_000_000,
            usize::MAX,
        ] {
            let config = OnlineConfig {
                selection,
                params: AdaptiveParams {
                    n_init,
                    ..AdaptiveParams::default()
                },
                ..OnlineConfig::default()
            };
            match OnlineCalibrator::new(config) {
                Err(handeye::Error::InvalidParameter { name, .. }) => assert_eq!(name, "n_init"),
                other => panic!("{selection:?} n_init {n_init}: {other:?}"),
            }
        }
    }
    let fine = AdaptiveParams {
        n_init: handeye::online::select::MAX_N_INIT,
        ..AdaptiveParams::default()
    };
    assert!(fine.validate().is_ok());
}

/// The paper's estimator has no checks of its own: the calibrator runs `calibrate`'s readings
/// check on its first 64 poses and says once what it found; as given, it finds nothing; the
/// accumulating estimator checks its readings itself.
#[test]
fn the_paper_estimator_checks_the_readings_of_its_first_poses() {
    use handeye::StreamReading;
    let s = simulate(&SimConfig::large_motions(), 5, 0);
    let inverted: Vec<PosePair> = (s.poses.iter())
        .map(|p| PosePair {
            base_from_gripper: p.base_from_gripper.inverse(),
            ..*p
        })
        .collect();
    let run = |poses: &[PosePair], estimator| {
        let config = OnlineConfig {
            estimator,
            ..OnlineConfig::default()
        };
        let mut calibrator = OnlineCalibrator::new(config).unwrap();
        let mut found = Vec::new();
        for (k, pose) in poses.iter().enumerate() {
            let pushed = calibrator.push(pose).unwrap();
            found.extend(pushed.misread.map(|f| (k + 1, f)));
        }
        let finished = calibrator.finish().unwrap();
        found.extend(finished.misread.map(|f| (0, f)));
        found
    };
    let found = run(&inverted, Estimator::Paper);
    assert_eq!(found.len(), 1, "{found:?}");
    assert_eq!(found[0].0, 64, "told at the 64th pose");
    assert!(
        matches!(found[0].1, StreamReading::ReadWrongly(_)),
        "{found:?}"
    );
    assert!(run(&s.poses, Estimator::Paper).is_empty());
    // A short stream is checked at its end.
    let short = run(&inverted[..30], Estimator::Paper);
    assert_eq!(short.len(), 1, "{short:?}");
    assert_eq!(short[0].0, 0, "told at finish");
    assert!(run(&inverted, Estimator::Accumulate).is_empty());
}
