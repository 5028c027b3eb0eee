#!/usr/bin/env python3
"""Test files for `scpkit diagnose` from a generator independent of the project's rig.

Usage: scripts/independent_cases.py OUT_DIR N [FIRST [SIDE-EFFECT]] [--once-per-hold]
[--ar-noise RHO] [--one-load] [--cells N] [--random-turns] [--noise-free]   (N files per effect and side, seeds FIRST..FIRST+N-1; file names
SIDE-EFFECT-I.csv carry the truth; SIDE-EFFECT, e.g. load-none, makes that kind only, with the
same seeds; --once-per-hold reads voltage creep once per hold instead of three times;
--ar-noise RHO makes the sensor noise AR(1) with lag-one correlation RHO; --one-load tests
voltage at the first of the drawn loads only, one segment, without the two effects that need
several loads; --cells N gives the Preisach truth N relay levels instead of 30 (load) and 24
(voltage): on the coarse grid a moving Preisach's shift often crosses no relay threshold and the
non-congruence is not in the data; --random-turns replaces the damped and repeated load
protocols and the voltage cycles by 5-9 turning points drawn on the step grid; all else alike). Then
scripts/independent_run.sh OUT_DIR prints one line per file: name, truth, named cause.

Written apart from lib/src/rig (plain Python, no numpy): a relay-grid Preisach truth with a
Gaussian-ridge density plus a linear term, protocols from 0 g (damped, repeated, minor loops
from two histories), the response in mm with optional quantisation; the effects as a reader
of PHYSICS.md section 5 might build them: a Kelvin element (readings during holds), a linear
drift, spikes, a moving Preisach (non-congruence), a lonely stroke of one sign after every load
change, an input-exponent shape change with load, a low-load knee in the offset map."""
import math, random, sys

from case_sets import write_sets

class Preisach:
    def __init__(self, lo, hi, n, dens):
        self.lo, self.hi, self.n = lo, hi, n
        h = (hi - lo) / n
        self.cells = []
        for i in range(n):
            a = lo + (i + 0.5) * h
            for j in range(i + 1):
                b = lo + (j + 0.5) * h
                self.cells.append([a, b, dens(a, b) * h * h, -1])
    def reset(self):
        for c in self.cells: c[3] = -1
    def step(self, u):
        s = 0.0
        for c in self.cells:
            if u >= c[0]: c[3] = 1
            elif u <= c[1]: c[3] = -1
            s += c[2] * c[3]
        return s

def density(spread, centre, width):
    return lambda a, b: math.exp(-((a - b) / spread) ** 2) * math.exp(-(((a + b) / 2 - centre) / width) ** 2) + 0.15

class Sensor:
    """Sensor noise: white, or AR(1) with lag-one correlation AR_RHO (--ar-noise RHO), the same
    standard deviation; at 0 the draws are exactly those of white noise."""
    def __init__(self):
        self.e = 0.0
    def read(self, rng, sd):
        self.e = AR_RHO * self.e + math.sqrt(1.0 - AR_RHO * AR_RHO) * rng.gauss(0, sd)
        return self.e

def quant(v, q):
    return round(v / q) * q if q > 0 else v

def reading(sensor, rng, y, noise, q):
    """One reading of the true value y, as written (--noise-free: y itself to 8 digits, the
    draw made either way)."""
    e = sensor.read(rng, noise)
    return f"{y:.8f}" if NOISE_FREE else f"{quant(y + e, q):.4f}"

class Hold:
    """The readings of one hold: a Kelvin element (creep) and a linear drift on the value g."""
    def __init__(self, effect, mag, tau, drift_size, total_t):
        self.effect, self.mag, self.tau = effect, mag, tau
        self.drift_size, self.total_t, self.kel, self.t = drift_size, total_t, None, 0.0
    def restart(self):
        self.kel = None
    def readings(self, g, per_hold, dwell):
        out = []
        for r in range(per_hold):
            dt = dwell / per_hold
            self.t += dt
            y = g
            if self.effect == "creep":
                if self.kel is None: self.kel = g
                self.kel = g + (self.kel - g) * math.exp(-dt / self.tau)
                y = (1 - self.mag) * g + self.mag * self.kel
            if self.effect == "drift":
                y += self.mag * self.drift_size * self.t / self.total_t
            out.append((self.t, dwell * (r + 1) / per_hold, y))
        return out

def random_turns(rng, top, step):
    """Inputs through 5-9 turning points drawn on the grid of `step` in [0, top], alternately
    up and down by at least two steps, more while they take fewer than four full cycles' steps,
    from 0 and back to it (--random-turns)."""
    k_top = int(round(top / step))
    seq, k, turns, r = [], 0, rng.randint(5, 9), 0
    while r < turns or len(seq) < 8 * k_top:
        if r % 2 == 0:
            k_next = rng.randint(min(k + 2, k_top), k_top)
        else:
            k_next = rng.randint(0, max(k - 2, 0))
        d = 1 if k_next > k else -1
        seq += [(k + d * j) * step for j in range(1, abs(k_next - k) + 1)]
        k, r = k_next, r + 1
    seq += [(k - j) * step for j in range(1, k + 1)]
    return seq

