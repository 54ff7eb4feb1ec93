#!/usr/bin/env python3
"""The library's shape in numbers, as docs/DECISIONS.md quotes them (issue 31).

    python3 scripts/architecture_counts.py [--doc] [--rosbag] [--unnameable] [--shape]

- public items: item pages of `cargo doc -p handeye --no-deps` (structs, enums, functions, traits,
  types, constants, macros, statics; rustdoc's redirect pages left out): what a user can name. With --doc the docs are built first
  (otherwise target/doc/handeye is read as it is); with --rosbag, with the `rosbag` feature.
- unnameable types (--unnameable): public types a user reaches through a public field, variant or
  return type but cannot name (rustc's `unnameable_types` lint over the library), listed.
- public modules: module pages of the same docs.
- files over 400 lines: crates/handeye/src/**/*.rs.
- upward imports: `crate::` paths that climb a layer (the rule of crates/handeye/tests/layers.rs).
- (--shape, issue 51) lines per layer; library functions over 100 lines; import circles between
  the library's files (each `crate::`/`super::` path taken to the file that defines the name, a
  module's re-export followed to its source; test modules left out; a file's use of an enclosing
  module's own file, its folder's face, not counted), the largest first; the
  lines that switch on the `internals` feature; the library's string literals that name a
  command-line flag (`--word`).
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


def rust_files():
    for dirpath, _, files in os.walk(SRC):
        for name in sorted(files):
            if name.endswith(".rs"):
                yield os.path.join(dirpath, name)


def without_tests(text):
    """The code before a file's `#[cfg(test)] mod tests` (always its last item here)."""
    at = re.search(r"^#\[cfg\(test\)\]\s*\nmod tests", text, re.M)
    return text[: at.start()] if at else text


def lines_per_layer():
    out = Counter()
    for path in rust_files():
        rel = os.path.relpath(path, SRC)
        layer = rel.split(os.sep)[0].removesuffix(".rs")
        with open(path, encoding="utf-8") as f:
            out[layer] += sum(1 for _ in f)
    return out


def long_functions(limit=100):
    """Functions whose body spans more than `limit` lines (from `fn` to its closing brace at the
    same indentation)."""
    out = []
    for path in rust_files():
        with open(path, encoding="utf-8") as f:
            lines = f.read().split("\n")
        for k, line in enumerate(lines):
            m = re.match(r"^(\s*)(?:pub(?:\([^)]*\))? )?(?:const )?(?:async )?(?:unsafe )?fn (\w+)", line)
            if not m or line.rstrip().endswith(";"):
                continue
            indent = m.group(1)
            for j in range(k + 1, len(lines)):
                if lines[j] == indent + "}":
                    if j - k + 1 > limit:
                        out.append((j - k + 1, os.path.relpath(path, SRC), m.group(2)))
                    break
    return sorted(out, reverse=True)


def module_files():
    """Module path (tuple) -> file, for every file of the library."""
    mods = {}
    for path in rust_files():
        rel = os.path.relpath(path, SRC)[:-3].split(os.sep)
        if rel[-1] in ("mod", "lib"):
            rel = rel[:-1]
        mods[tuple(rel)] = path
    return mods


def resolve(mods, module, path, seen=0):
    """The file that defines the item at `path` (a list of segments from the crate root) or, for
    a module, the module's file; a module's `use` re-export of the name is followed."""
    k = len(path)
    while k > 0 and tuple(path[:k]) not in mods:
        k -= 1
    if k == 0:
        return None
    file = mods[tuple(path[:k])]
    rest = path[k:]
    if rest and seen < 8:
        with open(file, encoding="utf-8") as f:
            text = without_tests(f.read())
        for m in re.finditer(r"^\s*pub(?:\([^)]*\))? use ([^;]+);", text, re.M):
            for target in expand(m.group(1)):
                if target and target[-1] == rest[0]:
                    full = absolute(path[:k], target, file)
                    if full:
                        return resolve(mods, path[:k], full + rest[1:], seen + 1) or file
    return file


def expand(tree):
    """`a::{b, c::d}` -> [[a, b], [a, c, d]] (`self` and renames kept simple)."""
    tree = re.sub(r"\s+", "", tree)
    out = []

    def walk(prefix, text):
        depth, start, parts = 0, 0, []
        for i, ch in enumerate(text):
            if ch == "{":
                depth += 1
            elif ch == "}":
                depth -= 1
            elif ch == "," and depth == 0:
                parts.append(text[start:i])
                start = i + 1
        parts.append(text[start:])
        for part in filter(None, parts):
            if "{" in part:
                head, inner = part.split("{", 1)
                walk(prefix + [p for p in head.split("::") if p], inner[:-1])
            else:
                segs = [p for p in part.split("as")[0].split("::") if p]
                if segs and segs[-1] == "self":
                    segs = segs[:-1]
                out.append(prefix + segs)

    walk([], tree)
    return out


