#!/usr/bin/env python3
"""Runs cargo's test executables (library, CLI, integration tests) as `cargo test` would, but
several at a time (`--jobs`, default: the number of cores), longest first.

`cargo test` runs one test executable after the other. Most of the suite's time sits in a few
executables whose long tests generate phantom jaws one after the other, so a core stays idle
while they run; running the executables side by side keeps both cores of the CI machine busy.
Each executable's output is captured and printed when it finishes (all of it when it failed).

Usage: python3 scripts/run_test_binaries.py [--jobs N] -- CARGO_TEST_ARGS...
  e.g. python3 scripts/run_test_binaries.py -- --release --lib --bins --tests
Builds with `cargo test --no-run CARGO_TEST_ARGS --message-format=json`, then runs every
executable from the package root. The order: the executables that took longest in the previous
run (durations kept in target/test-durations.json; on a fresh clone, where there is no previous
run, those of scripts/test-durations.json, committed, so that a fresh CI machine also starts the
longest first), unknown ones first. Exit status 1 when any executable failed (every executable
still runs).
"""

import argparse
import concurrent.futures
import json
import os
import subprocess
import sys
import time

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def executables(cargo_args):
    """The test executables cargo builds for `cargo test --no-run cargo_args` (name, path)."""
    cmd = ["cargo", "test", "--no-run", "--message-format=json-render-diagnostics", *cargo_args]
    out = subprocess.run(cmd, cwd=ROOT, stdout=subprocess.PIPE, check=True, text=True).stdout
    found = []
    for line in out.splitlines():
        try:
            msg = json.loads(line)
        except json.JSONDecodeError:
            continue
        if msg.get("reason") != "compiler-artifact" or not msg.get("executable"):
            continue
        if not msg.get("profile", {}).get("test"):
            continue
        target = msg["target"]
        name = f"{'/'.join(target['kind'])} {target['name']}"
        found.append((name, msg["executable"]))
    return found


def target_dir():
    meta = subprocess.run(
        ["cargo", "metadata", "--format-version", "1", "--no-deps"],
        cwd=ROOT, stdout=subprocess.PIPE, check=True, text=True,
    ).stdout
    return json.loads(meta)["target_directory"]


def run_one(name, path):
    start = time.monotonic()
    proc = subprocess.run([path], cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          text=True, errors="replace")
    return name, proc.returncode, proc.stdout, time.monotonic() - start


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--jobs", type=int, default=os.cpu_count() or 2)
    parser.add_argument("cargo_args", nargs=argparse.REMAINDER)
    args = parser.parse_args()
    cargo_args = [a for a in args.cargo_args if a != "--"]
    exes = executables(cargo_args)
    durations_file = os.path.join(target_dir(), "test-durations.json")
    previous = {}
    for path in (os.path.join(ROOT, "scripts", "test-durations.json"), durations_file):
        try:
            with open(path) as f:
                previous.update(json.load(f))
        except (OSError, ValueError):
            pass
    # Longest first (unknown ones count as long), so the long ones do not finish last alone.
    exes.sort(key=lambda e: -previous.get(e[0], float("inf")))
    print(f"running {len(exes)} test executables, {args.jobs} at a time", flush=True)
    start = time.monotonic()
    failed = []
    durations = {}
    with concurrent.futures.ThreadPoolExecutor(max_workers=args.jobs) as pool:
        futures = [pool.submit(run_one, name, path) for name, path in exes]
        for fut in concurrent.futures.as_completed(futures):
            name, code, output, secs = fut.result()
            durations[name] = round(secs, 2)
            summary = [ln for ln in output.splitlines() if ln.startswith("test result:")]
            status = "ok" if code == 0 else f"FAILED (exit status {code})"
            print(f"---- {name}: {status} in {secs:.1f} s; {' '.join(summary)}", flush=True)
            if code != 0:
                failed.append(name)
                print(output, flush=True)
    previous.update(durations)
    with open(durations_file, "w") as f:
        json.dump(previous, f, indent=1, sort_keys=True)
    print(f"{len(exes)} test executables in {time.monotonic() - start:.0f} s", flush=True)
    if failed:
        print("failed: " + ", ".join(failed), file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
