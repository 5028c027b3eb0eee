#!/usr/bin/env python3
"""A second generator of test files for `scpkit diagnose`, built on other choices than
independent_cases.py (and than lib/src/rig), to judge the detectors on data they were not tuned on.

Usage: scripts/independent_cases_b.py OUT_DIR N [FIRST [SIDE-EFFECT]]
[--noise-free] [--no-effect]
(N files per effect and side, seeds FIRST..FIRST+N-1; file names SIDE-EFFECT-I.csv carry the
truth; SIDE-EFFECT, e.g. load-none, makes that kind only; --noise-free writes the same files
without noise or rounding, --no-effect with the effect's magnitude set to 0, every random draw
alike, so the two give an effect's noise-free size). Then scripts/independent_run.sh OUT_DIR
prints one line per file: name, truth, named cause.

Where independent_cases.py uses a 30-level relay grid, white noise in mm and one set of
protocols, this one uses:
- a continuous Preisach truth: an Everett table (150 nodes) of a log-normal coercivity times
  Gaussian interaction density, interpolated bilinearly, evaluated from the wiped-out memory;
- protocols: nested minor loops repeated from two histories, staircases with back-steps,
  first-order reversal curves, damped cycles, random turning points; holds jittered or not,
  one to four readings per hold;
- the noise as a fraction of the range (0.2-1 %), a 0.04 mm step in a third of the files;
  responses in disp_mm or strain_pct, loads in g or N, columns in random order, `segment`
  left out of half the voltage files;
- the effects built otherwise: creep as a two-term Prony kernel superposed over every past
  step; drift linear or saturating; spikes of 1-3 % of the readings; non-congruence as a moving
  Preisach Gamma[u + a y] solved implicitly (fixed point) or an exponential map of the output;
  the lonely stroke as the square of the running maximum; load-shape coupling as a mixture of
  two Preisach truths whose weight follows the load; the offset nonlinearity as a soft knee at
  low load or a cubic in load."""
import math, random, sys

from case_sets import write_sets


class Everett:
    """E(a, b): the density's measure on {b <= beta <= alpha <= a}, tabulated on n nodes."""

    def __init__(self, lo, hi, dens, n=150):
        self.lo, self.hi, self.n = lo, hi, n
        self.h = (hi - lo) / (n - 1)
        x = [lo + i * self.h for i in range(n)]
        # cell (p, q): alpha in [x_p, x_p+1], beta in [x_q, x_q+1]; q == p is half a cell
        m = [[0.0] * n for _ in range(n)]
        for p in range(n - 1):
            for q in range(p + 1):
                a, b = x[p] + 0.5 * self.h, x[q] + 0.5 * self.h
                m[p][q] = dens(a, b) * self.h * self.h * (0.5 if q == p else 1.0)
        E = [[0.0] * n for _ in range(n)]
        for i in range(1, n):
            suffix = 0.0
            for j in range(i - 1, -1, -1):
                suffix += m[i - 1][j]
                E[i][j] = E[i - 1][j] + suffix
        self.E = E

    def __call__(self, a, b):
        if a <= b:
            return 0.0
        fa = min(max((a - self.lo) / self.h, 0.0), self.n - 1 - 1e-9)
        fb = min(max((b - self.lo) / self.h, 0.0), self.n - 1 - 1e-9)
        i, j = int(fa), int(fb)
        s, t = fa - i, fb - j
        E = self.E
        return ((1 - s) * (1 - t) * E[i][j] + s * (1 - t) * E[i + 1][j] +
                (1 - s) * t * E[i][j + 1] + s * t * E[i + 1][j + 1])


def wipe(seq, u, lo):
    """The dominant turning points after input u: seq starts at lo (every hysteron off)."""
    if u <= lo:
        return [lo]
    s = seq + [u]
    while len(s) >= 3:
        a, b, c = s[-3], s[-2], s[-1]
        if (b - a) * (c - b) >= 0:  # no turning point at b
            s.pop(-2)
        elif len(s) >= 4 and (c - b) * (a - b) > 0 and abs(c - b) >= abs(a - b):
            s.pop(-2)  # c passes a: the loop a-b is wiped out
            s.pop(-2)
        else:
            break
    return s


def preisach_output(E, seq):
    """The measure of the hysterons that are on, from the turning points seq = [lo, M1, m1, ...]."""
    y = 0.0
    for k in range(1, len(seq), 2):
        M = seq[k]
        y += E(M, seq[k - 1])
        if k + 1 < len(seq):
            y -= E(M, seq[k + 1])
    return y


