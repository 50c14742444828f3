#!/usr/bin/env bash
# Time a fresh clone's set-up: clone this repository's HEAD into a temporary directory, run
# scripts/setup.sh there with an empty kernel cache (and, with --no-pip-cache, without
# pip's download cache), and print the time of each phase and in all, and the CPU time
# (user + sys, of the set-up and every process it started: on a shared machine the wall
# time says how loaded it was as much as how long the set-up takes).
#
#   bash scripts/time_setup.sh                 # pip may reuse its download cache
#   bash scripts/time_setup.sh --no-pip-cache  # every wheel downloaded again
#   bash scripts/time_setup.sh --keep          # keep the clone (its path is printed)
#
# The clone, its .venv and its kernel cache are removed at the end (unless --keep). The
# figures are those of this machine as it is: say whether other jobs were running.
set -euo pipefail

REPO_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
NO_PIP_CACHE=0
KEEP=0
for arg in "$@"; do
  case "$arg" in
    --no-pip-cache) NO_PIP_CACHE=1 ;;
    --keep) KEEP=1 ;;
    -h|--help) sed -n '2,12p' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "time_setup.sh: unknown argument: $arg (allowed --no-pip-cache, --keep)" >&2; exit 2 ;;
  esac
done

TMP="$(mktemp -d -t brake_sim_time_setup.XXXXXX)"
cleanup() { if [[ $KEEP == 0 ]]; then rm -rf "$TMP"; else echo "kept: $TMP"; fi; }
trap cleanup EXIT

echo "time_setup: load average before $(cut -d' ' -f1-3 /proc/loadavg) on $(nproc) cores"
t0=$SECONDS
git clone --quiet "$REPO_ROOT" "$TMP/clone"
echo "time_setup: clone $((SECONDS - t0)) s"
export BRAKE_SIM_CACHE_DIR="$TMP/kernel-cache"   # an empty kernel cache
unset NUMBA_CACHE_DIR
if [[ $NO_PIP_CACHE == 1 ]]; then export PIP_NO_CACHE_DIR=1; fi
LOG="$TMP/setup.out"
t1=$SECONDS
CPU="$TMP/cpu.txt"
TIMER=(); [[ -x /usr/bin/time ]] && TIMER=(/usr/bin/time -o "$CPU" -f "cpu %U %S")
# the set-up's own lines, stamped with the seconds since it started
"${TIMER[@]}" bash "$TMP/clone/scripts/setup.sh" 2>&1 | while IFS= read -r line; do
  printf '%4d s  %s\n' "$((SECONDS - t1))" "$line"
done | tee "$LOG"
status=${PIPESTATUS[0]}
total=$((SECONDS - t1))
echo "time_setup: phases (from the set-up's lines):"
grep -E "done in [0-9]+ s|kernels compiled in" "$LOG" | sed -E 's/^ *[0-9]+ s  /  /' || true
cpu="(no /usr/bin/time: CPU time not measured)"
if [[ -s "$CPU" ]]; then
  cpu="$(awk '$1 == "cpu" { printf "CPU %.0f s (user %.0f s + sys %.0f s)", $2 + $3, $2, $3 }' "$CPU")"
fi
echo "time_setup: set-up $total s in all (exit $status), $cpu; load average after $(cut -d' ' -f1-3 /proc/loadavg)"
exit "$status"
