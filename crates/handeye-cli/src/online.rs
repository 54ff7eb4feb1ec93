//! `handeye online`: the online calibrator on a stream, one JSON line per calibration.

use std::path::PathBuf;

use anyhow::{Result, bail};
use clap::Args as ClapArgs;
use handeye::io::read_truth;
use handeye::online::{ErrorSource, Estimator, Event, OnlineCalibrator, OnlineConfig};
use handeye::select::{AdaptiveParams, Selection};
use serde_json::{Map, Value, json};

use crate::input::{InputArgs, records};
use crate::output::{insert_transform, print_line};

/// Options of `handeye online`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    #[command(flatten)]
    input: InputArgs,
    /// Motion selection: the paper's adaptive thresholds, Shi et al.'s fixed ones, or none (the
    /// conventional method).
    #[arg(long, default_value = "adaptive", value_parser = ["adaptive", "fixed", "none"])]
    selection: String,
    /// Estimator: `paper` (Andreff on the two selected motions of each calibration) or
    /// `accumulate` (every pair of poses since the last detected change of X).
    #[arg(long, default_value = "paper", value_parser = ["paper", "accumulate"])]
    estimator: String,
    /// Also refine over the last five selected motions (the paper's optimal method).
    #[arg(long)]
    optimal: bool,
    /// Source of rmsR/rmsT: the AX − XB residuals, or the true X (needs --truth).
    #[arg(long, default_value = "residual", value_parser = ["residual", "truth"])]
    error_source: String,
    /// Truth file (the true X), for --error-source truth.
    #[arg(long)]
    truth: Option<PathBuf>,
    /// What to do with a bad line: report it and skip it, or stop (exit 2).
    #[arg(long, default_value = "skip", value_parser = ["skip", "stop"])]
    on_bad_line: String,
    /// N of Eq. (1): motions averaged for the initial thresholds.
    #[arg(long, default_value_t = AdaptiveParams::default().n_init)]
    n_init: usize,
    /// Candidates tried before the thresholds are relaxed.
    #[arg(long, default_value_t = AdaptiveParams::default().interval)]
    interval: usize,
    /// Relaxation factor of sin α₀ and β₀.
    #[arg(long, default_value_t = AdaptiveParams::default().relax_down)]
    relax_down: f64,
    /// Relaxation factor of d₀.
    #[arg(long, default_value_t = AdaptiveParams::default().relax_up)]
    relax_up: f64,
    /// Exploration factor after calibrations 1–3.
    #[arg(long, default_value_t = AdaptiveParams::default().explore)]
    explore: f64,
    /// Required rotation accuracy rmsRMax.
    #[arg(long, default_value_t = AdaptiveParams::default().rms_r_max)]
    rms_r_max: f64,
    /// Required translation accuracy rmsTMax.
    #[arg(long, default_value_t = AdaptiveParams::default().rms_t_max)]
    rms_t_max: f64,
    /// Floor of a predicted sin α₀ (default sin 15°).
    #[arg(long, default_value_t = AdaptiveParams::default().alpha_min)]
    alpha_min: f64,
    /// Floor of a predicted β₀, degrees [default: 3, the library's default].
    #[arg(long)]
    beta_min_deg: Option<f64>,
    /// Ceiling of a predicted d₀, in the input's length unit (0.1 m; use 100 for millimetres).
    #[arg(long, default_value_t = AdaptiveParams::default().d_max)]
    d_max: f64,
    /// Opt-in remedy for thresholds that lock when their four records are equal.
    #[arg(long)]
    unfreeze: bool,
}

