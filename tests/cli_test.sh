#!/usr/bin/env bash
# End-to-end checks of the scpkit command line: help, exit codes, outputs, and bad input
# (one clear error naming file:line:column, non-zero exit, no partial or clobbered output).
# Usage: cli_test.sh SCPKIT_BINARY SOURCE_DIR
set -u
bin=$1
src=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
pass=0
fail=0

# check NAME EXPECTED_EXIT PATTERN -- COMMAND...: runs COMMAND, compares the exit code and
# greps stdout+stderr for PATTERN (extended regex).
check() {
  local name=$1 want=$2 pattern=$3
  shift 4
  local out rc
  out=$("$@" 2>&1)
  rc=$?
  if [ "$rc" -eq "$want" ] && grep -Eq -- "$pattern" <<<"$out"; then
    pass=$((pass + 1))
  else
    fail=$((fail + 1))
    echo "FAIL: $name (exit $rc, wanted $want; pattern '$pattern')"
    echo "$out" | head -20 | sed 's/^/    /'
  fi
}

# assert NAME CONDITION...: a plain test command.
assert() {
  local name=$1
  shift
  if "$@"; then pass=$((pass + 1)); else fail=$((fail + 1)); echo "FAIL: $name"; fi
}

ex=$src/examples/data
check "help" 0 "commands:" -- "$bin" --help
check "no args is a usage error" 2 "usage: scpkit" -- "$bin"
check "version" 0 "^scpkit [0-9]+\.[0-9]+\.[0-9]+" -- "$bin" --version
check "unknown command" 2 "unknown command 'frobnicate'" -- "$bin" frobnicate
for c in fit predict map simulate diagnose; do
  check "$c --help" 0 "usage: scpkit $c" -- "$bin" "$c" --help
done
check "unknown option" 2 "unrecognised option|unrecognized option" -- "$bin" fit "$ex/pair-2ply.csv" --bogus
check "missing positional" 2 "missing DATA" -- "$bin" fit
check "unknown model" 2 "unknown model 'spline'" -- "$bin" fit "$ex/pair-2ply.csv" --model spline
for mdl in gpi lonely linear poly2; do
  check "fit --model $mdl" 0 "identification: E_max" -- "$bin" fit "$ex/pair-2ply.csv" --model $mdl -o "$work/$mdl.json"
  check "predict with a $mdl model" 0 "\"model\": \"$mdl\"" -- "$bin" predict "$work/$mdl.json" "$ex/pair-2ply.csv" --json
done

# The main job.
check "fit paired 2-ply" 0 "SCP gain: scp = [0-9.]+ \* thread" -- "$bin" fit "$ex/pair-2ply.csv" -o "$work/m2.json"
assert "model file written" test -s "$work/m2.json"
check "fit --json is one object" 0 '"rms_pct_range"' -- "$bin" fit "$ex/pair-2ply.csv" -o "$work/m2b.json" --json
if command -v python3 >/dev/null; then
  assert "fit --json parses" python3 -c "import json,sys; json.loads(sys.stdin.read())" \
    < <("$bin" fit "$ex/pair-2ply.csv" -o "$work/m2c.json" --json 2>/dev/null)
  assert "predict --json parses with the SPEC keys" python3 -c "
import json,sys; d=json.loads(sys.stdin.read())
assert all(k in d for k in ('rms_pct_range','max_pct_range','mean_abs','sd_abs')), d" \
    < <("$bin" predict "$work/m2.json" "$ex/pair-2ply.csv" --json 2>/dev/null)
