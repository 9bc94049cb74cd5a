"""The Tables 5-7 bi-stable scene as the peers of `peers.py` integrate it: the model compiled with
numba, a fixed-step RK4 driver and a driver for numbalsoda's LSODA, each with located events
(contact onset and separation, the back stop, the travel switch) and a peak search on a cubic
Hermite interpolant, as a competent engineer would write them.

The equations are host-harness/src/plant's for this scene (eq 24-25, 28, 33, 37, 7; MODEL.md):
state y = [x_r, v_r, x_t, v_t] (m, m/s), s = x_t - x_r,
  m_r x_r'' = c_r (x_c' - x_r') + k_r (x_c - x_r) - F_dec                      (compliant robot)
  m_t x_t'' = F_dec - F_c + m_t g                                                (tool)
  F_dec = N k_b (L0 - L) s / L, L = sqrt(H^2 + s^2)                              (bi-stable springs)
        + min(-k_fe (s - C1) - c_fe s', 0)              for s > C1              (front stop, eq 28)
        + max(k_be d^1.5 + chi_be d^1.5 d', 0), d = -C2 - s > 0, d' = -s'     (back stop, eq 37)
  F_c  = max(k_c d^1.5 + chi_c d^1.5 x_t', 0),  d = x_t - x_surface > 0          (surface, eq 5-7)
chi = 1.5 (1 - e) k / max(|v_in|, 1 mm/s) fixed at each onset from the approach velocity (eq 7,
Hunt-Crossley). The flange accelerates at a_c to V_c, cruises, and brakes at d_c from
t_detect + DT (t_detect: the tool has travelled `threshold` back from its front stop).

Reported, as `flinch run` reports them: peak contact force, peak robot force (|F_dec|, the force the
tool puts on the robot), contact and detection instants, number of contacts, RHS evaluations.
"""
import math

import numpy as np
from numba import carray, cfunc, njit, types
from numbalsoda import lsoda

# Parameter vector P: the scene, then the discrete state the events set, then the RHS counter.
V, ACC, DEC, DT, MR, KR, CR, MT, NK, L0, H, C1, KFE, CFE, BACK, KBE, ALPHA_BE, SURF, KC, ALPHA_C, THR, G, T1 = range(23)
CHI_C, CHI_B, T_BRAKE, XB, VB, T_REST, COUNT = range(23, 30)
NP = 30
V_IN_MIN = 1e-3  # m/s, plant::contact::V_IN_MIN

# Result vector of a run.
R_PEAK_C, R_PEAK_R, R_T_CONTACT, R_T_DETECT, R_CONTACTS, R_EVALS, R_STEPS = range(7)
NR = 7


@njit(cache=True)
def commanded(t, p):
    """x_c, x_c', x_c'' at t: the trapezoid, braking from T_BRAKE (MotionLaw::at)."""
    tb = p[T_BRAKE]
    if t > tb:
        tau = min(t - tb, p[T_REST])
        moving = t - tb < p[T_REST]
        return p[XB] + p[VB] * tau - 0.5 * p[DEC] * tau * tau, max(p[VB] - p[DEC] * tau, 0.0), -p[DEC] if moving else 0.0
    tt = max(t, 0.0)
    if tt < p[T1]:
        return 0.5 * p[ACC] * tt * tt, p[ACC] * tt, p[ACC]
    return 0.5 * p[V] * p[T1] + p[V] * (tt - p[T1]), p[V], 0.0


@njit(cache=True)
def forces(s, sd, xt, vt, p):
    """(F_dec, F_c), N."""
    L = math.sqrt(p[H] * p[H] + s * s)
    f = p[NK] * (p[L0] - L) * s / L
    if s > p[C1]:
        f += min(-p[KFE] * (s - p[C1]) - p[CFE] * sd, 0.0)
    d = p[BACK] - s
    if d > 0.0:
        dn = d * math.sqrt(d)
        f += max(p[KBE] * dn - p[CHI_B] * dn * sd, 0.0)
    fc = 0.0
    dc = xt - p[SURF]
    if dc > 0.0:
        dn = dc * math.sqrt(dc)
        fc = max(p[KC] * dn + p[CHI_C] * dn * vt, 0.0)
    return f, fc


