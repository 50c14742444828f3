"""``brake-sim view FILE.mcap``: a recording of the simulator's stream, shown in Rerun.

The recording is checked whole by the checked reader
(:func:`~brake_sim_ros.recording.reader.open_recording`: every chunk's CRC, every message
against the installed definition of its type) before anything is shown; a damaged or
foreign file is refused with one line. Messages are then decoded with the installed
definitions (:func:`~brake_sim_ros.recording.cdr.decoder`, never the file's schema text)
and handed, in log-time order, to the same :class:`~.rerun_sink.RerunSink` the node and
the offline simulator use. The drawing's geometry comes from the recording's
``brake_sim_model`` metadata (``model_values`` of the run, values as ``repr`` strings,
each checked to be a plain number); without it the built-in geometry is drawn and the
event log says so. ``brake_sim_scenario`` metadata (name, source, toml) is shown as the
run's description.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass

from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.model.defects import Defects
from brake_sim_ros.model.parameters import NAMED_FIELDS, BrakeParameters
from brake_sim_ros.recording import cdr
from brake_sim_ros.recording.metadata import MODEL, SCENARIO
from brake_sim_ros.recording.reader import Recording, RecordingReadError
from brake_sim_ros.stream import parameters as ros_params
from brake_sim_ros.viz.rerun_sink import RerunSink

MAX_VALUE_CHARS = 100  # a model value is the repr() of one number or name
MAX_TEXT_CHARS = 100_000  # scenario text shown in the viewer


@dataclass(frozen=True)
class RecordingInfo:
    """What a recording says about its run, before its messages are read."""

    params: BrakeParameters | None
    defects: Defects | None
    run_text: str


@dataclass(frozen=True)
class ViewSummary:
    messages: int
    samples: int
    states: int
    first_s: float | None
    last_s: float | None


def _model_value(name: str, text: str) -> float | int | bool | str:
    if len(text) > MAX_VALUE_CHARS:
        raise ValueError(f"value of {name} is {len(text)} characters long")
    value = ast.literal_eval(text)
    if isinstance(value, str) and name in NAMED_FIELDS:
        return value
    if not isinstance(value, float | int | bool):
        raise ValueError(f"value of {name} is not a number")
    return value


def read_info(recording: Recording) -> RecordingInfo:
    """The model and scenario metadata of a checked recording.

    Raises:
        RecordingReadError: model metadata that is not numbers (names where the model
            has them), or that the core refuses.
    """
    params = defects = None
    model = recording.metadata_record(MODEL)
    if model is not None:
        try:
            values = {k: _model_value(k, v) for k, v in model.items()}
            params, defects = ros_params.build_model(values)
        except (ValueError, SyntaxError, KeyError, TypeError, RecursionError, MemoryError) as exc:
            problem = f"no value for {exc}" if isinstance(exc, KeyError) else str(exc)
            if isinstance(exc, SyntaxError):
                problem = "a value is not a Python literal"
            raise RecordingReadError(
                f"{recording.name}: metadata '{MODEL}' does not describe a brake ({problem})"
            ) from None
    scenario = recording.metadata_record(SCENARIO) or {}
    lines = [f"### Recording `{recording.path.name}`"]
    if scenario:
        name = scenario.get("name", "?")[:200]
        lines.append(f"scenario **{name}** from `{scenario.get('source', '?')[:1000]}`")
        if scenario.get("toml"):
            lines += ["", "```toml", scenario["toml"][:MAX_TEXT_CHARS].rstrip(), "```"]
    else:
        lines.append("(no scenario metadata in the recording)")
    return RecordingInfo(params=params, defects=defects, run_text="\n".join(lines))


def replay(recording: Recording, sinks: list[RerunSink]) -> ViewSummary:
    """Feed every message of the checked recording to ``sinks`` and close them.

    Raises:
        RecordingReadError: the file changed since it was checked, or a message holds
            values the sinks cannot show (which message, on which topic).
    """
    count = 0
    try:
        for message in recording.messages():
            try:
                decoded = cdr.decoder(message.topic.type_name)(message.data)
                for sink in sinks:
                    sink.write(message.topic, decoded, message.log_time_ns)
            except BrakeSimError as exc:
                raise RecordingReadError(
                    f"{recording.name}: message {message.index} on {message.topic.name}"
                    f" cannot be shown ({exc})"
                ) from None
            except (ValueError, TypeError, ArithmeticError, IndexError) as exc:
                raise RecordingReadError(
                    f"{recording.name}: message {message.index} on {message.topic.name}"
                    f" holds values that cannot be shown ({type(exc).__name__})"
                ) from None
            count += 1
    finally:
        for sink in sinks:
            sink.close()
    first = sinks[0] if sinks else None
    return ViewSummary(
        messages=count,
        samples=first.samples_logged if first else 0,
        states=first.states_logged if first else 0,
        first_s=None if first is None or first.first_ns is None else first.first_ns * 1e-9,
        last_s=None if first is None or first.last_ns is None else first.last_ns * 1e-9,
    )
