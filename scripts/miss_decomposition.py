#!/usr/bin/env python3
"""What the misses of `scpkit diagnose` on the five independent generators are.

Usage: scripts/miss_decomposition.py OUT_DIR N FIRST [--scpkit PATH] [--jobs J]

Writes N records per effect, side and generator (seeds FIRST..FIRST+N-1) with
scripts/independent_cases{,_b,_c,_d,_e}.py into OUT_DIR/noisy, runs `scpkit diagnose --json`
on each, then writes every missed record again with --noise-free (every random draw alike:
the same truth, protocol and effect, without sensor noise or rounding) into OUT_DIR/exact and
diagnoses that. Each miss falls in one of three classes:

- noise: named right without the noise. The effect is in the data; at this noise the evidence
  for it does not reach the detectors' levels.
- not in the data: wrong without the noise too, and the baseline's held-out error on the exact
  readings whose memory the training identified (at least 10, and a quarter of the held-out
  ones) is below 0.1 % of the range: the protocol and
  the truth make the effect one a rate-independent model reproduces (on a coarse relay grid a
  moving Preisach's shift crosses no threshold; a Prandtl-Ishlinskii operator with
  output-dependent play widths on one family of loops is one with other widths).
- other: wrong without the noise, with the effect in the data. These are the detectors' own
  limits and the protocols' (readings the training never identified, one reading per hold at
  one length, a warm-up that settles over evenly timed cycles).

Prints one line per miss, then the counts per class and per generator. Slow (a few seconds
per record): N = 4 is 240 records, about 12 minutes on two cores.
"""
import argparse
import concurrent.futures
import json
import os
import re
import subprocess
import sys

GENERATORS = ["", "_b", "_c", "_d", "_e"]
EXACT_ID_ERROR = 0.1  # % of range: below it the effect is not in the data


def diagnose(scpkit, path):
    """The JSON diagnose writes for `path`, or None where it refuses the file."""
    run = subprocess.run([scpkit, "diagnose", path, "--json"], capture_output=True, text=True)
    return json.loads(run.stdout) if run.returncode == 0 else None


def not_in_the_data(baseline):
    """Whether the baseline reproduces the exact record where its training fixed the memory:
    below EXACT_ID_ERROR on at least 10 held-out readings, and a quarter of them (on fewer the
    error says nothing of the effect)."""
    identified = baseline["identified_rows"]
    return (baseline["identified_sustained_rms_pct_range"] < EXACT_ID_ERROR and identified >= 10
            and 4 * identified >= baseline["heldout_rows"])


def truth_of(name):
    return re.match(r"^(load|voltage)-(.*)-\d+\.csv$", name).group(2)


def generate(script_dir, out, n, first, gen, extra):
    script = os.path.join(script_dir, f"independent_cases{gen}.py")
    subprocess.run([sys.executable, script, out, str(n), str(first)] + extra, check=True,
                   stdout=subprocess.DEVNULL)


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("out", help="directory for the records (noisy/ and exact/)")
    parser.add_argument("n", type=int, help="records per effect, side and generator")
    parser.add_argument("first", type=int, help="first seed")
    parser.add_argument("--scpkit", default=os.path.join(os.path.dirname(__file__), "..", "build",
                                                         "cli", "scpkit"))
    parser.add_argument("--jobs", type=int, default=2, help="diagnose runs at once")
    a = parser.parse_args()
    out, n, first, scpkit, jobs = a.out, a.n, a.first, a.scpkit, a.jobs
    script_dir = os.path.dirname(os.path.abspath(__file__))
    records = []  # (generator, noisy path)
    for gen in GENERATORS:
        d = os.path.join(out, "noisy", f"gen{gen or '_a'}")
        generate(script_dir, d, n, first, gen, [])
        records += [(gen, os.path.join(d, f)) for f in sorted(os.listdir(d)) if f.endswith(".csv")]
    with concurrent.futures.ThreadPoolExecutor(jobs) as pool:
        causes = list(pool.map(lambda r: diagnose(scpkit, r[1]), records))
    misses = [(g, p, j) for (g, p), j in zip(records, causes)
              if j is None or j["cause"] != truth_of(os.path.basename(p))]
    for gen in GENERATORS:
        if any(g == gen for g, _, _ in misses):
            generate(script_dir, os.path.join(out, "exact", f"gen{gen or '_a'}"), n, first, gen,
                     ["--noise-free"])
    exact_paths = [p.replace(os.path.join(out, "noisy"), os.path.join(out, "exact"), 1)
                   for _, p, _ in misses]
    with concurrent.futures.ThreadPoolExecutor(jobs) as pool:
        exact = list(pool.map(lambda p: diagnose(scpkit, p), exact_paths))
    classes = {"noise": 0, "not in the data": 0, "other": 0}
    per_gen = {}
    for (gen, path, noisy), e in zip(misses, exact):
        name = os.path.basename(path)
        truth = truth_of(name)
        named = noisy["cause"] if noisy else "refused"
        if e is not None and e["cause"] == truth:
            cls = "noise"
        elif e is not None and not_in_the_data(e["baseline"]):
            cls = "not in the data"
        else:
            cls = "other"
        classes[cls] += 1
        per_gen.setdefault(gen or "_a", {}).setdefault(cls, 0)
        per_gen[gen or "_a"][cls] += 1
        exact_named = e["cause"] if e else "refused"
        id_err = e["baseline"]["identified_sustained_rms_pct_range"] if e else float("nan")
        print(f"gen{gen or '_a'} {name:48s} named {named:26s} exact: {exact_named:26s} "
              f"identified error {id_err:.3f} %  -> {cls}")
    print(f"right {len(records) - len(misses)}/{len(records)}; misses {len(misses)}: "
          + ", ".join(f"{k} {v}" for k, v in classes.items()))
    for gen, c in sorted(per_gen.items()):
        print(f"  gen{gen}: " + ", ".join(f"{k} {v}" for k, v in sorted(c.items())))


if __name__ == "__main__":
    main()
