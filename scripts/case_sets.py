"""The file-set driver of the diagnose test-case generators (scripts/independent_cases*.py):
the positional arguments OUT_DIR N [FIRST [SIDE-EFFECT]], the effect vocabulary per side
(SPEC.md), one file SIDE-EFFECT-I.csv per effect, side and seed, and the CSV writer. The
generators share this and nothing of their physics."""
import os
import sys

KINDS = [("load", ["none", "drift", "outliers", "creep", "minor_loop_noncongruence"]),
         ("voltage", ["none", "drift", "outliers", "creep", "lonely_stroke", "load_shape_coupling",
                      "offset_nonlinearity"])]


def write_csv(out, meta, cols, rows):
    """One measurement file: `# key: value` lines from meta, the header cols, then rows (lists
    of cells already formatted)."""
    with open(out, "w") as f:
        for k, v in meta:
            f.write(f"# {k}: {v}\n")
        f.write(",".join(cols) + "\n")
        for r in rows:
            f.write(",".join(r) + "\n")


def write_sets(prog, doc, args, make, rng_for, magnitude, skip=lambda effect: False):
    """--help (the docstring's first two paragraphs), or every file the positional args ask for
    (flags already taken out of args): make(side, rng, effect, mag, path) writes one, with
    rng_for(side, effect, i) and magnitude(effect, i); effects for which skip(effect) is true
    are left out."""
    if not args or args[0] in ("-h", "--help"):
        print("\n\n".join(doc.split("\n\n")[:2]))
        sys.exit(0 if args else 2)
    if len(args) < 2 or not args[1].isdigit():
        sys.exit(f"{prog}: need OUT_DIR and N (files per kind); --help for usage")
    outdir, n = args[0], int(args[1])
    first = int(args[2]) if len(args) > 2 else 0
    only = args[3] if len(args) > 3 else None
    names = [f"{side}-{e}" for side, effects in KINDS for e in effects]
    if only is not None and only not in names:
        sys.exit(f"{prog}: unknown kind '{only}' (one of: {', '.join(names)})")
    os.makedirs(outdir, exist_ok=True)
    for side, effects in KINDS:
        for e in effects:
            if (only is not None and only != f"{side}-{e}") or skip(e):
                continue
            for i in range(first, first + n):
                make(side, rng_for(side, e, i), e, magnitude(e, i), os.path.join(outdir, f"{side}-{e}-{i}.csv"))
