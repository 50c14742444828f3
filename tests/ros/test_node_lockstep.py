"""The brake_sim node in lock-step (paused + ~/step), over real DDS, against the offline core.

One node process, started paused, is driven by this module's client: steps, resets,
actuation commands and run-time parameter changes. Every published sample is compared
with the scenario's stepper (``stepper_for``) run offline with the same samples, commands
and model changes: equal, bit for bit, also where a change needs more substeps. Commands
are synchronised through /diagnostics (published every 0.1 s here), so a command is known
to be in the node before the next step request.
"""

from __future__ import annotations

import dataclasses
import math
import uuid

import numpy as np
import pytest

from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.layout import COL
from brake_sim_ros.ros.harness import LOSSLESS, SimClient, domain_id_for
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.stream import conversion
from brake_sim_ros.stream.build import stepper_for
from brake_sim_ros.viz.annotations import shoe_defects

# a ~/step call is bounded by the node's measured wall cost per sample
pytestmark = pytest.mark.realtime

DOMAIN = domain_id_for(2)
DT = 1 / 25_600  # the sample period
MAX_FORCE = 5000.0  # the largest command accepted: 3 substeps per sample (limit 16.7 us)
STATE_RATE_HZ = 1024.0
STATE_STRIDE = 25  # 25.6 kHz / 1024 Hz


@pytest.fixture(scope="module")
def client(node_and_client):
    args = ["--ros-args", "-p", "paused:=true", "-p", "diagnostics_period_s:=0.1",
            "-p", f"max_actuation_force_n:={MAX_FORCE}",
            "-p", f"state_rate_hz:={STATE_RATE_HZ}"]  # fmt: skip
    with node_and_client(args, DOMAIN, stream_qos=LOSSLESS, wait_s=30.0) as (_, sim):
        yield sim


@pytest.fixture
def sim(client):
    """The client, with the node reset to t = 0 and the symmetric defaults."""
    assert client.reset(scenario="symmetric").success
    client.set_parameters(
        {
            "on_command_timeout": "profile",
            "command_timeout_s": 0.2,
            "command_ramp_rate_n_per_s": 5000.0,
        }
    )
    client.forget()
    return client


# samples per ~/step call: the node bounds one call by its measured wall cost (0.5 s),
# which a reliable subscriber of 32-sample chunks makes tens of us per sample
MAX_CALL_SAMPLES = 4096


def step(sim: SimClient, state_stride: int = STATE_STRIDE, **request) -> None:
    """Call ~/step (in calls of at most MAX_CALL_SAMPLES samples) and wait until every
    chunk and state it produced has arrived."""
    steps = request.get("steps", 0)
    while steps > MAX_CALL_SAMPLES:
        response = sim.step(steps=MAX_CALL_SAMPLES)
        assert response.success, response.message
        steps -= MAX_CALL_SAMPLES
    if "steps" in request:
        request = {**request, "steps": steps}
    response = sim.step(**request)
    assert response.success, response.message
    last = response.sample_index
    sim.wait_for(lambda: sim.next_sample_index == last + 1, 10.0, "the stepped samples")
    last_state = last - last % state_stride
    sim.wait_for(
        lambda: sim.rx.states and sim.rx.states[-1].sample_index == last_state,
        10.0,
        "the stepped states",
    )


def command_and_sync(sim: SimClient, left: float, right: float) -> None:
    """Publish a command and wait until /diagnostics shows the node accepted it."""
    before = int(sim.next_diagnostics()["commands_accepted"])
    for _ in range(3):  # a best-effort subscription may, rarely, lose one
        sim.command(left, right)
        try:
            sim.wait_for(
                lambda: int(sim.diagnostics()["commands_accepted"]) > before,
                1.0,
                "the command in /diagnostics",
            )
            return
        except TimeoutError:
            continue
    raise TimeoutError("the node never accepted the command")


def offline(segments, setup=None, start: int = 0) -> np.ndarray:
    """Offline samples for ``[(n, forces or None, new_setup or None), ...]``."""
    scenario = load_scenario("symmetric")
    stepper = stepper_for(scenario, setup=setup)
    rows = []
    for n, forces, new_setup in segments:
        if new_setup is not None:
            stepper.replace_setup(new_setup)
        rows.append(stepper.advance(n, actuation_n=forces).data)
    return np.concatenate(rows)[start:]


