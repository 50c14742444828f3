""":meth:`Recording.brake`: the brake a recording says its run simulated (what
``brake-sim replay``'s node says in its parameter ``brake``), or why it says none. Real
recordings (the shipped example, checked whole); the records a damaged or foreign file
could hold are put in place of the example's."""

from __future__ import annotations

from pathlib import Path

import pytest

from brake_sim_ros.recording import metadata
from brake_sim_ros.recording.playback import Recording

EXAMPLE = Path(__file__).parents[2] / "bags" / "symmetric.mcap"


@pytest.fixture
def recording():
    with_records = Recording(EXAMPLE)
    yield with_records
    with_records.close()


def test_the_example_says_the_study_brake(recording):
    assert recording.brake() == ("study", "")


@pytest.mark.parametrize(
    ("records", "why"),
    [
        ([], "no brake_sim_model metadata"),
        ([(metadata.MODEL, {"contact.stiffness": "__import__('os')"})], "not a model"),
        ([(metadata.MODEL, {"no.such.parameter": "1.0"})], "not a model"),
        ([(metadata.MODEL, {"friction.coefficient": "(" * 200})], "not a model"),
        ([(metadata.MODEL, {})], "not a model"),  # another version's: fields missing
    ],
)
def test_a_recording_without_a_readable_model_says_no_brake(recording, records, why):
    recording._recording.metadata = records
    brake, reason = recording.brake()
    assert brake == "" and why in reason
    assert "__import__" not in reason and "((" not in reason  # nothing of the file echoed