@njit(cache=True)
def rhs_into(t, x_r, v_r, x_t, v_t, p):
    """The right-hand side as one function of scalars (what `commanded` and `forces` compute,
    written out so nothing is called per evaluation): (v_r', v_t')."""
    tb = p[T_BRAKE]
    if t > tb:
        tau = min(t - tb, p[T_REST])
        xc = p[XB] + p[VB] * tau - 0.5 * p[DEC] * tau * tau
        vc = max(p[VB] - p[DEC] * tau, 0.0)
    elif t < p[T1]:
        tt = max(t, 0.0)
        xc = 0.5 * p[ACC] * tt * tt
        vc = p[ACC] * tt
    else:
        xc = 0.5 * p[V] * p[T1] + p[V] * (t - p[T1])
        vc = p[V]
    s = x_t - x_r
    sd = v_t - v_r
    L = math.sqrt(p[H] * p[H] + s * s)
    f = p[NK] * (p[L0] - L) * s / L
    if s > p[C1]:
        f += min(-p[KFE] * (s - p[C1]) - p[CFE] * sd, 0.0)
    d = p[BACK] - s
    if d > 0.0:
        dn = d * math.sqrt(d)
        f += max(p[KBE] * dn - p[CHI_B] * dn * sd, 0.0)
    fc = 0.0
    dc = x_t - p[SURF]
    if dc > 0.0:
        dn = dc * math.sqrt(dc)
        fc = max(p[KC] * dn + p[CHI_C] * dn * v_t, 0.0)
    return (p[CR] * (vc - v_r) + p[KR] * (xc - x_r) - f) / p[MR], (f - fc + p[MT] * p[G]) / p[MT]


@njit(cache=True)
def rhs(t, y, dy, p):
    p[COUNT] += 1.0
    a_r, a_t = rhs_into(t, y[0], y[1], y[2], y[3], p)
    dy[0] = y[1]
    dy[1] = a_r
    dy[2] = y[3]
    dy[3] = a_t


lsoda_sig = types.void(types.double, types.CPointer(types.double), types.CPointer(types.double), types.CPointer(types.double))


@cfunc(lsoda_sig, cache=True)
def rhs_c(t, u, du, p):
    """The same right-hand side for numbalsoda (C pointers; P is the `data` array)."""
    p[COUNT] += 1.0
    pa = carray(p, NP)
    a_r, a_t = rhs_into(t, u[0], u[1], u[2], u[3], pa)
    du[0] = u[1]
    du[1] = a_r
    du[2] = u[3]
    du[3] = a_t


NE = 5  # events: contact, back stop, switch, front stop, front stop pushing


@njit(cache=True)
def events(y, p):
    """Event functions, each positive "inside": contact penetration, back-stop penetration, the
    switch signal (fires upwards, once), front-stop penetration, and the front stop's unclamped
    force (its clamp at zero force is a kink of F_dec, where the peak robot force sits)."""
    s = y[2] - y[0]
    return y[2] - p[SURF], p[BACK] - s, (p[C1] - s) - p[THR], s - p[C1], p[KFE] * (s - p[C1]) + p[CFE] * (y[3] - y[1])


@njit(cache=True)
def event(y, p, i):
    """Event function i of `events`, without building the tuple (a tuple indexed at run time is
    slow in numba)."""
    s = y[2] - y[0]
    if i == 0:
        return y[2] - p[SURF]
    if i == 1:
        return p[BACK] - s
    if i == 2:
        return (p[C1] - s) - p[THR]
    if i == 3:
        return s - p[C1]
    return p[KFE] * (s - p[C1]) + p[CFE] * (y[3] - y[1])


@njit(cache=True)
def next_breakpoint(t, p, t_end):
    """The next instant after t where x_c'' jumps: end of the acceleration, start and end of braking."""
    b = t_end
    for c in (p[T1], p[T_BRAKE], p[T_BRAKE] + p[T_REST]):
        if c > t and c < b:
            b = c
    return b


@njit(cache=True)
def hermite(t0, y0, f0, t1, y1, f1, t, out):
    """Cubic Hermite interpolant of the step [t0, t1] at t (state and derivative at both ends)."""
    h = t1 - t0
    th = (t - t0) / h
    h00 = (1.0 + 2.0 * th) * (1.0 - th) ** 2
    h10 = th * (1.0 - th) ** 2
    h01 = th * th * (3.0 - 2.0 * th)
    h11 = th * th * (th - 1.0)
    for i in range(4):
        out[i] = h00 * y0[i] + h * h10 * f0[i] + h01 * y1[i] + h * h11 * f1[i]