def assert_stream_equals(sim: SimClient, expected_rows: np.ndarray, first_index: int = 0):
    got = sim.chunk_arrays()
    np.testing.assert_array_equal(got["index"], first_index + np.arange(len(expected_rows)))
    for side in ("left", "right"):
        for axis in ("fx", "fy"):
            np.testing.assert_array_equal(
                got[f"{side}_{axis}_n"], expected_rows[:, COL[f"{side}_pivot_{axis}_n"]]
            )


def actuation(sim: SimClient) -> dict[int, tuple[float, float]]:
    return {
        s.sample_index: (s.left_actuation_force_n, s.right_actuation_force_n) for s in sim.rx.states
    }


def test_step_and_reset_are_deterministic_and_equal_the_offline_run(sim):
    step(sim, steps=2000)
    step(sim, steps=3001)
    # 2560 samples by duration: half what one call may take at 97 us a sample (a loaded
    # machine), then on through the start of the profile's ramp
    step(sim, duration_s=0.1)
    step(sim, steps=2560)
    first = sim.chunk_arrays()
    assert len(first["index"]) == 10_121
    assert_stream_equals(sim, offline([(10_121, None, None)]))
    assert sim.reset().success
    sim.forget()
    step(sim, steps=10_121)
    again = sim.chunk_arrays()
    for name, values in first.items():
        np.testing.assert_array_equal(again[name], values)
    assert [s.sample_index for s in sim.rx.states] == list(range(0, 10_121, STATE_STRIDE))
    ns = [s.header.stamp.sec * 10**9 + s.header.stamp.nanosec for s in sim.rx.states]
    assert ns == [conversion.stamp_ns(s.sample_index, DT) for s in sim.rx.states]


def test_command_overrides_the_profile_then_the_profile_resumes(sim):
    step(sim, steps=1000)
    command_and_sync(sim, 1500.0, 1200.0)
    step(sim, steps=7500)  # 5120 samples of command (0.2 s timeout), then the profile
    forces = actuation(sim)
    assert forces[975] == (0.0, 0.0)  # the profile is 0 until 0.2 s
    assert forces[1000] == (1500.0, 1200.0) and forces[6100] == (1500.0, 1200.0)
    t = 6125 * DT  # the profile again: 0 until 0.2 s, linear to 1300 N at 0.7 s
    assert forces[6125][0] == pytest.approx(1300.0 * (t - 0.2) / 0.5)
    normal = {s.sample_index: s.left_normal_force_n for s in sim.rx.states}
    assert max(normal[k] for k in range(1000, 6000, STATE_STRIDE)) > 1000.0  # shoes pressed
    assert_stream_equals(
        sim, offline([(1000, None, None), (5120, (1500.0, 1200.0), None), (2380, None, None)])
    )


def test_hold_and_ramp_to_zero_after_commands_stop(sim):
    assert sim.set_parameter("on_command_timeout", "hold").successful
    step(sim, steps=500)
    command_and_sync(sim, 1000.0, 800.0)
    step(sim, steps=10_000)
    forces = actuation(sim)
    assert forces[5500] == (1000.0, 800.0) and forces[10_475] == (1000.0, 800.0)
    assert sim.next_diagnostics()["actuation_source"] == "hold"

    assert sim.reset().success
    sim.forget()
    assert sim.set_parameters(
        {"on_command_timeout": "ramp_to_zero", "command_ramp_rate_n_per_s": 10_000.0}
    )[0].successful
    step(sim, steps=500)
    command_and_sync(sim, 1000.0, 800.0)
    step(sim, steps=10_000)
    forces = actuation(sim)
    t_out = 500 + 5120  # the end of the 0.2 s window
    for k in range(5625, 10_500, STATE_STRIDE):
        elapsed = (k - t_out) * DT
        assert forces[k][0] == pytest.approx(max(0.0, 1000.0 - 10_000.0 * elapsed), abs=1e-9)
        assert forces[k][1] == pytest.approx(max(0.0, 800.0 - 10_000.0 * elapsed), abs=1e-9)
    # 1000 N at 10 kN/s: zero after 0.1 s = 2560 samples
    assert forces[t_out + 2580] == (0.0, 0.0) and forces[10_475] == (0.0, 0.0)