/// Bad lines shown one by one before `online` shows only every 2^k-th.
const SHOWN_BAD_LINES: usize = 100;

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    let truth = args.truth.as_ref().map(|p| read_truth(p)).transpose()?;
    let setup = args.input.setup();
    if let Some(t) = &truth
        && t.frame != setup.x_frame()
    {
        bail!(
            "the truth file gives `{}` but --setup {} needs `{}`",
            t.frame,
            setup.name(),
            setup.x_frame()
        );
    }
    let config = OnlineConfig {
        setup,
        selection: args.selection.parse::<Selection>()?,
        params: AdaptiveParams {
            n_init: args.n_init,
            interval: args.interval,
            relax_down: args.relax_down,
            relax_up: args.relax_up,
            explore: args.explore,
            rms_r_max: args.rms_r_max,
            rms_t_max: args.rms_t_max,
            alpha_min: args.alpha_min,
            beta_min: args
                .beta_min_deg
                .map_or(AdaptiveParams::default().beta_min, f64::to_radians),
            d_max: args.d_max,
            unfreeze: args.unfreeze,
        },
        error_source: args.error_source.parse::<ErrorSource>()?,
        truth: truth.map(|t| t.x),
        optimal: args.optimal,
        estimator: args.estimator.parse::<Estimator>()?,
        ..OnlineConfig::default()
    };
    let mut calibrator = OnlineCalibrator::new(config)?;
    let (records, source, time_offset) = records(&args.input)?;
    let mut skipped: usize = 0;
    for record in records {
        // A pose the calibrator refuses is a bad line too, named by its place.
        let pushed = record.and_then(|r| {
            calibrator.push(&r.pose).map_err(|e| handeye::Error::Parse {
                file: source.clone(),
                line: r.line,
                field: "-".to_string(),
                message: e.to_string(),
            })
        });
        let events = match pushed {
            Ok(events) => events,
            Err(e) if args.on_bad_line == "skip" && matches!(e, handeye::Error::Parse { .. }) => {
                skipped += 1;
                // Every bad line is counted; the first ones are shown, later ones sparsely, so
                // that an endless bad stream cannot flood the terminal.
                if skipped <= SHOWN_BAD_LINES || skipped.is_power_of_two() {
                    eprintln!("skipped: {e}");
                }
                if skipped == SHOWN_BAD_LINES {
                    eprintln!(
                        "further bad lines are counted and shown only at the 2^k-th (the count is given at the end)"
                    );
                }
                continue;
            }
            Err(e) => return Err(e.into()),
        };
        if let Some(pose) = calibrator.change_detected() {
            print_line(&json!({"change": pose}))?;
            eprintln!("change of X detected at pose {pose}: accumulation restarted");
        }
        for event in events {
            print_line(&event_json(&event, time_offset))?;
        }
    }
    eprintln!(
        "{} calibration(s) from {} pose(s){}; last X: {}",
        calibrator.calibrations(),
        calibrator.poses(),
        if skipped > 0 {
            format!(", {skipped} bad line(s) skipped")
        } else {
            String::new()
        },
        calibrator.last_x().map_or("none".to_string(), |x| {
            let t = x.translation.vector;
            format!(
                "t = [{:.6}, {:.6}, {:.6}], rotation {:.4}°",
                t.x,
                t.y,
                t.z,
                x.rotation.angle().to_degrees()
            )
        })
    );
    Ok(())
}

/// One event as its JSON line (SPEC sec. 7).
pub fn event_json(e: &Event, time_offset: Option<f64>) -> Value {
    let mut out = Map::new();
    out.insert("calibration".into(), json!(e.calibration));
    out.insert("poses".into(), json!(e.poses));
    if let Some(t) = e.thresholds {
        out.insert(
            "thresholds".into(),
            json!({"sin_alpha": t.sin_alpha, "beta": t.beta, "d": t.d}),
        );
    }
    out.insert("rms_r".into(), json!(e.rms.rms_r));
    out.insert("rms_t".into(), json!(e.rms.rms_t));
    match &e.accumulated {
        Some(a) => {
            // The accumulated X is the event's transform; the paper's two-motion X is kept apart.
            insert_transform(&mut out, &a.x);
            out.insert("estimator".into(), json!("accumulate"));
            out.insert(
                "accumulated".into(),
                json!({"poses": a.poses, "conditioning": a.conditioning, "noise_rotation_deg": a.noise[0], "noise_translation": a.noise[1], "uncertainty_rotation_deg": a.uncertainty.map(|u| u[0]), "uncertainty_translation": a.uncertainty.map(|u| u[1]), "last_change": a.change_at}),
            );
            let mut paper = Map::new();
            insert_transform(&mut paper, &e.x);
            out.insert("paper".into(), Value::Object(paper));
        }
        None => insert_transform(&mut out, &e.x),
    }
    if let Some(o) = &e.optimal {
        let mut opt = Map::new();
        insert_transform(&mut opt, &o.x);
        opt.insert("number".into(), json!(o.number));
        opt.insert("motions".into(), json!(o.motions));
        out.insert("optimal".into(), Value::Object(opt));
    }
    out.insert("seconds".into(), json!(e.seconds));
    if let Some(t) = time_offset {
        out.insert("time_offset_s".into(), json!(t));
    }
    Value::Object(out)
}
