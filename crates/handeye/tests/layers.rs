//! The library's folders are its layers (lib.rs, "# Layers"): a file may use its own folder and
//! the layers below it, never a layer above nor a sibling of its own rank. This test reads every
//! `crate::` path in the code of `src/` (unit tests included, comments and doc links left out)
//! and fails on each one that climbs, naming the file, the line and the path.

use std::fs;
use std::path::{Path, PathBuf};

/// The layers, bottom first: each folder (or top-level file) with its rank. Folders of one rank
/// are siblings and may not use each other.
const LAYERS: &[(&str, usize)] = &[
    ("model", 0),
    ("sim", 1),
    ("solve", 2),
    ("check", 3),
    ("track", 4),
    ("calibrate", 5),
    ("rig", 5),
    ("online", 6),
    ("io", 7),
    ("experiment", 7),
    ("detect", 8),
];

fn rank(layer: &str) -> Option<usize> {
    LAYERS.iter().find(|(name, _)| *name == layer).map(|l| l.1)
}

fn source_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in fs::read_dir(dir).expect("src/ is readable") {
        let path = entry.expect("a directory entry").path();
        if path.is_dir() {
            source_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The line without its comment (`//` outside a string literal).
fn code_of(line: &str) -> &str {
    let mut in_string = false;
    let bytes = line.as_bytes();
    let mut i = 0;
    while i < bytes.len() {
        match bytes[i] {
            b'\\' if in_string => i += 1,
            b'"' => in_string = !in_string,
            b'/' if !in_string && bytes.get(i + 1) == Some(&b'/') => return &line[..i],
            _ => {}
        }
        i += 1;
    }
    line
}

/// The layers a line of code names through `crate::`: `crate::solve::x` and the groups of
/// `use crate::{solve::x, check::y}`.
fn layers_named(code: &str) -> Vec<String> {
    let mut named = Vec::new();
    let mut rest = code;
    while let Some(at) = rest.find("crate::") {
        let before = rest[..at].chars().next_back();
        rest = &rest[at + "crate::".len()..];
        if before.is_some_and(|c| c.is_alphanumeric() || c == '_' || c == '$') {
            continue; // `$crate::` in a macro, or a longer name
        }
        if let Some(group) = rest.strip_prefix('{') {
            let end = group.find('}').unwrap_or(group.len());
            for item in group[..end].split(',') {
                named.push(first_segment(item.trim()));
            }
        } else {
            named.push(first_segment(rest));
        }
    }
    named.retain(|n| !n.is_empty());
    named
}

fn first_segment(path: &str) -> String {
    path.chars()
        .take_while(|c| c.is_alphanumeric() || *c == '_')
        .collect()
}

#[test]
fn no_import_climbs_a_layer() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    source_files(&src, &mut files);
    files.sort();
    assert!(files.len() > 40, "src/ has only {} files", files.len());
    let mut climbs = Vec::new();
    let mut checked = 0;
    for file in &files {
        let relative = file.strip_prefix(&src).expect("under src/");
        let first = relative
            .components()
            .next()
            .and_then(|c| c.as_os_str().to_str())
            .expect("a file name")
            .trim_end_matches(".rs");
        if first == "lib" {
            continue; // the root re-exports every layer
        }
        let own = rank(first).unwrap_or_else(|| {
            panic!(
                "{}: a file outside every layer: add it to LAYERS and to lib.rs's table",
                relative.display()
            )
        });
        let text = fs::read_to_string(file).expect("a readable source file");
        for (number, line) in text.lines().enumerate() {
            for layer in layers_named(code_of(line)) {
                checked += 1;
                // `crate::named_enum!` is the model's macro (model/names.rs), exported at the root.
                let layer = if layer == "named_enum" {
                    "model".to_string()
                } else {
                    layer
                };
                if layer == first {
                    continue;
                }
                // Any other root path is a re-export that hides its layer: name the layer.
                let theirs = rank(&layer).unwrap_or(usize::MAX);
                if theirs == usize::MAX {
                    climbs.push(format!(
                        "{}:{}: `crate::{layer}` is a root re-export: use its layer's path: {}",
                        relative.display(),
                        number + 1,
                        line.trim()
                    ));
                } else if theirs >= own {
                    climbs.push(format!(
                        "{}:{}: `{first}` (rank {own}) uses `crate::{layer}` (rank {theirs}): {}",
                        relative.display(),
                        number + 1,
                        line.trim()
                    ));
                }
            }
        }
    }
    assert!(
        checked > 200,
        "only {checked} crate paths found: is the scan broken?"
    );
    assert!(
        climbs.is_empty(),
        "{} import(s) climb a layer or cross to a sibling:\n{}",
        climbs.len(),
        climbs.join("\n")
    );
}

/// The layers whose paths a newcomer's first read does not need: the root re-exports every job
/// and every type the jobs return.
const PRIVATE_LAYERS: &[&str] = &["model", "solve", "check", "track", "calibrate", "online"];

/// What a user reads first uses only the facade (the root's re-exports, `io`, `sim`,
/// `experiment`): the examples and the README's Rust. The layers are public modules (the
/// toolbox), so the code would compile either way: the scan is what keeps the first read simple.
#[test]
fn examples_and_the_readme_use_only_the_public_surface() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut texts = vec![root.join("../../README.md")];
    for entry in fs::read_dir(root.join("examples")).expect("examples/ is readable") {
        texts.push(entry.expect("a directory entry").path());
    }
    let mut private = Vec::new();
    for path in &texts {
        let text = fs::read_to_string(path).expect("a readable file");
        for (number, line) in text.lines().enumerate() {
            for layer in PRIVATE_LAYERS {
                if line.contains(&format!("handeye::{layer}::")) {
                    private.push(format!(
                        "{}:{}: {}",
                        path.display(),
                        number + 1,
                        line.trim()
                    ));
                }
            }
        }
    }
    assert!(texts.len() >= 3, "no examples found");
    assert!(
        private.is_empty(),
        "{} line(s) name a layer's path (use the root's re-export):\n{}",
        private.len(),
        private.join("\n")
    );
}

#[test]
fn the_scan_sees_paths_groups_and_skips_comments() {
    assert_eq!(layers_named("use crate::solve::andreff;"), ["solve"]);
    assert_eq!(
        layers_named("use crate::{check::outliers::median, model::pose::Transform};"),
        ["check", "model"]
    );
    assert_eq!(layers_named("let x = crate::io::read(p);"), ["io"]);
    assert!(layers_named("$crate::names::Named").is_empty());
    assert_eq!(code_of("let a = 1; // see crate::io"), "let a = 1; ");
    assert_eq!(
        code_of("let s = \"// not a comment\";"),
        "let s = \"// not a comment\";"
    );
}
