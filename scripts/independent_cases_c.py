#!/usr/bin/env python3
"""A third generator of test files for `scpkit diagnose`, on choices neither independent_cases.py
nor independent_cases_b.py (nor lib/src/rig) makes, to judge the detectors on data they were
not tuned on.

Usage: scripts/independent_cases_c.py OUT_DIR N [FIRST [SIDE-EFFECT]] [--noise-free]
(N files per effect and side, seeds FIRST..FIRST+N-1; file names SIDE-EFFECT-I.csv carry the
truth; SIDE-EFFECT, e.g. load-none, makes that kind only; --noise-free writes the same files without noise). Then scripts/independent_run.sh
OUT_DIR prints one line per file: name, truth, named cause.

Where the other two hold each input on a grid and read it during or after the hold, this one:
- samples continuously: the input ramps at a constant rate between turning points and is read
  every 1-4 s, its values continuous (not on a grid), `dwell_s` left out;
- takes a Prandtl-Ishlinskii truth (8-16 play operators of random widths and positive weights,
  plus a linear part), which is a Preisach model with its density on lines;
- protocols: turning points drawn at random, or damped, or a repeated major loop with one
  minor loop inside;
- noise white or AR(1) (rho 0.6), 0.2-1 % of the range; responses in disp_mm or strain_pct;
- effects: drift linear in time; spikes of 1-2 % of the readings; creep as a first-order lag
  of part of the output (tau 2-8 readings); non-congruence as a play operator whose width
  follows the output (Gamma[u; r (1 + a y)]); the lonely stroke as a term in the running
  maximum of the voltage since the last load change, kept through the segment; load-shape
  coupling as play weights that move from narrow to wide plays with the load; the offset
  nonlinearity as a knee exp(-(F - F_lo) / w) in f1."""
import math, random, sys

from case_sets import write_csv, write_sets


class Plays:
    """A Prandtl-Ishlinskii operator: play operators of widths r_i, weights w_i; with `a`, each
    width scaled by 1 + a y (y the output in units of its range), solved by fixed point."""

    def __init__(self, rng, lo, hi, n, a=0.0):
        span = hi - lo
        self.r = sorted(rng.uniform(0.0, 0.45) * span for _ in range(n))
        self.w = [rng.uniform(0.2, 1.0) for _ in range(n)]
        self.lo, self.span, self.a = lo, span, a
        self.reset(lo)

    def reset(self, u):
        self.p = [u + r for r in self.r]  # negative saturation: descended to u from above

    def out(self, ps):
        return sum(w * (p - self.lo) for w, p in zip(self.w, ps)) / (sum(self.w) * self.span)

    def step(self, u):
        y = self.out(self.p)
        for _ in range(40 if self.a else 1):
            ps = []
            for r, p in zip(self.r, self.p):
                rr = r * (1.0 + self.a * y)
                ps.append(min(max(p, u - rr), u + rr))
            y_new = self.out(ps)
            if abs(y_new - y) < 1e-12:
                break
            y = y_new
        self.p = ps
        return self.out(ps)


def turning_points(rng, kind):
    if kind == "random":
        return [0.0] + [rng.uniform(0.0, 1.0) if i % 2 else rng.uniform(0.0, 1.0) for i in range(rng.randint(6, 10))] + [1.0, 0.0]
    if kind == "damped":
        n = rng.randint(4, 6)
        return [0.0] + [x for k in range(n) for x in (1.0 - 0.8 * k / n, 0.1 * k / n + 0.4 * k / n)] + [0.0]
    reps = rng.randint(3, 4)
    lo, hi = sorted((rng.uniform(0.2, 0.5), rng.uniform(0.55, 0.85)))
    return [0.0] + [x for _ in range(reps) for x in (1.0, lo, hi, lo, 0.0)]


def ramp(points, per_unit):
    """The input sampled along straight ramps between turning points (fractions of the range)."""
    u = [points[0]]
    for a, b in zip(points, points[1:]):
        k = max(2, int(round(abs(b - a) * per_unit)))
        u += [a + (b - a) * (i + 1) / k for i in range(k)]
    return u


def noise(rng, n, sigma, ar):
    e, out = 0.0, []
    for _ in range(n):
        e = ar * e + math.sqrt(1 - ar * ar) * rng.gauss(0, sigma)
        out.append(e)
    return out


def effects(rng, effect, mag, ys, t, dt, span):
    """Drift, creep, spikes on the noise-free response ys (range `span`)."""
    if effect == "drift":
        ys = [y + mag * span * (ti - t[0]) / (t[-1] - t[0]) for y, ti in zip(ys, t)]
    if effect == "creep":
        tau = rng.uniform(2.0, 8.0) * dt
        v, out = ys[0], []
        for i, y in enumerate(ys):
            v = y if i == 0 else y + (v - y) * math.exp(-dt / tau)
            out.append((1 - mag) * y + mag * v)
        ys = out
    if effect == "outliers":
        ys = list(ys)
        for k in rng.sample(range(3, len(ys) - 3), max(2, int(len(ys) * rng.uniform(0.01, 0.02)))):
            ys[k] += rng.choice([-1, 1]) * mag * span * rng.uniform(1.0, 1.5)
    return ys


def sensor(rng, ys, span):
    sigma = span * rng.choice([0.002, 0.005, 0.01])
    ar = 0.6 if rng.random() < 0.3 else 0.0
    e = noise(rng, len(ys), sigma, ar)
    return [y + (0.0 if NOISE_FREE else ei) for y, ei in zip(ys, e)], f"noise {sigma:.4f} ar {ar}"