def load_protocol(rng, kind, umax, step):
    seq = []
    def ramp(a, b):
        n = max(1, int(round(abs(b - a) / step)))
        return [a + (b - a) * k / n for k in range(1, n + 1)]
    u = 0.0
    seq.append(0.0)
    if kind == "damped":
        for amp in [1.0, 0.8, 0.6, 0.45, 0.3]:
            seq += ramp(u, amp * umax); u = amp * umax
            seq += ramp(u, 0.0); u = 0.0
        seq += ramp(u, umax); u = umax; seq += ramp(u, 0.0)
    elif kind == "repeated":
        for _ in range(6):
            seq += ramp(u, umax); u = umax
            seq += ramp(u, 0.0); u = 0.0
    elif kind == "random":  # turning points drawn on the step grid (--random-turns)
        seq += random_turns(rng, umax, step)
    else:  # minor loops between the same extrema from different histories
        lo_m, hi_m = 0.35 * umax, 0.7 * umax
        for _ in range(2):
            seq += ramp(u, umax); u = umax
            seq += ramp(u, lo_m); u = lo_m
            seq += ramp(u, hi_m); u = hi_m
            seq += ramp(u, lo_m); u = lo_m
            seq += ramp(u, 0.0); u = 0.0
            seq += ramp(u, hi_m); u = hi_m
            seq += ramp(u, lo_m); u = lo_m
            seq += ramp(u, hi_m); u = hi_m
            seq += ramp(u, 0.0); u = 0.0
    return seq

def make_load(rng, effect, mag, out):
    umax = rng.choice([250.0, 300.0, 400.0])
    step = umax / rng.choice([8, 10, 12])
    kind = "minor" if effect == "minor_loop_noncongruence" else rng.choice(["damped", "repeated", "minor"])
    if RANDOM_TURNS and kind != "minor":
        kind = "random"
    seq = load_protocol(rng, kind, umax, step)
    P = Preisach(0.0, umax * 1.001, CELLS or 30, density(umax * rng.uniform(0.15, 0.4), umax * rng.uniform(0.3, 0.6), umax * 0.5))
    lin = rng.uniform(0.3, 0.8)
    # scale: total range about 2.5-4 mm
    raw = []
    for u in seq: raw.append(P.step(u))
    P.reset()
    rmin, rmax = min(raw), max(raw)
    target = rng.uniform(2.5, 4.0)
    k_h = target * (1 - lin) / (rmax - rmin)
    k_l = target * lin / umax
    per_hold = 3 if effect == "creep" or rng.random() < 0.3 else 1
    dwell = rng.choice([30.0, 60.0, 120.0])
    noise = rng.choice([0.005, 0.01, 0.02])
    q = rng.choice([0.0, 0.01, 0.04])
    tau = dwell * rng.uniform(0.3, 1.0)
    rows = []
    yprev = 0.0
    hold = Hold(effect, mag, tau, target, len(seq) * dwell)
    for i, u in enumerate(seq):
        ue = u
        if effect == "minor_loop_noncongruence":
            ue = u + mag * umax * (yprev / target)
        g = k_l * u + k_h * (P.step(ue) - rmin)
        yprev = g
        for tt, dw, y in hold.readings(g, per_hold, dwell):
            rows.append([tt, dw, u, y])
    if effect == "outliers":
        for _ in range(rng.choice([2, 3, 4])):
            k = rng.randrange(5, len(rows) - 5)
            rows[k][3] += rng.choice([-1, 1]) * mag * target
    with open(out, "w") as f:
        f.write("# specimen: thread\n# length_mm: 100\n# plies: 2\n")
        f.write(f"# gen: {effect} {mag} kind {kind} noise {noise} q {q} per_hold {per_hold} tau {tau:.0f} dwell {dwell}\n")
        f.write("time_s,dwell_s,load_g,disp_mm\n")
        sensor = Sensor()
        for tt, dw, u, y in rows:
            f.write(f"{tt:.1f},{dw:.1f},{u:.3f},{reading(sensor, rng, y, noise, q)}\n")

