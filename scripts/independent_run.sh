#!/bin/bash
# Runs `scpkit diagnose --json` on every file that scripts/independent_cases.py or independent_cases_b.py wrote and prints
# "name truth named ok|MISS" per file, then the count right. Usage: independent_run.sh DIR [SCPKIT]
set -u
dir=$1
scpkit=${2:-$(dirname "$0")/../build/cli/scpkit}
right=0
total=0
for f in "$dir"/*.csv; do
  b=$(basename "$f" .csv)
  truth=$(echo "$b" | sed -E 's/^(load|voltage)-(.*)-[0-9]+$/\2/')
  named=$("$scpkit" diagnose "$f" --json 2>/dev/null |
    python3 -c 'import json, sys; print(json.load(sys.stdin)["cause"])' 2>/dev/null || echo error)
  total=$((total + 1))
  if [ "$truth" = "$named" ]; then right=$((right + 1)); ok=ok; else ok=MISS; fi
  echo "$b $truth $named $ok"
done
echo "right: $right/$total"
