"""``brake-sim node --rerun save FILE.rrd``: the node, started as a user would, writes a
Rerun file that ``rerun rrd verify`` accepts and that holds every published sample."""

from __future__ import annotations

import numpy as np
import pytest

from tests.rerun_helpers import read, verify

pytestmark = [
    pytest.mark.ros,
    pytest.mark.filterwarnings("ignore:module 'sre_(parse|constants)' is deprecated"),
]

pytest.importorskip("rclpy", reason="rclpy not installed (run scripts/setup.sh)")
pytest.importorskip("rerun")

from brake_sim_ros.ros.harness import NodeProcess, domain_id_for  # noqa: E402
from brake_sim_ros.stream import conversion  # noqa: E402
from brake_sim_ros.viz import entities as E  # noqa: E402

RUN_S = 0.5
SAMPLE_RATE_HZ = 25_600.0
N_SAMPLES = round(RUN_S * SAMPLE_RATE_HZ)


def test_node_rerun_save(tmp_path):
    rrd = tmp_path / "node.rrd"
    node = NodeProcess.start(
        [
            "--duration",
            str(RUN_S),
            "--exit-at-end",
            "--rerun",
            "save",
            str(rrd),
            "--ros-args",
            "-p",
            "real_time_factor:=0.0",
            "-p",
            "defects.left.pivot_radius_change_pct:=3.0",
        ],
        domain_id=domain_id_for(7),
        log_path=tmp_path / "node.log",
    )
    try:
        code = node.wait(60.0)
    finally:
        node.stop()
    assert code == 0, node.output()
    assert f"published {N_SAMPLES} samples" in node.output()
    verify(rrd)
    c = read(rrd)
    for side in E.SIDES:
        t = c.times(E.pivot_path(side, "magnitude"))
        expected = [conversion.stamp_ns(k, 1 / SAMPLE_RATE_HZ) for k in range(N_SAMPLES)]
        np.testing.assert_array_equal(t, expected)
    assert c.times(f"{E.SPEED}/drum").size == 50
    # the ground truth and drawing follow the model in force, --ros-args override included
    truth = c.texts[f"{E.DEFECTS}/ground_truth"][0]
    assert "| pivot_radius_change | left | +3 | % |" in truth
    assert c.values(f"{E.DEFECTS}/left/pivot_radius_change")[0] == pytest.approx(3.0)
    assert c.times(f"{E.DRAWING}/linings").size == 25
