#!/usr/bin/env python3
"""Where a sweep point's instructions go (issue 28, docs/performance.md): runs
`flinch sweep SCENE --vary motion.dead_time=D:D+1e-12:N --jobs 1` under callgrind (every point the
same scene), reads the inclusive instruction counts of the functions that do one kind of work, and
prints them per sweep point and per RHS evaluation.

Instruction counts are exact and do not depend on the machine's load, unlike times on a shared
machine. Functions the compiler inlined have no count of their own: their instructions are in their
caller's row (the DOPRI5 stages, for example, are inside `Driver::advance_to`'s own part).

Run (from the repository root): python3 python/bench/callgrind_breakdown.py [--flinch BIN] [--points N] SCENE...
"""
import argparse
import csv
import re
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

# (label, regex on callgrind_annotate's "file:function" column); inclusive counts.
PARTS = [
    ("whole program", None),
    ("sweep: run the points (`sim::run`)", r":flinch_harness::sim::run \["),
    ("  integration (`Driver::advance_to`)", r"solver/driver\.rs:flinch_harness::solver::driver::Driver<_,_>::advance_to \["),
    ("    RHS: the plant's equations (`Plant::eval`)", r"flinch_harness::plant::Plant::eval \["),
    ("    peaks and bookkeeping after each step (`on_step`)", r"sim/mod\.rs:<flinch_harness::sim::Simulation as flinch_harness::solver::driver::Hybrid<\d+_usize,\d+_usize>>::on_step \["),
    ("      of which the step's interpolant (the `dense` closure)", r"solver/driver\.rs:flinch_harness::solver::driver::Driver<_,_>::advance_to::\{\{closure\}\} \["),
    ("    event functions (`events`)", r"sim/mod\.rs:<flinch_harness::sim::Simulation as flinch_harness::solver::driver::Hybrid<\d+_usize,\d+_usize>>::events \["),
    ("    breakpoints (`next_breakpoint`)", r"::next_breakpoint \["),
    ("    pow (step-size control; the gas law's is in the RHS)", r"e_pow\.c:__ieee754_pow"),
    ("    the rest: DOPRI5's stages, error norm, step control, the driver", "REST"),
    ("  set-up (`Run::new`)", r"flinch_harness::sim::Run::new \["),
    ("  summary (`Run::summary`)", r"flinch_harness::sim::Run::summary \["),
    ("sweep: validate each point's scene (`scene::parse`)", r"scene/mod\.rs:flinch_harness::scene::parse \["),
    ("sweep: CSV and metrics (`write_csv`, `metric`)", r"flinch_harness::sweep::SweepResult::(write_csv|metric) \["),
]


def annotate(out):
    text = subprocess.run(["callgrind_annotate", "--inclusive=yes", "--threshold=100", str(out)], capture_output=True, text=True, check=True).stdout
    rows = []
    for line in text.splitlines():
        mm = re.match(r"\s*([\d,]+) \([ \d.]+%\)\s+(.*)$", line)
        if mm:
            rows.append((int(mm.group(1).replace(",", "")), mm.group(2)))
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("scenes", nargs="+")
    ap.add_argument("--flinch", default=str(ROOT / "target" / "release" / "flinch"))
    ap.add_argument("--points", type=int, default=21)
    a = ap.parse_args()
    for scene in a.scenes:
        with tempfile.TemporaryDirectory() as tmp:
            text = subprocess.run([a.flinch, "scenes", "show", scene], capture_output=True, text=True).stdout if not Path(scene).is_file() else Path(scene).read_text()
            dt = re.search(r"(?m)^dead_time\s*=\s*([0-9.eE+-]+)", text)
            d = float(dt.group(1)) if dt else 0.016
            out = Path(tmp) / "cg.out"
            sw = Path(tmp) / "sw.csv"
            cmd = ["valgrind", "--tool=callgrind", f"--callgrind-out-file={out}", a.flinch, "sweep", scene, "--vary", f"motion.dead_time={d}:{d + 1e-12}:{a.points}", "--jobs", "1", "--csv", str(sw)]
            subprocess.run(cmd, check=True, capture_output=True)
            rows = annotate(out)
            with open(sw) as f:
                pts = list(csv.DictReader(f))
            evals = float(pts[0]["rhs_evals"])
            duration = float(pts[0]["t_end_s"])
        n = a.points
        print(f"\n### {scene}: {int(evals)} RHS evaluations a run, {duration} s simulated, {n} points\n")
        print(f"`{' '.join(cmd[:2])} --callgrind-out-file=OUT {' '.join(cmd[3:-1])} /tmp/sw.csv`\n")
        print("| part | instructions per point | per RHS evaluation | share of a point |")
        print("|---|---:|---:|---:|")
        total = max(c for c, _ in rows)
        per_point = None
        for label, rx in PARTS:
            if rx is None:
                c = total
            elif rx == "REST":
                got = lambda r: max([c for c, name in rows if re.search(r, name)], default=0)
                c = got(PARTS[2][1]) - sum(got(PARTS[k][1]) for k in (3, 4, 6, 7))
            else:
                hits = [c for c, name in rows if re.search(rx, name)]
                c = sum(hits) if "pow" in label or "write_csv" in rx else max(hits, default=0)
            pp = c / n
            if per_point is None:
                per_point = pp
                print(f"| {label} (all {n} points and start-up) | {pp:,.0f} | {pp / evals:,.0f} | 100 % |")
                continue
            print(f"| {label} | {pp:,.0f} | {pp / evals:,.0f} | {100 * pp / per_point:.1f} % |")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