def absolute(module, segs, file):
    """A `use` path made absolute from the module `module` (list)."""
    if not segs:
        return None
    if segs[0] == "crate":
        return segs[1:]
    if segs[0] == "super":
        base = list(module)
        while segs and segs[0] == "super":
            base, segs = base[:-1], segs[1:]
        return base + segs
    if segs[0] == "self":
        return list(module) + segs[1:]
    if segs[0] in ("std", "core", "alloc", "nalgebra", "serde", "serde_json"):
        return None
    # A child module of this one (`use child::Item` in a mod.rs), else an outside crate.
    return list(module) + segs


def import_graph():
    mods = module_files()
    by_file = {f: m for m, f in mods.items()}
    graph = {f: set() for f in mods.values()}
    for file, module in by_file.items():
        with open(file, encoding="utf-8") as f:
            text = without_tests(f.read())
        text = re.sub(r"//.*", "", text)
        paths = []
        for m in re.finditer(r"\buse ([^;]+);", text):
            paths += expand(m.group(1))
        for m in re.finditer(r"\b((?:crate|super)(?:::\w+)+)", text):
            paths.append(m.group(1).split("::"))
        for segs in paths:
            if segs and segs[-1] == "*":
                continue
            full = absolute(module, segs, file)
            if full is None:
                continue
            target = resolve(mods, module, full)
            # A file's use of an enclosing module's own file (its folder's face, mod.rs) is
            # not counted: a module and its parts are one room.
            if target and by_file.get(target) is not None and tuple(module[: len(by_file[target])]) == by_file[target]:
                continue
            # A module's own declaration of its children is no import.
            if target and target != file and tuple(full) not in mods:
                graph[file].add(target)
            elif target and target != file and len(full) and mods.get(tuple(full)) == target:
                # `use crate::a::b` naming a module: an import of that module's file.
                if tuple(full[:-1]) != tuple(module):
                    graph[file].add(target)
    return graph


def circles(graph):
    """Strongly connected components of more than one file (Tarjan)."""
    index, low, stack, on, out = {}, {}, [], set(), []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on.add(v)
        for w in graph[v]:
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            comp = []
            while True:
                w = stack.pop()
                on.discard(w)
                comp.append(w)
                if w == v:
                    break
            if len(comp) > 1:
                out.append(sorted(os.path.relpath(c, SRC) for c in comp))

    sys.setrecursionlimit(10000)
    for v in graph:
        if v not in index:
            visit(v)
    return sorted(out, key=len, reverse=True)


def shape():
    layers = lines_per_layer()
    print(f"lines per layer: {', '.join(f'{k} {v}' for k, v in sorted(layers.items(), key=lambda kv: -kv[1]))} (total {sum(layers.values())})")
    funcs = long_functions()
    print(f"library functions over 100 lines: {len(funcs)}")
    for n, path, name in funcs:
        print(f"  {n:5} {path} {name}")
    found = circles(import_graph())
    print(f"import circles between files: {len(found)} (largest {max(map(len, found), default=0)} files)")
    for c in found:
        print(f"  {len(c)}: {', '.join(c)}")
    internals = flags = 0
    for path in rust_files():
        with open(path, encoding="utf-8") as f:
            text = f.read()
        internals += len(re.findall(r'feature = "internals"', text))
        flags += len(re.findall(r'"[^"\n]*--[a-z][a-z-]+[^"\n]*"', without_tests(text)))
    print(f"lines switching on `internals`: {internals}")
    print(f"library string literals naming a flag (--word): {flags}")


def unnameable(features):
    """The types rustc's `unnameable_types` lint names (the library rebuilt with the lint on)."""
    out = subprocess.run(
        ["cargo", "rustc", "-p", "handeye", "--lib", "-q", *features, "--", "-W", "unnameable_types"],
        cwd=ROOT, capture_output=True, text=True, check=True,
    )
    found = re.findall(r"warning: (?:struct|enum|trait|type alias|union) `([^`]+)` is reachable but cannot be named", out.stderr)
    return sorted(set(found))


def main():
    if "--shape" in sys.argv:
        shape()
        if not any(a in sys.argv for a in ("--doc", "--unnameable")):
            return
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
