#!/usr/bin/env python3
"""A fourth generator of test files for `scpkit diagnose`, on choices none of the other three
(independent_cases{,_b,_c}.py) nor lib/src/rig makes, to judge the detectors on data they were
not tuned on.

Usage: scripts/independent_cases_d.py OUT_DIR N [FIRST [SIDE-EFFECT]] [--noise-free]
(N files per effect and side, seeds FIRST..FIRST+N-1; file names SIDE-EFFECT-I.csv carry the
truth; SIDE-EFFECT, e.g. load-none, makes that kind only; --noise-free writes the same files
without noise or rounding). Then scripts/independent_run.sh OUT_DIR prints one line per file:
name, truth, named cause.

Its choices:
- the truth: 150-400 relays at thresholds drawn at random (not on a grid) from a correlated
  bivariate law, with random weights, plus a reversible tanh part and a linear part; every relay
  switches inside the tested range, so the return to the lowest input wipes the memory;
- the input sampled in time: triangle waves of varied amplitudes read every dt, dwells of 5-30 s
  at the turning points read throughout, or staircases held and read once per step;
- loads in N or mN; voltage tests driven by `voltage_V` or by `power_W`; responses as `strain`
  (a fraction) or `disp_mm`; three to six loads per voltage test, in any order;
- noise Gaussian, 0.2-1 % of the range, quantised to 0.01 or 0.04 mm in half the files;
- magnitudes drawn from a continuous range, not from three levels;
- the effects: creep as a two-term Kelvin chain on part of the response, or (voltage) a thermal
  lag of the input that drives the hysteresis; drift quadratic, settling, or one slow swing of
  the ambient; outliers in bursts of one to three readings; non-congruence as a moving Preisach
  with negative feedback Gamma[u - a y]; the lonely stroke as the square root of the running
  maximum since the load change, its sign set by the direction of the change; load-shape
  coupling as relay thresholds scaled with the load; the offset nonlinearity as a kinked f1
  (stiffer below a contact load)."""
import math, random, sys

from case_sets import write_csv, write_sets


class Relays:
    """Relays at (alpha >= beta) thresholds in (0, 1) with weights; state -1 below, +1 above."""

    def __init__(self, rng, n):
        self.a, self.b, self.w = [], [], []
        while len(self.a) < n:
            c = rng.gauss(0.5, 0.18)  # centre of the loop
            h = abs(rng.gauss(0.0, 0.15)) + 0.01  # half width
            al, be = c + h, c - h
            if 0.02 < be < al < 0.98:
                self.a.append(al)
                self.b.append(be)
                self.w.append(rng.uniform(0.2, 1.0))
        self.total = sum(self.w)
        self.reset()

    def reset(self):
        self.s = [-1] * len(self.a)

    def out(self, s):
        return 0.5 + 0.5 * sum(w * si for w, si in zip(self.w, s)) / self.total

    def step(self, u, fb=0.0):
        """The output at input u; with fb, the moving model Gamma[u - fb * y] by fixed point."""
        s0 = self.s
        y = self.out(s0)
        for _ in range(30 if fb else 1):
            ue = u - fb * y
            s = [1 if ue >= al else (-1 if ue <= be else si) for al, be, si in zip(self.a, self.b, s0)]
            y_new = self.out(s)
            if abs(y_new - y) < 1e-12:
                break
            y = y_new
        self.s = s
        return self.out(s)


def lag(xs, ts, tau):
    """First-order lag of xs (sampled at times ts) with time constant tau."""
    out, z = [], xs[0]
    for i, x in enumerate(xs):
        if i:
            z = x + (z - x) * math.exp(-(ts[i] - ts[i - 1]) / tau)
        out.append(z)
    return out


def protocol(rng, kind):
    """(times, inputs as fractions of the range): the input sampled in time, drawn afresh for
    every call (so each segment of a voltage test has its own rate and sampling)."""
    dt = rng.choice([0.5, 1.0, 2.0])
    t, u = [0.0], [0.0]
    if kind == "stairs":
        dwell = rng.choice([10.0, 20.0, 40.0])
        steps = rng.choice([6, 8, 10])
        amps = [1.0, 0.7, 1.0, 0.45, 0.8]
        for a in amps[: rng.randint(3, 5)]:
            n = max(2, int(round(a * steps)))
            for k in list(range(1, n + 1)) + list(range(n - 1, -1, -1)):
                t.append(t[-1] + dwell)
                u.append(a * k / n)
        return t, u
    if kind == "nested":  # minor loops between the same extrema after two histories
        lo, hi = rng.uniform(0.2, 0.45), rng.uniform(0.55, 0.8)
        points = [1.0, lo, hi, lo, 0.0, hi, lo, hi, 0.0] * rng.randint(1, 2)
    else:
        amps = [1.0, 0.6, 1.0, 0.35, 0.8, 0.5, 1.0]
        points = [x for a in amps[: rng.randint(4, len(amps))] for x in (a, 0.0)]
    rate = rng.uniform(0.02, 0.06)  # of the range per second
    hold = rng.uniform(5.0, 30.0) if kind == "dwell" else 0.0
    for target in points:
        start = u[-1]
        n = max(2, int(abs(target - start) / rate / dt))
        for k in range(1, n + 1):
            t.append(t[-1] + dt)
            u.append(start + (target - start) * k / n)
        for _ in range(int(hold / dt)):
            t.append(t[-1] + dt)
            u.append(target)
    return t, u


