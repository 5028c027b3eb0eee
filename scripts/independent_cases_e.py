#!/usr/bin/env python3
"""A fifth generator of test files for `scpkit diagnose`, on choices none of the other four
(independent_cases{,_b,_c,_d}.py) nor lib/src/rig makes, to judge the detectors on data they
were not tuned on.

Usage: scripts/independent_cases_e.py OUT_DIR N [FIRST [SIDE-EFFECT]] [--noise-free]
(N files per effect and side, seeds FIRST..FIRST+N-1; file names SIDE-EFFECT-I.csv carry the
truth; SIDE-EFFECT, e.g. load-none, makes that kind only; --noise-free writes the same files
without noise or rounding). Then scripts/independent_run.sh OUT_DIR prints one line per file:
name, truth, named cause.

Its choices:
- voltage tests: a generalized Prandtl-Ishlinskii truth (plays on asymmetric tanh envelopes,
  paper 000's operator) driven by the electrical power, (V / V_max)^2, so the response is
  hysteretic in V^2; the input column `voltage_V` or, in a quarter of the files, `temp_C`
  (ambient plus a rise proportional to the power); five to eight loads in load_g or load_mN;
- load tests: a Preisach plane of a regular 24-level relay grid whose density is a mixture of
  two Gaussian blobs, plus a reversible part; loads in load_N, the response as `strain`
  (a fraction) with `length_mm`, or in `disp_mm` rounded to 0.04 mm;
- protocols: first-order reversal curves, a sampled sine of decaying amplitude, or minor loops
  between the same extrema reached from above and from below; every step held (`dwell_s`) and
  read one to three times during the hold;
- noise Gaussian, 0.3-1 % of the range; magnitudes drawn from a continuous range;
- the effects: creep logarithmic in the time since each input step (superposed over every past
  step, as polymers creep); drift as a warm-up that settles exponentially; outliers as sensor
  dropouts (a reading pulled towards the zero of the sensor); non-congruence as a Bouc-Wen
  term beside the Preisach plane (rate-independent, without wiping-out or congruency); the
  lonely stroke as the running maximum since the load change to the power 1.5; load-shape
  coupling as envelope steepness that changes with the load; the offset nonlinearity as a
  softplus knee in f1 at low load."""
import math, random, sys

from case_sets import write_csv, write_sets


class PreisachGrid:
    """Relays on a regular grid (alpha > beta) of [0, 1] with a two-blob density; all off at 0."""

    def __init__(self, rng, levels=24):
        blobs = [(rng.uniform(0.35, 0.75), rng.uniform(0.05, 0.35), rng.uniform(0.08, 0.2), rng.uniform(0.4, 1.0))
                 for _ in range(2)]
        self.cells = []
        for i in range(levels):
            for j in range(i + 1):
                a, b = (i + 0.5) / levels, (j + 0.5) / levels - 0.5 / levels
                w = sum(h * math.exp(-(((a + b) / 2 - c) ** 2 + ((a - b) / 2 - r) ** 2) / (2 * s * s))
                        for c, r, s, h in blobs)
                self.cells.append([a, b, w, -1])
        self.total = sum(c[2] for c in self.cells)

    def step(self, u):
        for c in self.cells:
            if u >= c[0]:
                c[3] = 1
            elif u <= c[1]:
                c[3] = -1
        return sum(c[2] * (c[3] + 1) / 2 for c in self.cells) / self.total


class GPI:
    """Generalized plays: z_i = max(g_up(u) - r_i, min(g_dn(u) + r_i, z_i)) on tanh envelopes."""

    def __init__(self, rng, n, k_up, k_dn):
        self.r = sorted(rng.uniform(0.0, 0.35) for _ in range(n))
        self.w = [rng.uniform(0.2, 1.0) for _ in range(n)]
        self.k_up, self.k_dn = k_up, k_dn
        self.reset()

    @staticmethod
    def env(k, u):
        return math.tanh(k * (u - 0.5)) / math.tanh(k * 0.5) * 0.5 + 0.5

    def reset(self):
        self.z = [self.env(self.k_dn, 0.0) + r for r in self.r]

    def step(self, u):
        up, dn = self.env(self.k_up, u), self.env(self.k_dn, u)
        self.z = [max(up - r, min(dn + r, z)) for r, z in zip(self.r, self.z)]
        return sum(w * z for w, z in zip(self.w, self.z)) / sum(self.w)


def bouc_wen(us, beta=0.6, gamma=0.3):
    """A rate-independent Bouc-Wen state (n = 1) along the input path, in units of its peak."""
    z, out = 0.0, []
    for a, b in zip([us[0]] + us, us):
        du = b - a
        z += du - beta * abs(du) * z - gamma * du * abs(z)
        out.append(z)
    peak = max(abs(v) for v in out) or 1.0
    return [v / peak for v in out]


