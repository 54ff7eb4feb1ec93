//! `handeye bench`: every solver timed in-process, on simulated data or on given files, and the
//! online calibrator's throughput. For speed comparisons run side by side in one process run
//! (see bench/compare_opencv.sh); the criterion benches in crates/handeye/benches are the
//! statistically careful ones.

use std::cell::Cell;
use std::hint::black_box;
use std::io::IsTerminal;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use anyhow::Result;
use clap::Args as ClapArgs;
use handeye::AdaptiveParams;
use handeye::TransformJson;
use handeye::errors_against_truth;
use handeye::io::{Format, PoseStream, Recording, RecordingOptions, Source, Truth};
use handeye::sim::{SimConfig, simulate};
use handeye::{AllPairs, Method, Pairing, PosePair, Setup, Transform, motion_pairs, solve};
use handeye::{OnlineCalibrator, OnlineConfig};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use serde_json::{Value, json};

use crate::output::print_json;
use crate::values;

/// Options of `handeye bench`.
#[derive(ClapArgs, Debug)]
pub struct Args {
    /// Pose counts of the simulated datasets (ignored with --input).
    #[arg(long, num_args = 1.., value_delimiter = ',', default_values_t = [10usize, 50, 200, 1000], value_parser = values::count(3, values::MAX_POSES))]
    poses: Vec<usize>,
    /// Pairings to time.
    #[arg(long, num_args = 1.., value_delimiter = ',', default_values_t = Pairing::ALL, value_parser = values::named::<Pairing>())]
    pairs: Vec<Pairing>,
    /// Methods to time.
    #[arg(long, num_args = 1.., value_delimiter = ',', default_values_t = Method::ALL, value_parser = values::named::<Method>())]
    methods: Vec<Method>,
    /// Pose files to time instead of simulated data (each may have a `<stem>.truth.json` beside
    /// it, or give --truth per file in the same order).
    #[arg(long)]
    input: Vec<PathBuf>,
    /// Truth files for the errors of --input datasets, in the same order.
    #[arg(long)]
    truth: Vec<PathBuf>,
    /// Least wall time spent timing each case, seconds (at most an hour).
    #[arg(long, default_value_t = 0.3, value_parser = values::budget_s)]
    min_time: f64,
    /// Print the JSON only (no table on stderr).
    #[arg(long)]
    quiet: bool,
}

/// Cases of the online calibrator timed after the solvers.
const ONLINE_CASES: u64 = 3;

/// The progress bar on stderr: drawn once the run has taken a second (and only on a terminal),
/// so quick runs stay quiet.
struct Progress {
    bar: ProgressBar,
    started: Instant,
    shown: Cell<bool>,
}

impl Progress {
    fn new(cases: u64) -> Self {
        let bar = ProgressBar::with_draw_target(Some(cases), ProgressDrawTarget::hidden());
        bar.set_style(
            ProgressStyle::with_template("{elapsed:>4} [{bar:30}] {pos}/{len} cases: {msg}")
                .unwrap_or_else(|_| ProgressStyle::default_bar()),
        );
        Self {
            bar,
            started: Instant::now(),
            shown: Cell::new(false),
        }
    }

    /// Marks the previous case done and names the next one.
    fn case(&self, name: &str) {
        if !self.shown.get()
            && self.started.elapsed() > Duration::from_secs(1)
            && std::io::stderr().is_terminal()
        {
            self.bar.set_draw_target(ProgressDrawTarget::stderr());
            self.bar.enable_steady_tick(Duration::from_millis(250));
            self.shown.set(true);
        }
        self.bar.set_message(name.to_string());
        self.bar.inc(1);
    }
}

/// One dataset: its name, poses and true X if known.
struct Dataset {
    name: String,
    poses: Vec<PosePair>,
    truth: Option<Transform>,
}

/// Runs the command.
pub fn run(args: Args) -> Result<()> {
    let datasets = datasets(&args)?;
    let methods = &args.methods;
    let budget = Duration::from_secs_f64(args.min_time);
    let progress =
        Progress::new((datasets.len() * args.pairs.len() * methods.len()) as u64 + ONLINE_CASES);
    let mut rows = Vec::new();
    for d in &datasets {
        for &pairing in &args.pairs {
            for &method in methods {
                // A call includes building the motions from the poses, as OpenCV's does; all
                // pairs are made on the fly, as `calibrate --pairs all` makes them.
                let call = || match pairing {
                    Pairing::All => solve(method, &AllPairs::new(&d.poses, Setup::EyeInHand)),
                    Pairing::Consecutive => {
                        solve(method, &motion_pairs(&d.poses, pairing, Setup::EyeInHand))
                    }
                };
                progress.case(&format!("{} {pairing} {method}", d.name));
                let result = call();
                let (median, calls) = time(|| black_box(call()).is_ok(), budget);
                let errors = match (&result, &d.truth) {
                    (Ok(c), Some(t)) => {
                        let e = errors_against_truth(&c.x, t);
                        json!({"rotation_deg": e.rot_deg, "translation_rel": e.trans_rel})
                    }
                    _ => Value::Null,
                };
                rows.push(json!({
                    "dataset": d.name,
                    "poses": d.poses.len(),
                    "pairs": pairing.name(),
                    "method": method.name(),
                    "median_s": median,
                    "calls": calls,
                    "error": errors,
                    "failed": result.err().map(|e| e.to_string()),
                }));
            }
        }
    }
    let online = online_throughput(budget, &progress)?;
    progress.bar.finish_and_clear();
    if !args.quiet {
        eprintln!("| dataset | poses | pairs | method | median per call | calls |");
        eprintln!("|---|---|---|---|---|---|");
        for r in &rows {
            eprintln!(
                "| {} | {} | {} | {} | {:.2} µs | {} |",
                r["dataset"].as_str().unwrap_or(""),
                r["poses"],
                r["pairs"].as_str().unwrap_or(""),
                r["method"].as_str().unwrap_or(""),
                r["median_s"].as_f64().unwrap_or(f64::NAN) * 1e6,
                r["calls"]
            );
        }
        eprintln!(
            "online push: {:.1} million poses/s without calibration; a calibration event in {:.2} µs; a JSON Lines record read in {:.2} µs",
            online["push_per_s"].as_f64().unwrap_or(0.0) / 1e6,
            online["calibration_s"].as_f64().unwrap_or(f64::NAN) * 1e6,
            online["parse_line_s"].as_f64().unwrap_or(f64::NAN) * 1e6
        );
    }
    print_json(&json!({"solvers": rows, "online": online}))
}

