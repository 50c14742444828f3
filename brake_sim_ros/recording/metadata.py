"""What a recording says about itself: MCAP metadata records and rosbag2's QoS text.

Metadata records (MCAP ``Metadata``; every value a string):

``brake_sim_model``
    ``ros_params.model_values(params, defects)``: every model parameter and defect under
    its ROS parameter name, each value the ``repr()`` of the Python value, so
    ``ros_params.build_model({k: ast.literal_eval(v) for k, v in record.items()})``
    rebuilds the ``BrakeParameters`` and ``Defects`` of the run (:func:`model_from_record`).
``brake_sim_scenario``
    ``name``, ``source`` (file path or ``<built-in NAME>``), ``toml`` (the scenario file's
    text), ``sha256`` (of that text), ``description``, ``solver`` (JSON: ``preset``,
    ``method``, ``max_step_s``, ``sample_rate_hz`` as the run had them, the command's
    options over the text included).
``brake_sim_run``
    ``run_id`` (of the ground-truth messages at the start of the recording; a live run
    makes a new one at each ~/reset, which its DefectState then carries), ``seed``,
    ``software_version``, ``sample_rate_hz`` and ``sample_period_s`` (the
    scenario's), the stepper at the start of the recording (``scheme``, ``preset``,
    ``physics_step_s``, ``substeps_per_sample``, ``step_limit_s``; a live run may re-pick
    the substeps later, which its /diagnostics and log say), ``mode`` (``live``,
    ``offline``, or ``resim``: re-simulated from a recording by ``brake-sim resim``,
    which adds ``resimulated_from`` and ``recorded_mode``), the run parameters in force at
    the start under their names (every entry of ``stream.run_parameters.RUN_PARAMETERS``
    but what runs and the pacing: ``duration_s``, ``continuous``, ``chunk_rate_hz``,
    ``state_rate_hz``, ``publish_clock``, ``publish_measured``, ``measured_rate_hz``,
    ``max_actuation_force_n``, the command timeout's, ...; a live drive's settings,
    ``max_drive_torque_n_m`` and ``speed_time_constant_s``, only for a run that takes
    live drive commands, a ``[vehicle]`` and no ``[cycle]``), ``time_base`` and
    ``model_note``; a live run adds its node name and ``real_time_factor``; values are
    ``repr()`` of the Python value except strings, which are given as they are.
``brake_sim_unit``
    which brake unit was run (:mod:`brake_sim_ros.fleet.scatter`): ``unit_id`` and
    ``fleet_seed`` (what draws the unit's scatter: the same brake in every run), ``seed``
    (the run's at the start of the recording: its noise and conditions) and
    ``unit_parameters``,
    JSON: a list of ``{key, unit, nominal, value}``, every scattered parameter of the brake
    and its sensors as the scenario gives it (``nominal``) and as the unit has it
    (``value``); all equal for unit ``nominal``; and ``conditions``, JSON: the run's
    operating conditions drawn from the scenario's ``[conditions]`` ranges
    (:mod:`brake_sim_ros.fleet.conditions`), per name ``{value, unit, range}`` (``{}``
    without them). ``brake_sim_model`` holds the drawn
    values too (with any ROS parameter overrides of a live run on top). The conditions at
    the start of the recording: a live ~/reset with a new seed draws them again, and its
    DefectState then carries the new seed.
``brake_sim_ros_parameters`` (live runs)
    every ROS parameter of the node at the start of the recording, ``repr()`` of its value.
``brake_sim_parameter_change`` (live runs, one record per change, in the order made)
    a parameter change the node accepted while it ran (``ros2 param set``):
    ``sample_index``, the sample it took effect at (the next one), and each parameter
    changed under its name, the ``repr()`` of its new value (:func:`parameter_change_record`);
    ``brake-sim resim`` applies them at their samples.
``rosbag2`` (written when the file is closed)
    ``serialized_metadata``: the bag's ``BagMetadata`` (version 9) in the YAML that
    rosbag2's MCAP storage plugin writes and reads (``ros2 bag info`` shows it).

Channel metadata (rosbag2 Jazzy, ``mcap_storage.cpp``): ``offered_qos_profiles``, a YAML
list of the offered profiles in the version 9 form (policy names as strings, durations as
``{sec, nsec}``), and ``topic_type_hash`` (``RIHS01_...``).
"""

from __future__ import annotations

import ast
import functools
import json
import subprocess
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from brake_sim_ros import __version__
from brake_sim_ros.model.defects import Defects
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.scenarios import Scenario
from brake_sim_ros.stream import parameters as ros_params
from brake_sim_ros.stream.session import RunSession
from brake_sim_ros.stream.topics import QosSpec

