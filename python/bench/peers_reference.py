"""The scene file read into the peers' parameter vector, and the reference the peers and Flinch are
judged against: SciPy's DOP853 at rtol 1e-12 stepped by hand (`scipy.integrate.DOP853.step`), with
every kink of the right-hand side located as an event on DOP853's 7th-order dense output, as
Flinch's own reference mode does (host-harness/src/sim: contact, front stop, back stop, the switch,
and the instants where a contact's or a stop's clamp at zero force takes over), and the peaks
searched on the dense output of every step.

Slow (the right-hand side is called from Python, a few seconds); it runs once per invocation.
"""
import math
import tomllib

import numpy as np
from scipy.integrate import DOP853
from scipy.optimize import brentq, minimize_scalar

import peers_model as m


def load(path, duration):
    """(P, y0) for the Tables 5-7 kind of scene (compliant robot, bi-stable decoupler without
    friction, Hunt-Crossley obstacle, travel switch) at `duration` s; refuses anything else."""
    sc = tomllib.loads(path.read_text())
    mo, r, t, d, tg, se = sc["motion"], sc["robot"], sc["tool"], sc["decoupler"], sc["target"], sc["sensor"]
    if d.get("kind") != "bistable" or "friction" in d or tg.get("kind") != "obstacle" or se.get("kind") != "travel":
        raise SystemExit(f"{path}: the peers model a bi-stable module without friction against an obstacle with a travel switch")
    if tg.get("damping_law", "hunt-crossley") != "hunt-crossley" or d["back_stop"].get("damping_law", "hunt-crossley") != "hunt-crossley":
        raise SystemExit(f"{path}: the peers model the Hunt-Crossley law (eq 7) only")
    if "restitution" in d["front_stop"] or d["front_stop"].get("law", "linear") != "linear":
        raise SystemExit(f"{path}: the peers model the linear front stop {{ stiffness, damping }} (eq 28) only")
    p = np.zeros(m.NP)
    p[m.V], p[m.ACC], p[m.DEC], p[m.DT], p[m.G] = mo["speed"], mo["accel"], mo["decel"], mo["dead_time"], mo.get("gravity", 0.0)
    p[m.MR], p[m.KR], p[m.CR], p[m.MT] = r["mass"], r["stiffness"], r["damping"], t["mass"]
    p[m.NK], p[m.L0], p[m.H] = d["springs"] * d["spring_rate"], d["free_length"], d["height"]
    p[m.C1], p[m.KFE], p[m.CFE] = d["front_stroke"], d["front_stop"]["stiffness"], d["front_stop"]["damping"]
    p[m.BACK], p[m.KBE], p[m.ALPHA_BE] = -d["back_stroke"], d["back_stop"]["stiffness"], 1.5 * (1.0 - d["back_stop"]["restitution"])
    p[m.KC], p[m.ALPHA_C], p[m.THR] = tg["stiffness"], 1.5 * (1.0 - tg["restitution"]), se["threshold"]
    p[m.T1] = p[m.V] / p[m.ACC]
    p[m.T_BRAKE] = math.inf
    w = p[m.MT] * p[m.G]
    # The stable rest nearest the front: spring + front stop + weight = 0 just inside the front stop
    # (Plant::rest_stroke), at rest; the robot lags by w / k_r.
    net = lambda s: m.forces(s, 0.0, -1.0, 0.0, p)[0] + w
    s_rest = brentq(net, p[m.C1] - 1e-3, p[m.C1] + 1e-2, xtol=1e-18, rtol=4 * np.finfo(float).eps)
    xr0 = w / p[m.KR]
    p[m.SURF] = xr0 + s_rest + tg["gap"]
    y0 = np.array([xr0, 0.0, xr0 + s_rest, 0.0])
    return p, y0, duration


def _fun(p):
    f = np.empty(4)

    def fun(t, y):
        m.rhs(t, y, f, p)
        return f.copy()

    return fun


def _g(y, p):
    """All event functions of the reference (Flinch's events 0-6), and what each watches: g > 0 is
    "inside" (in contact, on a stop, pushing)."""
    s, sd = y[2] - y[0], y[3] - y[1]
    dc = y[2] - p[m.SURF]
    return np.array([
        dc,                                          # contact
        s - p[m.C1],                                 # front stop
        p[m.BACK] - s,                               # back stop
        (p[m.C1] - s) - p[m.THR],                    # switch
        p[m.KC] + p[m.CHI_C] * y[3],                 # contact pushes (unclamped law > 0)
        p[m.KFE] * (s - p[m.C1]) + p[m.CFE] * sd,    # front stop pushes
        p[m.KBE] - p[m.CHI_B] * sd,                  # back stop pushes
    ])