def make_load(rng, effect, mag, out):
    top = rng.choice([200.0, 300.0, 500.0])
    kind = rng.choice(["random", "damped", "minor"]) if effect != "minor_loop_noncongruence" else "minor"
    dt = rng.choice([1.0, 2.0, 4.0])
    u = ramp(turning_points(rng, kind), rng.choice([12, 20, 30]))
    truth = Plays(rng, 0.0, 1.0, rng.randint(8, 16), 3.0 * mag if effect == "minor_loop_noncongruence" else 0.0)
    lin = rng.uniform(0.2, 0.6)
    span = rng.uniform(2.0, 5.0)
    ys = [span * (lin * x + (1 - lin) * truth.step(x)) for x in u]
    t = [dt * (i + 1) for i in range(len(u))]
    ys = effects(rng, effect, mag, ys, t, dt, span)
    ys, how = sensor(rng, ys, span)
    strain = rng.random() < 0.5
    length = 100.0
    cols = ["time_s", "load_g", "strain_pct" if strain else "disp_mm"]
    rows = [[f"{ti:.1f}", f"{x * top:.2f}", f"{100 * y / length:.6f}" if strain else f"{y:.5f}"]
            for ti, x, y in zip(t, u, ys)]
    write_csv(out, [("specimen", "thread"), ("length_mm", "100"), ("genc", f"{effect} {mag} kind {kind} dt {dt} {how}")],
          cols, rows)


def make_voltage(rng, effect, mag, out):
    nl = rng.randint(4, 7)
    loads = rng.sample(range(20, 200, 10), nl)
    if rng.random() < 0.5:
        loads.sort()
    vmax = rng.choice([4.0, 6.0, 8.0])
    kind = rng.choice(["random", "damped", "minor"])
    points = turning_points(rng, kind)
    dt = rng.choice([1.0, 2.0])
    per_unit = rng.choice([12, 20])
    n = rng.randint(8, 14)
    lo_F, hi_F = min(loads), max(loads)
    narrow = Plays(rng, 0.0, 1.0, n)
    wide = Plays(rng, 0.0, 1.0, n)
    wide.r = [min(0.45, 2.0 * r) for r in wide.r]
    span = rng.uniform(3.0, 6.0)
    knee_w = rng.uniform(0.1, 0.25)
    rows, t0 = [], 0.0
    seg_ys, seg_t = [], []
    for s, F in enumerate(loads):
        x = (F - lo_F) / (hi_F - lo_F)
        f1 = span * (0.5 * x + 0.2 * x * x)
        if effect == "offset_nonlinearity":
            f1 -= mag * span * math.exp(-x / knee_w)
        f2 = span * (0.6 + 0.4 * x)
        c = (mag * (x - 0.5)) if effect == "load_shape_coupling" else 0.0
        narrow.reset(0.0)
        wide.reset(0.0)
        u = ramp(points, per_unit)
        # the lonely stroke: a term in the running maximum since the load change
        M, ys = 0.0, []
        for v in u:
            M = max(M, v)
            h = (1 - c) * narrow.step(v) + c * wide.step(v)
            y = f1 - f2 * (0.3 * v + 0.7 * h)
            if effect == "lonely_stroke":
                y -= mag * span * M
            ys.append(y)
        t = [t0 + dt * (i + 1) for i in range(len(u))]
        t0 = t[-1]
        seg_ys.append(ys)
        seg_t.append((t, u, F))
    flat = [y for ys in seg_ys for y in ys]
    rng_span = max(flat) - min(flat)
    tt = [ti for t, _, _ in seg_t for ti in t]
    flat = effects(rng, effect if effect in ("drift", "creep", "outliers") else "none", mag, flat, tt, dt, rng_span)
    flat, how = sensor(rng, flat, rng_span)
    i = 0
    for s, (t, u, F) in enumerate(seg_t):
        for ti, v in zip(t, u):
            rows.append([f"{ti:.1f}", f"{F}", f"{v * vmax:.4f}", str(s), f"{flat[i]:.5f}"])
            i += 1
    write_csv(out, [("specimen", "scp"), ("genc", f"{effect} {mag} loads {loads} kind {kind} dt {dt} {how}")],
          ["time_s", "load_g", "voltage_V", "segment", "disp_mm"], rows)


NOISE_FREE = False  # --noise-free: the same files without noise (every draw alike)
MAGS = {
    "none": [0], "drift": [0.03, 0.06, 0.12], "outliers": [0.05, 0.1, 0.15],
    "creep": [0.1, 0.2, 0.3], "minor_loop_noncongruence": [0.1, 0.2, 0.3],
    "lonely_stroke": [0.03, 0.06, 0.1], "load_shape_coupling": [0.3, 0.6, 1.0],
    "offset_nonlinearity": [0.1, 0.2, 0.4],
}

if __name__ == "__main__":
    args = sys.argv[1:]
    NOISE_FREE = "--noise-free" in args
    args = [a for a in args if a != "--noise-free"]
    write_sets("independent_cases_c.py", __doc__, args,
               lambda side, rng, e, mag, out: (make_load if side == "load" else make_voltage)(rng, e, mag, out),
               lambda side, e, i: random.Random(f"c{side}{e}{i}"),
               lambda e, i: MAGS[e][i % len(MAGS[e])])
