//! Where the tests find other projects' data: the shared folder, read in place (docs/DECISIONS.md,
//! "Other projects' data is read in place"). The repository keeps no copy of another project's
//! recordings; they sit in `../shared/data/` beside the repository (camodocal's pose pairs,
//! ethz-asl's streams, the converted peers' sets of `testdata/peers/make_peers.py`, ...).
//!
//! One rule, here for every Rust test (the library's, its unit tests' and the command line's
//! include this file) and in `testdata/shared_data.py` for the Python side (pytest, the golden
//! outputs' `record.py`):
//!
//! - the folder is `$HANDEYE_SHARED_DATA` when set (a relative value is taken from the repository's
//!   root), else `<repository root>/../shared/data`;
//! - a set that is not there skips the test (or the part of it) that needs it, with one line on
//!   stderr saying what and why; with `HANDEYE_SHARED_REQUIRED=1` (CI, `.ci/run`) it fails instead.
#![allow(dead_code)] // Each includer uses its own part.

use std::io::Write;
use std::path::{Path, PathBuf};

/// The variable naming the shared folder.
pub const SHARED_DATA: &str = "HANDEYE_SHARED_DATA";

/// The variable that makes a missing set a failure rather than a skip.
pub const SHARED_REQUIRED: &str = "HANDEYE_SHARED_REQUIRED";

/// The placeholder that stands for the shared folder in `testdata/golden/commands.txt` and in the
/// recorded outputs.
pub const PLACEHOLDER: &str = "{shared}";

/// The repository's root (every crate that includes this file is two folders below it).
pub fn repo_root() -> PathBuf {
    let manifest = Path::new(env!("CARGO_MANIFEST_DIR"));
    manifest
        .parent()
        .and_then(Path::parent)
        .unwrap_or(manifest)
        .to_path_buf()
}

/// The shared folder: `$HANDEYE_SHARED_DATA` (relative to the repository's root), else
/// `<repository root>/../shared/data`. It may not exist.
pub fn shared_dir() -> PathBuf {
    let root = repo_root();
    match std::env::var_os(SHARED_DATA) {
        Some(dir) if !dir.is_empty() => root.join(dir),
        _ => root.parent().unwrap_or(&root).join("shared/data"),
    }
}

/// Whether a missing set fails (`HANDEYE_SHARED_REQUIRED` set and not empty nor `0`).
pub fn required() -> bool {
    std::env::var(SHARED_REQUIRED).is_ok_and(|v| !v.is_empty() && v != "0")
}

/// Whether `rel` (a set's folder or a file, e.g. `camodocal` or `peers/visp_eye_in_hand`) is
/// missing from the shared folder.
pub fn missing(rel: &str) -> bool {
    !shared_dir().join(rel).exists()
}

/// Says on one line that `what` is skipped because it is not in the shared folder, written past
/// the test harness's capture so that it shows in `cargo test`'s output; panics instead when
/// `HANDEYE_SHARED_REQUIRED` is set.
pub fn skip(what: &str) {
    let why = format!(
        "not in {}, the shared folder of other projects' data ({SHARED_DATA} names another place)",
        shared_dir().display()
    );
    assert!(!required(), "{what}: {why}; {SHARED_REQUIRED} is set");
    // One write, so that the line is not split among the harness's own.
    let line = format!("skipped {what}: {why}\n");
    let _ = std::io::stderr().lock().write_all(line.as_bytes());
}

/// `rel` in the shared folder, or `None` when it is not there (after [`skip`]'s line, or its
/// panic with `HANDEYE_SHARED_REQUIRED` set).
pub fn shared(rel: &str) -> Option<PathBuf> {
    shared_each(&[rel]).pop().flatten()
}

/// Each of `rels` in the shared folder, or `None` for those that are not there: one line says
/// which are skipped (a panic with `HANDEYE_SHARED_REQUIRED` set).
pub fn shared_each(rels: &[&str]) -> Vec<Option<PathBuf>> {
    let absent: Vec<&str> = rels.iter().copied().filter(|rel| missing(rel)).collect();
    if !absent.is_empty() {
        skip(&absent.join(", "));
    }
    rels.iter()
        .map(|rel| (!absent.contains(rel)).then(|| shared_dir().join(rel)))
        .collect()
}

/// `text` with the shared folder's path written as the placeholder (as the golden outputs hold it).
pub fn masked(text: &str) -> String {
    text.replace(&shared_dir().display().to_string(), PLACEHOLDER)
}

/// `word` with the placeholder replaced by the shared folder's path.
pub fn unmasked(word: &str) -> String {
    word.replace(PLACEHOLDER, &shared_dir().display().to_string())
}
