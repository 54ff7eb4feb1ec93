//! `handeye simulate`: a series of the paper's protocol as JSON Lines, and its truth.

use std::io::Write;
use std::path::PathBuf;

use anyhow::{Context, Result};
use clap::Args as ClapArgs;
use handeye::io::Truth;
use handeye::sim::{SimConfig, simulate};
use serde_json::json;

use crate::values;

/// Options of `handeye simulate`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Number of poses.
    #[arg(long, default_value_t = 200, value_parser = values::count(1, values::MAX_POSES))]
    poses: usize,
    /// Seed of the run.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Series number within the run (each has its own generator).
    #[arg(long, default_value_t = 0)]
    series: u64,
    /// Motion preset: the paper's small steps, or large motions (60° steps, 50 mm standoff).
    #[arg(long, default_value_t = Preset::Paper, value_parser = values::named::<Preset>())]
    preset: Preset,
    /// Without measurement noise.
    #[arg(long)]
    noise_free: bool,
    /// Output file (JSON Lines: `base_from_gripper`, `camera_from_target` as 4×4, `stamp`), or
    /// `-` for standard output.
    #[arg(long)]
    out: PathBuf,
    /// Truth file to write (the true X and the target pose).
    #[arg(long)]
    truth: Option<PathBuf>,
}

/// The motion presets of `--preset`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Preset {
    /// The paper's protocol ([`SimConfig::default`]).
    Paper,
    /// [`SimConfig::large_motions`].
    Large,
}

handeye::named_enum!(Preset, "preset", "preset" {
    Paper => "paper",
    Large => "large",
});

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    let base = match args.preset {
        Preset::Paper => SimConfig::default(),
        Preset::Large => SimConfig::large_motions(),
    };
    let mut config = SimConfig {
        poses: args.poses,
        ..base
    };
    if args.noise_free {
        config = config.noise_free();
    }
    let s = simulate(&config, args.seed, args.series);
    let to_stdout = args.out.as_os_str() == "-";
    let sink: Box<dyn Write> = if to_stdout {
        Box::new(std::io::stdout().lock())
    } else {
        Box::new(
            std::fs::File::create(&args.out)
                .with_context(|| format!("cannot create {}", args.out.display()))?,
        )
    };
    let mut w = std::io::BufWriter::new(sink);
    for (k, p) in s.poses.iter().enumerate() {
        let m = |t: &handeye::Transform| {
            let h = t.to_homogeneous();
            (0..4)
                .map(|r| (0..4).map(|c| h[(r, c)]).collect::<Vec<_>>())
                .collect::<Vec<_>>()
        };
        let line = json!({"stamp": k as f64, "base_from_gripper": m(&p.base_from_gripper), "camera_from_target": m(&p.camera_from_target)});
        writeln!(w, "{line}")?;
    }
    w.flush()?;
    if let Some(path) = &args.truth {
        let truth = Truth {
            x: s.gripper_from_camera,
            frame: "gripper_from_camera".into(),
            target: Some(("base_from_target".into(), s.base_from_target)),
        };
        std::fs::write(path, serde_json::to_string_pretty(&truth.json())? + "\n")
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    crate::tell!(
        "wrote {} poses (millimetres) to {}",
        s.poses.len(),
        if to_stdout {
            "standard output".to_string()
        } else {
            args.out.display().to_string()
        }
    );
    Ok(())
}
