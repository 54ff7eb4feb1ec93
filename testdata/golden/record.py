#!/usr/bin/env python3
"""Records (or checks) the golden outputs of the `handeye` CLI.

    python3 testdata/golden/record.py --bin target/release/handeye           # write outputs.jsonl
    python3 testdata/golden/record.py --bin /tmp/other/handeye --check       # compare, write nothing

Runs every command of testdata/golden/commands.txt from the repository root and writes
testdata/golden/outputs.jsonl: one JSON object per command, in order,
{"args": [...], "exit": N, "stdout": "...", "stderr": "..."}. crates/handeye-cli/tests/golden.rs
replays the same commands and compares.

Other projects' data is read in place from the shared folder (testdata/shared_data.py: ../shared/data
beside the repository, or $HANDEYE_SHARED_DATA). A command names it `{shared}`; it runs with the
folder's path in its place, and its outputs name the folder `{shared}` again, so that the baseline
does not depend on where the folder is. Recording needs every set the commands read; `--check`
skips the commands whose set is missing, saying so on one line (HANDEYE_SHARED_REQUIRED=1: exit 1).

Masking (the same in golden.rs), and nothing else: the shared folder's path is written `{shared}`
(above); the one wall-clock timing in the outputs, the `"seconds": <number>` field of `online`'s
events and of their `optimal` transform, is replaced by `"seconds":"*"` (whatever the spacing after
the colon, kept as it was); and in `online`'s stderr the note on rotation matrices projected onto
SO(3), which its reader thread prints at a moment that races with the other thread's messages, is
moved to the end (see PROJECTED below).

The commands run with an empty environment (no RUST_BACKTRACE, CLICOLOR_FORCE, …) and argv[0]
`handeye`, as in the test, so that clap's usage lines name `handeye` whatever the binary's file
is called. Python 3 standard library only.
"""

import argparse
import json
import os
import re
import shlex
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.dirname(HERE))
import shared_data  # noqa: E402  (testdata/shared_data.py: the shared folder's one rule)
COMMANDS = os.path.join(HERE, "commands.txt")
OUTPUTS = os.path.join(HERE, "outputs.jsonl")

# `"seconds":` then spaces or tabs, then a JSON number: the number becomes "*".
SECONDS = re.compile(r'("seconds":[ \t]*)-?[0-9][0-9.eE+\-]*')

# The note that rotation matrices were projected onto SO(3). `online` reads its input on a second
# thread, which prints this note when the input ends, while the first thread is already printing
# its own messages: where the note lands among them is a race. For `online`, these lines are moved
# to the end of stderr (in their order).
PROJECTED = "(rounded when printed): projected onto the nearest rotation"


def mask(text):
    return SECONDS.sub(r'\1"*"', text)


def normalize_stderr(args, text):
    if not args or args[0] != "online":
        return text
    lines = text.split("\n")
    tail = lines.pop() if lines else ""  # what follows the last newline ("" when it ends one)
    notes = [line for line in lines if line.endswith(PROJECTED)]
    others = [line for line in lines if not line.endswith(PROJECTED)]
    return "\n".join(others + notes + [tail])


def read_commands(path):
    """The commands of `path`: each non-blank line not starting with `#`, shell-word split."""
    commands = []
    with open(path, encoding="utf-8") as f:
        for number, line in enumerate(f, 1):
            stripped = line.strip()
            if not stripped or stripped.startswith("#"):
                continue
            try:
                commands.append(shlex.split(stripped, comments=False, posix=True))
            except ValueError as e:
                sys.exit(f"{path}:{number}: {e}")
    return commands


def sets_missing(args):
    """The shared sets a command reads (`{shared}/SET/...`) that are missing."""
    prefix = shared_data.PLACEHOLDER + "/"
    sets = {w.split(prefix, 1)[1].split("/", 1)[0] for w in args if prefix in w}
    return sorted(s for s in sets if shared_data.missing(s))


def run(binary, args):
    done = subprocess.run(
        ["handeye", *[shared_data.unmasked(w) for w in args]],
        executable=binary,
        cwd=ROOT,
        env={},
        stdin=subprocess.DEVNULL,
        capture_output=True,
    )
    return {
        "args": args,
        # Killed by a signal: -1, as in golden.rs.
        "exit": done.returncode if done.returncode >= 0 else -1,
        "stdout": mask(shared_data.masked(done.stdout.decode("utf-8"))),
        "stderr": normalize_stderr(args, mask(shared_data.masked(done.stderr.decode("utf-8")))),
    }