def test_every_kind_of_bad_command_is_rejected_and_counted(sim):
    step(sim, steps=500)
    command_and_sync(sim, 700.0, 700.0)
    before = sim.next_diagnostics()
    for left, right in [
        (math.nan, 1.0),
        (1.0, math.inf),
        (-math.inf, 1.0),
        (-0.5, 1.0),
        (MAX_FORCE + 1.0, 1.0),
    ]:
        sim.command(left, right)
    sim.wait_for(
        lambda: int(sim.diagnostics()["commands_rejected"]) == int(before["commands_rejected"]) + 5,
        5.0,
        "5 rejections counted",
    )
    diag = sim.diagnostics()
    assert int(diag["commands_accepted"]) == int(before["commands_accepted"])
    assert "exceeds max_actuation_force_n" in diag["last_command_rejection"]
    step(sim, steps=500)
    assert set(actuation(sim).values()) >= {(700.0, 700.0)}
    assert actuation(sim)[975] == (700.0, 700.0)  # the valid command, untouched by the rest


def test_command_above_the_limit_force_takes_more_substeps_and_equals_offline(sim):
    """5000 N (accepted: max_actuation_force_n) on a step limit computed for the profile's
    1300 N: the node re-picks its substeps instead of refusing, says so in /diagnostics,
    and the stream equals the offline stepper given the same commands."""
    step(sim, steps=6400)  # 0.25 s: impacting
    assert sim.next_diagnostics()["substeps_per_sample"] == "1"
    command_and_sync(sim, 5000.0, 5000.0)
    step(sim, steps=2560)
    diag = sim.next_diagnostics()
    assert (diag["substeps_per_sample"], diag["step_limit_force_n"]) == ("3", "5000")
    assert float(diag["physics_step_s"]) == pytest.approx(DT / 3, rel=1e-12)
    assert float(diag["sample_rate_hz"]) == 25_600.0
    assert_stream_equals(sim, offline([(6400, None, None), (2560, (5000.0, 5000.0), None)]))
    assert sim.reset().success  # back to the substeps of the profile's peak
    assert sim.next_diagnostics()["substeps_per_sample"] == "1"


def test_a_model_change_that_needs_a_smaller_step_is_accepted_at_run_time(sim):
    """Friction smoothed over 5 mm/s (a limit of about 14 us) while the brake is impacting:
    accepted, 3 substeps per sample from then on, reported; the stream equals offline."""
    try:
        step(sim, steps=6400)  # 0.25 s: impacting
        result = sim.set_parameter("friction.smoothing_speed_m_s", 0.005)
        assert result.successful, result.reason
        step(sim, steps=2560)
        diag = sim.next_diagnostics()
        assert diag["substeps_per_sample"] == "3"
        assert DT / 3 <= float(diag["step_limit_s"]) < DT / 2  # three whole substeps
        assert float(diag["physics_step_s"]) == pytest.approx(DT / 3, rel=1e-12)
        assert float(diag["sample_rate_hz"]) == 25_600.0
        scenario = load_scenario("symmetric")
        narrow = dataclasses.replace(
            scenario.setup,
            params=scenario.setup.params.with_overrides(
                {"friction": {"smoothing_speed_m_s": 0.005}}
            ),
        )
        assert_stream_equals(sim, offline([(6400, None, None), (2560, None, narrow)]))
    finally:
        sim.set_parameter("friction.smoothing_speed_m_s", 0.02)


def test_defect_change_at_run_time_changes_the_shoe_and_the_ground_truth(sim):
    try:
        step(sim, steps=25_600)  # 1 s: both shoes on the drum
        n_truth = len(sim.rx.defects)
        result = sim.set_parameter("defects.left.pivot_radius_change_pct", 3.0)
        assert result.successful, result.reason
        sim.wait_for(lambda: len(sim.rx.defects) > n_truth, 5.0, "republished ground truth")
        truth = sim.rx.defects[-1]
        assert shoe_defects(truth)["left"].pivot_radius_change_pct == 3.0 and not truth.healthy
        assert [(d.kind, d.location, d.severity, d.unit) for d in truth.defects] == [
            ("pivot_radius_change", "left", 3.0, "%")
        ]
        assert list(truth.labels) == ["left pivot_radius_change +3 %"]
        assert truth.header.stamp.sec == 1 and truth.header.stamp.nanosec == 0
        step(sim, steps=5000)
        scenario = load_scenario("symmetric")
        changed = dataclasses.replace(
            scenario.setup, defects=Defects(left=ShoeDefect(pivot_radius_change_pct=3.0))
        )
        expected = offline([(25_600, None, None), (5000, None, changed)])
        assert_stream_equals(sim, expected)
        baseline = offline([(30_600, None, None)])
        got = sim.chunk_arrays()
        left_before = np.hypot(
            baseline[25_600:, COL["left_pivot_fx_n"]], baseline[25_600:, COL["left_pivot_fy_n"]]
        )
        left_change = np.abs(got["left_magnitude_n"][25_600:] - left_before)
        assert left_change.mean() > 100.0  # newtons: the left shoe's pivot force moved
        right_before = np.hypot(
            baseline[25_600:, COL["right_pivot_fx_n"]], baseline[25_600:, COL["right_pivot_fy_n"]]
        )
        np.testing.assert_allclose(got["right_magnitude_n"][25_600:], right_before, rtol=1e-6)
    finally:
        sim.set_parameter("defects.left.pivot_radius_change_pct", 0.0)


