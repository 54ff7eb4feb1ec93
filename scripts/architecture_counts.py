#!/usr/bin/env python3
"""The library's shape in numbers, as docs/DECISIONS.md quotes them (issue 31).

    python3 scripts/architecture_counts.py [--doc] [--rosbag] [--unnameable]

- public items: item pages of `cargo doc -p handeye --no-deps` (structs, enums, functions, traits,
  types, constants, macros, statics; rustdoc's redirect pages left out): what a user can name. With --doc the docs are built first
  (otherwise target/doc/handeye is read as it is); with --rosbag, with the `rosbag` feature.
- unnameable types (--unnameable): public types a user reaches through a public field, variant or
  return type but cannot name (rustc's `unnameable_types` lint over the library), listed.
- public modules: module pages of the same docs.
- files over 400 lines: crates/handeye/src/**/*.rs.
- upward imports: `crate::` paths that climb a layer (the rule of crates/handeye/tests/layers.rs).
"""
import os
import re
import shutil
import subprocess
import sys
from collections import Counter

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
SRC = os.path.join(ROOT, "crates", "handeye", "src")
KINDS = ("struct", "enum", "fn", "trait", "type", "constant", "macro", "static")


def doc_dir():
    target = os.environ.get("CARGO_TARGET_DIR", os.path.join(ROOT, "target"))
    return os.path.join(target, "doc", "handeye")


def is_redirect(path):
    """rustdoc leaves a redirect page at a re-exported item's private path: not an item."""
    with open(path, encoding="utf-8") as f:
        return 'http-equiv="refresh"' in f.read(600)


def public_items(doc):
    kinds = Counter()
    modules = 0
    for dirpath, _, files in os.walk(doc):
        for name in files:
            kind = name.split(".", 1)[0]
            path = os.path.join(dirpath, name)
            if not name.endswith(".html") or is_redirect(path):
                continue
            if kind in KINDS:
                kinds[kind] += 1
            elif name == "index.html" and dirpath != doc:
                modules += 1
    return kinds, modules


def long_files():
    out = []
    for dirpath, _, files in os.walk(SRC):
        for name in files:
            if name.endswith(".rs"):
                path = os.path.join(dirpath, name)
                with open(path, encoding="utf-8") as f:
                    lines = sum(1 for _ in f)
                if lines > 400:
                    out.append((lines, os.path.relpath(path, SRC)))
    return sorted(out, reverse=True)


def unnameable(features):
    """The types rustc's `unnameable_types` lint names (the library rebuilt with the lint on)."""
    out = subprocess.run(
        ["cargo", "rustc", "-p", "handeye", "--lib", "-q", *features, "--", "-W", "unnameable_types"],
        cwd=ROOT, capture_output=True, text=True, check=True,
    )
    found = re.findall(r"warning: (?:struct|enum|trait|type alias|union) `([^`]+)` is reachable but cannot be named", out.stderr)
    return sorted(set(found))


def main():
    features = ["--features", "rosbag"] if "--rosbag" in sys.argv else []
    if "--doc" in sys.argv:
        shutil.rmtree(doc_dir(), ignore_errors=True)  # no pages left from an earlier shape
        subprocess.run(["cargo", "doc", "-p", "handeye", "--no-deps", "-q", *features], cwd=ROOT, check=True)
    doc = doc_dir()
    if not os.path.isdir(doc):
        sys.exit(f"no docs at {doc}: run with --doc")
    kinds, modules = public_items(doc)
    total = sum(kinds.values())
    print(f"public items: {total} ({', '.join(f'{n} {k}' for k, n in kinds.most_common())})")
    print(f"public modules: {modules}")
    if "--unnameable" in sys.argv:
        names = unnameable(features)
        print(f"unnameable types: {len(names)}")
        for name in names:
            print(f"  {name}")
    files = long_files()
    print(f"files over 400 lines: {len(files)}")
    for lines, path in files:
        print(f"  {lines:5} {path}")


if __name__ == "__main__":
    main()
