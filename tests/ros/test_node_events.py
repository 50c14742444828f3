"""~/contact_events of the node, over real DDS, against the offline stream.

One node process, started paused, is stepped with step sizes unlike the offline stream's
10 ms chunks, reset in the middle of a contact episode and switched to another scenario:
each time the ContactEvents received equal those of :func:`offline_messages`, field for
field, so the node's detector state follows resets and does not depend on the chunking.
The node runs with a ``run_id`` parameter, which every run keeps across resets and the
offline stream is given, and with its sensors on: after a reset with a new seed, what it
measures equals the offline stream of the scenario with that seed, bit for bit.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from brake_sim_ros import stream
from brake_sim_ros.analysis import contact_events as ce
from brake_sim_ros.ros.harness import LOSSLESS, SimClient, domain_id_for
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.stream.offline import StreamSettings, offline_messages

DOMAIN = domain_id_for(8)
N_STEPS = 7680  # 0.3 s of 25.6 kHz samples: every bounce of the symmetric run, contact starts
RUN_ID = "events-test.run_1"  # the node's run_id parameter: kept across resets
FIELDS = (
    "sample_index",
    "shoe",
    "kind",
    "peak_pivot_force_n",
    "peak_sample_index",
    "duration_s",
    "run_id",  # last: the tests read the fields above by position
)


def as_tuple(msg) -> tuple:
    stamp = (msg.header.stamp.sec, msg.header.stamp.nanosec, msg.header.frame_id)
    return (stamp, *(getattr(msg, f) for f in FIELDS))


def offline_events(scenario_name: str, n_steps: int) -> list[tuple]:
    scenario = load_scenario(scenario_name)
    messages = offline_messages(
        scenario, duration_s=n_steps * scenario.sample_period_s, run_id=RUN_ID
    )
    return [as_tuple(msg) for topic, msg, _ in messages if topic is stream.CONTACT_EVENTS]


@pytest.fixture(scope="module")
def sim(node_and_client):
    args = ["--ros-args", "-p", "paused:=true", "-p", f"run_id:={RUN_ID}",
            "-p", "publish_measured:=true"]  # fmt: skip
    with node_and_client(args, DOMAIN, stream_qos=LOSSLESS, wait_s=30.0) as (_, client):
        yield client


def step_all(sim: SimClient, sizes: list[int], total: int) -> None:
    """Step ``total`` steps in ``sizes`` (cycled) and wait until every sample arrived."""
    done, k = 0, 0
    while done < total:
        n = min(sizes[k % len(sizes)], total - done)
        response = sim.step(steps=n)
        assert response.success, response.message
        done, k = done + n, k + 1
    sim.wait_for(lambda: sim.next_sample_index == total, 20.0, "the stepped samples")
    sim.spin_for(0.2)  # events of the last chunk travel on their own topic


def received(sim: SimClient) -> list[tuple]:
    return [as_tuple(m) for m in sim.rx.contact_events]


def test_node_publishes_the_offline_events_whatever_the_steps_and_resets(sim):
    sim.wait_for(lambda: sim.rx.defects, 5.0, "the latched ground truth")
    assert {d.run_id for d in sim.rx.defects} == {RUN_ID}
    expected = offline_events("symmetric", N_STEPS)
    assert len(expected) >= 28  # measured: 15 onsets and 13 separations
    step_all(sim, [1234, 1, 77, 5000], N_STEPS)
    assert received(sim) == expected

    # reset in the middle of a contact episode: nothing of it may leak into the next run
    onset, sep = expected[0][1], expected[2][1]
    assert sep - onset > 2 and expected[0][3] == ce.KIND_ONSET
    assert sim.reset().success
    sim.forget()
    step_all(sim, [onset + 2], onset + 2)
    assert [e[1] for e in received(sim)] == [onset, onset]  # both shoes touch at once
    response = sim.reset()
    assert response.success and f"run id {RUN_ID}" in response.message, response.message
    sim.forget()
    step_all(sim, [256], N_STEPS)  # the offline chunking
    assert received(sim) == expected


def test_scenario_switch_resets_the_events(sim):
    try:
        assert sim.reset().success
        sim.forget()
        in_contact = offline_events("symmetric", N_STEPS)[0][1] + 2  # inside the first episode
        step_all(sim, [333], in_contact)
        assert len(sim.rx.contact_events) == 2  # both onsets, no separation yet
        response = sim.reset(scenario="case5_left_tilted")
        assert response.success, response.message
        sim.forget()
        step_all(sim, [999, 4321], N_STEPS)
        expected = offline_events("case5_left_tilted", N_STEPS)
        assert expected
        assert received(sim) == expected
    finally:
        assert sim.reset(scenario="symmetric").success


def measured_series(chunks) -> dict[str, bytes]:
    """Each measured series (values and fault labels) over ``chunks``, concatenated."""
    out: dict[str, bytearray] = {}
    for msg in chunks:
        start = 0
        for name, count in zip(msg.channel_names, msg.channel_sample_counts, strict=True):
            values = np.asarray(msg.values[start : start + count], dtype=np.float64)
            labels = np.asarray(msg.fault_labels[start : start + count], dtype=np.uint8)
            out.setdefault(name, bytearray()).extend(values.tobytes())
            out.setdefault(f"{name}/labels", bytearray()).extend(labels.tobytes())
            start += count
    return {k: bytes(v) for k, v in out.items()}


def test_measured_after_a_reset_with_a_seed_equals_offline(sim):
    """The node's sensor bank restarts at each reset with the run's seed: chunked by
    unlike ~/step sizes, the series equal the offline stream's for that seed."""
    seed, n_steps = 5, 2560
    try:
        assert sim.reset(seed=seed).success
        sim.forget()
        step_all(sim, [1000, 3, 700], n_steps)
        sim.wait_for(
            lambda: sum(m.sample_count for m in sim.rx.measured) == n_steps, 5.0, "measured"
        )
        scenario = dataclasses.replace(load_scenario("symmetric"), seed=seed)
        messages = offline_messages(
            scenario,
            duration_s=n_steps * scenario.sample_period_s,
            settings=StreamSettings(publish_measured=True),
            run_id=RUN_ID,
        )
        expected = measured_series(m for t, m, _ in messages if t is stream.MEASURED)
        # each ~/step publishes what it stepped: its samples are one chunk (each call is
        # shorter than a 100 ms chunk), none wait for the next call
        sizes: list[int] = []
        while sum(sizes) < n_steps:  # as step_all cuts them
            sizes.append(min((1000, 3, 700)[len(sizes) % 3], n_steps - sum(sizes)))
        assert [m.sample_count for m in sim.rx.measured] == sizes
        got = measured_series(sim.rx.measured)
        assert got.keys() == expected.keys() and len(got) >= 10
        assert got == expected
        other_seed = dataclasses.replace(scenario, seed=seed + 1)
        other = offline_messages(
            other_seed,
            duration_s=n_steps * scenario.sample_period_s,
            settings=StreamSettings(publish_measured=True),
        )
        assert measured_series(m for t, m, _ in other if t is stream.MEASURED) != got
    finally:
        assert sim.reset(scenario="symmetric").success