def protocol(rng, kind):
    """Input levels in [0, 1] held one step each."""
    if kind == "forc":
        pts = [0.0]
        for r in sorted((rng.uniform(0.05, 0.85) for _ in range(rng.randint(4, 6))), reverse=True):
            pts += [1.0, r]
        pts += [1.0, 0.0]
    elif kind == "sine":
        n, cyc = rng.randint(90, 140), rng.uniform(3.0, 5.0)
        return [0.5 - 0.5 * math.cos(2 * math.pi * cyc * i / n) * (1.0 - 0.6 * i / n) for i in range(n)] + [0.0]
    else:  # minor loops between lo and hi, reached from above and from below
        lo, hi = sorted((rng.uniform(0.2, 0.45), rng.uniform(0.55, 0.8)))
        pts = [0.0, 1.0, lo, hi, lo, hi, 0.0, lo, hi, lo, hi, 1.0, 0.0]
    step = rng.choice([0.05, 0.0625, 0.1])
    us = [pts[0]]
    for a, b in zip(pts, pts[1:]):
        k = max(1, int(round(abs(b - a) / step)))
        us += [a + (b - a) * (i + 1) / k for i in range(k)]
    return us


def readings(rng, us, t0):
    """Each level held dwell s and read 1-3 times during the hold: (time, dwell, index of level)."""
    dwell = rng.choice([5.0, 10.0, 20.0])
    per = rng.choice([1, 1, 2, 3])
    rows, t = [], t0
    for k in range(len(us)):
        for m in range(per):
            rows.append((t + dwell * (m + 1) / per, dwell, k))
        t += dwell
    return rows, t


def log_creep(us, rows, span, mag, t_steps):
    """Creep logarithmic in time since each step, superposed: mag * span after one hold per unit step."""
    t0 = 1.0
    out = []
    for t, dwell, k in rows:
        c = 0.0
        for j in range(1, k + 1):
            du = us[j] - us[j - 1]
            if du:
                c += du * math.log(1.0 + (t - t_steps[j]) / t0)
        out.append(mag * span * c / math.log(1.0 + dwell / t0))
    return out


def effects(rng, effect, mag, ys, ts, span):
    if effect == "drift":
        T = (ts[-1] - ts[0]) * rng.uniform(0.2, 0.6)
        sign = rng.choice([-1, 1])
        ys = [y + sign * mag * span * (1 - math.exp(-(t - ts[0]) / T)) for y, t in zip(ys, ts)]
    if effect == "outliers":
        ys = list(ys)
        for k in rng.sample(range(4, len(ys) - 2), max(2, int(len(ys) * rng.uniform(0.01, 0.025)))):
            ys[k] -= mag * span * rng.uniform(1.0, 1.6)
    return ys


def sensor(rng, ys, span, mm):
    sigma = span * rng.uniform(0.003, 0.01)
    q = 0.04 if mm and rng.random() < 0.5 else 0.0
    out = []
    for y in ys:
        v = y if NOISE_FREE else y + rng.gauss(0, sigma)
        out.append(round(v / q) * q if q and not NOISE_FREE else v)
    return out, f"noise {sigma:.4f} q {q}"


def make_load(rng, effect, mag, out):
    kind = "minor" if effect == "minor_loop_noncongruence" else rng.choice(["forc", "sine", "minor"])
    us = protocol(rng, kind)
    rows, _ = readings(rng, us, 0.0)
    t_steps = [dw * k for k, dw in enumerate([rows[0][1]] * len(us))]
    truth = PreisachGrid(rng)
    hyst = [truth.step(u) for u in us]
    rev = rng.uniform(0.1, 0.4)
    length = rng.choice([60.0, 80.0, 100.0])
    span = length * rng.uniform(0.04, 0.1)  # mm
    base = [span * (rev * u + (1 - rev) * h) for u, h in zip(us, hyst)]
    if effect == "minor_loop_noncongruence":
        bw = bouc_wen(us)
        base = [b + mag * span * z for b, z in zip(base, bw)]
    ys = [base[k] for _, _, k in rows]
    ts = [t for t, _, _ in rows]
    if effect == "creep":
        ys = [y + c for y, c in zip(ys, log_creep(us, rows, span, mag, t_steps))]
    ys = effects(rng, effect, mag, ys, ts, span)
    mm = rng.random() < 0.5
    ys, how = sensor(rng, ys, span, mm)
    top = rng.choice([1.5, 2.5, 4.0])  # N
    cols = ["time_s", "dwell_s", "load_N", "disp_mm" if mm else "strain"]
    data = [[f"{t:.2f}", f"{dw:g}", f"{us[k] * top + 0.05:.4f}", f"{y:.4f}" if mm else f"{y / length:.7f}"]
            for (t, dw, k), y in zip(rows, ys)]
    write_csv(out, [("specimen", "thread"), ("length_mm", f"{length:g}"), ("gene", f"{effect} {mag:.3f} kind {kind} {how}")],
              cols, data)