def trend(rng, t):
    kind = rng.choice(["quadratic", "settling", "swing"])
    T = t[-1] - t[0]
    x = [(ti - t[0]) / T for ti in t]
    if kind == "quadratic":
        c = rng.uniform(-0.5, 1.0)
        return [(1 - c) * xi + c * xi * xi for xi in x], kind
    if kind == "settling":
        k = rng.uniform(2.0, 5.0)
        return [(1 - math.exp(-k * xi)) / (1 - math.exp(-k)) for xi in x], kind
    ph = rng.uniform(0, math.pi)
    raw = [math.sin(ph + math.pi * xi) for xi in x]
    lo_, hi_ = min(raw), max(raw)
    return [(r - raw[0]) / (hi_ - lo_) for r in raw], kind


def effects(rng, effect, mag, ys, t, span):
    """Drift, creep on the response, outliers; the others act inside the model."""
    how = ""
    if effect == "drift":
        d, how = trend(rng, t)
        sign = rng.choice([-1, 1])
        ys = [y + sign * mag * span * di for y, di in zip(ys, d)]
    if effect == "creep_out":
        t1, t2 = rng.uniform(2.0, 8.0), rng.uniform(20.0, 80.0)
        c1 = rng.uniform(0.3, 0.7)
        l1, l2 = lag(ys, t, t1), lag(ys, t, t2)
        ys = [(1 - mag) * y + mag * (c1 * a + (1 - c1) * b) for y, a, b in zip(ys, l1, l2)]
        how = f"kelvin {t1:.1f} {t2:.1f}"
    if effect == "outliers":
        ys = list(ys)
        n = max(2, int(len(ys) * rng.uniform(0.005, 0.02)))
        for k in rng.sample(range(5, len(ys) - 8), n):
            sign = rng.choice([-1, 1])
            size = mag * span * rng.uniform(0.8, 1.5)
            for j in range(rng.choice([1, 1, 2, 3])):
                ys[k + j] += sign * size
        how = f"{n} bursts"
    return ys, how


def sensor(rng, ys, span, mm_per_unit):
    """Noise of 0.2-1 % of the range, quantised in half the files (steps in mm)."""
    sigma = span * rng.choice([0.002, 0.005, 0.01])
    q = rng.choice([0.0, 0.0, 0.01, 0.04])
    out = []
    for y in ys:
        v = y if NOISE_FREE else y + rng.gauss(0.0, sigma)
        if q and not NOISE_FREE:
            v = round(v * mm_per_unit / q) * q / mm_per_unit
        out.append(v)
    return out, f"noise {sigma / span:.3f} q {q}"


def response(rng, length):
    """Column name and formatter: strain (fraction) or disp_mm, the model in mm."""
    if rng.random() < 0.5:
        return "strain", (lambda y: f"{y / length:.7f}")
    return "disp_mm", (lambda y: f"{y:.5f}")


def load_column(rng, newtons):
    if rng.random() < 0.5:
        return "load_N", [f"{f:.4f}" for f in newtons]
    return "load_mN", [f"{1000 * f:.1f}" for f in newtons]


def make_load(rng, effect, mag, out):
    kind = "nested" if effect == "minor_loop_noncongruence" else rng.choice(["triangle", "dwell", "stairs", "nested"])
    if effect == "creep" and kind == "triangle":
        kind = "dwell"
    t, u = protocol(rng, kind)
    top = rng.uniform(2.0, 5.0)  # N
    R = Relays(rng, rng.randint(150, 400))
    lin, rev = rng.uniform(0.2, 0.5), rng.uniform(0.0, 0.2)
    span = rng.uniform(2.0, 6.0)  # mm
    fb = mag if effect == "minor_loop_noncongruence" else 0.0
    ys = [span * (lin * x + rev * math.tanh(2 * (x - 0.5)) + (1 - lin - rev) * R.step(x, fb)) for x in u]
    ys, how = effects(rng, "creep_out" if effect == "creep" else effect, mag, ys, t, span)
    length = rng.choice([80.0, 100.0, 150.0])
    ys, noise = sensor(rng, ys, span, 1.0)
    name, fmt = response(rng, length)
    lcol, loads = load_column(rng, [x * top for x in u])
    rows = [[f"{ti:.1f}", l, fmt(y)] for ti, l, y in zip(t, loads, ys)]
    write_csv(out, [("specimen", "thread"), ("length_mm", f"{length:g}"),
                ("gend", f"{effect} {mag:.3f} kind {kind} {how} {noise}")],
          ["time_s", lcol, name], rows)