MODEL = "brake_sim_model"
SCENARIO = "brake_sim_scenario"
RUN = "brake_sim_run"
UNIT = "brake_sim_unit"
ROS_PARAMETERS = "brake_sim_ros_parameters"
PARAMETER_CHANGE = "brake_sim_parameter_change"
ROSBAG2 = "rosbag2"
RECOVERY = "brake_sim_recovery"  # written by brake-sim recover (recording/recover.py)
ROS_DISTRO = "jazzy"
BAG_METADATA_VERSION = 9  # rosbag2 Jazzy's BagMetadata::version
TIME_BASE = "simulated time, ns since the start (or last ~/reset) of the run"


@functools.cache
def software_version() -> str:
    """``brake-sim-ros <version>``, plus ``git <commit>[-dirty]`` when run from a checkout.

    Never fails: without git, outside a checkout or on any git error, only the version.
    """
    version = f"brake-sim-ros {__version__}"
    root = Path(__file__).resolve().parents[2]
    try:
        out = subprocess.run(
            ["git", "-C", str(root), "describe", "--always", "--dirty", "--abbrev=12"],
            capture_output=True,
            text=True,
            timeout=5.0,
            check=True,
        )
    except (OSError, subprocess.SubprocessError):
        return version
    commit = out.stdout.strip()
    return f"{version} (git {commit})" if commit else version


def model_record(params: BrakeParameters, defects: Defects) -> dict[str, str]:
    """The ``brake_sim_model`` record: every model value as its ``repr()``."""
    return {k: repr(v) for k, v in ros_params.model_values(params, defects).items()}


def model_from_record(record: Mapping[str, str]) -> tuple[BrakeParameters, Defects]:
    """``BrakeParameters`` and ``Defects`` back from a ``brake_sim_model`` record."""
    return ros_params.build_model({k: ast.literal_eval(v) for k, v in record.items()})


def scenario_record(scenario: Scenario) -> dict[str, str]:
    """The ``brake_sim_scenario`` record."""
    return {
        "name": scenario.name,
        "source": scenario.source,
        "toml": scenario.text,
        "sha256": scenario.digest,
        "description": scenario.description,
        # what the run's options changed over the text (simulate --preset/--method/
        # --max-step/--sample-rate, resim --preset): re-simulation applies them again
        "solver": json.dumps(solver_values(scenario)),
    }


def solver_values(scenario: Scenario) -> dict[str, Any]:
    """The solver settings and sample rate ``scenario`` runs with (JSON-ready)."""
    solver = scenario.solver
    return {
        "preset": solver.preset,
        "method": solver.method,
        "max_step_s": solver.max_step_s,
        "sample_rate_hz": scenario.sample_rate_hz,
    }


def unit_record(scenario: Scenario) -> dict[str, str]:
    """The ``brake_sim_unit`` record of ``scenario``'s unit."""
    return {
        "unit_id": scenario.unit_id,
        "seed": repr(scenario.seed),
        "fleet_seed": repr(scenario.fleet_seed),
        "unit_parameters": json.dumps([v.as_dict() for v in scenario.unit_values()]),
        "conditions": json.dumps(scenario.conditions_record()),
    }


def parameter_change_record(changes: Mapping[str, Any], sample_index: int) -> dict[str, str]:
    """A ``brake_sim_parameter_change`` record: the new values at ``sample_index``."""
    record = {name: repr(value) for name, value in sorted(changes.items())}
    record["sample_index"] = repr(int(sample_index))
    return record


def run_record(
    session: RunSession, *, mode: str, extra: Mapping[str, Any] | None = None
) -> dict[str, str]:
    """The ``brake_sim_run`` record (see the module doc) of ``session`` as it is now: its
    stepper, and the run parameters the table records (:meth:`RunSession.record_values`)."""
    if mode not in ("live", "offline", "resim"):
        raise ValueError(f"mode={mode!r}: allowed 'live', 'offline' or 'resim'")
    stepper, scenario = session.stepper, session.scenario
    values: dict[str, Any] = {
        "mode": mode,
        "run_id": session.run_id,
        "seed": session.seed,
        "software_version": software_version(),
        "sample_rate_hz": scenario.sample_rate_hz,
        "sample_period_s": stepper.sample_period_s,
        "scheme": stepper.scheme,
        "preset": scenario.solver.preset,
        "physics_step_s": stepper.physics_step_s,
        "substeps_per_sample": stepper.substeps,
        "step_limit_s": stepper.limit.max_step_s,
        **session.record_values(),
        "time_base": TIME_BASE,
        "model_note": (
            "brake_sim_model holds the model at the start of the recording; changes made"
            " while it ran are in brake_sim_parameter_change records and, for the defects,"
            " on /brake_sim/defects (DefectState)"
        ),
        **(extra or {}),
    }
    return {k: v if isinstance(v, str) else repr(v) for k, v in values.items()}


def run_records(
    session: RunSession, *, mode: str, extra: Mapping[str, Any] | None = None
) -> dict[str, dict[str, str]]:
    """The model, scenario, unit and run records of ``session``'s recording (a live
    node's, an offline run's or a re-simulation's: one builder for all)."""
    return {
        MODEL: {k: repr(v) for k, v in session.model.items()},
        SCENARIO: scenario_record(session.scenario),
        UNIT: unit_record(session.scenario),
        RUN: run_record(session, mode=mode, extra=extra),
    }


