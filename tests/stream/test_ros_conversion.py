"""SampleBlock -> ROS messages, and the diagnostics built from run counters: no rclpy, no DDS.

Needs the message packages (brake_sim_msgs and the ROS wheels) but not rclpy; skipped
where they are not installed.
"""

from __future__ import annotations

import itertools
import math
import uuid

import numpy as np
import pytest

pytest.importorskip("brake_sim_msgs", reason="brake_sim_msgs not built (run scripts/setup.sh)")

from brake_sim_ros import stream
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.layout import COL, N_COLUMNS
from brake_sim_ros.model.run_setup import SampleBlock
from brake_sim_ros.ros.diagnostics import (
    RunStats,
    RunView,
    diagnostic_array,
    summary,
)
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.stream import conversion
from brake_sim_ros.stream.offline import offline_messages
from brake_sim_ros.viz.annotations import shoe_defects

DT = 4e-5


@pytest.fixture(scope="module")
def block() -> SampleBlock:
    """1.2 s of the symmetric scenario: free flight, impacts and contact."""
    scenario = load_scenario("symmetric")
    return FixedStepStepper(scenario.setup, DT).advance(30_000)


def test_stamps_are_simulated_time_in_integer_nanoseconds():
    assert conversion.stamp_ns(0, DT) == 0
    assert conversion.stamp_ns(1, DT) == 40_000
    assert conversion.stamp_ns(187_500, DT) == 7_500_000_000
    assert conversion.stamp_ns(10**9, DT) == 40_000 * 10**9
    # 25.6 kHz, the default rate: 39062.5 ns per sample, exact, ties to even, no drift
    period = 1 / 25_600
    assert [conversion.stamp_ns(k, period) for k in range(5)] == [0, 39062, 78125, 117188, 156250]
    assert conversion.stamp_ns(256, period) == 10_000_000  # one 10 ms chunk
    assert conversion.stamp_ns(192_000, period) == 7_500_000_000
    assert conversion.stamp_ns(10**12 + 1, period) == 39_062_500_000_039_062
    t = conversion.time_msg(7_500_000_123)
    assert (t.sec, t.nanosec) == (7, 500_000_123)
    assert conversion.header(5).frame_id == "brake_backing_plate"
    assert conversion.sample_rate_hz(DT) == 25_000.0
    assert conversion.sample_rate_hz(1 / 30_000) == 30_000.0
    assert conversion.sample_rate_hz(3e-5 * math.pi) == 1 / (3e-5 * math.pi)


def test_pivot_force_chunk_carries_every_sample(block):
    part = SampleBlock(block.data[1000:1250], 1000, DT)
    msg = conversion.pivot_force_chunk(part)
    assert msg.first_sample_index == 1000
    assert msg.sample_rate_hz == 25_000.0
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (0, 40_000_000)
    assert msg.header.frame_id == "brake_backing_plate"
    for side in ("left", "right"):
        fx, fy = part[f"{side}_pivot_fx_n"], part[f"{side}_pivot_fy_n"]
        np.testing.assert_array_equal(np.asarray(getattr(msg, f"{side}_fx_n")), fx)
        np.testing.assert_array_equal(np.asarray(getattr(msg, f"{side}_fy_n")), fy)
        np.testing.assert_array_equal(
            np.asarray(getattr(msg, f"{side}_magnitude_n")), np.hypot(fx, fy)
        )


def test_state_rows_do_not_depend_on_chunking(block):
    whole = [block.first_index + r for r in conversion.state_rows(block, 250)]
    pieces = []
    start = 0
    for n in (1, 249, 250, 77, 423, 1000, 28_000):
        part = SampleBlock(block.data[start : start + n], start, DT)
        pieces += [start + r for r in conversion.state_rows(part, 250)]
        start += n
    assert pieces == whole == list(range(0, 30_000, 250))