def excerpt(line, at, width=200):
    """Up to `width` characters of `line` around the character `at` (where it first differs)."""
    if len(line) <= width:
        return line
    start = min(max(at - 40, 0), len(line) - width)
    end = start + width
    return ("…" if start > 0 else "") + line[start:end] + ("…" if end < len(line) else "")


def first_difference(expected, actual):
    """Where two texts first differ (as golden.rs says it), or None."""
    a, b = expected.split("\n"), actual.split("\n")
    for k in range(max(len(a), len(b))):
        x = a[k] if k < len(a) else None
        y = b[k] if k < len(b) else None
        if x != y:
            column = 0
            for p, q in zip(x or "", y or ""):
                if p != q:
                    break
                column += 1
            show = lambda line: "<no line>" if line is None else excerpt(line, column)
            return (f"first differing line {k + 1}, column {column + 1} (lines of "
                    f"{len(x or '')} and {len(y or '')} characters):\n"
                    f"    recorded: {show(x)}\n    now:      {show(y)}")
    return None


def check(records, path, commands):
    try:
        with open(path, encoding="utf-8") as f:
            baseline = [json.loads(line) for line in f if line.strip()]
    except FileNotFoundError:
        sys.exit(f"{path} does not exist: record it first (without --check)")
    if [r["args"] for r in baseline] != commands:
        print(f"{path} does not hold the commands of commands.txt (stale): re-record it")
    by_args = {json.dumps(r["args"]): r for r in baseline}
    differing = 0
    for r in records:
        old = by_args.get(json.dumps(r["args"]))
        if old is None:
            print(f"new command (not in the baseline): handeye {shlex.join(r['args'])}")
            differing += 1
            continue
        notes = []
        if old["exit"] != r["exit"]:
            notes.append(f"  exit code: recorded {old['exit']}, now {r['exit']}")
        for stream in ("stdout", "stderr"):
            d = first_difference(old[stream], r[stream])
            if d:
                notes.append(f"  {stream}, {d}")
        if notes:
            differing += 1
            print(f"handeye {shlex.join(r['args'])}")
            print("\n".join(notes))
    print(f"{differing} of {len(records)} command(s) differ")
    return differing == 0


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--bin", required=True, help="the handeye binary to run")
    parser.add_argument("--check", action="store_true",
                        help="compare with outputs.jsonl instead of writing it; exit 1 on a difference")
    parser.add_argument("--jobs", type=int, default=2, help="commands run at once (default 2)")
    parser.add_argument("--commands", default=COMMANDS, help=argparse.SUPPRESS)
    parser.add_argument("--outputs", default=OUTPUTS, help=argparse.SUPPRESS)
    a = parser.parse_args()
    binary = os.path.abspath(a.bin)
    if not os.access(binary, os.X_OK):
        sys.exit(f"{a.bin}: not an executable")
    commands = all_commands = read_commands(a.commands)
    missing = sorted({s for args in commands for s in sets_missing(args)})
    if missing:
        skipped = [args for args in commands if sets_missing(args)]
        why = shared_data.why(f"{len(skipped)} of {len(commands)} command(s), which read " + ", ".join(missing))
        if not a.check or shared_data.required():
            sys.exit(f"cannot run {why}")
        print(f"skipped {why}")
        commands = [args for args in commands if not sets_missing(args)]
    with ThreadPoolExecutor(max_workers=max(1, a.jobs)) as pool:
        records = list(pool.map(lambda args: run(binary, args), commands))
    for r in records:
        if "panicked" in r["stderr"]:
            print(f"warning: handeye {shlex.join(r['args'])} panicked", file=sys.stderr)
    if a.check:
        sys.exit(0 if check(records, a.outputs, all_commands) else 1)
    with open(a.outputs, "w", encoding="utf-8", newline="\n") as f:
        for r in records:
            f.write(json.dumps(r, ensure_ascii=False) + "\n")
    codes = {}
    for r in records:
        codes[r["exit"]] = codes.get(r["exit"], 0) + 1
    size = os.path.getsize(a.outputs)
    summary = ", ".join(f"{n} exit {c}" for c, n in sorted(codes.items()))
    print(f"{len(records)} commands ({summary}); {os.path.relpath(a.outputs, ROOT)}: {size:,} bytes")


if __name__ == "__main__":
    main()
