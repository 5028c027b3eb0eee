#!/usr/bin/env bash
# The main job on the bundled example data: fit a 2-ply thread test (paired with its SCP
# actuator), map it to 4- and 6-ply threads and SCP actuators, and compare the predictions
# with the 4- and 6-ply tests. The example data are synthetic (scpkit's virtual test rig,
# examples/rig/*.toml); see examples/README.md.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
scpkit=build/cli/scpkit
out=build/demo
mkdir -p "$out"
echo "== fit the 2-ply thread (and its SCP gain)"
"$scpkit" fit examples/data/pair-2ply.csv -o "$out/thread-2ply.model.json"
for q in 4 6; do
  echo
  echo "== map to ${q} plies and compare with the ${q}-ply test"
  "$scpkit" map "$out/thread-2ply.model.json" --plies "$q" --data "examples/data/pair-${q}ply.csv" \
    -o "$out/map-${q}ply.csv"
done