def test_brake_state_and_joint_state_map_the_columns(block):
    row = 29_000  # riding on the drum
    msg = conversion.brake_state(block, row)
    r = block.data[row]
    assert msg.sample_index == row
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (1, 160_000_000)
    pairs = {
        "flywheel_angle_rad": "flywheel_angle_rad",
        "drum_speed_rad_s": "drum_speed_rad_s",
        "left_shoe_angle_rad": "left_angle_rad",
        "right_shoe_speed_rad_s": "right_speed_rad_s",
        "left_normal_force_n": "left_normal_force_n",
        "right_friction_force_n": "right_friction_force_n",
        "left_actuation_force_n": "left_actuation_force_n",
        "right_contact_y_m": "right_contact_y_m",
        "left_indentation_m": "left_indentation_m",
    }
    for field, column in pairs.items():
        assert getattr(msg, field) == r[COL[column]], field
    assert msg.left_in_contact is bool(r[COL["left_indentation_m"]] > 0) is True
    assert msg.regime == int(r[COL["regime"]])
    joints = conversion.joint_state(block, row)
    assert list(joints.name) == ["flywheel", "drum", "left_shoe", "right_shoe"]
    assert list(joints.position) == [
        msg.flywheel_angle_rad,
        msg.drum_angle_rad,
        msg.left_shoe_angle_rad,
        msg.right_shoe_angle_rad,
    ]
    assert list(joints.velocity) == [
        msg.flywheel_speed_rad_s,
        msg.drum_speed_rad_s,
        msg.left_shoe_speed_rad_s,
        msg.right_shoe_speed_rad_s,
    ]
    assert joints.header == msg.header


def test_messages_read_the_columns_by_name(block):
    """A block keeping its columns in another order gives the same messages."""
    shuffled = block.select(("time_s", *reversed(block.columns[1:])))
    for row in (0, 5_600, 29_000):
        assert conversion.brake_state(shuffled, row) == conversion.brake_state(block, row)
        assert conversion.joint_state(shuffled, row) == conversion.joint_state(block, row)
    assert conversion.pivot_force_chunk(shuffled) == conversion.pivot_force_chunk(block)


def test_all_finite_catches_any_non_finite_number(block):
    assert conversion.all_finite(block)
    for value in (math.nan, math.inf, -math.inf):
        data = np.zeros((3, N_COLUMNS))
        data[1, COL["right_contact_x_m"]] = value
        assert not conversion.all_finite(SampleBlock(data, 0, DT))


def test_defect_state_is_the_ground_truth_in_force():
    defects = Defects(
        left=ShoeDefect(pivot_radius_change_pct=3.0, initial_angle_deg=-2.0, actuation_share=0.55),
        right=ShoeDefect(actuation_share=0.45),
    )
    msg = conversion.defect_state(
        scenario="mine",
        defects=defects,
        initial_angles_deg=(-2.0, 0.0),
        ns=1_500_000_000,
        run_id="abc",
        seed=7,
        unit_id="VIN-0042",
    )
    assert msg.scenario == "mine" and not msg.healthy and msg.run_id == "abc"
    assert (msg.seed, msg.unit_id) == (7, "VIN-0042")
    entries = {(d.location, d.kind): (d.severity, d.unit, d.onset_s, d.growth) for d in msg.defects}
    assert entries == {
        ("left", "pivot_radius_change"): (3.0, "%", 0.0, "step"),
        ("left", "initial_angle"): (-2.0, "deg", 0.0, "step"),
        ("left", "actuation_share_change"): (pytest.approx(0.05), "1", 0.0, "step"),
        ("right", "actuation_share_change"): (pytest.approx(-0.05), "1", 0.0, "step"),
    }
    assert list(msg.labels) == defects.labels() and len(msg.labels) == len(msg.defects)
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec) == (1, 500_000_000)
    # the list read back gives the shoes' defects (the Rerun sink draws the shoes from it)
    shoes = shoe_defects(msg)
    assert shoes["left"].pivot_radius_change_pct == 3.0
    assert shoes["left"].actuation_share == pytest.approx(0.55)
    assert shoes["right"].actuation_share == pytest.approx(0.45)
    assert shoes["right"].pivot_radius_change_pct == 0.0 == shoes["right"].initial_angle_deg
    # a changed initial angle applies at the next reset: the run's own start is reported
    pending = conversion.defect_state(
        scenario="s",
        defects=Defects(left=ShoeDefect(initial_angle_deg=-1.0)),
        initial_angles_deg=(0.0, 0.0),
        ns=0,
        run_id="abc",
        seed=0,
        unit_id="nominal",
    )
    assert pending.healthy and list(pending.defects) == [] and list(pending.labels) == []