/// The datasets: the given files, or simulated series.
fn datasets(args: &Args) -> Result<Vec<Dataset>> {
    if args.input.is_empty() {
        return Ok(args
            .poses
            .iter()
            .map(|&n| {
                let s = simulate(
                    &SimConfig {
                        poses: n,
                        ..SimConfig::default()
                    },
                    42,
                    n as u64,
                );
                Dataset {
                    name: format!("sim{n}"),
                    poses: s.poses,
                    truth: Some(s.gripper_from_camera),
                }
            })
            .collect());
    }
    args.input
        .iter()
        .enumerate()
        .map(|(k, path)| {
            let source = Source::File {
                path: path.clone(),
                format: Format::Auto,
            };
            let poses = Recording::read(&source, &RecordingOptions::default())?.poses;
            let beside = path.with_extension("truth.json");
            let truth_path = args
                .truth
                .get(k)
                .cloned()
                .or_else(|| beside.exists().then_some(beside));
            let truth = truth_path
                .map(|p| Truth::read(&p))
                .transpose()?
                .map(|t| t.x);
            let name = path
                .file_stem()
                .map_or("input".into(), |s| s.to_string_lossy().into_owned());
            Ok(Dataset { name, poses, truth })
        })
        .collect()
}

/// Median seconds per call over batches, and the number of calls timed.
fn time(mut f: impl FnMut() -> bool, budget: Duration) -> (f64, usize) {
    // Calibrate a batch size that takes about 10 ms.
    let started = Instant::now();
    let mut batch = 1usize;
    loop {
        let t = Instant::now();
        for _ in 0..batch {
            f();
        }
        if t.elapsed() > Duration::from_millis(10) || batch > 1 << 24 {
            break;
        }
        batch *= 2;
    }
    let mut samples = Vec::new();
    let mut calls = 0;
    while samples.len() < 5 || started.elapsed() < budget {
        let t = Instant::now();
        for _ in 0..batch {
            f();
        }
        samples.push(t.elapsed().as_secs_f64() / batch as f64);
        calls += batch;
        if samples.len() >= 1000 {
            break;
        }
    }
    samples.sort_by(f64::total_cmp);
    (samples[samples.len() / 2], calls)
}

/// Poses per second through `push` without calibrations, the time of one calibration event, and
/// the time to read one JSON Lines record (the fast path).
fn online_throughput(budget: Duration, progress: &Progress) -> Result<Value> {
    progress.case("online push");
    let s = simulate(
        &SimConfig {
            poses: 1000,
            ..SimConfig::default()
        },
        42,
        0,
    );
    // Thresholds nothing meets and relaxation out of reach: every push searches, none calibrates.
    let params = AdaptiveParams {
        d_max: 100.0,
        interval: usize::MAX / 2,
        ..AdaptiveParams::default()
    };
    let mut quiet = OnlineCalibrator::new(OnlineConfig {
        params,
        ..OnlineConfig::default()
    })?;
    let still = PosePair {
        base_from_gripper: Transform::identity(),
        camera_from_target: Transform::identity(),
    };
    for _ in 0..6 {
        quiet.push(&still)?;
    }
    let mut k = 0;
    let (push, _) = time(
        || {
            k = (k + 1) % s.poses.len();
            quiet.push(&s.poses[k]).is_ok_and(|o| o.events.is_empty())
        },
        budget,
    );
    progress.case("online calibration");
    let pairs = motion_pairs(&s.poses[..3], Pairing::Consecutive, Setup::EyeInHand);
    let (calibration, _) = time(
        || handeye::solve(Method::Andreff, black_box(&pairs)).is_ok(),
        budget,
    );
    progress.case("online parse line");
    // A record as `handeye simulate` writes it: what `online -` reads per pose.
    let matrix = |t| json!(TransformJson::from(t).matrix);
    let line = json!({
        "stamp": 1.0,
        "base_from_gripper": matrix(&s.poses[1].base_from_gripper),
        "camera_from_target": matrix(&s.poses[1].camera_from_target),
    })
    .to_string();
    // Lines per timed call: the stream's opening (its format told from the first line) is
    // spread over as many lines as a real stream's is.
    const LINES: usize = 1000;
    let text: std::rc::Rc<[u8]> = format!("{line}\n").repeat(LINES).into_bytes().into();
    let (stream, _) = time(
        || {
            let input = std::io::Cursor::new(black_box(text.clone()));
            PoseStream::from_reader(
                input,
                "-",
                Format::Auto,
                Default::default(),
                Setup::EyeInHand,
            )
            .is_ok_and(|s| s.filter(Result::is_ok).count() == LINES)
        },
        budget,
    );
    let parse = stream / LINES as f64;
    Ok(json!({
        "push_s": push,
        "push_per_s": 1.0 / push,
        "calibration_s": calibration,
        "parse_line_s": parse,
    }))
}