@njit(cache=True)
def force_pair(y, p):
    fd, fc = forces(y[2] - y[0], y[3] - y[1], y[2], y[3], p)
    return fc, abs(fd)


@njit(cache=True)
def force_of(y, p, which):
    """The contact force (which = 0) or the robot force's magnitude (1)."""
    fd, fc = forces(y[2] - y[0], y[3] - y[1], y[2], y[3], p)
    return fc if which == 0 else abs(fd)


@njit(cache=True)
def force_at(t0, y0, f0, t1, y1, f1, t, p, which, yi):
    hermite(t0, y0, f0, t1, y1, f1, t, yi)
    return force_of(yi, p, which)


@njit(cache=True)
def refine(t0, y0, f0, t1, y1, f1, p, which, a, m, b, yi):
    """The maximum of the contact (which = 0) or robot (1) force on the step's Hermite interpolant,
    from its samples at the ends and the middle (a, m, b): successive parabolic interpolation inside
    the bracket until the gain is below 1e-13 of the peak (forces only, no RHS evaluation)."""
    xa, xb, xc = t0, 0.5 * (t0 + t1), t1
    fa, fb, fc = a, m, b
    best = max(a, m, b)
    for _ in range(12):
        p1 = (xb - xa) * (fb - fc)
        q1 = (xb - xc) * (fb - fa)
        den = p1 - q1
        if den == 0.0:
            break
        x = xb - 0.5 * ((xb - xa) * p1 - (xb - xc) * q1) / den
        if not (x > xa and x < xc) or x == xb:
            break
        fx = force_at(t0, y0, f0, t1, y1, f1, x, p, which, yi)
        gain = fx - fb
        if fx > fb:
            if x < xb:
                xc, fc = xb, fb
            else:
                xa, fa = xb, fb
            xb, fb = x, fx
        elif x < xb:
            xa, fa = x, fx
        else:
            xc, fc = x, fx
        if fx > best:
            best = fx
        if abs(gain) <= 1e-13 * abs(fb):
            break
    return best


@njit(cache=True)
def locate(t0, y0, f0, t1, y1, f1, p, which, up, yi):
    """theta in (0, 1] where event `which` first reaches its new side on the Hermite interpolant
    (bisection to 1e-14 of the step; the end returned is on the new side)."""
    a, b = 0.0, 1.0
    for _ in range(60):
        if b - a < 1e-14:
            break
        m = 0.5 * (a + b)
        hermite(t0, y0, f0, t1, y1, f1, t0 + m * (t1 - t0), yi)
        g = event(yi, p, which)
        if (g > 0.0) == up:
            b = m
        else:
            a = m
    return b


@njit(cache=True)
def react(which, t, y, p, flags, res):
    """An event's reaction. flags = [in_contact, on_back, detected, on_front, front_pushing]."""
    s_dot = y[3] - y[1]
    if which == 0:
        if flags[0] == 0:
            flags[0] = 1
            p[CHI_C] = p[ALPHA_C] * p[KC] / max(abs(y[3]), V_IN_MIN)
            res[R_CONTACTS] += 1
            if res[R_T_CONTACT] < 0:
                res[R_T_CONTACT] = t
        else:
            flags[0] = 0
    elif which == 1:
        if flags[1] == 0:
            flags[1] = 1
            p[CHI_B] = p[ALPHA_BE] * p[KBE] / max(abs(s_dot), V_IN_MIN)
        else:
            flags[1] = 0
    elif which == 3:
        flags[3] = 1 - flags[3]
        if flags[3] == 1:
            flags[4] = 1 if event(y, p, 4) > 0.0 else 0
    elif which == 4:
        flags[4] = 1 - flags[4]
    else:
        flags[2] = 1
        res[R_T_DETECT] = t
        tb = t + p[DT]
        xc, vc, _ = commanded(tb, p)
        p[T_BRAKE] = tb
        p[XB] = xc
        p[VB] = vc
        p[T_REST] = vc / p[DEC]


@njit(cache=True)
def crossing_of(y0, y1, p, flags, i):
    """Event i armed and crossed to its new side between the states y0 and y1."""
    if (i == 2 and flags[2] == 1) or (i == 4 and flags[3] == 0):
        return False
    up = is_up(flags, i)
    return ((event(y0, p, i) > 0.0) != up) and ((event(y1, p, i) > 0.0) == up)