def density(rng, lo, hi):
    span = hi - lo
    h0 = span * rng.uniform(0.06, 0.2)
    sh = rng.uniform(0.4, 0.9)
    c0 = lo + span * rng.uniform(0.35, 0.65)
    sc = span * rng.uniform(0.2, 0.45)

    def f(a, b):
        hh = max((a - b) / 2.0, 1e-6 * span)
        cc = (a + b) / 2.0
        return math.exp(-(math.log(hh / h0) / sh) ** 2 / 2) * math.exp(-((cc - c0) / sc) ** 2 / 2) / hh ** 0.3
    return f


class Truth:
    """A Preisach truth on [lo, hi]; with `move` a != 0 a moving Preisach Gamma[u + a y], solved
    by fixed-point iteration, its memory in the moved input."""

    def __init__(self, E, lo, hi, move=0.0):
        self.E, self.lo, self.hi, self.move = E, lo, hi, move
        self.seq = [lo]
        self.top = preisach_output(E, [lo, hi])
        self.y = 0.0

    def reset(self):
        self.seq, self.y = [self.lo], 0.0

    def step(self, u):
        span = self.hi - self.lo
        ue = u
        if self.move != 0.0:
            y = self.y
            for _ in range(60):
                ue = min(max(u + self.move * span * y / self.top, self.lo), self.hi)
                y_new = preisach_output(self.E, wipe(self.seq, ue, self.lo))
                if abs(y_new - y) < 1e-12 * self.top:
                    break
                y = 0.5 * (y + y_new)
        self.seq = wipe(self.seq, min(max(ue, self.lo), self.hi), self.lo)
        self.y = preisach_output(self.E, self.seq)
        return self.y / self.top  # 0 .. 1


def grid_ramp(a, b):
    d = 1 if b > a else -1
    return [a + d * k for k in range(1, abs(b - a) + 1)]