def test_initial_angle_and_a_lone_actuation_share_change(sim):
    try:
        result = sim.set_parameter("defects.left.initial_angle_deg", -1.0)
        assert result.successful, result.reason
        sim.wait_for(lambda: sim.rx.defects, 5.0, "ground truth")
        # an initial condition: the run in progress keeps its start, the next reset uses it
        assert shoe_defects(sim.rx.defects[-1])["left"].initial_angle_deg == 0.0
        result = sim.set_parameter("defects.left.actuation_share", 0.55)
        assert result.successful, result.reason
        values = sim.get_parameters(["defects.right.actuation_share"])
        assert values["defects.right.actuation_share"] == pytest.approx(0.45)
        assert sim.reset().success
        sim.wait_for(
            lambda: shoe_defects(sim.rx.defects[-1])["left"].initial_angle_deg != 0.0,
            5.0,
            "ground truth after the reset",
        )
        truth = sim.rx.defects[-1]
        assert shoe_defects(truth)["left"].initial_angle_deg == pytest.approx(-1.0)
        assert shoe_defects(truth)["left"].actuation_share == pytest.approx(0.55)
        sim.forget()
        step(sim, steps=100)
        assert sim.rx.states[0].left_shoe_angle_rad == pytest.approx(math.radians(-1.0))
    finally:
        sim.set_parameters(
            {"defects.left.initial_angle_deg": 0.0, "defects.left.actuation_share": 0.5}
        )


def test_every_kind_of_bad_parameter_is_refused_and_counted(sim):
    before = int(sim.next_diagnostics()["parameter_changes_refused"])
    refusals = [
        sim.set_parameter("friction.coefficient", -0.1),
        sim.set_parameter("friction.coefficient", "steel"),
        sim.set_parameter("defects.right.pivot_radius_change_pct", 20.0),
        sim.set_parameter("driveline.drum_inertia_kg_m2", 1e-6),  # a 2 ns step limit
        sim.set_parameter("scenario", "case1_left_pivot_out"),
        sim.set_parameter("on_command_timeout", "stop"),
        sim.set_parameter("duration_s", 0.0),
        sim.set_parameters_atomically(
            {"defects.left.actuation_share": 0.6, "defects.right.actuation_share": 0.6}
        ),
    ]
    assert not any(r.successful for r in refusals)
    assert "allowed a sum of exactly 1" in refusals[-1].reason
    assert "smallest step taken" in refusals[3].reason  # pathological, not a headroom refusal
    assert 'allowed "hold", "ramp_to_zero", "profile"' in refusals[5].reason
    refusals.append(sim.set_parameter("no.such.parameter", 1.0))
    assert not refusals[-1].successful
    sim.wait_for(
        lambda: int(sim.diagnostics()["parameter_changes_refused"]) == before + len(refusals),
        5.0,
        "refusals counted",
    )
    assert "no.such.parameter" in sim.diagnostics()["last_parameter_refusal"]
    step(sim, steps=2000)  # the model is unchanged
    assert_stream_equals(sim, offline([(2000, None, None)]))


def test_chunk_rate_state_rate_and_clock_are_configurable(sim):
    try:
        # as fast as possible: 32-sample chunks are about the chunking, not whether this
        # machine's publishing costs fit a real-time budget at 800 chunks per second
        results = sim.set_parameters(
            {
                "real_time_factor": 0.0,
                "chunk_rate_hz": 800.0,
                "state_rate_hz": 100.0,
                "publish_clock": False,
            }
        )
        assert all(r.successful for r in results), [r.reason for r in results]
        assert sim.next_diagnostics()
        clocks = len(sim.rx.clocks)
        step(sim, steps=512, state_stride=256)
        assert [len(c.left_fx_n) for c in sim.rx.chunks] == [32] * 16
        assert [s.sample_index for s in sim.rx.states] == [0, 256]
        sim.spin_for(0.2)
        assert len(sim.rx.clocks) == clocks
    finally:
        sim.set_parameters(
            {
                "chunk_rate_hz": 100.0,
                "state_rate_hz": STATE_RATE_HZ,
                "publish_clock": True,
                "real_time_factor": 1.0,
            }
        )


