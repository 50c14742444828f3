"""The node's message stream, produced offline: no DDS, no pacing, as fast as the CPU goes.

:func:`offline_messages` steps a scenario exactly as :class:`~brake_sim_ros.ros.node.
BrakeSimNode` does with its default run parameters and no actuation commands (the stepper
from :func:`~brake_sim_ros.stream.build.stepper_for`, same chunking, same state
decimation, same /clock), so the sequence it yields equals what the node publishes for the
same scenario, message for message. /diagnostics is the one
topic it does not produce: that is a wall-clock report of a live node.
"""

from __future__ import annotations

from collections.abc import Iterator, Mapping, Sequence
from dataclasses import asdict, dataclass
from typing import Any

from brake_sim_ros.scenarios import Scenario
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.stream import Topic, run_parameters
from brake_sim_ros.stream.build import require_measured
from brake_sim_ros.stream.session import RunSession

_DEFAULTS = run_parameters.defaults()

Change = tuple[int, Mapping[str, Any]]
"""``(sample, values)``: parameters changed from ``sample`` on, as a node accepts them."""


@dataclass(frozen=True)
class StreamSettings:
    """The run parameters of the node that shape its stream (same names, same defaults)."""

    chunk_rate_hz: float = _DEFAULTS["chunk_rate_hz"]
    state_rate_hz: float = _DEFAULTS["state_rate_hz"]
    publish_clock: bool = _DEFAULTS["publish_clock"]
    publish_measured: bool = _DEFAULTS["publish_measured"]
    measured_rate_hz: float = _DEFAULTS["measured_rate_hz"]


def offline_session(
    scenario: Scenario,
    *,
    duration_s: float | None = None,
    settings: StreamSettings | None = None,
    stepper: FixedStepStepper | None = None,
    run_id: str | None = None,
) -> RunSession:
    """The session :func:`offline_messages` drives (the arguments are its).

    Raises:
        FidelityError: ``publish_measured`` on a scenario whose plan has no sensors.
    """
    settings = settings or StreamSettings()
    if settings.publish_measured:
        require_measured(scenario, "publish_measured")
    values = {**asdict(settings), "duration_s": duration_s or 0.0}
    return RunSession(scenario, settings=values, run_id=run_id, stepper=stepper)


def offline_messages(
    scenario: Scenario,
    *,
    duration_s: float | None = None,
    settings: StreamSettings | None = None,
    stepper: FixedStepStepper | None = None,
    run_id: str | None = None,
    changes: Sequence[Change] = (),
    session: RunSession | None = None,
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
        changes: parameter changes (run or model parameters) at their samples, in
            order, applied as a node applies them (:meth:`RunSession.apply`); a chunk
            ends where a change takes effect, as a node's does. The run still ends at
            ``duration_s`` (a change of ``duration_s`` or ``continuous`` is recorded
            and kept in the session's settings, not followed).
        session: the session to drive (default :func:`offline_session` of the above).

    Raises:
        FidelityError: ``publish_measured`` on a scenario whose fidelity plan has no
            sensors (``[needs]`` without ``measured_signals``), at the first message.
        ParameterError: a change the session refuses (one line).
    """
    if session is None:
        session = offline_session(
            scenario, duration_s=duration_s, settings=settings, stepper=stepper, run_id=run_id
        )
    end = session.end_sample
    pending = sorted(changes, key=lambda change: change[0])
    yield from session.start()
    while session.sample_index < end:
        while pending and pending[0][0] <= session.sample_index:
            yield from session.apply(pending.pop(0)[1])
        stop = pending[0][0] if pending else end
        n = min(session.chunk_samples, min(stop, end) - session.sample_index)
        yield from session.messages(session.advance(n))
    yield from session.flush()  # the node publishes what is pending when the run ends