@njit(cache=True)
def is_up(flags, i):
    """The crossing watched: upwards (into) for an event whose flag is off; the switch always."""
    return True if i == 2 else flags[i] == 0


@njit(cache=True)
def note_peaks(t0, y0, f0, t1, y1, f1, p, res, yi):
    """Peaks on the step [t0, t1]: its ends, and inside it where the parabola through the ends and
    the middle (Hermite interpolant) has its vertex in or near the step above 99.9 % of the peak
    so far; there successive parabolic interpolation refines it."""
    h = t1 - t0
    hermite(t0, y0, f0, t1, y1, f1, t0 + 0.5 * h, yi)
    a0, a1 = force_pair(y0, p)
    b0, b1 = force_pair(y1, p)
    m0, m1 = force_pair(yi, p)
    for which in range(2):
        a = a0 if which == 0 else a1
        b = b0 if which == 0 else b1
        m = m0 if which == 0 else m1
        peak = res[R_PEAK_C + which]
        top = max(a, m, b)
        if top > peak:
            peak = top
        # Parabola through (0, a), (1/2, m), (1, b) in theta: vertex and value.
        c2 = 2.0 * (a - 2.0 * m + b)
        if c2 < 0.0 and top > 0.0:
            c1 = -3.0 * a + 4.0 * m - b
            th = -c1 / (2.0 * c2)
            vmax = a + c1 * th + c2 * th * th
            if th > -0.25 and th < 1.25 and vmax > (1.0 - 1e-3) * peak:
                v = refine(t0, y0, f0, t1, y1, f1, p, which, a, m, b, yi)
                if v > peak:
                    peak = v
        res[R_PEAK_C + which] = peak


@njit(cache=True)
def rk4_step(t, y, k1, h, p, out, w):
    """One RK4 step; w is (3, 4) scratch."""
    k2, k3, yt = w[0], w[1], w[2]
    for i in range(4):
        yt[i] = y[i] + 0.5 * h * k1[i]
    rhs(t + 0.5 * h, yt, k2, p)
    for i in range(4):
        yt[i] = y[i] + 0.5 * h * k2[i]
    rhs(t + 0.5 * h, yt, k3, p)
    for i in range(4):
        yt[i] = y[i] + h * k3[i]
        k2[i] += k3[i]
    rhs(t + h, yt, k3, p)
    for i in range(4):
        out[i] = y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + k3[i])


@njit(cache=True)
def earliest(t0, y0, f0, t1, y1, f1, p, flags, yi):
    """The earliest armed event crossing in [t0, t1] located on the Hermite interpolant:
    (event, theta), or (-1, 1.0)."""
    first, best = -1, 2.0
    for i in range(NE):
        if crossing_of(y0, y1, p, flags, i):
            up = is_up(flags, i)
            th = locate(t0, y0, f0, t1, y1, f1, p, i, up, yi)
            if th < best:
                first, best = i, th
    return first, best


@njit(cache=True)
def initial_flags(y0, p):
    """The discrete state at the start: the tool rests on its front stop, which pushes."""
    flags = np.zeros(5, dtype=np.int64)
    g = events(y0, p)
    flags[3] = 1 if g[3] > 0.0 else 0
    flags[4] = 1 if flags[3] == 1 and g[4] > 0.0 else 0
    return flags


@njit(cache=True)
def run_rk4(p0, y0, h, t_end):
    """Fixed-step RK4 at step h over [0, t_end]; steps land on the motion law's breakpoints, events
    are located on the step's Hermite interpolant and the step is taken again to the event.
    Allocation-free inner loop (scratch arrays made once)."""
    p = p0.copy()
    res = np.zeros(NR)
    res[R_T_CONTACT] = -1.0
    res[R_T_DETECT] = -1.0
    flags = initial_flags(y0, p)
    buf = np.empty((9, 4))
    y, f, y1, f1, ye, fe, yi = buf[0], buf[1], buf[2], buf[3], buf[4], buf[5], buf[6]
    w = np.empty((3, 4))
    t = 0.0
    y[:] = y0
    rhs(t, y, f, p)
    steps = 0
    while t < t_end:
        b = next_breakpoint(t, p, t_end)
        lands = t + h >= b
        t1 = b if lands else t + h
        rk4_step(t, y, f, t1 - t, p, y1, w)
        rhs(t1, y1, f1, p)
        steps += 1
        ev, th = earliest(t, y, f, t1, y1, f1, p, flags, yi)
        if ev >= 0:
            te = t + th * (t1 - t)
            rk4_step(t, y, f, te - t, p, ye, w)
            rhs(te, ye, fe, p)
            note_peaks(t, y, f, te, ye, fe, p, res, yi)
            react(ev, te, ye, p, flags, res)
            t = te
            y[:] = ye
            rhs(t, y, f, p)
        else:
            note_peaks(t, y, f, t1, y1, f1, p, res, yi)
            t = t1
            y[:] = y1
            if lands:
                rhs(t, y, f, p)
            else:
                f[:] = f1
    res[R_EVALS] = p[COUNT]
    res[R_STEPS] = steps
    return res


