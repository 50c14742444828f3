"""The node's message stream, produced offline: no DDS, no pacing, as fast as the CPU goes.

:func:`offline_messages` steps a scenario exactly as :class:`~brake_sim_ros.ros.node.
BrakeSimNode` does with its default run parameters and no actuation commands (the stepper
from :func:`~brake_sim_ros.stream.build.stepper_for`, same chunking, same state
decimation, same /clock), so the sequence it yields equals what the node publishes for the
same scenario, message for message. /diagnostics is the one
topic it does not produce: that is a wall-clock report of a live node.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass
from typing import Any

from brake_sim_ros import stream
from brake_sim_ros.analysis.contact_events import ContactEventDetector
from brake_sim_ros.scenarios import Scenario
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.stream import Topic, conversion
from brake_sim_ros.stream import parameters as ros_params
from brake_sim_ros.stream.build import require_measured, sensor_bank_for, stepper_for
from brake_sim_ros.stream.ground_truth import TruthUpdates, recorded_wear


def _default(name: str):
    return next(s.default for s in ros_params.run_parameter_specs() if s.name == name)


@dataclass(frozen=True)
class StreamSettings:
    """The run parameters of the node that shape its stream (same names, same defaults)."""

    chunk_rate_hz: float = _default("chunk_rate_hz")
    state_rate_hz: float = _default("state_rate_hz")
    publish_clock: bool = _default("publish_clock")
    publish_measured: bool = _default("publish_measured")
    measured_rate_hz: float = _default("measured_rate_hz")


def offline_messages(
    scenario: Scenario,
    *,
    duration_s: float | None = None,
    settings: StreamSettings | None = None,
    stepper: FixedStepStepper | None = None,
    run_id: str | None = None,
) -> Iterator[tuple[Topic, Any, int]]:
    """Every message the node would publish for ``scenario``, with its simulated time (ns).

    Args:
        scenario: the scenario, actuated by its own force profile.
        duration_s: simulated seconds (default: the scenario's duration).
        settings: chunk and state rates, /clock and ~/measured on or off (default: the
            node's defaults).
        stepper: a stepper to use (default :func:`stepper_for` the scenario, as the node
            builds it); it is reset first.
        run_id: the run id of the ground-truth messages (DefectState, ContactEvent);
            default a fresh one (:func:`~brake_sim_ros.stream.conversion.new_run_id`).
            Give the node's to reproduce its stream byte for byte.

    Raises:
        FidelityError: ``publish_measured`` on a scenario whose fidelity plan has no
            sensors (``[needs]`` without ``measured_signals``), at the first message.
    """
    settings = settings or StreamSettings()
    if settings.publish_measured:
        require_measured(scenario, "publish_measured")
    run_id = conversion.new_run_id() if run_id is None else run_id
    stepper = stepper or stepper_for(scenario)
    stepper.reset()
    period = stepper.sample_period_s
    duration = scenario.duration_s if duration_s is None else duration_s
    end = round(duration / period)
    chunk = stream.samples_per(settings.chunk_rate_hz, period)
    stride = stream.samples_per(settings.state_rate_hz, period)
    setup = stepper.setup
    initial_angles = (setup.defects.left.initial_angle_deg, setup.defects.right.initial_angle_deg)
    yield (
        stream.DEFECTS,
        conversion.defect_state(
            scenario=scenario.name,
            defects=setup.defects,
            initial_angles_deg=initial_angles,
            ns=0,
            run_id=run_id,
            seed=scenario.seed,
            unit_id=scenario.unit_id,
        ),
        0,
    )
    if settings.publish_clock:
        yield stream.CLOCK, conversion.clock(0), 0
    detector = ContactEventDetector()
    measured = (
        stream.MeasuredStream(
            sensor_bank_for(scenario), stream.samples_per(settings.measured_rate_hz, period)
        )
        if settings.publish_measured
        else None
    )
    truth = TruthUpdates(setup.defects)
    while stepper.sample_index < end:
        block = stepper.advance(min(chunk, end - stepper.sample_index))
        for row in truth.due_rows(block.time_s, recorded_wear(block)):
            index = block.first_index + row
            ns = conversion.stamp_ns(index, period)
            msg = conversion.defect_state(
                scenario=scenario.name,
                defects=setup.defects,
                initial_angles_deg=initial_angles,
                ns=ns,
                run_id=run_id,
                seed=scenario.seed,
                unit_id=scenario.unit_id,
                time_s=float(block.time_s[row]),
                wear_m=recorded_wear(block, row),
            )
            yield stream.DEFECTS, msg, ns
        yield from stream.block_messages(
            block,
            stride,
            with_clock=settings.publish_clock,
            contact_events=detector,
            run_id=run_id,
            measured=measured,
        )
    if measured is not None:  # the node publishes what is pending when the run ends
        yield from measured.flush()
