#!/usr/bin/env python3
"""Flinch beside compiled peers on the Tables 5-7 bi-stable scene (issue 28, docs/performance.md).

Runs, in one process and one timing loop (round-robin, so a burst of load hits all alike):
* Flinch: the `flinch` binary's time per run inside a one-thread sweep (`flinch sweep --jobs 1`):
  the difference between a sweep of --points + 2 points and one of 2 points, divided by --points,
  so start-up, reading the scene and writing the CSV's header are not counted; every point is the
  same scene (the swept dead time moves by 1e-12 s in all);
* numbalsoda: LSODA (C) with the right-hand side compiled by numba (`peers_model.rhs_c`), events
  located between its outputs, peaks on a cubic Hermite interpolant;
* numba RK4: a fixed step, events and peaks the same way, with a convergence study of its step;
* the reference: SciPy DOP853 at rtol 1e-12 with every kink located (`peers_reference.py`), checked
  against Flinch's own `fidelity = "reference"`.

Errors are against the reference, on what Flinch reports: peak contact force and peak robot force
(relative), and the detection instant relative to the detection delay (t_detect - t_contact), as
`flinch bench` measures them; "worst" is the largest of the three. Times are medians over
--repeats rounds (each round runs a peer configuration --runs times and takes its median).

Run (from the repository root, after `cargo build --release -p flinch-harness --bin flinch`):

    python3 -m venv target/peers-venv
    target/peers-venv/bin/pip install -r python/bench/requirements-peers.txt
    target/peers-venv/bin/python python/bench/peers.py      # a few minutes; --help for the options

numbalsoda builds from source: it needs a C++ and a Fortran compiler (apt-get install g++ gfortran).
"""
import argparse
import json
import os
import platform
import re
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import peers_model as m  # noqa: E402
import peers_reference as ref  # noqa: E402

ROOT = Path(__file__).resolve().parents[2]
RK4_STEPS = [1.6e-4, 1.2e-4, 8e-5, 6e-5, 4e-5, 3e-5, 2e-5, 1e-5, 5e-6, 2.5e-6]
LSODA_RTOLS = [1e-4, 1e-5, 1e-6, 1e-7, 1e-8, 1e-9, 1e-10]


def scene_text(path, duration, solver):
    text = path.read_text()
    text, n = re.subn(r"(?m)^duration\s*=\s*[0-9.eE+-]+", f"duration = {duration}", text)
    if n != 1:
        raise SystemExit(f"{path}: no top-level `duration = ...` line to set")
    if solver:
        if re.search(r"(?m)^\[solver\]", text):
            raise SystemExit(f"{path}: has a [solver] table already; give one without")
        text += "\n[solver]\n" + "".join(f"{k} = {v}\n" for k, v in solver.items())
    return text


class Flinch:
    def __init__(self, binary, scene, duration, tmp):
        self.bin, self.scene, self.duration, self.tmp = binary, scene, duration, tmp

    def file(self, name, solver):
        p = Path(self.tmp) / f"{name}.toml"
        p.write_text(scene_text(self.scene, self.duration, solver))
        return p

    def run(self, path):
        out = subprocess.run([self.bin, "run", str(path), "--json"], capture_output=True, text=True, check=True)
        return json.loads(out.stdout)

    def sweep_time(self, path, points, dead_time):
        """(wall s, user + sys s) of a one-thread sweep of `points` points."""
        csv = Path(self.tmp) / "sweep.csv"
        spec = f"motion.dead_time={dead_time}:{dead_time + 1e-12}:{points}"
        r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        subprocess.run([self.bin, "sweep", str(path), "--vary", spec, "--jobs", "1", "--csv", str(csv)], check=True, capture_output=True)
        wall = time.perf_counter() - t0
        r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
        return wall, (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)


def quantities_of_flinch(s):
    return dict(peak_contact=s["peak_contact_force"], peak_robot=s["peak_robot_force"], t_contact=s["t_contact"], t_detect=s["t_detect"], contacts=s["contacts"], evals=s["rhs_evals"])