def make_voltage(rng, effect, mag, out):
    nl = rng.randint(3, 6)
    grams = rng.sample(range(20, 160, 10), nl)
    order = rng.choice(["up", "down", "any"])
    grams = sorted(grams) if order == "up" else sorted(grams, reverse=True) if order == "down" else grams
    power = rng.random() < 0.5
    top = rng.uniform(0.5, 1.5) if power else rng.uniform(4.0, 10.0)
    kind = rng.choice(["triangle", "dwell", "stairs", "nested"])
    if effect == "creep" and kind == "triangle":
        kind = "dwell"
    R = Relays(rng, rng.randint(150, 400))
    lin, rev = rng.uniform(0.1, 0.4), rng.uniform(0.0, 0.15)
    L = rng.choice([60.0, 80.0, 100.0])
    k_knee = rng.uniform(0.2, 0.4)
    creep_lag = effect == "creep" and rng.random() < 0.5
    tau_th = rng.uniform(2.0, 6.0)
    lo_g, hi_g = min(grams), max(grams)
    rows_t, rows_u, rows_y, rows_F, rows_s = [], [], [], [], []
    t0 = 0.0
    prev = None
    for s, g in enumerate(grams):
        x = (g - lo_g) / (hi_g - lo_g)
        t, u = protocol(rng, kind)
        t = [t0 + 1.0 + ti for ti in t]
        t0 = t[-1]
        f1 = L * (0.01 + 0.04 * x + 0.01 * x * x)
        if effect == "offset_nonlinearity":
            f1 += mag * L * 0.04 * max(0.0, k_knee - x) / k_knee
        f2 = L * (0.03 + 0.02 * x)
        scale = 1.0 + (mag * (x - 0.5) if effect == "load_shape_coupling" else 0.0)
        drive = lag(u, t, tau_th * (1 + 2 * mag)) if creep_lag else u
        R.reset()
        sign = -1.0 if prev is not None and g > prev else 1.0
        M = 0.0
        for ti, v, d in zip(t, u, drive):
            M = max(M, v)
            h = lin * d + rev * (math.tanh(2.5 * d) / math.tanh(2.5)) + (1 - lin - rev) * R.step(d / scale)
            y = f1 - f2 * h
            if effect == "lonely_stroke":
                y -= sign * mag * f2 * math.sqrt(M)
            rows_t.append(ti)
            rows_u.append(v)
            rows_y.append(y)
            rows_F.append(g * 9.81e-3)
            rows_s.append(s)
        prev = g
    span = max(rows_y) - min(rows_y)
    how = f"lag {tau_th * (1 + 2 * mag):.1f}" if creep_lag else ""
    e = "creep_out" if effect == "creep" and not creep_lag else effect
    rows_y, how2 = effects(rng, e, mag, rows_y, rows_t, span)
    rows_y, noise = sensor(rng, rows_y, span, 1.0)
    name, fmt = response(rng, L)
    lcol, loads = load_column(rng, rows_F)
    # power heats like voltage squared: the file's input is the power when `power` is set
    ucol = "power_W" if power else "voltage_V"
    rows = [[f"{ti:.1f}", l, f"{v * top:.4f}", str(s), fmt(y)]
            for ti, l, v, s, y in zip(rows_t, loads, rows_u, rows_s, rows_y)]
    write_csv(out, [("specimen", "scp"), ("length_mm", f"{L:g}"),
                ("gend", f"{effect} {mag:.3f} loads {grams} kind {kind} {how}{how2} {noise}")],
          ["time_s", lcol, ucol, "segment", name], rows)


NOISE_FREE = False
RANGES = {
    "none": (0.0, 0.0), "drift": (0.03, 0.12), "outliers": (0.05, 0.15), "creep": (0.1, 0.3),
    "minor_loop_noncongruence": (0.1, 0.3), "lonely_stroke": (0.03, 0.1),
    "load_shape_coupling": (0.3, 1.0), "offset_nonlinearity": (0.1, 0.4),
}

if __name__ == "__main__":
    args = sys.argv[1:]
    NOISE_FREE = "--noise-free" in args
    args = [a for a in args if a != "--noise-free"]
    write_sets("independent_cases_d.py", __doc__, args,
               lambda side, rng, e, mag, out: (make_load if side == "load" else make_voltage)(rng, e, mag, out),
               lambda side, e, i: random.Random(f"d{side}{e}{i}"),
               lambda e, i: random.Random(f"dmag{e}{i}").uniform(*RANGES[e]))