def test_every_offline_run_has_its_own_run_id_in_all_its_ground_truth():
    """A run id is 32 hex digits (a UUID4), one per run, in its DefectState and every
    ContactEvent; a given one is used as it is."""
    scenario = load_scenario("symmetric")
    duration = 0.3  # the first bounces: ContactEvents

    def run_ids(**kwargs) -> set[str]:
        messages = offline_messages(scenario, duration_s=duration, **kwargs)
        truth = [m for t, m, _ in messages if t in (stream.DEFECTS, stream.CONTACT_EVENTS)]
        assert len(truth) > 10 and type(truth[0]).__name__ == "DefectState"
        return {m.run_id for m in truth}

    (first,), (second,) = run_ids(), run_ids()
    assert first != second
    for run_id in (first, second):
        assert len(run_id) == 32 and uuid.UUID(hex=run_id).version == 4
        assert run_id == uuid.UUID(hex=run_id).hex  # lower case, no dashes
    assert run_ids(run_id="given") == {"given"}


def view(**changes) -> RunView:
    values = dict(
        node_name="brake_sim",
        scenario="symmetric",
        state="running",
        message="",
        sim_time_s=7.5,
        sample_index=192_000,
        sample_rate_hz=25_600.0,
        duration_s=7.5,
        target_real_time_factor=1.0,
        measured_real_time_factor=0.998,
        actuation_source="profile",
        stop_time_s=6.58,
        physics_step_s=1.953125e-5,
        substeps=2,
        step_limit_s=3.2e-5,
        step_limit_force_n=2600.0,
        max_actuation_force_n=2600.0,
        seed=0,
        run_id="0123456789abcdef0123456789abcdef",
    )
    values.update(changes)
    return RunView(**values)


def test_diagnostics_report_every_counter():
    stats = RunStats(
        samples_done=192_000,
        physics_steps_done=384_000,
        deadline_misses=2,
        commands_accepted=3,
        commands_rejected=4,
        commands_dropped=1,
        parameter_changes_refused=5,
        free_run_sim_s=7.5,
        free_run_wall_s=7.5,
    )
    array = diagnostic_array(view(), stats, ns=7_500_000_000, new_misses=0)
    assert (array.header.stamp.sec, array.header.stamp.nanosec) == (7, 500_000_000)
    (status,) = array.status
    values = {kv.key: kv.value for kv in status.values}
    assert values["deadline_misses"] == "2"
    assert values["samples_done"] == "192000"
    assert values["physics_steps_done"] == "384000"
    assert values["sample_rate_hz"] == "25600"
    assert (values["physics_step_s"], values["substeps_per_sample"]) == ("1.953125e-05", "2")
    assert (values["step_limit_s"], values["step_limit_force_n"]) == ("3.2e-05", "2600")
    assert values["commands_accepted"] == "3"
    assert values["commands_rejected"] == "4"
    assert values["commands_dropped"] == "1"
    assert values["parameter_changes_refused"] == "5"
    assert float(values["real_time_factor_measured"]) == pytest.approx(0.998)
    assert float(values["real_time_factor_achieved"]) == 1.0
    assert status.level == status.OK
    warn = diagnostic_array(view(), stats, ns=0, new_misses=3).status[0]
    assert warn.level == warn.WARN and "3 deadline misses" in warn.message
    failed = diagnostic_array(
        view(state="failed", message="non-finite state"), stats, ns=0, new_misses=0
    ).status[0]
    assert failed.level == failed.ERROR and "non-finite state" in failed.message


def test_summary_is_one_paragraph_with_the_figures():
    stats = RunStats(
        samples_published=192_000,
        chunks_published=750,
        states_published=750,
        commands_accepted=3,
        commands_rejected=4,
        free_run_sim_s=7.5,
        free_run_wall_s=7.5,
    )
    text = summary(view(state="finished"), stats)
    assert "\n" not in text
    for fragment in (
        "7.5000 s",
        "192000 samples in 750 chunks",
        "accepted 3",
        "rejected 4",
        "stopped at t = 6.5800 s",
        "real-time factor achieved 1.000",
    ):
        assert fragment in text


def _measured(scenario, **settings) -> dict[str, np.ndarray]:
    """Every measured series of 0.2 s of ``scenario``'s stream, concatenated over chunks."""
    from brake_sim_ros.stream.offline import StreamSettings

    out: dict[str, list[float]] = {}
    labels: dict[str, list[int]] = {}
    settings = {"publish_measured": True, **settings}
    messages = offline_messages(scenario, duration_s=0.2, settings=StreamSettings(**settings))
    for topic, msg, _ns in messages:
        if topic is not stream.MEASURED:
            continue
        assert len(msg.values) == len(msg.fault_labels) == sum(msg.channel_sample_counts)
        start = 0
        for name, count in zip(msg.channel_names, msg.channel_sample_counts, strict=True):
            out.setdefault(name, []).extend(msg.values[start : start + count])
            labels.setdefault(name, []).extend(msg.fault_labels[start : start + count])
            start += count
    return {n: np.asarray(v) for n, v in out.items()} | {
        f"{n}/labels": np.asarray(v) for n, v in labels.items()
    }


