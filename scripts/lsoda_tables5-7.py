#!/usr/bin/env python3
"""SciPy's LSODA on the window `host-harness/benches/solvers.rs` times our DOPRI5 and the
`differential-equations` crate's on (docs/accuracy.md, issue 12).

The plant of scenes/tables5-7_bistable.toml (read from the file) with the same equations as
host-harness/src/plant: compliant robot m_r x_r'' = c_r (x_c' - x_r') + k_r (x_c - x_r) - F_dec
(eq 33), bi-stable spring F_b = N k_b (L0 - L) s / L, L = sqrt(H^2 + s^2) (eq 24-25), linear
front stop F = -(k d + c s')  for d = s - C1 > 0, pushing only (eq 28), back stop k d^1.5
(d = -C2 - s; never reached here, asserted), tool m_t x_t'' = F_dec + m_t g. The flange
accelerates at a_c to V_c (breakpoint at V_c / a_c, where the integration stops and restarts, as
ours does) and cruises; window [0, 0.2] s, before the tool reaches the target. Starting state: at
rest in static equilibrium (robot offset m_t g / k_r, tool on its front stop), as Plant::new.

Tolerances as our defaults: rtol 1e-6, atol 1e-9, largest step 10 ms. Prints the end state (to
compare with the one `cargo bench -p flinch-harness --bench solvers` prints), the RHS evaluations,
and the median wall time of --repeats runs in this process (the RHS is a plain Python function, as
a SciPy user writes it).

Run: python3 scripts/lsoda_tables5-7.py [--repeats 21]
"""
import argparse
import math
import statistics
import time
import tomllib
from pathlib import Path

import numpy as np
import scipy
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

ROOT = Path(__file__).resolve().parent.parent
T_END = 0.2


def plant(path):
    sc = tomllib.loads(path.read_text())
    m, r, t, d = sc["motion"], sc["robot"], sc["tool"], sc["decoupler"]
    p = dict(
        V=m["speed"], a=m["accel"], g=m.get("gravity", 0.0),
        mr=r["mass"], kr=r["stiffness"], cr=r["damping"], mt=t["mass"],
        nk=d["springs"] * d["spring_rate"], L0=d["free_length"], H=d["height"],
        C1=d["front_stroke"], C2=d["back_stroke"],
        kfe=d["front_stop"]["stiffness"], cfe=d["front_stop"]["damping"], kbe=d["back_stop"]["stiffness"],
    )
    p["t1"] = p["V"] / p["a"]
    return p


def commanded(p, t):
    if t < p["t1"]:
        return 0.5 * p["a"] * t * t, p["a"] * t
    return 0.5 * p["V"] * p["t1"] + p["V"] * (t - p["t1"]), p["V"]


def decoupler(p, s, sd):
    L = math.sqrt(p["H"] ** 2 + s * s)
    f = p["nk"] * (p["L0"] - L) * s / L
    if s > p["C1"]:
        f += min(-p["kfe"] * (s - p["C1"]) - p["cfe"] * sd, 0.0)
    if s < -p["C2"]:
        raise RuntimeError("back stop reached: outside the window this script models")
    return f


def rhs_of(p, counter):
    def rhs(t, y):
        counter[0] += 1
        xr, vr, xt, vt = y
        xc, vc = commanded(p, t)
        fd = decoupler(p, xt - xr, vt - vr)
        ar = (p["cr"] * (vc - vr) + p["kr"] * (xc - xr) - fd) / p["mr"]
        at = (fd + p["mt"] * p["g"]) / p["mt"]
        return [vr, ar, vt, at]
    return rhs


def initial(p):
    w = p["mt"] * p["g"]
    # The stable rest nearest the front: spring + stop + weight = 0 just inside the front stop.
    s_rest = brentq(lambda s: decoupler(p, s, 0.0) + w, p["C1"] - 1e-3, p["C1"] + 1e-2, xtol=1e-18, rtol=1e-15)
    xr0 = w / p["kr"]
    return [xr0, 0.0, xr0 + s_rest, 0.0]


def solve(p, counter):
    y = initial(p)
    rhs = rhs_of(p, counter)
    for a, b in [(0.0, p["t1"]), (p["t1"], T_END)]:
        sol = solve_ivp(rhs, (a, b), y, method="LSODA", rtol=1e-6, atol=1e-9, max_step=1e-2)
        assert sol.success, sol.message
        y = sol.y[:, -1]
    return y


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=21)
    ap.add_argument("--scene", default=str(ROOT / "scenes" / "tables5-7_bistable.toml"))
    args = ap.parse_args()
    p = plant(Path(args.scene))
    counter = [0]
    y = solve(p, counter)
    evals = counter[0]
    times = []
    for _ in range(args.repeats):
        c = [0]
        t0 = time.perf_counter()
        solve(p, c)
        times.append(time.perf_counter() - t0)
    med = statistics.median(times)
    print(f"scipy {scipy.__version__}, numpy {np.__version__}: LSODA rtol 1e-6 atol 1e-9 max_step 1e-2 over [0, {T_END}] s")
    print(f"end state: x_r {y[0]:.12e} m, v_r {y[1]:.12e} m/s, x_t {y[2]:.12e} m, v_t {y[3]:.12e} m/s")
    print(f"rhs_evaluations {evals}, median_wall_s {med:.6e} over {args.repeats} runs, per_rhs_us {med / evals * 1e6:.3f}")


if __name__ == "__main__":
    main()