fi
check "predict to file" 0 "predictions written" -- "$bin" predict "$work/m2.json" "$ex/pair-2ply.csv" -o "$work/p.csv"
assert "predicted column added" grep -q "^time_s,dwell_s,load_g,thread_strain_pct,scp_strain_pct,predicted_thread_strain_pct$" "$work/p.csv"
check "predict to stdout" 0 "predicted_thread_strain_pct" -- "$bin" predict "$work/m2.json" "$ex/pair-2ply.csv"
check "predict on its own output" 0 "predictions written" -- "$bin" predict "$work/m2.json" "$work/p.csv" -o "$work/pp.csv"
assert "predict: a column name the file has gets _2" grep -q "^time_s,dwell_s,load_g,thread_strain_pct,scp_strain_pct,predicted_thread_strain_pct,predicted_thread_strain_pct_2$" "$work/pp.csv"
check "map 4-ply with data" 0 "corrected Eq. 8" -- "$bin" map "$work/m2.json" --plies 4 --data "$ex/pair-4ply.csv" -o "$work/map4.csv"
assert "map csv has the band" grep -q "scp_band_lo_strain_pct" "$work/map4.csv"
check "map without data" 0 "predicted 6-ply SCP major loop" -- "$bin" map "$work/m2.json" --plies 6
check "map needs --plies" 2 "--plies Q is required" -- "$bin" map "$work/m2.json"
check "map rejects an impossible coil" 2 "spring index" -- "$bin" map "$work/m2.json" --plies 4 --coil-d 0.3 --coil-D 0.2 --coil-n 100
for mdl in gpi preisach lonely linear poly2; do
  check "augmented $mdl fit on voltage tests" 0 "augmented $mdl model over 8 constant-load segments" -- "$bin" fit "$ex/voltage-8loads.csv" --model $mdl -o "$work/v-$mdl.json"
done
# A load read back by a load cell scatters about each held load: still 8 segments (no segment
# column), each at its mean load.
awk -F, -v OFS=, '/^#/ { print; next } !h { h = 1; print $1, $2, $4, $5, $6; next }
  { print $1, $2, $4 + (NR % 3 - 1) * 0.1, $5, $6 }' "$ex/voltage-8loads.csv" >"$work/v-cell.csv"
check "augmented fit on a scattered load" 0 "augmented linear model over 8 constant-load segments" -- "$bin" fit "$work/v-cell.csv" --model linear -o "$work/v-cell.json"
printf 'test = "voltage"\nlength_mm = 70\n[voltage]\nloads_g = [120, 130]\n' >"$work/heavy.toml"
"$bin" simulate "$work/heavy.toml" -o "$work/v-heavy.csv" >/dev/null
check "augmented predict warns outside the load range" 0 "outside the identified range" -- "$bin" predict "$work/v-gpi.json" "$work/v-heavy.csv" -o "$work/v-heavy-pred.csv"
check "augmented invert" 0 "[0-9]+ unreachable; tracking" -- "$bin" invert "$work/v-gpi.json" "$ex/voltage-8loads.csv" -o "$work/v-inv.csv"
assert "augmented invert keeps the load column" grep -q "^time_s,segment,load_g,voltage_V,disp_mm," "$work/v-inv.csv"
for name in pair-2ply pair-4ply pair-6ply voltage-8loads voltage-lonely; do
  "$bin" simulate "$src/examples/rig/$name.toml" -o "$work/$name.csv" >/dev/null
  assert "example data $name regenerates byte for byte" cmp -s "$work/$name.csv" "$ex/$name.csv"
done
check "invert --help" 0 "usage: scpkit invert" -- "$bin" invert --help
check "invert a measured response" 0 "[0-9]+ unreachable; tracking" -- "$bin" invert "$work/m2.json" "$ex/pair-2ply.csv" -o "$work/inv.csv"
assert "inverted loads stay in the identified range" awk -F, 'NR > 1 && ($2 < 0.19 || $2 > 2.46) {bad = 1} END {exit bad}' "$work/inv.csv"
if command -v python3 >/dev/null; then
  assert "predict(invert(target)) reproduces the inversion's tracking" python3 -c "
import json,subprocess,sys
inv = json.loads(subprocess.run(['$bin','invert','$work/m2.json','$ex/pair-2ply.csv','--json'],capture_output=True,text=True).stdout)
pre = json.loads(subprocess.run(['$bin','predict','$work/m2.json','$work/inv.csv','--json'],capture_output=True,text=True).stdout)
assert abs(inv['rms_pct_range'] - pre['rms_pct_range']) < 1e-4, (inv, pre)
assert inv['rms_pct_range'] < 0.2, inv"
fi
check "simulate to stdout" 0 "# truth_effects: creep=0" -- "$bin" simulate "$src/examples/rig/pair-2ply.toml"