def reference(p0, y0, t_end, rtol=1e-12, atol=1e-15):
    """The reference run: a dict of the quantities `peers.py` compares."""
    p = p0.copy()
    fun = _fun(p)
    inside = [bool(v > 0.0) for v in _g(y0, p)]
    inside[3] = False
    armed = lambda i: i in (0, 1, 2, 3) or (i == 4 and inside[0]) or (i == 5 and inside[1]) or (i == 6 and inside[2])
    out = dict(peak_contact=0.0, peak_robot=0.0, t_contact=None, t_detect=None, contacts=0, steps=0)
    best = {0: (0.0, None), 1: (0.0, None)}
    t, y = 0.0, y0.copy()
    while t < t_end:
        tb = m.next_breakpoint(t, p, t_end)
        sol = DOP853(fun, t, y, tb, rtol=rtol, atol=atol, max_step=1e-2)
        hit = None
        while sol.status == "running":
            sol.step()
            out["steps"] += 1
            dense = sol.dense_output()
            g1 = _g(sol.y, p)
            first = None
            for i in range(7):
                if not armed(i) or (i == 3 and out["t_detect"] is not None):
                    continue
                want_up = not inside[i]
                if (g1[i] > 0.0) == want_up:
                    gi = lambda tt, i=i: _g(dense(tt), p)[i]
                    a, b = sol.t_old, sol.t
                    for _ in range(200):  # bisection to the last bit; b stays on the new side
                        mid = 0.5 * (a + b)
                        if mid <= a or mid >= b:
                            break
                        if (gi(mid) > 0.0) == want_up:
                            b = mid
                        else:
                            a = mid
                    if first is None or b < first[1]:
                        first = (i, b)
            t_hi = first[1] if first else sol.t
            _peaks(dense, sol.t_old, t_hi, p, best)
            if first:
                hit = (first[0], first[1], dense(first[1]))
                break
        if hit is None:
            t, y = sol.t, sol.y.copy()
            continue
        i, te, ye = hit
        inside[i] = not inside[i]
        if i == 0 and inside[0]:
            p[m.CHI_C] = p[m.ALPHA_C] * p[m.KC] / max(abs(ye[3]), m.V_IN_MIN)
            out["contacts"] += 1
            out["t_contact"] = out["t_contact"] if out["t_contact"] is not None else te
        if i == 2 and inside[2]:
            p[m.CHI_B] = p[m.ALPHA_BE] * p[m.KBE] / max(abs(ye[3] - ye[1]), m.V_IN_MIN)
        if i == 3:
            out["t_detect"] = te
            tbk = te + p[m.DT]
            xc, vc, _ = m.commanded(tbk, p)
            p[m.T_BRAKE], p[m.XB], p[m.VB], p[m.T_REST] = tbk, xc, vc, vc / p[m.DEC]
        if i in (0, 1, 2) and inside[i]:
            g = _g(ye, p)
            inside[i + 4] = bool(g[i + 4] > 0.0)
        t, y = te, ye.copy()
    for which, key in ((0, "peak_contact"), (1, "peak_robot")):
        out[key] = _refine(best[which], p, which)
    return out


def _force(y, p, which):
    fd, fc = m.forces(y[2] - y[0], y[3] - y[1], y[2], y[3], p)
    return fc if which == 0 else abs(fd)


def _peaks(dense, t0, t1, p, best):
    """Keeps, per force, the step holding the largest of 17 samples (with its dense output and the
    discrete state's chi values then): refined at the end."""
    if t1 <= t0:
        return
    ts = np.linspace(t0, t1, 17)
    ys = dense(ts)
    for which in (0, 1):
        vals = [_force(ys[:, k], p, which) for k in range(17)]
        k = int(np.argmax(vals))
        if vals[k] > best[which][0]:
            best[which] = (vals[k], (dense, ts[max(k - 1, 0)], ts[min(k + 1, 16)], p.copy()))


def _refine(entry, p, which):
    value, where = entry
    if where is None:
        return value
    dense, a, b, pp = where
    r = minimize_scalar(lambda tt: -_force(dense(tt), pp, which), bounds=(a, b), method="bounded", options=dict(xatol=1e-16, maxiter=500))
    return max(value, -r.fun)
