//! Reading one JSON Lines record: the fast path (the common shape, as `handeye simulate` writes
//! it, with shortest round-trip numbers, and as kinhec's recordings print it, with ten significant
//! digits: orthonormal only to about 1e-10, so projected) and the general path (the same record
//! with one more key, which the fast path leaves to serde_json).
//!
//! `cargo bench -p handeye --bench parse_line`

use criterion::{Criterion, criterion_group, criterion_main};
use handeye::TransformJson;
use handeye::io::parse_pose_line;
use handeye::sim::{SimConfig, simulate};
use std::hint::black_box;

/// One simulated pose pair as a JSON line (fixed seed), with `extra` before the closing brace.
fn line(extra: &str, digits: Option<usize>) -> String {
    let s = simulate(&SimConfig::default(), 42, 0);
    let p = &s.poses[1];
    let m = |t| {
        let matrix = TransformJson::from(t).matrix;
        match digits {
            None => serde_json::to_string(&matrix).unwrap(),
            Some(d) => {
                let rows = matrix
                    .map(|row| row.map(|v| format!("{v:.*e}", d - 1).parse::<f64>().unwrap()));
                serde_json::to_string(&rows).unwrap()
            }
        }
    };
    format!(
        "{{\"stamp\":1.0,\"base_from_gripper\":{},\"camera_from_target\":{}{extra}}}",
        m(&p.base_from_gripper),
        m(&p.camera_from_target)
    )
}

fn parse(c: &mut Criterion) {
    for (name, text) in [
        ("parse_line/fast_path", line("", None)),
        ("parse_line/fast_path_10_digits", line("", Some(10))),
        (
            "parse_line/general_path",
            line(",\"frame\":\"tool0\"", None),
        ),
    ] {
        assert!(parse_pose_line(&text, "-", 1).is_ok());
        c.bench_function(name, |b| {
            b.iter(|| parse_pose_line(black_box(&text), "-", 1).unwrap())
        });
    }
}

criterion_group!(benches, parse);
criterion_main!(benches);