# Bad input: located errors, exit 3, and outputs neither created nor clobbered.
printf 'load_g,strain_pct\n20,0.1\n30,x1\n' >"$work/bad.csv"
check "non-numeric cell" 3 "bad.csv:3:4: 'x1' is not a number" -- "$bin" fit "$work/bad.csv" -o "$work/new.json"
assert "no output after a failed fit" test ! -e "$work/new.json"
echo keep >"$work/keep.json"
check "failed fit keeps the old output" 3 "bad.csv:3:4" -- "$bin" fit "$work/bad.csv" -o "$work/keep.json"
assert "old output intact" grep -qx keep "$work/keep.json"
assert "no temporary files left" test -z "$(find "$work" -name '.*.tmp-*')"
printf 'load_g,strain_pct\n20,0.1\n30,0.2\n' >"$work/short.csv"
check "too few rows" 3 "short.csv:1:8: cannot identify the model: 2 samples are too few" -- "$bin" fit "$work/short.csv"
printf 'load_g,strain_pct\n20,0.1\n20,0.2\n20,0.3\n' >"$work/flat.csv"
check "no excitation" 3 "flat.csv:1: no varying input" -- "$bin" fit "$work/flat.csv"
printf 'load_lbs,strain_pct\n20,0.1\n' >"$work/unit.csv"
check "unknown unit" 3 "unit.csv:1:1: unknown unit 'lbs'" -- "$bin" fit "$work/unit.csv"
# Unknown columns are ignored (SPEC.md), those named like a quantity too when the file gives
# that quantity in a known unit; several varying inputs: a load swept from reading to reading
# is the input of a load test logging temperature, the voltage that of a test at one load.
awk 'BEGIN { print "time_s,load_g,load_cell_raw,temp_C,strain_pct";
  for (i = 0; i < 60; i++) { l = 50 * (i % 20 < 10 ? i % 10 : 10 - i % 10);
    printf "%d,%d,%d,%.1f,%.4f\n", i, l, 3 * l, 23 + (i % 3) / 10, l / 250 }}' >"$work/logged.csv"
check "a load test logging temperature" 0 "the input is load_g \(the load changes from reading to reading\), not temp_C" -- "$bin" fit "$work/logged.csv" --model linear -o "$work/logged.json"
awk 'BEGIN { print "load_g,voltage_V,power_W,strain_pct";
  for (i = 0; i < 60; i++) { v = (i % 20 < 10 ? i % 10 : 10 - i % 10) / 2;
    printf "100,%.1f,%.3f,%.4f\n", v, v * v / 20, -v / 50 }}' >"$work/powered.csv"
check "a voltage test logging power" 0 "the input is voltage_V, not power_W" -- "$bin" fit "$work/powered.csv" --model linear -o "$work/powered.json"
: >"$work/empty.csv"
check "empty file" 3 "empty.csv:1: empty file" -- "$bin" fit "$work/empty.csv"
check "missing file" 3 "nope.csv: cannot open" -- "$bin" fit "$work/nope.csv"
check "predict with a broken model" 3 "bad.csv:.*not a JSON model file" -- "$bin" predict "$work/bad.csv" "$ex/pair-2ply.csv"
printf 'specimen = "thread"\n[sensor]\nnosie_mm = 0.1\n' >"$work/typo.toml"
check "rig typo" 3 "typo.toml:3:1: unknown key 'nosie_mm'" -- "$bin" simulate "$work/typo.toml"
printf 'specimen = "thread"\n[effects]\ncreep = 3\n' >"$work/creep.toml"
check "rig out of range" 3 "creep is a fraction" -- "$bin" simulate "$work/creep.toml"