def make_voltage(rng, effect, mag, out):
    loads = rng.choice([[30, 40, 50, 60, 70, 80, 90, 100], [25, 40, 55, 70, 85, 100], [30, 45, 60, 75, 90, 105, 120]])
    if rng.random() < 0.5:
        loads = loads[:]; rng.shuffle(loads)
    if ONE_LOAD:
        loads = loads[:1]
    vmax = rng.choice([6.0, 8.0, 10.0])
    steps = rng.choice([6, 8, 10])
    P = Preisach(0.0, vmax * 1.001, CELLS or 24, density(vmax * rng.uniform(0.1, 0.3), vmax * rng.uniform(0.5, 0.7), vmax * 0.4))
    dwell = rng.choice([10.0, 30.0, 60.0])
    noise = rng.choice([0.005, 0.01, 0.02])
    q = rng.choice([0.0, 0.01, 0.04])
    per_hold = 3 if effect == "creep" and not ONCE_PER_HOLD else 1
    tau = dwell * rng.uniform(0.3, 1.0)
    L = 70.0
    seq = []
    for amp in [1.0, 0.75, 0.5] if rng.random() < 0.5 else [1.0, 1.0, 1.0]:
        for k in range(1, steps + 1): seq.append(amp * vmax * k / steps)
        for k in range(steps - 1, -1, -1): seq.append(amp * vmax * k / steps)
    seq = [0.0] + (random_turns(rng, vmax, vmax / steps) if RANDOM_TURNS else seq)
    ref = [P.step(v) for v in seq]; P.reset()
    hmin, hmax = min(ref), max(ref)
    rows = []
    Fmin, Fmax = min(loads), max(loads)
    hold = Hold(effect, mag, tau, 0.06 * L, len(loads) * len(seq) * dwell)
    for s, Fg in enumerate(loads):
        F = Fg * 9.81e-3
        x = (Fg - Fmin) / (Fmax - Fmin) if Fmax > Fmin else 0.5
        f1 = L * (0.02 + 0.05 * x - 0.01 * x * x)  # elongation under load (mm)
        if effect == "offset_nonlinearity":
            f1 -= mag * L * 0.05 * math.exp(-(Fg - Fmin) / ((Fmax - Fmin) * 0.12))
        f2 = L * (0.03 + 0.03 * x - 0.012 * x * x)  # stroke (mm)
        P.reset()
        hold.restart()
        M = 0.0
        for i, v in enumerate(seq):
            ve = v
            if effect == "load_shape_coupling":
                ve = vmax * (v / vmax) ** (1.0 + mag * (x - 0.5))
            h = (P.step(ve) - hmin) / (hmax - hmin)
            M = max(M, v)
            g = f1 - f2 * h
            if effect == "lonely_stroke":
                g -= mag * f2 * M / vmax
            for tt, dw, y in hold.readings(g, per_hold, dwell):
                rows.append([tt, dw, s, Fg, v, y])
    if effect == "outliers":
        for _ in range(rng.choice([2, 3, 4])):
            k = rng.randrange(5, len(rows) - 5)
            rows[k][5] += rng.choice([-1, 1]) * mag * 0.05 * L
    with open(out, "w") as f:
        f.write(f"# specimen: scp\n# length_mm: {L}\n")
        f.write(f"# gen: {effect} {mag} loads {loads} noise {noise} q {q} tau {tau:.0f} dwell {dwell}\n")
        f.write("time_s,dwell_s,segment,load_g,voltage_V,disp_mm\n")
        sensor = Sensor()
        for tt, dw, s, Fg, v, y in rows:
            f.write(f"{tt:.1f},{dw:.1f},{s},{Fg},{v:.4f},{reading(sensor, rng, y, noise, q)}\n")

MAGS = {
    "none": [0], "drift": [0.03, 0.06, 0.12], "outliers": [0.05, 0.1, 0.2],
    "creep": [0.1, 0.2, 0.4], "minor_loop_noncongruence": [0.1, 0.2, 0.3],
    "lonely_stroke": [0.03, 0.06, 0.1], "load_shape_coupling": [0.3, 0.6, 1.0],
    "offset_nonlinearity": [0.05, 0.1, 0.2],
}
ONCE_PER_HOLD = False  # --once-per-hold: voltage creep read once per hold (no readings during holds)
AR_RHO = 0.0  # --ar-noise RHO: AR(1) sensor noise (clean records with it should stay `none`)
ONE_LOAD = False  # --one-load: voltage tests at the first of the drawn loads only (one segment)
RANDOM_TURNS = False  # --random-turns: damped and repeated load protocols and voltage cycles become random turning points
NOISE_FREE = False  # --noise-free: the same files without noise or rounding (every draw alike)
CELLS = None  # --cells N: N relay levels in the Preisach truth (default 30 load, 24 voltage)
def take_value(args, flag, convert, default):
    """Removes `flag VALUE` from args and returns convert(VALUE), or default without the flag."""
    if flag not in args:
        return default
    k = args.index(flag)
    value = convert(args[k + 1])
    del args[k:k + 2]
    return value

if __name__ == "__main__":
    args = sys.argv[1:]
    AR_RHO = take_value(args, "--ar-noise", float, AR_RHO)
    CELLS = take_value(args, "--cells", int, CELLS)
    ONCE_PER_HOLD = "--once-per-hold" in args
    ONE_LOAD = "--one-load" in args
    RANDOM_TURNS = "--random-turns" in args
    NOISE_FREE = "--noise-free" in args
    args = [a for a in args if a not in ("--once-per-hold", "--one-load", "--random-turns", "--noise-free")]
    write_sets("independent_cases.py", __doc__, args,
               lambda side, rng, e, mag, out: (make_load if side == "load" else make_voltage)(rng, e, mag, out),
               lambda side, e, i: random.Random(i * 7919 + len(e) * 31 + (0 if side == "load" else 100000)),
               lambda e, i: MAGS[e][i % len(MAGS[e])],
               skip=lambda e: ONE_LOAD and e in ("load_shape_coupling", "offset_nonlinearity"))
