"""``brake-sim view FILE.mcap``: a recording of the simulator's stream, shown in Rerun.

Messages are decoded with ``mcap_ros2`` and handed, in log-time order, to the same
:class:`~.rerun_sink.RerunSink` the node and the offline simulator use. The drawing's
geometry comes from the recording's ``brake_sim_model`` metadata (``model_values`` of
the run, values as ``repr`` strings); without it the built-in geometry is drawn and the
event log says so. ``brake_sim_scenario`` metadata (name, source, toml) is shown as the
run's description.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from pathlib import Path

from mcap.exceptions import McapError
from mcap.reader import make_reader
from mcap_ros2.decoder import DecoderFactory

from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.model.defects import Defects
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.ros import parameters as ros_params
from brake_sim_ros.ros.stream import Topic
from brake_sim_ros.viz.rerun_sink import RerunSink

MODEL_METADATA = "brake_sim_model"
SCENARIO_METADATA = "brake_sim_scenario"


class RecordingError(BrakeSimError, ValueError):
    """An MCAP file that cannot be shown (missing, not MCAP, bad metadata)."""


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


def read_info(path: Path) -> RecordingInfo:
    """The model and scenario metadata of an MCAP recording.

    Raises:
        RecordingError: not a readable MCAP file, or model metadata the core refuses.
    """
    if not path.is_file():
        raise RecordingError(f"{path}: no such file")
    try:
        with path.open("rb") as f:
            metadata = {m.name: dict(m.metadata) for m in make_reader(f).iter_metadata()}
    except (McapError, ValueError, OSError) as exc:
        raise RecordingError(f"{path}: not a readable MCAP file ({exc})") from None
    params = defects = None
    model = metadata.get(MODEL_METADATA)
    if model is not None:
        try:
            values = {k: ast.literal_eval(v) for k, v in model.items()}
            params, defects = ros_params.build_model(values)
        except (ValueError, SyntaxError, KeyError, TypeError) as exc:
            raise RecordingError(
                f"{path}: metadata '{MODEL_METADATA}' does not describe a brake ({exc})"
            ) from None
    scenario = metadata.get(SCENARIO_METADATA, {})
    lines = [f"### Recording `{path.name}`"]
    if scenario:
        lines.append(
            f"scenario **{scenario.get('name', '?')}** from `{scenario.get('source', '?')}`"
        )
        if scenario.get("toml"):
            lines += ["", "```toml", scenario["toml"].rstrip(), "```"]
    else:
        lines.append("(no scenario metadata in the recording)")
    return RecordingInfo(params=params, defects=defects, run_text="\n".join(lines))


def replay(path: Path, sinks: list[RerunSink]) -> ViewSummary:
    """Feed every message of the recording to ``sinks`` and close them.

    Raises:
        RecordingError: the file cannot be read or decoded.
    """
    count = 0
    try:
        with path.open("rb") as f:
            reader = make_reader(f, decoder_factories=[DecoderFactory()])
            for schema, channel, message, decoded in reader.iter_decoded_messages(
                log_time_order=True
            ):
                topic = Topic(channel.topic, schema.name if schema else "")
                for sink in sinks:
                    sink.write(topic, decoded, int(message.log_time))
                count += 1
    except (McapError, ValueError, KeyError, OSError) as exc:
        raise RecordingError(f"{path}: cannot read its messages ({exc})") from None
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
