#!/usr/bin/env bash
# Regenerate the example recordings in bags/ (offline: the same messages the node
# publishes, written faster than real time). Run after scripts/setup.sh.
set -euo pipefail
cd "$(dirname "$0")/.."
SIM=.venv/bin/brake-sim
for scenario in symmetric case1_left_pivot_out case5_left_tilted; do
  "$SIM" simulate "$scenario" --quiet --overwrite --mcap "bags/$scenario.mcap"
done
ls -l bags/*.mcap
