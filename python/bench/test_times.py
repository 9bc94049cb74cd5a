#!/usr/bin/env python3
"""Where the host tests' time goes (issue 28, docs/performance.md section 4): builds the test
binaries of `cargo test --workspace` (a no-op when built), then runs each binary alone as
`cargo test` runs it (its own cwd, its default threads) and prints its wall and CPU (user + sys)
time; with --one-thread NAME..., runs those binaries on one thread and prints each test's time.

Run from the repository root:
    python3 python/bench/test_times.py                       # every binary
    python3 python/bench/test_times.py --one-thread box avoid_adversarial
"""
import argparse
import json
import os
import resource
import subprocess
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def binaries():
    out = subprocess.run(["cargo", "test", "--workspace", "--no-run", "--message-format=json"], cwd=ROOT, capture_output=True, text=True, check=True).stdout
    seen, found = set(), []
    for line in out.splitlines():
        d = json.loads(line)
        if d.get("reason") == "compiler-artifact" and d.get("executable") and d["profile"]["test"] and "bench" not in d["target"]["kind"]:
            if d["executable"] not in seen:
                seen.add(d["executable"])
                found.append((d["target"]["name"], d["target"]["kind"][0], d["executable"], os.path.dirname(d["manifest_path"])))
    return found


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--one-thread", nargs="*", default=None, metavar="NAME")
    a = ap.parse_args()
    bins = binaries()
    if a.one_thread is None:
        print("| test binary | wall, s | CPU (user + sys), s | load |\n|---|---:|---:|---:|")
        for name, kind, exe, cwd in bins:
            r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
            t0 = time.time()
            subprocess.run([exe, "-q"], cwd=cwd, env=dict(os.environ, CARGO_MANIFEST_DIR=cwd), capture_output=True, check=False)
            wall = time.time() - t0
            r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
            cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
            print(f"| {name} ({kind}) | {wall:.1f} | {cpu:.1f} | {os.getloadavg()[0]:.1f} |", flush=True)
        return
    exes = {name: (exe, cwd) for name, _, exe, cwd in bins}
    print("| binary | test | s, one thread |\n|---|---|---:|")
    for name in a.one_thread:
        exe, cwd = exes[name]
        p = subprocess.Popen([exe, "--test-threads=1"], cwd=cwd, env=dict(os.environ, CARGO_MANIFEST_DIR=cwd), stdout=subprocess.PIPE, text=True)
        t = time.time()
        for line in p.stdout:
            if line.startswith("test ") and (" ... ok" in line or "FAILED" in line or "ignored" in line):
                now = time.time()
                print(f"| {name} | `{line.split()[1]}` | {now - t:.1f} |", flush=True)
                t = now
        p.wait()


if __name__ == "__main__":
    main()