# Design and sweeps.
"$bin" fit "$ex/pair-2ply.csv" -o "$work/thread-2ply.model.json" >/dev/null
assert "the example thread model regenerates byte for byte" cmp -s "$work/thread-2ply.model.json" "$src/examples/design/thread-2ply.model.json"
"$bin" fit "$ex/voltage-8loads.csv" --model gpi -o "$work/voltage-gpi.model.json" >/dev/null
assert "the example voltage model regenerates byte for byte" cmp -s "$work/voltage-gpi.model.json" "$src/examples/design/voltage-gpi.model.json"
check "design --help" 0 "usage: scpkit design" -- "$bin" design --help
check "the characterised design reproduces its loop" 0 "against the protocol file's SCP strain: E_max [0-9.]+ %  E_RMS 0\.[0-9]+ %" -- "$bin" design "$src/examples/design/characterised-2ply.toml"
check "bicep design with the voltage side" 0 "voltage for 8 mm: [0-9.]+ V" -- "$bin" design "$src/examples/design/bicep-design.toml" -o "$work/loop.csv"
assert "design loop csv" grep -q "^load_g,predicted_scp_strain_pct$" "$work/loop.csv"
printf 'thread_model = "%s"\nplies = 4\n[coil]\nn = 200\nlength_mm = 90\nspring_index = 2\nlegz = 2\n' "$(cd "$src" && pwd)/examples/design/thread-2ply.model.json" >"$work/typo-design.toml"
check "design file typos are located" 3 "typo-design.toml:7:1: unknown key 'legz'" -- "$bin" design "$work/typo-design.toml"
sweep=$src/examples/design/bicep-sweep.toml
check "sweep needs -o" 2 "-o OUT.csv is required" -- "$bin" sweep "$sweep"
check "sweep, 1 thread" 0 "2672 of 2672 candidates" -- "$bin" sweep "$sweep" -o "$work/s1.csv" --threads 1
check "sweep, 2 threads" 0 "feasible" -- "$bin" sweep "$sweep" -o "$work/s2.csv" --threads 2
assert "same bytes for 1 and 2 threads" cmp -s "$work/s1.csv" "$work/s2.csv"
check "shard 0/2" 0 "shard 0/2" -- "$bin" sweep "$sweep" -o "$work/sh0.csv" --shard 0/2
check "shard 1/2 from Slurm's variables" 0 "shard 1/2" -- env SLURM_ARRAY_TASK_ID=1 SLURM_ARRAY_TASK_COUNT=2 "$bin" sweep "$sweep" -o "$work/sh1.csv"
check "merge" 0 "2 shards merged" -- "$bin" merge "$work/sh1.csv" "$work/sh0.csv" -o "$work/merged.csv"
assert "merged shards equal the full sweep" cmp -s "$work/merged.csv" "$work/s1.csv"
check "merge refuses a missing shard" 3 "shards missing: 1" -- "$bin" merge "$work/sh0.csv" -o "$work/bad-merge.csv"
assert "no output after a refused merge" test ! -e "$work/bad-merge.csv"
check "bad shard spec" 2 "--shard must be i/N" -- "$bin" sweep "$sweep" -o "$work/x.csv" --shard 2/2
printf 'thread_model = "nope.json"\n[space]\nplies = [2, 0]\n' >"$work/bad-sweep.toml"
check "sweep spec errors are located" 3 "bad-sweep.toml:3:13: 'plies' must hold integers 1..100" -- "$bin" sweep "$work/bad-sweep.toml" -o "$work/x.csv"

printf '[protocol]\nshape = "zigzag"\n' >"$work/bad-shape.toml"
check "rig protocol shape errors are located" 3 "bad-shape.toml:2:9: 'shape' must be damped or repeated" -- "$bin" simulate "$work/bad-shape.toml" -o "$work/bad-shape.csv"
assert "no output on a bad rig description" test ! -e "$work/bad-shape.csv"
printf 'test = "voltage"\n[voltage]\nshape = "ramp"\n' >"$work/bad-vshape.toml"
check "rig voltage shape errors are located" 3 "bad-vshape.toml:3:9: 'shape' must be damped or repeated" -- "$bin" simulate "$work/bad-vshape.toml" -o "$work/bad-vshape.csv"