def test_step_service_refusals(sim):
    for request in (
        {"steps": 0, "duration_s": 0.0},
        {"steps": 10, "duration_s": 0.1},
        {"duration_s": -1.0},
        {"duration_s": math.nan},
        {"duration_s": 1e-6},
        {"duration_s": 61.0},
    ):
        response = sim.step(**request)
        assert not response.success, request
        assert response.message
    assert sim.set_parameter("paused", False).successful
    try:
        assert "paused" in sim.step(steps=1).message
    finally:
        assert sim.set_parameter("paused", True).successful


def test_each_reset_makes_a_new_run_id(sim):
    """Without a run_id parameter every run (start, each ~/reset) has a fresh 32-hex UUID4
    id, said in the reply, the DefectState, /diagnostics and the ContactEvents."""
    ids = []
    for _ in range(2):
        n_truth = len(sim.rx.defects)
        response = sim.reset()
        assert response.success, response.message
        sim.wait_for(lambda n=n_truth: len(sim.rx.defects) > n, 5.0, "new ground truth")
        run_id = sim.rx.defects[-1].run_id
        assert len(run_id) == 32 and uuid.UUID(hex=run_id).version == 4
        assert f"run id {run_id}" in response.message
        assert sim.next_diagnostics()["run_id"] == run_id
        ids.append(run_id)
    assert ids[0] != ids[1]
    sim.forget()
    step(sim, steps=7680)  # the first bounces: contact events
    sim.spin_for(0.2)
    assert sim.rx.contact_events
    assert {e.run_id for e in sim.rx.contact_events} == {ids[1]}


def test_reset_to_another_scenario_and_seed(sim):
    try:
        response = sim.reset(scenario="case1_left_pivot_out", seed=7)
        assert response.success, response.message
        sim.wait_for(
            lambda: sim.rx.defects and sim.rx.defects[-1].scenario == "case1_left_pivot_out",
            5.0,
            "new ground truth",
        )
        assert sim.get_parameters(["defects.left.pivot_radius_change_pct", "scenario"]) == {
            "defects.left.pivot_radius_change_pct": 3.0,
            "scenario": "case1_left_pivot_out",
        }
        step(sim, steps=3000)
        setup = load_scenario("case1_left_pivot_out").setup
        assert_stream_equals(sim, offline([(3000, None, None)], setup=setup))
        assert sim.next_diagnostics()["seed"] == "7"
        refused = sim.reset(scenario="no_such_scenario")
        assert not refused.success and "unknown scenario" in refused.message
        assert sim.get_parameters(["scenario"])["scenario"] == "case1_left_pivot_out"
        assert sim.reset(seed=-5).success is False
    finally:
        assert sim.reset(scenario="symmetric").success


def test_a_continuous_run_goes_past_its_duration_until_turned_off(sim):
    """continuous: the free run does not end at duration_s; turned off past it, it ends."""
    duration = 0.02  # 512 samples
    try:
        results = sim.set_parameters(
            {"duration_s": duration, "continuous": True, "real_time_factor": 0.0}
        )
        assert all(r.successful for r in results), [r.reason for r in results]
        results = sim.set_parameters({"paused": False})
        assert all(r.successful for r in results), [r.reason for r in results]
        sim.wait_for(
            lambda: int(sim.diagnostics().get("sample_index", 0)) > 4 * 512,
            20.0,
            "a continuous run past four durations",
        )
        assert sim.diagnostics()["state"] == "running"
        assert sim.set_parameters({"continuous": False})[0].successful
        sim.wait_for(
            lambda: sim.diagnostics().get("state") == "finished", 10.0, "the end of the run"
        )
        ended = int(sim.next_diagnostics()["sample_index"])
        sim.next_diagnostics()
        assert int(sim.diagnostics()["sample_index"]) == ended  # it stays ended
    finally:
        sim.set_parameters(
            {
                "paused": True,
                "continuous": False,
                "real_time_factor": 1.0,
                "duration_s": load_scenario("symmetric").duration_s,
            }
        )
        sim.reset(scenario="symmetric")
