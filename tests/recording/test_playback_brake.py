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


def test_a_recording_from_before_pose_rules_reads_as_the_tip_abutment(recording):
    """A recording made before shoes had pose rules has no ``shoe.pose``: its model reads
    with the only rule there was; a name is read only where the model has one."""
    record = dict(recording._recording.metadata_record(metadata.MODEL))
    assert metadata.model_from_record(record)[0].shoe.pose == "eye-piston"  # the study's
    del record["shoe.pose"]
    assert metadata.model_from_record(record)[0].shoe.pose == "tip-abutment"
    for bad in ({**record, "shoe.pose": repr("eye")}, {**record, "shoe.mass_kg": repr("1.6")}):
        recording._recording.metadata = [(metadata.MODEL, bad)]
        brake, reason = recording.brake()
        assert brake == "" and "not a model" in reason
