"""scripts/setup.sh's progress lines: a long step says every TICK seconds what it does, the
time so far and how far it is, and its status is the command's. The kernel compile runs
beside the msg_defs build; either failing stops the other, in one line.

The script's own functions are run (cut from the file between ``TICK=`` and ``run_pip``),
on commands that stand in for ninja and pip.
"""

from __future__ import annotations

import subprocess
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]


def _run(tmp_path: Path, body: str) -> subprocess.CompletedProcess[str]:
    text = (ROOT / "scripts" / "setup.sh").read_text()
    functions = text[text.index("TICK=10") : text.index("run_pip() {")]
    script = (
        "set -euo pipefail\nlog() { printf '[setup] %s\\n' \"$*\"; }\n"
        f"REPO_ROOT={tmp_path}\n{functions}\nTICK=1\n{body}\n"
    )
    return subprocess.run(["bash", "-c", script], capture_output=True, text=True, timeout=60)


def test_a_build_says_how_far_ninja_is_every_tick(tmp_path):
    steps = 'for i in 1 2 3 4; do echo "[$i/4] Building C object"; sleep 0.7; done'
    result = _run(tmp_path, f"with_progress 'msg_defs: build' {tmp_path}/b.log bash -c '{steps}'")
    assert result.returncode == 0, result.stderr
    lines = result.stdout.splitlines()
    assert len(lines) >= 3
    assert all(" s so far; ninja [" in line for line in lines[:-1])
    assert lines[-1].startswith("[setup] msg_defs: build: done in ")


def test_pip_says_its_latest_package_and_a_failure_is_its_status(tmp_path):
    steps = "echo Collecting numpy; sleep 1.5; echo Collecting scipy; sleep 1.5; exit 3"
    result = _run(
        tmp_path,
        f"if with_progress pip {tmp_path}/p.log bash -c '{steps}'; then echo ok;"
        ' else echo "st=$?"; fi',
    )
    lines = result.stdout.splitlines()
    assert lines[-1] == "st=3"
    assert any("packages resolved; Collecting" in line for line in lines)
    assert not any("done in" in line for line in lines)


def test_while_pip_installs_it_says_how_many_the_venv_holds(tmp_path):
    site = tmp_path / "venv" / "lib" / "python3.11" / "site-packages"
    steps = (
        "echo 'Installing collected packages: a, b, c'; sleep 1.5;"
        f" mkdir -p {site}/a-1.dist-info {site}/b-1.dist-info; sleep 1.5"
    )
    result = _run(
        tmp_path, f'VENV={tmp_path}/venv\nwith_progress pip {tmp_path}/p.log bash -c "{steps}"'
    )
    assert result.returncode == 0, result.stderr
    lines = [line for line in result.stdout.splitlines() if "so far" in line]
    assert "installing 3 packages; .venv holds 0" in lines[0]
    assert "installing 3 packages; .venv holds 2" in lines[-1]


def test_another_step_says_its_latest_line(tmp_path):
    steps = "echo '-- Found Python3'; sleep 1.5; echo '-- Configuring done'; sleep 1.5"
    result = _run(tmp_path, f'with_progress configure {tmp_path}/c.log bash -c "{steps}"')
    lines = [line for line in result.stdout.splitlines() if "so far" in line]
    assert lines[0].endswith("s so far; -- Found Python3")
    assert lines[-1].endswith("s so far; -- Configuring done")


def _fake_python(tmp_path: Path, body: str) -> None:
    """A .venv whose python stands in for ``python -m brake_sim_ros.solvers.warmup``."""
    python = tmp_path / "venv" / "bin" / "python"
    python.parent.mkdir(parents=True)
    python.write_text(f"#!/usr/bin/env bash\n{body}\n")
    python.chmod(0o755)


def _gone(pid_file: Path) -> bool:
    """Whether the process whose pid ``pid_file`` holds has ended (a zombie has: its parent
    ended before it, and nothing reaped it yet)."""
    try:
        stat = Path(f"/proc/{int(pid_file.read_text())}/stat").read_text()
    except FileNotFoundError:
        return True
    return stat.rsplit(")", 1)[1].split()[0] == "Z"


_DIE = "die() { printf '[setup] ERROR: %s\\n' \"$*\" >&2; exit 1; }"


def test_a_failed_kernel_compile_stops_the_build_beside_it_in_one_line(tmp_path):
    _fake_python(tmp_path, "sleep 1; echo 'Traceback'; echo 'RuntimeError: no LLVM' >&2; exit 4")
    build = f"sleep 60 & echo $! > {tmp_path}/child.pid; wait"
    start = time.monotonic()
    result = _run(
        tmp_path,
        f"{_DIE}\nVENV={tmp_path}/venv\nstart_kernels\n"
        f"with_progress 'msg_defs: build' {tmp_path}/b.log bash -c '{build}'\necho unreached",
    )
    assert time.monotonic() - start < 10
    assert result.returncode == 1
    assert result.stderr.splitlines() == [
        "[setup] ERROR: compiling the physics kernels failed (exit 4): RuntimeError: no LLVM"
        f" (full log: {tmp_path}/build/kernels.log)"
    ]
    assert "unreached" not in result.stdout
    time.sleep(0.2)
    assert _gone(tmp_path / "child.pid")  # the build's own children stopped too


def test_a_failed_build_stops_the_kernel_compile_beside_it(tmp_path):
    _fake_python(tmp_path, f"echo $$ > {tmp_path}/kernels.pid; sleep 60")
    result = _run(
        tmp_path,
        f"{_DIE}\nVENV={tmp_path}/venv\nstart_kernels\n"
        f"with_progress 'msg_defs: build' {tmp_path}/b.log bash -c 'sleep 1.5; exit 3'"
        " || die 'build failed'",
    )
    assert result.returncode == 1
    assert result.stderr.splitlines() == ["[setup] ERROR: build failed"]
    time.sleep(0.2)
    assert _gone(tmp_path / "kernels.pid")


def test_the_kernels_compile_beside_a_step_and_the_set_up_waits_for_them(tmp_path):
    _fake_python(tmp_path, f"sleep 2.5; echo 'brake-sim: kernels compiled'; touch {tmp_path}/k")
    result = _run(
        tmp_path,
        f"{_DIE}\nVENV={tmp_path}/venv\nstart_kernels\n"
        f"with_progress 'msg_defs: build' {tmp_path}/b.log sleep 1\n"
        f"[[ ! -e {tmp_path}/k ]] && echo 'build done first'\n"
        'kernels_ended wait; echo "kernels $KERNEL_ST"',
    )
    assert result.returncode == 0, result.stderr
    lines = [line for line in result.stdout.splitlines() if " s so far" not in line]
    assert lines[0].startswith("[setup] msg_defs: build: done in ")
    # side by side: the build ended before the kernels, and the set-up waited for them
    assert lines[1:] == ["build done first", "brake-sim: kernels compiled", "kernels 0"]