def quantities_of_res(res):
    return dict(peak_contact=res[m.R_PEAK_C], peak_robot=res[m.R_PEAK_R], t_contact=res[m.R_T_CONTACT], t_detect=res[m.R_T_DETECT], contacts=int(res[m.R_CONTACTS]), evals=int(res[m.R_EVALS]))


def errors(q, r):
    """Relative errors on the peak forces, the detection instant relative to the detection delay,
    and the worst of the three; contacts must agree (else the worst is infinite)."""
    delay = r["t_detect"] - r["t_contact"]
    e = dict(
        contact=abs(q["peak_contact"] - r["peak_contact"]) / r["peak_contact"],
        robot=abs(q["peak_robot"] - r["peak_robot"]) / r["peak_robot"],
        detect=abs(q["t_detect"] - r["t_detect"]) / delay if q["t_detect"] >= 0 else float("inf"),
    )
    e["worst"] = max(e.values()) if q["contacts"] == r["contacts"] else float("inf")
    return e


def time_peer(fn, runs):
    """Median of up to `runs` runs, fewer for slow ones (about 0.3 s a round, at least 3)."""
    t0 = time.perf_counter()
    fn()
    one = time.perf_counter() - t0
    ts = [one]
    for _ in range(max(2, min(runs, int(0.3 / max(one, 1e-9)))) - 1):
        t0 = time.perf_counter()
        fn()
        ts.append(time.perf_counter() - t0)
    return statistics.median(ts)