# diagnose: SPEC's JSON keys; drift hidden in rig data is named.
printf 'specimen = "thread"\nseed = 11\n[effects]\ndrift = 0.05\n' >"$work/drift.toml"
"$bin" simulate "$work/drift.toml" -o "$work/drift.csv" >/dev/null
# One thread and three: the same bytes (the baseline's shifted grids run on worker threads).
"$bin" diagnose "$work/drift.csv" --json --threads 1 >"$work/drift-1.json" 2>/dev/null
assert "diagnose --threads 1 exits 0" test $? -eq 0
"$bin" diagnose "$work/drift.csv" --json --threads 3 >"$work/drift-3.json" 2>/dev/null
assert "diagnose --threads 3 exits 0" test $? -eq 0
check "diagnose names a hidden drift" 0 '"cause": "drift"' -- cat "$work/drift-1.json"
assert "diagnose: the same JSON for any --threads" cmp -s "$work/drift-1.json" "$work/drift-3.json"
check "diagnose --threads 0 is a usage error" 2 "--threads must be 1..1024" -- "$bin" diagnose "$work/drift.csv" --threads 0
check "fit --threads 0 is a usage error" 2 "--threads must be 1..1024" -- "$bin" fit "$ex/pair-2ply.csv" --threads 0
if command -v python3 >/dev/null; then
  assert "diagnose JSON follows SPEC" python3 -c "
import json,sys; d=json.loads(sys.stdin.read())
assert set(['input','baseline','findings','cause']) <= set(d), d.keys()
assert set(['model','rms_pct_range','max_pct_range']) <= set(d['baseline'])
for f in d['findings']:
    assert set(['effect','detected','score','evidence','extended_model','heldout_rms_before','heldout_rms_after','gain_pct']) <= set(f), f
assert [l['effect'] for l in d['protocol_limits']] == ['lonely_stroke', 'creep'], d['protocol_limits']
assert all(l['note'] for l in d['protocol_limits'])" \
    <"$work/drift-3.json"
fi
# --residuals: where the model fails, per reading, beside the file's own columns; the same JSON.
"$bin" diagnose "$work/drift.csv" --json --residuals "$work/drift-res.csv" >"$work/drift-r.json" 2>/dev/null
assert "diagnose --residuals exits 0" test $? -eq 0
assert "diagnose --residuals: the same JSON" cmp -s "$work/drift-1.json" "$work/drift-r.json"
if command -v python3 >/dev/null; then
  # Recomputed from the file: the scored readings' RMS residual (% of the response's range) is
  # the baseline's held-out E_RMS, the cause's residuals its extension's E_RMS after.
  assert "diagnose --residuals: one row per reading, the JSON's held-out errors" python3 -c "
import csv, json, math, sys
data = [l for l in open(sys.argv[1]) if not l.startswith('#')]
rows = list(csv.DictReader(l for l in open(sys.argv[2]) if not l.startswith('#')))
d = json.load(open(sys.argv[3]))
assert len(rows) == len(data) - 1, (len(rows), len(data))
resp = [c for c in rows[0] if c.startswith('residual_')][0][len('residual_'):]
y = [float(r[resp]) for r in rows]
rng = max(y) - min(y)
def rms(col):
    e = [float(r[col]) for r in rows if r[col] != '']
    return len(e), 100 * math.sqrt(sum(x * x for x in e) / len(e)) / rng
n, base = rms('residual_' + resp)
assert n == d['baseline']['heldout_rows'], (n, d['baseline']['heldout_rows'])
assert abs(base - d['baseline']['rms_pct_range']) < 1e-6 * base, (base, d['baseline'])
cause = [f for f in d['findings'] if f['effect'] == d['cause']][0]
_, after = rms(d['cause'] + '_residual_' + resp)
assert abs(after - cause['heldout_rms_after']) < 1e-6 * after, (after, cause['heldout_rms_after'])
assert all(r['heldout_fold'] in [str(k) for k in range(1, d['baseline']['heldout_folds'] + 1)]
           for r in rows if r['baseline_' + resp] != '')" \
    "$work/drift.csv" "$work/drift-res.csv" "$work/drift-r.json"
