"""``brake-sim node --rerun save FILE.rrd``: the node, started as a user would, writes a
Rerun file that ``rerun rrd verify`` accepts and that holds every published sample."""

from __future__ import annotations

import numpy as np
import pytest

from tests.rerun_helpers import read, verify

pytest.importorskip("rerun")

from brake_sim_ros.ros.harness import domain_id_for
from brake_sim_ros.stream import conversion
from brake_sim_ros.viz import entities as E

RUN_S = 0.5
SAMPLE_RATE_HZ = 25_600.0
N_SAMPLES = round(RUN_S * SAMPLE_RATE_HZ)


@pytest.mark.slow
def test_node_rerun_save(tmp_path, nodes):
    rrd = tmp_path / "node.rrd"
    code, out = nodes.run(
        ["--duration", str(RUN_S), "--exit-at-end", "--rerun", "save", str(rrd), "--ros-args",
         "-p", "real_time_factor:=0.0", "-p", "defects.left.pivot_radius_change_pct:=3.0"],
        domain_id_for(7),
    )  # fmt: skip
    assert code == 0, out
    assert f"published {N_SAMPLES} samples" in out
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
