"""scripts/setup.sh's progress lines: a long step says every TICK seconds what it does, the
time so far and how far it is, and its status is the command's.

The script's own functions are run (cut from the file between ``TICK=`` and ``run_pip``),
on commands that stand in for ninja and pip.
"""

from __future__ import annotations

import subprocess
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