fi
# The spike screen's flags: a rig record with spikes against the same seed's run without them
# (the noise differs by a sensor step at most, a spike by at least 10 % of the range).
printf 'specimen = "thread"\nseed = 12\n[effects]\noutliers = 0.1\n' >"$work/spikes.toml"
printf 'specimen = "thread"\nseed = 12\n' >"$work/nospikes.toml"
"$bin" simulate "$work/spikes.toml" -o "$work/spikes.csv" >/dev/null
"$bin" simulate "$work/nospikes.toml" -o "$work/nospikes.csv" >/dev/null
check "diagnose names the rig's spikes" 0 '"cause": "outliers"' -- "$bin" diagnose "$work/spikes.csv" --json --residuals "$work/spikes-res.csv"
if command -v python3 >/dev/null; then
  assert "diagnose --residuals: the readings flagged outlier are the spikes" python3 -c "
import csv, sys
def rows(path):
    return list(csv.DictReader(l for l in open(path) if not l.startswith('#')))
a, b, res = rows(sys.argv[1]), rows(sys.argv[2]), rows(sys.argv[3])
y = [float(r['disp_mm']) for r in b]
rng = max(y) - min(y)
spikes = {i for i, (p, q) in enumerate(zip(a, b)) if abs(float(p['disp_mm']) - float(q['disp_mm'])) > 0.05 * rng}
flagged = {i for i, r in enumerate(res) if r['outlier'] == '1'}
assert spikes and flagged == spikes, (sorted(spikes), sorted(flagged))" \
    "$work/spikes.csv" "$work/nospikes.csv" "$work/spikes-res.csv"
fi
check "diagnose --residuals: the report says where it wrote" 0 "residuals per reading written to .*spikes-res2.csv" -- "$bin" diagnose "$work/spikes.csv" --residuals "$work/spikes-res2.csv"
assert "diagnose --residuals: the same file with and without --json" cmp -s "$work/spikes-res.csv" "$work/spikes-res2.csv"
# Its own output diagnosed again: the earlier columns are kept, the new ones take a suffix.
check "diagnose --residuals on its own output" 0 '"cause": "outliers"' -- "$bin" diagnose "$work/spikes-res.csv" --json --residuals "$work/spikes-res3.csv"
assert "diagnose --residuals keeps the file's metadata (the length that makes disp_mm a strain)" grep -q "^# length_mm: 100$" "$work/spikes-res.csv"
assert "diagnose --residuals: a name the file has gets _2" grep -q "^time_s,dwell_s,load_g,disp_mm,heldout_fold,identified,baseline_disp_mm,residual_disp_mm,outlier,heldout_fold_2,identified_2,baseline_disp_mm_2,residual_disp_mm_2,outlier_2$" "$work/spikes-res3.csv"
check "diagnose --residuals into a missing folder is an error naming it" 3 "no/such/r.csv" -- "$bin" diagnose "$work/drift.csv" --residuals "$work/no/such/r.csv"
assert "diagnose --residuals writes nothing on an error" test ! -e "$work/no/such/r.csv"
check "diagnose --residuals on a paired file is a usage error" 2 "--residuals is for a test" -- "$bin" diagnose "$ex/pair-4ply.csv" --residuals "$work/pair-res.csv"
# Voltage tests at several loads: the augmented baseline, held out by load segment; clean data.
check "diagnose voltage tests (clean) names none" 0 '"cause": "none"' -- "$bin" diagnose "$src/examples/data/voltage-8loads.csv" --json
"$bin" diagnose "$src/examples/data/voltage-8loads.csv" >"$work/v8.txt" 2>&1
assert "diagnose voltage tests: human report exits 0" test $? -eq 0
assert "diagnose voltage tests: augmented baseline by load segment" grep -q "held out by load segments" "$work/v8.txt"
# Its loads rise through the file (30 to 100 g), one reading per hold, holds of one length.
assert "diagnose says the load order hides a drift" grep -q "protocol hides drift: the loads were tested in the order of their size" "$work/v8.txt"
assert "diagnose says one reading per equal hold hides creep" grep -q "protocol hides creep: with one reading per hold" "$work/v8.txt"
# Paper 001's protocol (100 -> 50 g, lonely stroke 0.08 in the rig file): named.
check "diagnose one load change names the lonely stroke" 0 '"cause": "lonely_stroke"' -- "$bin" diagnose "$src/examples/data/voltage-lonely.csv" --json
# A file without a clock (time_s, the rig's first column, dropped): times from dwell_s.
awk -F, -v OFS=, '/^#/ { print; next } { $1 = ""; sub(/^,/, ""); print }' "$work/drift.csv" >"$work/drift-noclock.csv"
check "diagnose without time_s still names the drift (times from dwell_s)" 0 '"cause": "drift"' -- "$bin" diagnose "$work/drift-noclock.csv" --json
# A paired thread/SCP test: the ply-mapping diagnosis (prediction from card and coil).
check "diagnose pair file: ply mapping, faithful rig file names none" 0 '"cause": "none"' -- "$bin" diagnose "$ex/pair-4ply.csv" --json
check "diagnose pair file: legs override changes the verdict" 0 '"cause": "legs"' -- "$bin" diagnose "$ex/pair-4ply.csv" --json --legs 1
check "diagnose pair file: report" 0 "SCP gain: predicted 13.59" -- "$bin" diagnose "$ex/pair-4ply.csv"
check "diagnose pair file: half a coil is a usage error" 2 "give all of --coil-d" -- "$bin" diagnose "$ex/pair-4ply.csv" --coil-d 0.3

