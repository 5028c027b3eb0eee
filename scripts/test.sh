#!/usr/bin/env bash
# Installs the dependencies, builds scpkit with its tests, and runs the whole suite (CTest).
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/build.sh
ctest --test-dir build --output-on-failure -j "$(nproc)"
