//! Helpers shared by the CLI's integration tests (each test binary uses some of them).
#![allow(dead_code)]

use std::path::{Path, PathBuf};

/// Other projects' data, read in place from the shared folder: the one rule every test follows.
#[path = "../../../handeye/tests/shared_data/mod.rs"]
pub mod shared_data;
#[allow(unused_imports)] // Not every test binary reads the shared folder.
pub use shared_data::shared;

/// A file or directory under the repository's `testdata/`.
pub fn testdata(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../testdata")
        .join(rel)
}

/// Runs `handeye` with `args` and returns (exit code, stdout, stderr); a panic fails the test.
pub fn run(args: &[&str]) -> (i32, String, String) {
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_handeye"))
        .args(args)
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr,
    )
}

/// Runs `handeye ARGS` with `stdin` written from another thread; a run longer than a minute (a
/// pipe waited on) is killed and fails the test. Returns (exit code, stdout, stderr).
pub fn run_fed(args: &[&str], stdin: Vec<u8>) -> (i32, String, String) {
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_handeye"))
        .args(args)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let mut pipe = child.stdin.take().unwrap();
    let writer = std::thread::spawn(move || {
        // The reader may stop early; a broken pipe is its business.
        let _ = std::io::Write::write_all(&mut pipe, &stdin);
    });
    let drain = |mut r: Box<dyn std::io::Read + Send>| {
        std::thread::spawn(move || {
            let mut bytes = Vec::new();
            let _ = r.read_to_end(&mut bytes);
            bytes
        })
    };
    let stdout = drain(Box::new(child.stdout.take().unwrap()));
    let stderr = drain(Box::new(child.stderr.take().unwrap()));
    let start = std::time::Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > std::time::Duration::from_secs(60) {
            child.kill().unwrap();
            let _ = child.wait();
            panic!("{args:?} still running after a minute: a pipe waited on");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    };
    writer.join().unwrap();
    let out = std::process::Output {
        status,
        stdout: stdout.join().unwrap(),
        stderr: stderr.join().unwrap(),
    };
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        stderr,
    )
}

/// `handeye ARGS` with INPUT (`{}` in `args`) a FIFO fed with `bytes`; `None` without `mkfifo`.
#[cfg(unix)]
pub fn run_on_fifo(args: &[&str], bytes: &[u8]) -> Option<(i32, String, String)> {
    use std::os::unix::fs::OpenOptionsExt;
    let dir = tempfile::tempdir().unwrap();
    // No extension: the format is told from the bytes, whatever they are.
    let fifo = dir.path().join("poses");
    if !std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .is_ok_and(|s| s.success())
    {
        eprintln!("mkfifo is missing: FIFO case skipped");
        return None;
    }
    let (bytes, path) = (bytes.to_vec(), fifo.clone());
    let writer = std::thread::spawn(move || {
        if let Ok(mut f) = std::fs::OpenOptions::new().write(true).open(&path) {
            let _ = std::io::Write::write_all(&mut f, &bytes);
        }
    });
    let name = fifo.to_str().unwrap();
    let args: Vec<&str> = args
        .iter()
        .map(|a| if *a == "{}" { name } else { a })
        .collect();
    let result = run_fed(&args, Vec::new());
    // Should the command have ended without opening the FIFO, let the writer go.
    let _ = std::fs::OpenOptions::new()
        .read(true)
        .custom_flags(0o4000) // O_NONBLOCK
        .open(&fifo);
    writer.join().unwrap();
    Some(result)
}

#[cfg(not(unix))]
pub fn run_on_fifo(_: &[&str], _: &[u8]) -> Option<(i32, String, String)> {
    None
}

/// `args` with INPUT (`{}`) replaced by `input`.
pub fn with_input<'a>(args: &[&'a str], input: &'a str) -> Vec<&'a str> {
    args.iter()
        .map(|a| if *a == "{}" { input } else { a })
        .collect()
}

/// A 4×4 matrix written as JSON rows.
pub fn matrix(v: &serde_json::Value) -> nalgebra::Matrix4<f64> {
    let rows = v.as_array().expect("a 4×4 matrix");
    nalgebra::Matrix4::from_fn(|r, c| rows[r][c].as_f64().unwrap())
}

/// The angle (degrees) and translation distance between two rigid transforms.
pub fn apart(a: &nalgebra::Matrix4<f64>, b: &nalgebra::Matrix4<f64>) -> (f64, f64) {
    let ra = a.fixed_view::<3, 3>(0, 0);
    let rb = b.fixed_view::<3, 3>(0, 0);
    let cos = (((ra.transpose() * rb).trace() - 1.0) / 2.0).clamp(-1.0, 1.0);
    let distance = (a.fixed_view::<3, 1>(0, 3) - b.fixed_view::<3, 1>(0, 3)).norm();
    (cos.acos().to_degrees(), distance)
}