@njit(cache=True)
def stream_push(t, y, p, res, st_t, st_y, st_v, n, fs, yi):
    """Peaks from a stream of output samples (LSODA): each sample's forces count; where the middle
    one of the last three is a local maximum above 99.9 % of the peak so far, the two intervals
    around it are searched on their Hermite interpolants (three RHS evaluations for the slopes).
    Returns the number of samples held (at most 3). fs is (3, 4) scratch."""
    for j in range(2):
        st_t[j] = st_t[j + 1]
        st_y[j, :] = st_y[j + 1, :]
        st_v[j, :] = st_v[j + 1, :]
    st_t[2] = t
    st_y[2, :] = y
    fc, fr = force_pair(y, p)
    st_v[2, 0] = fc
    st_v[2, 1] = fr
    for which in range(2):
        if st_v[2, which] > res[R_PEAK_C + which]:
            res[R_PEAK_C + which] = st_v[2, which]
    n = min(n + 1, 3)
    if n < 3:
        return n
    have = False
    for which in range(2):
        v0, v1, v2 = st_v[0, which], st_v[1, which], st_v[2, which]
        if v1 > v0 and v1 >= v2 and v1 > (1.0 - 1e-3) * res[R_PEAK_C + which]:
            if not have:
                for j in range(3):
                    rhs(st_t[j], st_y[j], fs[j], p)
                have = True
            for j in range(2):
                t0, t1 = st_t[j], st_t[j + 1]
                if t1 <= t0:
                    continue
                hermite(t0, st_y[j], fs[j], t1, st_y[j + 1], fs[j + 1], 0.5 * (t0 + t1), yi)
                m = force_of(yi, p, which)
                v = refine(t0, st_y[j], fs[j], t1, st_y[j + 1], fs[j + 1], p, which, st_v[j, which], m, st_v[j + 1, which], yi)
                if v > res[R_PEAK_C + which]:
                    res[R_PEAK_C + which] = v
    return n


@njit(cache=True)
def land(funcptr, t0, y0, te, p, rtol, atol, seg, out):
    """LSODA from (t0, y0) to te (a fresh start); False if it failed."""
    if te - t0 <= 1e-13 * max(1.0, abs(te)):
        out[:] = y0
        return True
    seg[0] = t0
    seg[1] = te
    u, ok = lsoda(funcptr, y0, seg, p, rtol, atol, 100000)
    out[:] = u[1]
    return ok


