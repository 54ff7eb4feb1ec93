//! `handeye calibrate`: one batch solve over a whole recording.

use anyhow::Result;
use clap::Args as ClapArgs;
use handeye::metrics::{OUTLIER_DEG, find_outliers, quality_report, remove_outliers};
use handeye::solve::{TsaiOptions, tsai_with};
use handeye::{AllPairs, Error, Method, MotionSource, Pairing, Setup, motion_pairs, solve};
use serde_json::{Map, Value, json};

use crate::input::{InputArgs, read_all};
use crate::output::{insert_transform, print_json};

/// Options of `handeye calibrate`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    #[command(flatten)]
    input: InputArgs,
    /// Solver.
    #[arg(long, default_value = "andreff", value_parser = ["andreff", "andreff-joint", "tsai", "park", "horaud", "daniilidis", "refine"])]
    method: String,
    /// Motions from consecutive poses, or from every pair i < j (as OpenCV does).
    #[arg(long, default_value = "consecutive", value_parser = ["consecutive", "all"])]
    pairs: String,
    /// Leave out motion pairs whose robot and camera rotation angles differ by more than
    /// --outlier-deg (they must be equal for a rigid X).
    #[arg(long)]
    reject_outliers: bool,
    /// Outlier threshold on |θ_A − θ_B|, degrees.
    #[arg(long, default_value_t = OUTLIER_DEG)]
    outlier_deg: f64,
    /// Drop the motions OpenCV's Tsai drops: robot or camera rotation with 2·sin(θ/2) outside
    /// [0.3, 1.7] (with --method tsai).
    #[arg(long)]
    tsai_opencv_filter: bool,
    /// Output: the JSON object, or a ROS-style YAML (translation {x,y,z}, rotation {x,y,z,w}).
    #[arg(long, default_value = "json", value_parser = ["json", "yaml"])]
    output: String,
}

/// Per-motion details are listed up to this many motions.
const MAX_PER_MOTION: usize = 10_000;

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    let method: Method = args.method.parse()?;
    let pairing = if args.pairs == "all" {
        Pairing::All
    } else {
        Pairing::Consecutive
    };
    let setup = args.input.setup();
    let (poses, time_offset) = read_all(&args.input)?;
    if poses.len() < 2 {
        return Err(Error::Parse {
            file: args
                .input
                .input
                .as_ref()
                .map_or("-".into(), |p| p.display().to_string()),
            line: 0,
            field: "-".into(),
            message: format!(
                "{} pose pair(s): at least 2 are needed to make a motion",
                poses.len()
            ),
        }
        .into());
    }
    if pairing == Pairing::All && !args.reject_outliers {
        // All pairs are made on the fly: memory stays O(poses), not O(poses²).
        let source = AllPairs::new(&poses, setup);
        return report(&args, method, setup, &source, None, time_offset);
    }
    let mut motions = motion_pairs(&poses, pairing, setup);
    let rejected = args.reject_outliers.then(|| {
        let outliers = find_outliers(&motions, args.outlier_deg);
        remove_outliers(&mut motions, &outliers);
        outliers
    });
    report(&args, method, setup, &motions, rejected, time_offset)
}

/// Solves X from the motions and prints the result with its quality report. `rejected` holds the
/// outliers already left out of `motions` (with `--reject-outliers`); otherwise the outliers are
/// the report's.
fn report(
    args: &Args,
    method: Method,
    setup: Setup,
    motions: &(impl MotionSource + ?Sized),
    rejected: Option<Vec<usize>>,
    time_offset: Option<f64>,
) -> Result<()> {
    let calibration = if method == Method::Tsai && args.tsai_opencv_filter {
        tsai_with(
            motions,
            &TsaiOptions {
                opencv_filter: true,
            },
        )?
    } else {
        solve(method, motions)?
    };
    let quality = quality_report(motions, &calibration.x, MAX_PER_MOTION, args.outlier_deg);
    let outliers = rejected.as_ref().unwrap_or(&quality.outliers);
    let residual = quality.residual;
    let mut out = Map::new();
    out.insert("method".into(), json!(method.name()));
    out.insert("setup".into(), json!(setup.name()));
    out.insert("frame".into(), json!(setup.x_frame()));
    insert_transform(&mut out, &calibration.x);
    out.insert("motions".into(), json!(calibration.motions));
    out.insert(
        "residual".into(),
        json!({
            "rotation_deg_rms": residual.rotation_deg_rms,
            "translation_rms": residual.translation_rms,
            "rotation_deg_max": residual.rotation_deg_max,
            "translation_max": residual.translation_max,
            "units": "rotation in degrees; translation in the input's length unit",
        }),
    );
    out.insert("conditioning".into(), json!(calibration.conditioning));
    // The report keeps per-motion entries only up to MAX_PER_MOTION motions.
    let per_motion = if quality.per_motion.len() == motions.count() {
        json!(quality.per_motion)
    } else {
        Value::Null
    };
    out.insert(
        "quality".into(),
        json!({
            "axis_spread_deg": quality.axis_spread_deg,
            "rotation_range_deg": quality.rotation_range_deg,
            "rotation_std_deg": quality.rotation_std_deg,
            "translation_std": quality.translation_std,
            "outliers": {
                "threshold_deg": args.outlier_deg,
                "count": outliers.len(),
                "rejected": args.reject_outliers,
                "motions": outliers,
            },
            "per_motion": per_motion,
        }),
    );
    // With --reject-outliers the motions kept have no outliers at the same threshold, so the
    // report's outlier warning cannot appear.
    let mut warnings: Vec<String> = calibration.warnings.iter().map(|w| w.to_string()).collect();
    warnings.extend(quality.warnings.iter().cloned());
    if args.reject_outliers && !outliers.is_empty() {
        eprintln!(
            "rejected {} outlier motion pair(s) of {}",
            outliers.len(),
            outliers.len() + motions.count()
        );
    }
    for w in &warnings {
        eprintln!("warning: {w}");
    }
    out.insert("warnings".into(), json!(warnings));
    if let Some(t) = time_offset {
        out.insert("time_offset_s".into(), json!(t));
    }
    if args.output == "yaml" {
        print!("{}", ros_yaml(&out, setup.x_frame(), &calibration.x));
        return Ok(());
    }
    print_json(&Value::Object(out))
}

/// The result as ROS-style YAML (easy_handeye / tf conventions: translation, rotation x y z w).
fn ros_yaml(out: &Map<String, Value>, frame: &str, x: &handeye::Transform) -> String {
    let t = x.translation.vector;
    let q = handeye::pose::quaternion_xyzw(x);
    format!(
        "# handeye calibrate: method {}, setup {}\nframe: {frame}\ntranslation: {{x: {}, y: {}, z: {}}}\nrotation: {{x: {}, y: {}, z: {}, w: {}}}\nresidual: {{rotation_deg_rms: {}, translation_rms: {}}}\nmotions: {}\n",
        out["method"].as_str().unwrap_or(""),
        out["setup"].as_str().unwrap_or(""),
        t.x,
        t.y,
        t.z,
        q[0],
        q[1],
        q[2],
        q[3],
        out["residual"]["rotation_deg_rms"],
        out["residual"]["translation_rms"],
        out["motions"],
    )
}
