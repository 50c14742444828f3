"""Ground truth of a growing defect through a recording: the offline MCAP writer (the
path ``brake-sim record`` uses) read back by rosbags alone (its own MCAP parser, CDR
decoder and a typestore built from the file's schemas)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

pytestmark = [
    pytest.mark.ros,
    pytest.mark.filterwarnings("ignore:module 'sre_(parse|constants)' is deprecated"),
]
pytest.importorskip("rclpy", reason="rclpy not installed (run scripts/setup.sh)")


from brake_sim_ros import stream  # noqa: E402
from brake_sim_ros.recording.record import record_offline  # noqa: E402
from brake_sim_ros.recording.writer import RecordingOptions  # noqa: E402
from brake_sim_ros.scenarios.loader import parse_scenario  # noqa: E402
from brake_sim_ros.stream.ground_truth import PUBLISH_FRACTION, PUBLISH_PERIOD_S  # noqa: E402
from tests.bag_helpers import rosbags_timed  # noqa: E402

RATE_HZ = 25_600.0
SCENARIO = """
name = "left_pin_and_drum_growing"
duration_s = 2.5
[defects.left]
pivot_radius_change_pct = {value = 3.0, onset_s = 0.5, growth = "linear", rate_per_s = 2.0}
[defects.drum]
harmonics = [{order = 2, amplitude_um = 40.0, phase_deg = 30.0}]
onset_s = 1.0
growth = "exponential"
doubling_time_s = 0.25
start = 5.0
"""


def pivot(t):
    """The scenario's left pin, written out: 2 %/s from 0.5 s, held at 3 %."""
    return np.clip(2.0 * (t - 0.5), 0.0, 3.0)


def drum(t):
    """The scenario's drum runout, written out: 5 um at 1 s doubling every 0.25 s to 40."""
    return np.where(t < 1.0, 0.0, np.minimum(5.0 * 2.0 ** ((t - 1.0) / 0.25), 40.0))


@pytest.fixture(scope="module")
def truths(tmp_path_factory) -> list[tuple[int, object]]:
    path: Path = tmp_path_factory.mktemp("rec") / "growing.mcap"
    record_offline(parse_scenario(SCENARIO), path, options=RecordingOptions(durable=False))
    return rosbags_timed(path)[stream.DEFECTS.name]


def _held(truths, kind: str, location: str, times: np.ndarray) -> np.ndarray:
    """The severity a subscriber holds at each of ``times``: the last DefectState's."""
    stamps = np.array([ns for ns, _ in truths]) * 1e-9
    values = np.array(
        [
            next((d.severity for d in m.defects if (d.kind, d.location) == (kind, location)), 0.0)
            for _, m in truths
        ]
    )
    last = np.searchsorted(stamps, times + 1e-9, side="right") - 1  # ns stamps
    return values[last]


def test_each_defect_state_carries_the_scenarios_severities_at_its_stamp(truths):
    assert len(truths) > 10
    for ns, msg in truths:
        t = round(ns * 1e-9 * RATE_HZ) / RATE_HZ  # the sample's time (stamps round to ns)
        got = {(d.kind, d.location): d for d in msg.defects}
        want = {("pivot_radius_change", "left"): pivot(t), ("drum_out_of_round", "drum"): drum(t)}
        for key, severity in want.items():
            if severity == 0.0:
                assert key not in got
            else:
                assert got[key].severity == pytest.approx(severity, rel=1e-9)
        if ("drum_out_of_round", "drum") in got:
            d = got[("drum_out_of_round", "drum")]
            assert (d.onset_s, d.growth) == (1.0, "exponential")
            assert d.growth_rate == pytest.approx(np.log(2.0) / 0.25)
            attrs = dict(zip(d.attribute_names, d.attribute_values, strict=True))
            assert attrs["order_2_amplitude_um"] == pytest.approx(drum(t), rel=1e-9)
            assert attrs["final_severity_um"] == 40.0 and attrs["start_severity_um"] == 5.0
        assert msg.healthy == (not msg.defects)


def test_at_every_sample_the_held_truth_is_within_the_publication_rule(truths):
    times = np.arange(round(2.5 * RATE_HZ)) / RATE_HZ
    for kind, location, law, limit in (
        ("pivot_radius_change", "left", pivot, 3.0),
        ("drum_out_of_round", "drum", drum, 150.0),
    ):
        held = _held(truths, kind, location, times)
        true = law(times)
        assert np.array_equal(held == 0.0, true == 0.0)  # the onset sample is published
        assert np.max(np.abs(held - true)) <= PUBLISH_FRACTION * limit + 1e-9
        assert held[-1] == true[-1]  # the final value is published when reached
    stamps = np.array([ns for ns, _ in truths]) * 1e-9
    changing = stamps[stamps <= 2.0]
    assert np.max(np.diff(changing)) <= PUBLISH_PERIOD_S + 1e-9


WEARING = """
name = "left_lining_wearing"
duration_s = 1.5
[defects.left.lining_wear_mm]
value = 3.0
growth = "friction_work"
wear_rate_mm_per_mj = 100.0
"""


def test_a_lining_wearing_with_its_work_reads_back_as_the_models_wear(tmp_path):
    """The wear follows the motion, not time: each DefectState read back by rosbags
    carries the wear the model recorded at its stamp (the run's own samples)."""
    from brake_sim_ros.stream.build import stepper_for

    scenario = parse_scenario(WEARING)
    path = tmp_path / "wearing.mcap"
    record_offline(scenario, path, options=RecordingOptions(durable=False))
    truths = rosbags_timed(path)[stream.DEFECTS.name]
    run = stepper_for(scenario).run(scenario.duration_s)
    wear_mm = run["left_lining_wear_m"] * 1e3
    held = []
    for ns, msg in truths[1:]:
        row = round(ns * 1e-9 * RATE_HZ)
        (severity,) = [d.severity for d in msg.defects if d.kind == "lining_wear"]
        assert severity == pytest.approx(wear_mm[row], rel=1e-12)
        held.append(severity)
    assert len(held) >= 2 and held == sorted(held) and held[-1] > 0.0