@njit(cache=True)
def run_lsoda(funcptr, p0, y0, rtol, atol, dt_out, chunk, t_end):
    """numbalsoda's LSODA in chunks of `chunk` s (each call starts LSODA afresh: it has neither
    events nor a way to continue), outputs every `dt_out` s. An event is found between two outputs
    and estimated on their Hermite interpolant (two RHS evaluations for the slopes); LSODA then
    integrates again from the output before it to each trial instant of an Illinois iteration on
    the event function, down to 1e-10 s; what the chunk computed after the event is discarded."""
    p = p0.copy()
    res = np.zeros(NR)
    res[R_T_CONTACT] = -1.0
    res[R_T_DETECT] = -1.0
    flags = initial_flags(y0, p)
    st_t = np.zeros(3)
    st_y = np.zeros((3, 4))
    st_v = np.zeros((3, 2))
    buf = np.empty((8, 4))
    buf2 = np.empty((1, 4))
    yn = buf2[0]
    y, fa, fb, ye, yi, fs = buf[0], buf[1], buf[2], buf[3], buf[4], buf[5:8]
    seg = np.empty(2)
    t = 0.0
    y[:] = y0
    n_st = stream_push(t, y, p, res, st_t, st_y, st_v, 0, fs, yi)
    calls = 0
    while t < t_end:
        bp = next_breakpoint(t, p, t_end)
        # A chunk ends at the next breakpoint when that is less than half a chunk further.
        tend = bp if bp - t < 1.5 * chunk else t + chunk
        n = max(1, int(math.ceil((tend - t) / dt_out - 1e-9)))
        grid = np.linspace(t, tend, n + 1)
        usol, ok = lsoda(funcptr, y, grid, p, rtol, atol, 100000)
        calls += 1
        if not ok:
            res[R_EVALS] = -1.0
            return res
        moved = False
        for k in range(n):
            ya = usol[k]
            yb = usol[k + 1]
            found = False
            for i in range(NE):
                if crossing_of(ya, yb, p, flags, i):
                    found = True
            if not found:
                n_st = stream_push(grid[k + 1], yb, p, res, st_t, st_y, st_v, n_st, fs, yi)
                continue
            rhs(grid[k], ya, fa, p)
            rhs(grid[k + 1], yb, fb, p)
            ev, th = earliest(grid[k], ya, fa, grid[k + 1], yb, fb, p, flags, yi)
            # Illinois on the event function, each value from LSODA landing on the trial
            # instant (from the output before it): the Hermite estimate first, then until the
            # bracket is below 1e-10 s (Flinch locates to 1e-12 s on its own interpolant).
            up = is_up(flags, ev)
            ta, tb_ = grid[k], grid[k + 1]
            ga, gb = event(ya, p, ev), event(yb, p, ev)
            yn[:] = yb
            te = ta + th * (tb_ - ta)
            side = 0
            for _ in range(12):
                if not land(funcptr, grid[k], ya, te, p, rtol, atol, seg, ye):
                    res[R_EVALS] = -1.0
                    return res
                calls += 1
                ge = event(ye, p, ev)
                if (ge > 0.0) == up:
                    tb_, gb = te, ge
                    yn[:] = ye
                    if side == 1:
                        ga *= 0.5
                    side = 1
                else:
                    ta, ga = te, ge
                    if side == -1:
                        gb *= 0.5
                    side = -1
                if tb_ - ta < 1e-10:
                    break
                te = tb_ - gb * (tb_ - ta) / (gb - ga) if gb != ga else 0.5 * (ta + tb_)
                if not (te > ta and te < tb_):
                    te = 0.5 * (ta + tb_)
            te = tb_
            ye[:] = yn
            n_st = stream_push(te, ye, p, res, st_t, st_y, st_v, n_st, fs, yi)
            react(ev, te, ye, p, flags, res)
            t = te
            y[:] = ye
            moved = True
            break
        if not moved:
            t = tend
            y[:] = usol[n]
    res[R_EVALS] = p[COUNT]
    res[R_STEPS] = calls
    return res


@njit(cache=True)
def run_lsoda_bare(funcptr, p0, y0, rtol, atol, t_end):
    """LSODA over [0, t_end] in one call, two outputs, no event: what numbalsoda costs on this
    right-hand side when nothing else is asked of it (the contact's chi stays 0 and the robot never
    brakes, so its answers are not this scene's; a lower bound of the cost, not a result)."""
    p = p0.copy()
    grid = np.array([0.0, t_end])
    lsoda(funcptr, y0, grid, p, rtol, atol, 1000000)
    return p[COUNT]


@njit(cache=True)
def run_rk4_parts(p0, y0, h, t_end, peaks, evs):
    """RK4 at h without breakpoints and reactions, with the peak search and the event check each
    switched on or off: what each part of `run_rk4` costs (`peers.py --parts`). Returns the RHS
    evaluations."""
    p = p0.copy()
    res = np.zeros(NR)
    flags = initial_flags(y0, p)
    buf = np.empty((5, 4))
    y, f, y1, f1, yi = buf[0], buf[1], buf[2], buf[3], buf[4]
    w = np.empty((3, 4))
    t = 0.0
    y[:] = y0
    rhs(t, y, f, p)
    while t < t_end:
        t1 = t + h
        rk4_step(t, y, f, h, p, y1, w)
        rhs(t1, y1, f1, p)
        if evs:
            earliest(t, y, f, t1, y1, f1, p, flags, yi)
        if peaks:
            note_peaks(t, y, f, t1, y1, f1, p, res, yi)
        t = t1
        y[:] = y1
        f[:] = f1
    return p[COUNT]
