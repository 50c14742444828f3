"""SampleBlock -> ROS messages. Pure functions: no rclpy, no clock, no DDS.

Every stamp is simulated time, ``t = sample_index * sample_period`` in integer
nanoseconds (:func:`stamp_ns`, exact for a whole-number sample rate), never the wall
clock; every frame_id is ``brake_backing_plate`` (see ``model/parameters.py`` for the
frame). Units and signs are those of the core's columns (``model/layout.py::COLUMNS``),
which the message definitions repeat.
"""

from __future__ import annotations

import array
import dataclasses
import uuid
from collections.abc import Callable, Iterable
from fractions import Fraction

import numpy as np
from brake_sim_msgs.msg import (
    BrakeState,
    ContactEvent,
    Defect,
    DefectState,
    MeasuredChunk,
    PivotForceChunk,
)
from builtin_interfaces.msg import Time
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Header

from brake_sim_ros.analysis import contact_events
from brake_sim_ros.analysis.onsets import in_contact
from brake_sim_ros.model.defects import Defects
from brake_sim_ros.model.run_setup import SampleBlock
from brake_sim_ros.sensing.sensors import SensorBank, SensorFrame

FRAME_ID = "brake_backing_plate"
JOINT_NAMES = ("flywheel", "drum", "left_shoe", "right_shoe")
_JOINT_ANGLES = ("flywheel_angle_rad", "drum_angle_rad", "left_angle_rad", "right_angle_rad")
_JOINT_SPEEDS = (
    "flywheel_speed_rad_s",
    "drum_speed_rad_s",
    "left_speed_rad_s",
    "right_speed_rad_s",
)
_NS_PER_S = 1_000_000_000
# the per-sample arrays of a PivotForceChunk, all of one length
PIVOT_CHUNK_ARRAYS = (
    "left_fx_n",
    "left_fy_n",
    "right_fx_n",
    "right_fy_n",
    "left_magnitude_n",
    "right_magnitude_n",
)


def new_run_id() -> str:
    """A fresh run id: a UUID4 as 32 lower-case hexadecimal digits (``run_id`` of the
    ground-truth messages)."""
    return uuid.uuid4().hex


def stamp_ns(sample_index: int, period_s: float) -> int:
    """Simulated time of a sample, integer ns: ``sample_index * period_s`` to the nearest ns
    (ties to even), in exact arithmetic on the sample rate (:func:`sample_rate_hz`), so
    the stamps of a 25.6 kHz stream are exact multiples of 39062.5 ns, without drift."""
    rate = Fraction(sample_rate_hz(period_s))
    return round(Fraction(sample_index * _NS_PER_S * rate.denominator, rate.numerator))


def sample_rate_hz(period_s: float) -> float:
    """``1 / period_s``, snapped to the integer it misses by rounding (1 / 4e-5 = 25000.0)."""
    rate = 1.0 / period_s
    nearest = round(rate)
    return float(nearest) if abs(rate - nearest) <= 1e-9 * rate else rate