def make_voltage(rng, effect, mag, out):
    nl = rng.randint(5, 8)
    loads = sorted(rng.sample(range(20, 220, 10), nl))
    if rng.random() < 0.6:
        rng.shuffle(loads)
    milli = rng.random() < 0.3
    temp = rng.random() < 0.25
    vmax = rng.choice([5.0, 8.0, 12.0])
    kind = rng.choice(["forc", "sine", "minor"])
    k_up, k_dn = rng.uniform(1.0, 3.0), rng.uniform(1.0, 3.0)
    n = rng.randint(8, 12)
    gpi = GPI(rng, n, k_up, k_dn)
    span = rng.uniform(4.0, 8.0)
    lo_F, hi_F = min(loads), max(loads)
    knee_F, knee_w = rng.uniform(0.1, 0.3), rng.uniform(0.05, 0.12)
    us = protocol(rng, kind)
    pieces, t0 = [], 0.0
    for F in loads:
        x = (F - lo_F) / (hi_F - lo_F)
        f1 = span * (0.8 * x + 0.15 * x * x)
        if effect == "offset_nonlinearity":
            f1 += mag * span * knee_w * math.log1p(math.exp((knee_F - x) / knee_w))
        f2 = span * (0.5 + 0.5 * x)
        if effect == "load_shape_coupling":
            gpi.k_up, gpi.k_dn = k_up * (1 + mag * (x - 0.5)), k_dn * (1 + mag * (0.5 - x))
        gpi.reset()
        M, base = 0.0, []
        for u in us:
            p = u * u
            M = max(M, p)
            y = f1 - f2 * gpi.step(p)
            if effect == "lonely_stroke":
                y -= mag * span * M ** 1.5
            base.append(y)
        rows, t_end = readings(rng, us, t0)
        t_steps = [t0 + rows[0][1] * k for k in range(len(us))]
        ys = [base[k] for _, _, k in rows]
        if effect == "creep":
            ys = [y - c for y, c in zip(ys, log_creep([u * u for u in us], rows, span, mag, t_steps))]
        pieces.append((F, rows, ys))
        t0 = t_end + rng.choice([30.0, 60.0])
    ts = [t for _, rows, _ in pieces for t, _, _ in rows]
    flat = [y for _, _, ys in pieces for y in ys]
    rng_span = max(flat) - min(flat)
    flat = effects(rng, effect, mag, flat, ts, rng_span)
    mm = rng.random() < 0.7
    flat, how = sensor(rng, flat, rng_span, mm)
    length = 90.0
    data, i = [], 0
    for s, (F, rows, _) in enumerate(pieces):
        for t, dw, k in rows:
            v = us[k] * vmax
            drive = f"{24.0 + 90.0 * us[k] ** 2:.3f}" if temp else f"{v:.4f}"
            y = flat[i]
            data.append([f"{t:.2f}", f"{dw:g}", f"{F * 9.80665:.1f}" if milli else f"{F}", drive,
                         f"{y:.4f}" if mm else f"{y / length:.7f}"])
            i += 1
    cols = ["time_s", "dwell_s", "load_mN" if milli else "load_g", "temp_C" if temp else "voltage_V",
            "disp_mm" if mm else "strain"]
    write_csv(out, [("specimen", "scp"), ("length_mm", f"{length:g}"),
                    ("gene", f"{effect} {mag:.3f} loads {loads} kind {kind} {how}")], cols, data)


NOISE_FREE = False  # --noise-free: the same files without noise or rounding (every draw alike)
RANGES = {
    "none": (0, 0), "drift": (0.03, 0.12), "outliers": (0.05, 0.15), "creep": (0.05, 0.25),
    "minor_loop_noncongruence": (0.1, 0.35), "lonely_stroke": (0.03, 0.1),
    "load_shape_coupling": (0.3, 0.9), "offset_nonlinearity": (0.1, 0.4),
}

if __name__ == "__main__":
    args = sys.argv[1:]
    NOISE_FREE = "--noise-free" in args
    args = [a for a in args if a != "--noise-free"]
    write_sets("independent_cases_e.py", __doc__, args,
               lambda side, rng, e, mag, out: (make_load if side == "load" else make_voltage)(rng, e, mag, out),
               lambda side, e, i: random.Random(f"e{side}{e}{i}"),
               lambda e, i: random.Random(f"emag{e}{i}").uniform(*RANGES[e]))
