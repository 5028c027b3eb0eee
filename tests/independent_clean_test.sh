#!/usr/bin/env bash
# No false alarm on clean data from a generator written apart from the project's rig
# (scripts/independent_cases.py): every clean load and voltage record of the seeds given is
# diagnosed `none`. Seeds 200-203 hold the damped load record (59 readings scored, one per
# hold) on which a Kelvin lag chosen by 2 of 6 folds once named `creep` by its gain alone.
# Usage: independent_clean_test.sh SCPKIT_BINARY SOURCE_DIR [FIRST_SEED]
set -u
bin=$1
src=$2
first=${3:-200}
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
python3 "$src/scripts/independent_cases.py" "$work" 4 "$first" || exit 1
pass=0
fail=0
for f in "$work"/*-none-*.csv; do
  cause=$("$bin" diagnose "$f" --json 2>/dev/null |
    python3 -c 'import json, sys; print(json.load(sys.stdin)["cause"])' 2>/dev/null || echo error)
  if [ "$cause" = none ]; then
    pass=$((pass + 1))
  else
    fail=$((fail + 1))
    echo "FAIL: $(basename "$f") ($(grep '^# gen' "$f")) named $cause, not none"
  fi
done
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ] && [ "$pass" -gt 0 ]