def custom_data(session: RunSession, mode: str) -> dict[str, str]:
    """The MCAP header's custom data of ``session``'s recording (``mode`` as recorded)."""
    return {
        "brake_sim_run_id": session.run_id,
        "brake_sim_scenario": session.scenario.name,
        "brake_sim_unit_id": session.scenario.unit_id,
        "brake_sim_seed": str(session.seed),
        "brake_sim_mode": mode,
        "brake_sim_version": software_version(),
    }


# -- rosbag2's YAML ---------------------------------------------------------------------------
def _scalar(value: Any) -> str:
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int):
        return str(value)
    return json.dumps(str(value))  # a double-quoted YAML scalar


@dataclass(frozen=True)
class RawYaml:
    """Block YAML text already rendered (e.g. a channel's ``offered_qos_profiles``)."""

    text: str


def _yaml(value: Any, indent: int) -> list[str]:
    """Block-style YAML lines of nested dicts, lists and scalars (what yaml-cpp emits)."""
    pad = " " * indent
    lines: list[str] = []
    if isinstance(value, dict):
        for key, item in value.items():
            if isinstance(item, RawYaml):
                lines.append(f"{pad}{key}:")
                lines.extend(f"{pad}  {line}" for line in item.text.splitlines())
            elif isinstance(item, dict | list) and item:
                lines.append(f"{pad}{key}:")
                lines.extend(_yaml(item, indent + 2))
            else:
                empty = "{}" if isinstance(item, dict) else "[]"
                lines.append(f"{pad}{key}: {empty if item in ({}, []) else _scalar(item)}")
    else:
        for item in value:
            sub = _yaml(item, indent + 2) if isinstance(item, dict | list) else None
            if sub:
                lines.append(f"{pad}- {sub[0].lstrip()}")
                lines.extend(sub[1:])
            else:
                lines.append(f"{pad}- {_scalar(item)}")
    return lines


def _duration(ns: int) -> dict[str, int]:
    return {"sec": ns // 1_000_000_000, "nsec": ns % 1_000_000_000}


def qos_dict(profile: QosSpec) -> dict[str, Any]:
    """One QoS profile as rosbag2 (version 9) serializes it (other policies at defaults)."""
    return {
        "history": profile.history,
        "depth": int(profile.depth),
        "reliability": profile.reliability,
        "durability": profile.durability,
        "deadline": _duration(0),
        "lifespan": _duration(0),
        "liveliness": "system_default",
        "liveliness_lease_duration": _duration(0),
        "avoid_ros_namespace_conventions": False,
    }


def qos_yaml(profiles: list[QosSpec]) -> str:
    """``offered_qos_profiles`` channel metadata: a YAML list of :func:`qos_dict`."""
    return "\n".join(_yaml([qos_dict(p) for p in profiles], 0))


def rosbag2_record(
    *,
    file_name: str,
    topics: list[dict[str, Any]],
    message_count: int,
    start_ns: int,
    end_ns: int,
    custom_data: Mapping[str, str],
) -> dict[str, str]:
    """The ``rosbag2`` record: ``{"serialized_metadata": <BagMetadata YAML>}``.

    Args:
        file_name: the MCAP file's name (rosbag2's ``relative_file_paths``).
        topics: per topic ``name``, ``type``, ``qos_yaml`` (its ``offered_qos_profiles``
            channel metadata), ``type_hash`` and ``message_count``.
        message_count: messages in the file.
        start_ns, end_ns: first and last log time, ns (simulated).
        custom_data: free key-values (rosbag2's ``custom_data``).
    """
    duration = max(0, end_ns - start_ns) if message_count else 0
    start = start_ns if message_count else 0
    bag = {
        "version": BAG_METADATA_VERSION,
        "storage_identifier": "mcap",
        "duration": {"nanoseconds": duration},
        "starting_time": {"nanoseconds_since_epoch": start},
        "message_count": message_count,
        "topics_with_message_count": [
            {
                "topic_metadata": {
                    "name": t["name"],
                    "type": t["type"],
                    "serialization_format": "cdr",
                    "offered_qos_profiles": RawYaml(t["qos_yaml"]),
                    "type_description_hash": t["type_hash"],
                },
                "message_count": t["message_count"],
            }
            for t in topics
        ],
        "compression_format": "",  # rosbag2 file/message compression: none (MCAP chunks are)
        "compression_mode": "",
        "relative_file_paths": [file_name],
        "files": [
            {
                "path": file_name,
                "starting_time": {"nanoseconds_since_epoch": start},
                "duration": {"nanoseconds": duration},
                "message_count": message_count,
            }
        ],
        "custom_data": dict(custom_data),
        "ros_distro": ROS_DISTRO,
    }
    return {"serialized_metadata": "\n".join(_yaml(bag, 0)) + "\n"}