# Two tests compared (--reference): the same rig specimen on another seed names nothing; the
# same record moved by 0.2 mm (0.2 % strain on 100 mm) names the offset and sizes it.
printf 'specimen = "thread"\nseed = 12\n' >"$work/again.toml"
"$bin" simulate "$work/again.toml" -o "$work/again.csv" >/dev/null
printf 'specimen = "thread"\nseed = 13\n' >"$work/ref.toml"
"$bin" simulate "$work/ref.toml" -o "$work/ref.csv" >/dev/null
check "diagnose --reference: the same specimen again names none" 0 '"cause": "none"' -- "$bin" diagnose "$work/again.csv" --reference "$work/ref.csv" --json
awk -F, -v OFS=, '/^#/ || /^time/ { print; next } { $4 = $4 + 0.2; print }' "$work/again.csv" >"$work/moved.csv"
check "diagnose --reference: a moved record names the offset" 0 '"cause": "offset"' -- "$bin" diagnose "$work/moved.csv" --reference "$work/ref.csv" --json
check "diagnose --reference: the report sizes it" 0 "offset .*c = 0\.(19|20)[0-9]* strain-%.*accepted" -- "$bin" diagnose "$work/moved.csv" --reference "$work/ref.csv"
check "diagnose --reference with --residuals is a usage error" 2 "not a comparison of two tests" -- "$bin" diagnose "$work/moved.csv" --reference "$work/ref.csv" --residuals "$work/x.csv"
check "diagnose --reference of another input names the reference" 3 "voltage-8loads.csv" -- "$bin" diagnose "$work/moved.csv" --reference "$src/examples/data/voltage-8loads.csv"
check "diagnose --reference: tests at several loads are not compared" 3 "several constant loads is not built" -- "$bin" diagnose "$src/examples/data/voltage-8loads.csv" --reference "$src/examples/data/voltage-lonely.csv"
check "diagnose --reference to a missing file names it" 3 "no/such/ref.csv" -- "$bin" diagnose "$work/moved.csv" --reference "$work/no/such/ref.csv"
grep -v '^# length_mm' "$work/ref.csv" >"$work/ref-mm.csv"
check "diagnose --reference in mm against strain names the reference" 3 "ref-mm.csv: the reference's response is disp_mm .*give length_mm to both" -- "$bin" diagnose "$work/moved.csv" --reference "$work/ref-mm.csv"
head -n 14 "$work/ref.csv" >"$work/short-ref.csv"
check "diagnose --reference too short to identify names the reference" 3 "short-ref.csv.*cannot compare: the reference" -- "$bin" diagnose "$work/moved.csv" --reference "$work/short-ref.csv"

echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