def time_msg(ns: int) -> Time:
    return Time(sec=ns // _NS_PER_S, nanosec=ns % _NS_PER_S)


def header(ns: int) -> Header:
    return Header(stamp=time_msg(ns), frame_id=FRAME_ID)


def all_finite(block: SampleBlock) -> bool:
    """True when every number of the block is finite (nothing else may be published)."""
    return bool(np.isfinite(block.data).all())


def _doubles(column: np.ndarray) -> array.array:
    out = array.array("d")
    out.frombytes(np.ascontiguousarray(column, dtype=np.float64).tobytes())
    return out


def pivot_force_chunk(block: SampleBlock) -> PivotForceChunk:
    """All samples of ``block`` as one chunk; header stamp = time of its first sample."""
    lx, ly = block["left_pivot_fx_n"], block["left_pivot_fy_n"]
    rx, ry = block["right_pivot_fx_n"], block["right_pivot_fy_n"]
    return PivotForceChunk(
        header=header(stamp_ns(block.first_index, block.sample_period_s)),
        first_sample_index=int(block.first_index),
        sample_rate_hz=sample_rate_hz(block.sample_period_s),
        left_fx_n=_doubles(lx),
        left_fy_n=_doubles(ly),
        right_fx_n=_doubles(rx),
        right_fy_n=_doubles(ry),
        left_magnitude_n=_doubles(np.hypot(lx, ly)),
        right_magnitude_n=_doubles(np.hypot(rx, ry)),
    )


def measured_chunk(block: SampleBlock, frame: SensorFrame, sensors: SensorBank) -> MeasuredChunk:
    """What the sensors measured over ``block`` (``frame``: the bank ``sensors``'s output for
    it), channel-major; stamp = time of the block's first sample.

    The tone-ring edges are the frame's (``SensorFrame.edges_s``, simulated time in s): the
    bank carries each ring's last sample from block to block, so a chunk holds the edges in
    (previous block's last sample, this block's last sample] and every edge of a run is in
    exactly one chunk."""
    decimation = sensors.output_decimation
    teeth = {c.name: c.tone_ring_teeth for c in sensors.sensors.channels}
    series = list(frame.series.values())
    edge_names = list(frame.edges_s)
    return MeasuredChunk(
        header=header(stamp_ns(block.first_index, block.sample_period_s)),
        first_sample_index=int(block.first_index),
        sample_count=len(block),
        sample_rate_hz=sample_rate_hz(block.sample_period_s),
        channel_names=[s.name for s in series],
        units=[s.unit for s in series],
        decimation=array.array("I", [decimation[s.name] for s in series]),
        channel_sample_counts=array.array("I", [len(s.values) for s in series]),
        values=_doubles(np.concatenate([s.values for s in series] or [np.empty(0)])),
        fault_labels=array.array(  # bytes: copied whole (frombytes), not per element
            "B",
            np.concatenate([s.fault_label for s in series] or [np.empty(0)])
            .astype(np.uint8)
            .tobytes(),
        ),
        edge_channel_names=edge_names,
        tone_ring_teeth=array.array("I", [teeth[n] for n in edge_names]),
        edge_counts=array.array("I", [len(frame.edges_s[n]) for n in edge_names]),
        edge_times_s=_doubles(
            np.concatenate([frame.edges_s[n] for n in edge_names] or [np.empty(0)])
        ),
    )


def measured_edges(msgs: Iterable[MeasuredChunk]) -> dict[str, np.ndarray]:
    """The tone-ring edge times, s, of each wheel-speed channel over ``msgs`` (consecutive
    chunks of one run, in order), joined: the inverse of :func:`measured_chunk` for edges.

    Raises:
        ValueError: a chunk whose ``edge_counts`` do not add up to its ``edge_times_s``.
    """
    parts: dict[str, list[np.ndarray]] = {}
    for msg in msgs:
        times = np.asarray(msg.edge_times_s, dtype=np.float64)
        counts = [int(c) for c in msg.edge_counts]
        if sum(counts) != times.size or len(counts) != len(msg.edge_channel_names):
            raise ValueError(
                f"measured chunk at sample {msg.first_sample_index}: {times.size} edge times,"
                f" its edge counts say {sum(counts)}"
            )
        bounds = np.cumsum([0, *counts])
        for k, name in enumerate(msg.edge_channel_names):
            parts.setdefault(name, []).append(times[bounds[k] : bounds[k + 1]])
    return {name: np.concatenate(p) for name, p in parts.items()}


def state_rows(block: SampleBlock, stride: int) -> list[int]:
    """Rows of ``block`` whose sample index is a multiple of ``stride``.

    Choosing state samples by index, not by position in a chunk, makes the published
    states independent of how the run was cut into chunks and service calls.
    """
    first = block.first_index
    start = (-first) % stride
    return list(range(start, len(block), stride))


def _reader(block: SampleBlock, row: int) -> Callable[[str], float]:
    """The value of a named column at ``row`` (by name: a block may keep only some columns,
    in its own order)."""
    r = block.data[row]
    return lambda name: float(r[block.index_of(name)])


def brake_state(block: SampleBlock, row: int) -> BrakeState:
    """Row ``row`` of ``block`` as a BrakeState."""
    value = _reader(block, row)
    index = block.first_index + row
    left_indent = value("left_indentation_m")
    right_indent = value("right_indentation_m")
    return BrakeState(
        header=header(stamp_ns(index, block.sample_period_s)),
        sample_index=int(index),
        flywheel_angle_rad=value("flywheel_angle_rad"),
        drum_angle_rad=value("drum_angle_rad"),
        left_shoe_angle_rad=value("left_angle_rad"),
        right_shoe_angle_rad=value("right_angle_rad"),
        flywheel_speed_rad_s=value("flywheel_speed_rad_s"),
        drum_speed_rad_s=value("drum_speed_rad_s"),
        left_shoe_speed_rad_s=value("left_speed_rad_s"),
        right_shoe_speed_rad_s=value("right_speed_rad_s"),
        left_indentation_m=left_indent,
        right_indentation_m=right_indent,
        left_normal_force_n=value("left_normal_force_n"),
        right_normal_force_n=value("right_normal_force_n"),
        left_friction_force_n=value("left_friction_force_n"),
        right_friction_force_n=value("right_friction_force_n"),
        left_actuation_force_n=value("left_actuation_force_n"),
        right_actuation_force_n=value("right_actuation_force_n"),
        left_contact_x_m=value("left_contact_x_m"),
        left_contact_y_m=value("left_contact_y_m"),
        right_contact_x_m=value("right_contact_x_m"),
        right_contact_y_m=value("right_contact_y_m"),
        left_in_contact=in_contact(left_indent),
        right_in_contact=in_contact(right_indent),
        regime=int(value("regime")),
    )


def joint_state(block: SampleBlock, row: int) -> JointState:
    """The four rotations at row ``row``: positions (rad) and velocities (rad/s).

    Shoe angles follow the core's sign (positive outward, toward the drum), so the left
    shoe turns counter-clockwise and the right shoe clockwise for a positive value.
    """
    value = _reader(block, row)
    index = block.first_index + row
    return JointState(
        header=header(stamp_ns(index, block.sample_period_s)),
        name=list(JOINT_NAMES),
        position=_doubles(np.array([value(n) for n in _JOINT_ANGLES])),
        velocity=_doubles(np.array([value(n) for n in _JOINT_SPEEDS])),
    )


def contact_event(event: contact_events.ContactEvent, dt_s: float, *, run_id: str) -> ContactEvent:
    """``event`` as a ContactEvent message of run ``run_id``; header stamp = time of its
    sample (``dt_s``: the sample period, s)."""
    return ContactEvent(
        header=header(stamp_ns(event.sample_index, dt_s)),
        run_id=run_id,
        sample_index=int(event.sample_index),
        shoe=int(event.shoe),
        kind=int(event.kind),
        peak_pivot_force_n=float(event.peak_pivot_force_n),
        peak_sample_index=int(event.peak_sample_index),
        duration_s=float(event.duration_s),
    )


def clock(ns: int) -> Clock:
    return Clock(clock=time_msg(ns))


def defect_state(
    *,
    scenario: str,
    defects: Defects,
    initial_angles_deg: tuple[float, float],
    ns: int,
    run_id: str,
    seed: int,
    unit_id: str,
    time_s: float | None = None,
    wear_m: dict[str, float] | None = None,
) -> DefectState:
    """Ground truth of the defects in force from simulated time ``ns`` on: the
    catalogue's list (:meth:`Defects.active`) with each severity at that time (a defect
    before its onset is not listed).

    Args:
        scenario: name of the active scenario.
        defects: defects in force.
        initial_angles_deg: (left, right) starting angles of the run in progress, deg.
            They differ from ``defects`` after a run-time change of
            ``initial_angle_deg``, which applies at the next reset.
        ns: simulated time from which it applies, ns.
        run_id: the run's id (:func:`new_run_id`, or the node's ``run_id`` parameter).
        seed: the run's seed.
        unit_id: the brake unit's id (the scenario's ``unit_id``; "nominal" for the
            drawing's brake, :mod:`brake_sim_ros.fleet.scatter`).
        time_s: the simulated time of the severities, s (the sample's; default ``ns``).
        wear_m: the linings' wear the model recorded at that sample, m, by shoe
            (:func:`~brake_sim_ros.stream.ground_truth.recorded_wear`): the severity of a
            lining wearing with its friction work (default unworn: the start of a run).
    """
    left = dataclasses.replace(defects.left, initial_angle_deg=initial_angles_deg[0])
    right = dataclasses.replace(defects.right, initial_angle_deg=initial_angles_deg[1])
    at = ns * 1e-9 if time_s is None else time_s
    if wear_m is None:
        wear_m = {"left": 0.0, "right": 0.0}
    active = dataclasses.replace(defects, left=left, right=right).active(at, wear_m)
    return DefectState(
        header=header(ns),
        run_id=run_id,
        scenario=scenario,
        unit_id=unit_id,
        seed=int(seed),
        healthy=not active,
        defects=[
            Defect(
                kind=d.kind,
                location=d.location,
                severity=float(d.severity),
                unit=d.unit,
                onset_s=float(d.onset_s),
                growth=d.growth,
                growth_rate=float(d.growth_rate),
                attribute_names=[name for name, _ in d.attributes],
                attribute_values=_doubles(np.array([v for _, v in d.attributes], dtype=float)),
            )
            for d in active
        ],
        labels=[d.label for d in active],
    )