def protocol(rng, kind, n):
    """Input levels (integers 0..n) of one test from 0."""
    seq, k = [0], 0

    def go(target):
        nonlocal k
        seq.extend(grid_ramp(k, target))
        k = target
    if kind == "nested":  # minor loops between the same levels after two histories, repeated
        lo_m = rng.randint(int(0.2 * n), int(0.4 * n))
        hi_m = rng.randint(lo_m + max(2, n // 4), int(0.85 * n))
        reps = rng.choice([1, 2])
        for _ in range(2):
            go(n)
            for _ in range(reps):
                go(lo_m), go(hi_m)
            go(0)
            go(hi_m)
            for _ in range(reps):
                go(lo_m), go(hi_m)
            go(0)
    elif kind == "staircase":  # up and down with one step back after each two
        for _ in range(2):
            while k < n:
                go(min(k + 2, n))
                if k < n:
                    go(k - 1)
            while k > 0:
                go(max(k - 2, 0))
                if k > 0:
                    go(k + 1)
    elif kind == "forc":  # first-order reversal curves from the top
        go(n)
        for m in sorted(rng.sample(range(0, n - 1), 4), reverse=True):
            go(m), go(n)
        go(0), go(n), go(0)
    elif kind == "damped":
        for f in [1.0, 0.7, 0.5, 0.3, 1.0]:
            go(max(1, int(round(f * n)))), go(0)
    else:  # random turning points
        for r in range(rng.randint(6, 10)):
            go(rng.randint(min(k + 2, n), n) if r % 2 == 0 else rng.randint(0, max(k - 2, 0)))
        go(0)
    return seq


def prony(steps, t, tau1, tau2):
    """The part of the past steps (time, size) not yet relaxed at time t."""
    return sum(d * (0.6 * math.exp(-(t - s) / tau1) + 0.4 * math.exp(-(t - s) / tau2)) for s, d in steps)


def readings(rng, levels, values, effect, mag, per_hold, dwell, jitter, tau, rng_range):
    """Rows (time, dwell, index) of the holds, their values with creep and drift."""
    total = len(levels) * dwell
    out, steps, t, last = [], [], 0.0, None
    drift_shape = rng.choice(["linear", "saturating"])
    for i, g in enumerate(values):
        hold = dwell * (rng.uniform(0.6, 1.4) if jitter else 1.0)
        if last is None or g != last:
            steps.append((t, g - (last if last is not None else g)))
        last = g
        for r in range(per_hold):
            tr = t + hold * (r + 1) / per_hold
            y = g
            if effect == "creep":
                y -= mag * prony(steps, tr, tau, 4 * tau)
            if effect == "drift":
                x = tr / total
                y += mag * rng_range * (x if drift_shape == "linear" else (1 - math.exp(-3 * x)) / (1 - math.exp(-3)))
            out.append((tr, hold * (r + 1) / per_hold, i, y))
        t += hold
    return out


def spikes(rng, ys, mag, rng_range):
    n = max(2, int(round(len(ys) * rng.uniform(0.01, 0.03))))
    for k in rng.sample(range(3, len(ys) - 3), n):
        ys[k] += rng.choice([-1, 1]) * mag * rng_range * rng.uniform(1.0, 1.6)


def measure(rng, levels, values, effect, mag, dwells, scale):
    """The readings of a test (holds, creep, drift, spikes) and its sensor: rows (time, dwell,
    index, value), the values with spikes, and the sensor and hold settings (noise, q, per_hold,
    dwell, jitter, tau); sizes in units of `scale`, the response's range."""
    per_hold = rng.choice([1, 1, 2, 4]) if effect != "creep" else rng.choice([1, 2, 4])
    dwell = rng.choice(dwells)
    jitter = rng.random() < 0.4
    tau = dwell * rng.uniform(0.2, 0.8)
    rows = readings(rng, levels, values, effect, mag, per_hold, dwell, jitter, tau, scale)
    ys = [r[3] for r in rows]
    if effect == "outliers":
        spikes(rng, ys, mag, scale)
    m = {"noise": scale * rng.choice([0.002, 0.005, 0.01]), "q": 0.04 if rng.random() < 0.33 else 0.0,
         "per_hold": per_hold, "dwell": dwell, "jitter": jitter, "tau": tau}
    return rows, ys, m


def sensor(rng, y, m):
    """One reading of the true value y (--noise-free: y itself; the draw is made either way)."""
    e = rng.gauss(0, m["noise"])
    return y if NOISE_FREE else quant(y + e, m["q"])


def settings(m):
    return (f"noise {m['noise']:.4f} q {m['q']} per_hold {m['per_hold']} dwell {m['dwell']} "
            f"jitter {m['jitter']} tau {m['tau']:.0f}")


def write(out, meta, cols, rows, rng):
    order = list(range(len(cols)))
    rng.shuffle(order)
    with open(out, "w") as f:
        for k, v in meta:
            f.write(f"# {k}: {v}\n")
        f.write(",".join(cols[j] for j in order) + "\n")
        for r in rows:
            f.write(",".join(r[j] for j in order) + "\n")


def quant(v, q):
    return round(v / q) * q if q > 0 else v


def make_load(rng, effect, mag, out):
    top = rng.choice([200.0, 300.0, 500.0])
    n = rng.choice([8, 10, 12, 16])
    kind = rng.choice(["nested", "staircase", "random"]) if effect == "minor_loop_noncongruence" else \
        rng.choice(["nested", "staircase", "forc", "damped", "random"])
    levels = protocol(rng, kind, n)
    E = Everett(0.0, top, density(rng, 0.0, top))
    nc_form = rng.choice(["moving", "map"]) if effect == "minor_loop_noncongruence" else ""
    truth = Truth(E, 0.0, top, mag if nc_form == "moving" else 0.0)
    h = [truth.step(k * top / n) for k in levels]
    if nc_form == "map" and mag > 0:
        b = 3.0 * mag
        h = [(math.exp(b * v) - 1) / (math.exp(b) - 1) for v in h]
    lin = rng.uniform(0.2, 0.7)
    rng_mm = rng.uniform(2.0, 5.0)
    values = [rng_mm * (lin * k / n + (1 - lin) * v) for k, v in zip(levels, h)]
    rows, ys, m = measure(rng, levels, values, effect, mag, [10.0, 30.0, 60.0, 180.0], rng_mm)
    length = rng.choice([60.0, 100.0, 150.0])
    strain = rng.random() < 0.5
    newton = rng.random() < 0.5
    cols = ["time_s", "dwell_s", "load_N" if newton else "load_g", "strain_pct" if strain else "disp_mm"]
    out_rows = []
    for (tr, dw, i, _), y in zip(rows, ys):
        u = levels[i] * top / n
        yv = sensor(rng, y, m)
        out_rows.append([f"{tr:.1f}", f"{dw:.1f}", f"{u * 9.81e-3:.5f}" if newton else f"{u:.2f}",
                         f"{100 * yv / length:.7f}" if strain else f"{yv:.6f}"])
    meta = [("specimen", "thread"), ("length_mm", f"{length:g}"), ("plies", rng.choice([1, 2, 3])),
            ("genb", f"{effect} {mag} kind {kind} {nc_form} {settings(m)}")]
    write(out, meta, cols, out_rows, rng)


def make_voltage(rng, effect, mag, out):
    nl = rng.randint(4, 8)
    loads = sorted(rng.sample(range(20, 160, 10), nl))
    if rng.random() < 0.5:
        rng.shuffle(loads)
    vmax = rng.choice([5.0, 8.0, 12.0])
    n = rng.choice([6, 8, 10, 12])
    E1 = Everett(0.0, vmax, density(rng, 0.0, vmax), 100)
    E2 = Everett(0.0, vmax, density(rng, 0.0, vmax), 100) if effect == "load_shape_coupling" else None
    kind = rng.choice(["cycles", "damped", "random"])
    if kind == "cycles":
        levels = [0]
        for _ in range(3):
            levels += grid_ramp(0, n) + grid_ramp(n, 0)
    else:
        levels = protocol(rng, "damped" if kind == "damped" else "random", n)
    L = rng.choice([70.0, 80.0, 100.0])
    Fmin, Fmax = min(loads), max(loads)
    a1, a2, a3 = rng.uniform(0.02, 0.04), rng.uniform(0.03, 0.06), rng.uniform(-0.015, 0.0)
    b1, b2, b3 = rng.uniform(0.02, 0.04), rng.uniform(0.01, 0.04), rng.uniform(-0.012, 0.0)
    knee = rng.choice(["knee", "cubic"])
    values, levels_all, seg_of = [], [], []
    stroke_ref = L * (b1 + 0.5 * b2)
    for s, Fg in enumerate(loads):
        x = (Fg - Fmin) / (Fmax - Fmin)
        f1 = L * (a1 + a2 * x + a3 * x * x)
        f2 = L * (b1 + b2 * x + b3 * x * x)
        if effect == "offset_nonlinearity":
            if knee == "knee":
                f1 -= mag * L * 0.04 * math.log1p(math.exp(-(x - 0.15) / 0.06)) / math.log1p(math.exp(0.15 / 0.06))
            else:
                f1 += mag * L * 0.08 * (x - 0.5) ** 3 * 8
        T1 = Truth(E1, 0.0, vmax)
        T2 = Truth(E2, 0.0, vmax) if E2 else None
        M = 0.0
        for k in levels:
            v = k * vmax / n
            hv = T1.step(v)
            if T2:
                w = mag * x
                hv = (1 - w) * hv + w * T2.step(v)
            M = max(M, v / vmax)
            g = f1 - f2 * hv
            if effect == "lonely_stroke":
                g -= mag * f2 * M * M
            values.append(g)
            levels_all.append(k)
            seg_of.append(s)
    rows, ys, m = measure(rng, levels_all, values, effect, mag, [10.0, 30.0, 60.0], stroke_ref)
    with_seg = rng.random() < 0.5
    cols = ["time_s", "dwell_s", "load_g", "voltage_V", "disp_mm"] + (["segment"] if with_seg else [])
    out_rows = []
    for (tr, dw, i, _), y in zip(rows, ys):
        r = [f"{tr:.1f}", f"{dw:.1f}", f"{loads[seg_of[i]]}", f"{levels_all[i] * vmax / n:.4f}",
             f"{sensor(rng, y, m):.6f}"]
        out_rows.append(r + ([str(seg_of[i])] if with_seg else []))
    meta = [("specimen", "scp"), ("length_mm", f"{L:g}"),
            ("genb", f"{effect} {mag} loads {loads} kind {kind} {knee if effect == 'offset_nonlinearity' else ''} "
                     f"{settings(m)}")]
    write(out, meta, cols, out_rows, rng)


NOISE_FREE = False  # --noise-free
NO_EFFECT = False  # --no-effect
MAGS = {
    "none": [0], "drift": [0.02, 0.05, 0.1], "outliers": [0.04, 0.08, 0.15],
    "creep": [0.05, 0.1, 0.25], "minor_loop_noncongruence": [0.1, 0.2, 0.4],
    "lonely_stroke": [0.03, 0.06, 0.1], "load_shape_coupling": [0.3, 0.6, 1.0],
    "offset_nonlinearity": [0.1, 0.2, 0.4],
}

if __name__ == "__main__":
    args = sys.argv[1:]
    NOISE_FREE = "--noise-free" in args
    NO_EFFECT = "--no-effect" in args
    args = [a for a in args if a not in ("--noise-free", "--no-effect")]
    write_sets("independent_cases_b.py", __doc__, args,
               lambda side, rng, e, mag, out: (make_load if side == "load" else make_voltage)(rng, e, mag, out),
               lambda side, e, i: random.Random(f"b{side}{e}{i}"),
               lambda e, i: 0.0 if NO_EFFECT else MAGS[e][i % len(MAGS[e])])