def test_measured_stream_same_seed_same_bits_other_seed_other_noise():
    """The sensors run in the stream: one seed gives the same bits whatever the chunking
    (the bank carries its state between blocks), another seed other noise; the measured
    series cover every sample, with the scenario's sensors' names and units."""
    import dataclasses

    scenario = load_scenario("symmetric")
    a = _measured(scenario)
    b = _measured(scenario, chunk_rate_hz=37.0)  # other chunks: 692 samples, not 256
    assert a.keys() == b.keys()
    for name in a:
        assert a[name].tobytes() == b[name].tobytes(), name
    n = round(0.2 * scenario.sample_rate_hz)
    names = [name for c in scenario.sensors.channels for name in c.output_names]
    assert [k for k in a if "/" not in k] == names
    assert all(a[name].size == n for name in names)
    other = _measured(dataclasses.replace(scenario, seed=scenario.seed + 1))
    assert a["backing_plate_accel_x"].tobytes() != other["backing_plate_accel_x"].tobytes()
    assert a["wheel_speed"].tobytes() == other["wheel_speed"].tobytes()  # no noise there
    assert _measured(scenario, publish_measured=False) == {}


def _measured_chunks(scenario, duration_s: float, **settings) -> list:
    from brake_sim_ros.stream.offline import StreamSettings

    settings = {"publish_measured": True, **settings}
    messages = offline_messages(
        scenario, duration_s=duration_s, settings=StreamSettings(**settings)
    )
    return [msg for topic, msg, _ns in messages if topic is stream.MEASURED]


def test_every_tone_ring_edge_is_in_exactly_one_chunk_at_its_drum_angle():
    """The chunks' edges, joined, are the edges of the run fed to the sensors as one block,
    bit for bit, whatever the chunking; each chunk holds those in (previous chunk's last
    sample, its last sample]; and the drum angle at consecutive edges (interpolated in the
    run's samples) is one tooth pitch, 2 pi / teeth, apart."""
    from brake_sim_ros.stream.build import sensor_bank_for
    from brake_sim_ros.stream.run import run_scenario

    scenario = load_scenario("symmetric")
    duration_s = 0.5
    run = run_scenario(scenario, duration_s=duration_s)
    whole = sensor_bank_for(scenario).advance(run.samples).edges_s
    (teeth,) = [c.tone_ring_teeth for c in scenario.sensors.channels if c.kind == "wheel_speed"]
    for chunk_rate_hz in (100.0, 37.0):  # 256 samples a chunk; 692
        chunks = _measured_chunks(scenario, duration_s, chunk_rate_hz=chunk_rate_hz)
        assert [list(m.edge_channel_names) for m in chunks[:1]] == [["wheel_speed"]]
        assert all(list(m.tone_ring_teeth) == [teeth] for m in chunks)
        joined = conversion.measured_edges(chunks)
        assert joined.keys() == whole.keys() == {"wheel_speed"}
        assert joined["wheel_speed"].tobytes() == whole["wheel_speed"].tobytes()
        period = 1 / scenario.sample_rate_hz
        for prev, msg in itertools.pairwise(chunks):
            edges = np.asarray(msg.edge_times_s)
            lo = (prev.first_sample_index + prev.sample_count - 1) * period
            hi = (msg.first_sample_index + msg.sample_count - 1) * period
            assert np.all((edges > lo) & (edges <= hi)), msg.first_sample_index
    edges = whole["wheel_speed"]
    assert edges.size > 200 and np.all(np.diff(edges) > 0)
    angle = np.interp(edges, run.samples.time_s, run.samples["drum_angle_rad"])
    pitch = 2 * np.pi / teeth
    np.testing.assert_allclose(np.diff(angle), pitch, rtol=1e-9)
    np.testing.assert_allclose(angle / pitch, np.round(angle / pitch), rtol=0, atol=1e-9)


def test_measured_edges_refuses_counts_that_do_not_add_up():
    (msg,) = _measured_chunks(load_scenario("symmetric"), 0.01)
    msg.edge_counts = [len(msg.edge_times_s) + 1]
    with pytest.raises(ValueError, match="edge counts say"):
        conversion.measured_edges([msg])
