#!/usr/bin/env bash
# Installs the dependencies (scripts/setup.sh) and builds scpkit into build/ (Release).
# Usage: scripts/build.sh [extra cmake configure args...]
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/setup.sh
cmake -S . -B build -G Ninja -DCMAKE_BUILD_TYPE=Release "$@" >/dev/null
cmake --build build -j "$(nproc)"