def fmt(x):
    return "-" if x is None else (f"{x:.1e}" if isinstance(x, float) else str(x))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--scene", type=Path, default=ROOT / "scenes" / "tables5-7_bistable.toml")
    ap.add_argument("--duration", type=float, default=0.5, help="simulated s (default 0.5, as issue 28)")
    ap.add_argument("--flinch", default=str(ROOT / "target" / "release" / "flinch"))
    ap.add_argument("--tolerances", default="1e-5,1e-6,1e-8", help="Flinch's rtol (atol = rtol / 1000)")
    ap.add_argument("--repeats", type=int, default=7, help="timing rounds (medians)")
    ap.add_argument("--runs", type=int, default=30, help="peer runs per round (their median)")
    ap.add_argument("--points", type=int, default=1000, help="Flinch sweep points per timing")
    ap.add_argument("--lsoda-chunk", type=float, default=0.01, help="s integrated per LSODA call")
    ap.add_argument("--lsoda-dt-out", default="1e-4,5e-4", help="s between LSODA outputs (each is a configuration)")
    ap.add_argument("--json", type=Path, help="also write every figure here")
    ap.add_argument("--parts", action="store_true", help="only time the parts of the RK4 peer (bare loop, + events, + peaks) and exit")
    a = ap.parse_args()
    tols = [float(x) for x in a.tolerances.split(",")]
    if not Path(a.flinch).is_file():
        raise SystemExit(f"{a.flinch}: no flinch binary (cargo build --release -p flinch-harness --bin flinch)")
    p, y0, t_end = ref.load(a.scene, a.duration)
    print(f"# {a.scene.name}, {t_end} s simulated; {platform.processor() or platform.machine()}, {os.cpu_count()} cores, load average {os.getloadavg()[0]:.2f} at start")

    if a.parts:
        for peaks, evs in ((False, False), (False, True), (True, False), (True, True)):
            n = m.run_rk4_parts(p, y0, 6e-5, t_end, peaks, evs)
            t = statistics.median(time_peer(lambda: m.run_rk4_parts(p, y0, 6e-5, t_end, peaks, evs), a.runs) for _ in range(a.repeats))
            print(f"RK4 h = 6e-5 s, events {'on' if evs else 'off'}, peaks {'on' if peaks else 'off'}: {t * 1e3:.3f} ms a run, {t / n * 1e9:.1f} ns an RHS evaluation ({int(n)})")
        print(f"load average {os.getloadavg()[0]:.2f}")
        return
    t0 = time.perf_counter()
    r = ref.reference(p, y0, t_end)
    print(f"reference (SciPy DOP853, rtol 1e-12, every kink located, {r['steps']} steps, {time.perf_counter() - t0:.1f} s): "
          f"peak contact {r['peak_contact']:.12g} N, peak robot {r['peak_robot']:.12g} N, t_contact {r['t_contact']:.12g} s, t_detect {r['t_detect']:.12g} s, {r['contacts']} contacts")

    with tempfile.TemporaryDirectory() as tmp:
        fl = Flinch(a.flinch, a.scene, t_end, tmp)
        fr = quantities_of_flinch(fl.run(fl.file("reference", {"fidelity": '"reference"'})))
        e = errors(fr, r)
        print(f"Flinch fidelity = \"reference\" against it: contact {e['contact']:.1e}, robot {e['robot']:.1e}, detection {e['detect']:.1e}")

        rows = {}
        for tol in tols:
            path = fl.file(f"rtol{tol:g}", {"rtol": tol, "atol": tol * 1e-3})
            q = quantities_of_flinch(fl.run(path))
            rows[("flinch", tol)] = dict(q=q, e=errors(q, r), path=path, label=f"Flinch rtol {tol:g}")

        m.run_rk4(p, y0, 1e-4, t_end)  # compile
        for h in RK4_STEPS:
            q = quantities_of_res(m.run_rk4(p, y0, h, t_end))
            rows[("rk4", h)] = dict(q=q, e=errors(q, r), label=f"RK4 h = {h:g} s")
        fptr = m.rhs_c.address
        dts = [float(x) for x in a.lsoda_dt_out.split(",")]
        m.run_lsoda(fptr, p, y0, 1e-6, 1e-9, dts[0], a.lsoda_chunk, t_end)
        for dto in dts:
            for rt in LSODA_RTOLS:
                res = m.run_lsoda(fptr, p, y0, rt, rt * 1e-3, dto, a.lsoda_chunk, t_end)
                q = quantities_of_res(res)
                rows[("lsoda", rt, dto)] = dict(q=q, e=errors(q, r), label=f"numbalsoda LSODA rtol {rt:g}, outputs every {dto:g} s")
        m.run_lsoda_bare(fptr, p, y0, 1e-6, 1e-9, t_end)
        for rt in tols:
            n = int(m.run_lsoda_bare(fptr, p, y0, rt, rt * 1e-3, t_end))
            q = dict(peak_contact=float("nan"), peak_robot=float("nan"), t_contact=float("nan"), t_detect=float("nan"), contacts=-1, evals=n)
            rows[("bare", rt)] = dict(q=q, e=dict(contact=float("nan"), robot=float("nan"), detect=float("nan"), worst=float("nan")), label=f"(bound) LSODA rtol {rt:g} in one call, no events: not this scene's answers")

        # The RK4 step a convergence study picks for an error target: the largest h whose
        # quantities move by less than the target when the step is halved (no reference needed).
        def study(target):
            for h in RK4_STEPS:
                half = [k for k in RK4_STEPS if abs(k - h / 2) < 1e-12 * h]
                if half and errors(rows[("rk4", h)]["q"], rows[("rk4", half[0])]["q"])["worst"] <= target:
                    return h
            return RK4_STEPS[-1]

        # Timing: every configuration, round-robin.
        timed = {}
        for rnd in range(a.repeats):
            for key, row in rows.items():
                if key[0] == "flinch":
                    w0, c0 = fl.sweep_time(row["path"], 2, 0.016)
                    w1, c1 = fl.sweep_time(row["path"], a.points + 2, 0.016)
                    timed.setdefault(key, []).append(((w1 - w0) / a.points, (c1 - c0) / a.points))
                elif key[0] == "rk4":
                    h = key[1]
                    timed.setdefault(key, []).append((time_peer(lambda: m.run_rk4(p, y0, h, t_end), a.runs),) * 2)
                elif key[0] == "bare":
                    rt = key[1]
                    timed.setdefault(key, []).append((time_peer(lambda: m.run_lsoda_bare(fptr, p, y0, rt, rt * 1e-3, t_end), a.runs),) * 2)
                else:
                    rt, dto = key[1], key[2]
                    timed.setdefault(key, []).append((time_peer(lambda: m.run_lsoda(fptr, p, y0, rt, rt * 1e-3, dto, a.lsoda_chunk, t_end), a.runs),) * 2)
            print(f"# timing round {rnd + 1}/{a.repeats} done, load average {os.getloadavg()[0]:.2f}", file=sys.stderr)
        for key, ts in timed.items():
            rows[key]["wall"] = statistics.median(t[0] for t in ts)
            rows[key]["cpu"] = statistics.median(t[1] for t in ts)
            rows[key]["wall_range"] = (min(t[0] for t in ts), max(t[0] for t in ts))

    print("\n## Every configuration (time per run: median of rounds; Flinch inside a one-thread sweep)\n")
    print("| configuration | worst error | contact | robot | detection | RHS evals | per run, ms (min-max of rounds) | x real time |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|")
    for key, row in rows.items():
        e, q = row["e"], row["q"]
        lo, hi = row["wall_range"]
        print(f"| {row['label']} | {e['worst']:.1e} | {e['contact']:.1e} | {e['robot']:.1e} | {e['detect']:.1e} | {q['evals']} | {row['wall'] * 1e3:.4f} ({lo * 1e3:.4f}-{hi * 1e3:.4f}) | {t_end / row['wall']:.0f} |")

    print("\n## At matched accuracy: the cheapest peer configuration whose worst error is at most Flinch's\n")
    print("| Flinch rtol | Flinch worst error | Flinch per run, ms | LSODA same rtol: error, ms | LSODA matched (rtol, outputs), ms | RK4 matched (h), ms | RK4 by convergence study (h), error, ms | best peer / Flinch |")
    print("|---:|---:|---:|---|---|---|---|---:|")
    summary = []
    for tol in tols:
        f = rows[("flinch", tol)]
        target = f["e"]["worst"]
        same = min([row for k, row in rows.items() if k[0] == "lsoda" and k[1] == tol], key=lambda row: row["wall"], default=None)
        ok = lambda fam: [row | dict(key=k) for k, row in rows.items() if k[0] == fam and row["e"]["worst"] <= target]
        ls = min(ok("lsoda"), key=lambda row: row["wall"], default=None)
        rk = min(ok("rk4"), key=lambda row: row["wall"], default=None)
        hs = study(target)
        st = rows[("rk4", hs)]
        best = min([x for x in (ls, rk) if x], key=lambda row: row["wall"], default=None)
        ratio = best["wall"] / f["wall"] if best else None
        cell = lambda x: f"{x['wall'] * 1e3:.4f} ({', '.join(f'{v:g}' for v in x['key'][1:])})" if x else "none reaches it"
        same_cell = f"{same['e']['worst']:.1e}, {same['wall'] * 1e3:.4f}" if same else "-"
        print(f"| {tol:g} | {target:.1e} | {f['wall'] * 1e3:.4f} | {same_cell} | {cell(ls)} | {cell(rk)} | {hs:g}: {st['e']['worst']:.1e}, {st['wall'] * 1e3:.4f} | {fmt(ratio if ratio is None else round(ratio, 2))} |")
        summary.append(dict(rtol=tol, flinch_ms=f["wall"] * 1e3, flinch_cpu_ms=f["cpu"] * 1e3, flinch_error=target, ratio_best_peer=ratio))
    print(f"\nload average at the end {os.getloadavg()[0]:.2f}; Flinch CPU (user + sys) per run, ms: " + ", ".join(f"rtol {s['rtol']:g} {s['flinch_cpu_ms']:.4f}" for s in summary))
    if a.json:
        a.json.write_text(json.dumps(dict(reference=r, rows={" ".join(f"{v:g}" if isinstance(v, float) else v for v in k): dict(label=v["label"], errors=v["e"], quantities=v["q"], wall_s=v["wall"], cpu_s=v["cpu"]) for k, v in rows.items()}, summary=summary), indent=1, default=str))


if __name__ == "__main__":
    main()
