//! `handeye calibrate`: one batch solve over a whole recording.

use anyhow::Result;
use clap::Args as ClapArgs;
use handeye::metrics::residual_summary;
use handeye::{Error, Method, Pairing, motion_pairs, solve};
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
}

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
    let motions = motion_pairs(&poses, pairing, setup);
    let calibration = solve(method, &motions)?;
    let residual = residual_summary(&motions, &calibration.x);
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
    out.insert(
        "warnings".into(),
        json!(
            calibration
                .warnings
                .iter()
                .map(|w| w.to_string())
                .collect::<Vec<_>>()
        ),
    );
    if let Some(t) = time_offset {
        out.insert("time_offset_s".into(), json!(t));
    }
    for w in &calibration.warnings {
        eprintln!("warning: {w}");
    }
    print_json(&Value::Object(out))
}
