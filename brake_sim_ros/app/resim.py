"""``brake-sim resim REC.mcap --out NEW.mcap``: re-simulate a recorded run offline.

A recording of a live node (``brake-sim node --record``, ``brake-sim live``) holds what the
run was made of: the scenario file's text, the unit and seed, the model as the node's
parameters had it, the run settings, the node's parameters, every command that took
effect (``~/actuation``, ``~/drive``), each at the log time of the sample it took effect
at (:meth:`brake_sim_ros.ros.node.BrakeSimNode._record_command`), and every parameter
change the node accepted while it ran (``brake_sim_parameter_change`` records, at their
samples). :func:`resimulate` rebuilds the run from the recording alone (no other file is
read), steps it offline with the same commands and changes at the same samples through
the node's own run session (:class:`~brake_sim_ros.stream.session.RunSession`: the
command timeout, the live drive, a change of any run parameter of the table
:mod:`~brake_sim_ros.stream.run_parameters` or of the model), cut into the recording's own
chunks, and writes the node's stream (minus /diagnostics) to a new MCAP file with the same
metadata (``brake_sim_run`` mode ``resim``). With the same preset, the samples equal the
recording's bit for bit; the recorded samples are compared as they are re-simulated and
the result says where they first differ, if they do.

What it refuses, in one line, leaving nothing written: a file the checked reader
refuses (missing, not MCAP, damaged: :func:`~brake_sim_ros.recording.reader.
open_recording`), a recording without the simulator's metadata, one of several runs (a
``~/reset``), a command not stamped at a sample, a parameter change it does not
re-simulate (one of a run parameter fixed at start, which a node refuses, or of an
unknown name), a scenario or model the core refuses.
The output follows :mod:`brake_sim_ros.recording.output` (never an input, never through a
link, written whole or not at all).
"""

from __future__ import annotations

import ast
import json
import os
import time
from collections.abc import Iterator
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Any

import numpy as np

from brake_sim_ros import stream
from brake_sim_ros.errors import BrakeSimError, SimulationError
from brake_sim_ros.model.run_setup import SampleBlock
from brake_sim_ros.recording import cdr, metadata
from brake_sim_ros.recording.mcap_format import describe_path
from brake_sim_ros.recording.output import atomic_output, check_outputs
from brake_sim_ros.recording.reader import Recording, open_recording
from brake_sim_ros.recording.writer import McapRecorder, RecordingOptions
from brake_sim_ros.scenarios import Scenario
from brake_sim_ros.scenarios.loader import parse_scenario
from brake_sim_ros.stream import Topic, conversion, run_parameters
from brake_sim_ros.stream.build import require_measured
from brake_sim_ros.stream.commands import drive_command
from brake_sim_ros.stream.run_parameters import Change
from brake_sim_ros.stream.session import RunSession

_PIVOT = stream.PIVOT_FORCES.type_name
_ACTUATION = stream.ACTUATION.type_name
_DRIVE = stream.DRIVE.type_name
_DEFECTS = stream.DEFECTS.type_name
_NEEDED = (metadata.SCENARIO, metadata.UNIT, metadata.RUN, metadata.MODEL)


class ResimError(BrakeSimError, ValueError):
    """A recording that cannot be re-simulated (one line: the file, what, what is allowed)."""


@dataclass(frozen=True)
class RecordedCommand:
    """A command that took effect: at ``sample`` (the first sample it holds for), the
    decoded ``msg`` on ``topic`` as recorded, ``log_time_ns`` its stamp."""

    sample: int
    topic: Topic
    msg: Any
    log_time_ns: int


@dataclass(frozen=True)
class RecordedChange:
    """Parameters the node accepted while it ran: from ``sample`` on, ``values`` (new
    values by parameter name)."""

    sample: int
    values: dict[str, Any]


@dataclass
class RecordedRun:
    """A recorded run, rebuilt from its recording (:func:`read_run`).

    Attributes:
        scenario: the scenario from the recorded text, as the recorded unit and seed.
        setup_values: the recorded model (flat ROS values), for a live run.
        start: the run parameters at the start (:func:`.run_parameters.start_values`).
        run: the ``brake_sim_run`` record; ``records``: the scenario, unit, run, model
            and (live) ROS parameter records, as read.
        chunks: ``(first sample, samples)`` of every recorded PivotForceChunk, in order,
            contiguous from sample 0.
        commands: the recorded commands in log-time order (file order within a time).
        changes: the parameter changes recorded (``brake_sim_parameter_change``), in order.
        pivot_topic: the recorded PivotForceChunk topic (its name as recorded).
        name: the recording's file name, for messages.
        mode: how the run was made: ``live`` (a node: its model from its parameters) or
            ``offline`` (the scenario's own setup); a re-simulation's is its source's.
    """

    scenario: Scenario
    setup_values: dict[str, Any] | None
    start: dict[str, Any]
    run: dict[str, str]
    records: dict[str, dict[str, str]]
    chunks: list[tuple[int, int]] = field(default_factory=list)
    commands: list[RecordedCommand] = field(default_factory=list)
    changes: list[RecordedChange] = field(default_factory=list)
    pivot_topic: str = stream.PIVOT_FORCES.name
    name: str = "recording"
    mode: str = "live"

    @property
    def samples(self) -> int:
        first, n = self.chunks[-1]
        return first + n


def _literal(value: str, where: str) -> Any:
    try:
        return ast.literal_eval(value)
    except (ValueError, SyntaxError, TypeError, MemoryError, RecursionError):
        raise ResimError(f"{where} = {value[:60]!r}: allowed a Python literal") from None


def _run_value(run: dict[str, str], key: str, name: str, kinds: tuple[type, ...]) -> Any:
    if key not in run:
        raise ResimError(f"{name}: its {metadata.RUN} record has no {key!r}")
    value = _literal(run[key], f"{name}: {metadata.RUN} {key}")
    if isinstance(value, bool) != (bool in kinds) or not isinstance(value, kinds):
        raise ResimError(f"{name}: {metadata.RUN} {key} = {run[key][:60]!r}: not a {kinds[0]}")
    return value


def _start_values(records: dict[str, dict[str, str]], name: str) -> dict[str, Any]:
    """The run parameters at the start (:func:`.run_parameters.start_values`): the run
    record's (strings as they are, the rest Python literals), a live node's parameters."""
    table = run_parameters.by_name()
    run = {
        k: v if isinstance(table[k].default, str) else _literal(v, f"{name}: {metadata.RUN} {k}")
        for k, v in records[metadata.RUN].items()
        if k in table
    }
    recorded = records.get(metadata.ROS_PARAMETERS)
    parameters = None
    if recorded is not None:
        parameters = {
            k: _literal(v, f"{name}: parameter {k}") for k, v in recorded.items() if k in table
        }
    try:
        return run_parameters.start_values(run, parameters, name)
    except BrakeSimError as exc:
        raise ResimError(str(exc)) from None


def _scenario(records: dict[str, dict[str, str]], name: str) -> Scenario:
    """The recorded scenario text, parsed, as the recorded unit and seed."""
    recorded = records[metadata.SCENARIO]
    text = recorded.get("toml")
    if text is None:
        raise ResimError(f"{name}: its {metadata.SCENARIO} record has no scenario text ('toml')")
    source = f"{name} (recorded scenario {recorded.get('source', '?')[:80]})"
    scenario = parse_scenario(text, source)
    if recorded.get("sha256", scenario.digest) != scenario.digest:
        raise ResimError(f"{name}: the recorded scenario text does not match its sha256")
    unit = records[metadata.UNIT]
    unit_id = unit.get("unit_id", scenario.unit_id)
    seed = _literal(unit.get("seed", repr(scenario.seed)), f"{name}: {metadata.UNIT} seed")
    fleet = _literal(
        unit.get("fleet_seed", repr(scenario.fleet_seed)), f"{name}: {metadata.UNIT} fleet_seed"
    )
    if (unit_id, seed, fleet) != (scenario.unit_id, scenario.seed, scenario.fleet_seed):
        scenario = scenario.with_unit(unit_id, seed=seed, fleet_seed=fleet)
    if "solver" in recorded:  # recordings before it ran with the text's own settings
        scenario = _recorded_solver(scenario, recorded["solver"], name)
    return scenario


_SOLVER_KINDS = {
    "preset": (str,),
    "method": (str,),
    "max_step_s": (float,),
    "sample_rate_hz": (float, int),
}


def _recorded_solver(scenario: Scenario, text: str, name: str) -> Scenario:
    """``scenario`` with the recorded solver settings and sample rate (the options the run
    was made with over its text), each checked as a scenario's own would be."""
    where = f"{name}: {metadata.SCENARIO} solver"
    try:
        values = json.loads(text)
    except (ValueError, RecursionError):
        raise ResimError(f"{where}: not JSON: allowed what brake-sim records") from None
    if not isinstance(values, dict) or set(values) != set(_SOLVER_KINDS):
        raise ResimError(f"{where}: allowed the keys {', '.join(_SOLVER_KINDS)}")
    for key, kinds in _SOLVER_KINDS.items():
        if isinstance(values[key], bool) or not isinstance(values[key], kinds):
            raise ResimError(f"{where} {key}: allowed a {kinds[0].__name__}")
    try:
        return scenario.with_solver(**values)
    except BrakeSimError as exc:
        raise ResimError(f"{where}: {exc}") from None


def _sample_of(ns: int, rate: Fraction, period_s: float, where: str) -> int:
    """The sample index whose stamp is ``ns`` (ResimError if none is)."""
    sample = round(Fraction(ns) * rate / 1_000_000_000)
    if sample < 0 or conversion.stamp_ns(sample, period_s) != ns:
        raise ResimError(f"{where}: log time {ns} ns is no sample's time: allowed a sample's")
    return sample


def read_run(recording: Recording) -> RecordedRun:
    """Everything :func:`resimulate` needs from a checked recording.

    Raises:
        ResimError: what the module doc lists (one line naming the file).
        ScenarioError, ParameterError: the recorded scenario or unit refused by the core.
    """
    name = recording.name
    records = {}
    for record_name in (*_NEEDED, metadata.ROS_PARAMETERS):
        record = recording.metadata_record(record_name)
        if record is not None:
            records[record_name] = record
    missing = [r for r in _NEEDED if r not in records]
    if missing:
        raise ResimError(
            f"{name}: no {', '.join(missing)} metadata: allowed a recording brake-sim made"
            " (brake-sim node --record, brake-sim live, brake-sim simulate --mcap)"
        )
    run = records[metadata.RUN]
    mode = run.get("mode")
    if mode == "resim":  # a re-simulation re-simulates as the run it came from
        mode = run.get("recorded_mode")
    if mode not in ("live", "offline"):
        raise ResimError(
            f"{name}: {metadata.RUN} mode {str(mode)[:20]!r}: allowed live, offline, resim"
        )
    scenario = _scenario(records, name)
    period = scenario.sample_period_s
    if _run_value(run, "sample_period_s", name, (float,)) != period:
        raise ResimError(f"{name}: the recorded sample period differs from its scenario's")
    run_id = run.get("run_id", "")
    setup_values = None
    if mode == "live":  # the node's model: its parameters at the start
        setup_values = {
            k: _literal(v, f"{name}: {metadata.MODEL} {k}")
            for k, v in records[metadata.MODEL].items()
        }
    out = RecordedRun(
        scenario=scenario,
        setup_values=setup_values,
        start=_start_values(records, name),
        run=run,
        records=records,
        name=name,
        mode=mode,
    )
    rate = Fraction(conversion.sample_rate_hz(period))
    channels = recording.channels.values()
    pivot_topics = {c.topic.name for c in channels if c.topic.type_name == _PIVOT}
    if len(pivot_topics) != 1:
        raise ResimError(
            f"{name}: {len(pivot_topics)} PivotForceChunk topics: allowed the recording of"
            " one node (one topic)"
        )
    out.pivot_topic = pivot_topics.pop()
    decoders = {t: cdr.decoder(t) for t in (_PIVOT, _ACTUATION, _DRIVE, _DEFECTS)}
    wanted = {
        c.topic.name
        for c in recording.channels.values()
        if c.topic.type_name in decoders and c.topic.type_name != _PIVOT
    } | {out.pivot_topic}
    next_sample = 0
    for message in recording.messages(topics=wanted):
        type_name = message.topic.type_name
        msg = decoders[type_name](message.data)
        where = f"{name}: {message.topic.name} message {message.index}"
        if type_name == _PIVOT:
            first, n = int(msg.first_sample_index), len(msg.left_fx_n)
            if first != next_sample:
                raise ResimError(
                    f"{where}: samples from {first} where {next_sample} was next (a ~/reset or"
                    " a gap): allowed one run recorded from its first sample to its last"
                )
            out.chunks.append((first, n))
            next_sample = first + n
        elif type_name == _DEFECTS:
            if msg.run_id != run_id:
                raise ResimError(
                    f"{where}: run {msg.run_id[:64]!r} after run {run_id[:64]!r} (a ~/reset):"
                    " allowed a recording of one run"
                )
        else:
            sample = _sample_of(message.log_time_ns, rate, period, where)
            out.commands.append(RecordedCommand(sample, message.topic, msg, message.log_time_ns))
    if not out.chunks:
        raise ResimError(f"{name}: no samples recorded: nothing to re-simulate")
    for record_name, record in recording.metadata:
        if record_name != metadata.PARAMETER_CHANGE:
            continue
        where = f"{name}: {metadata.PARAMETER_CHANGE}"
        values = {k: _literal(v, f"{where} {k[:64]}") for k, v in record.items()}
        sample = values.pop("sample_index", None)
        if isinstance(sample, bool) or not isinstance(sample, int) or sample < 0:
            raise ResimError(f"{where}: sample_index {sample!r}: allowed a sample index >= 0")
        out.changes.append(RecordedChange(sample, values))
    return out


@dataclass
class Comparison:
    """The re-simulated samples against the recorded ones (pivot forces, every sample)."""

    samples: int = 0
    first_difference: int | None = None
    column: str = ""

    def describe(self) -> str:
        if self.first_difference is None:
            return f"{self.samples} samples equal to the recording's, bit for bit"
        return (
            f"samples differ from the recording's from sample {self.first_difference}"
            f" ({self.column}): another preset or model, a recording made before parameter"
            " changes were recorded, or another software version"
        )

    def check(self, recorded: Any, block: SampleBlock) -> None:
        """Compare one recorded PivotForceChunk with the block re-simulated for it."""
        self.samples += len(block)
        if self.first_difference is not None:
            return
        ours = conversion.pivot_force_chunk(block)
        for column in conversion.PIVOT_CHUNK_ARRAYS:
            a = np.asarray(getattr(recorded, column), dtype=float)
            b = np.asarray(getattr(ours, column), dtype=float)
            n = min(len(a), len(b))
            # bits, not values: -0.0 against 0.0, or one NaN against another, is a difference
            differ = np.flatnonzero(a[:n].view(np.int64) != b[:n].view(np.int64))
            if len(a) != len(b) or len(differ):
                at = int(differ[0]) if len(differ) else n
                self.first_difference = block.first_index + at
                self.column = column
                return


@dataclass
class Resimulation:
    """What :func:`resimulate` wrote and found."""

    path: str
    messages: int
    commands: int
    comparison: Comparison
    cpu_s: float
    sim_s: float

    def describe(self) -> str:
        return (
            f"re-simulated {self.sim_s:g} s with {self.commands} recorded commands in"
            f" {self.cpu_s:.2f} s CPU: {self.path} ({self.messages} messages);"
            f" {self.comparison.describe()}"
        )


def _change(session: RunSession, run: RecordedRun, change: RecordedChange) -> list:
    """Apply a recorded parameter change through the session; refused in one line when a
    node could not have made it (a run parameter fixed at start, an unknown name)."""
    table = run_parameters.by_name()
    for key in change.values:
        if (key in table and table[key].changes is Change.ANY_TIME) or key in session.model:
            continue
        why = "fixed at start-up, a node refuses it" if key in table else "unknown"
        raise ResimError(
            f"{run.name}: parameter {key[:64]!r} set at sample {change.sample}: not"
            f" re-simulated ({why}; allowed: the model's and the run parameters a node may"
            " change while it runs)"
        )
    return session.apply(change.values)


def _command(session: RunSession, command: RecordedCommand) -> tuple:
    msg = command.msg
    if command.topic.type_name == _ACTUATION:
        session.planner.command((float(msg.left_force_n), float(msg.right_force_n)), command.sample)
        topic = stream.ACTUATION
    else:
        drive, reason = drive_command(msg.mode, msg.drive_torque_n_m, msg.target_speed_m_s)
        if drive is None:
            raise ValueError(f"recorded drive command refused: {reason}")
        session.drive(drive)
        topic = stream.DRIVE
    return topic, msg, command.log_time_ns  # the decoded message encodes as it was


def _apply(session: RunSession, run: RecordedRun, event: RecordedCommand | RecordedChange) -> list:
    """Apply one recorded event from its sample on; the messages it makes."""
    try:
        if isinstance(event, RecordedChange):
            return _change(session, run, event)
        return [_command(session, event)]
    except ResimError:
        raise
    except (BrakeSimError, ValueError, TypeError, ArithmeticError) as exc:
        raise ResimError(f"{run.name}: at sample {event.sample}: {exc}") from None


def _messages(
    run: RecordedRun,
    session: RunSession,
    *,
    recorded_chunks: Iterator[Any],
    comparison: Comparison,
) -> Iterator[tuple[Topic, Any, int]]:
    """The node's stream for ``run``: its commands and parameter changes applied at their
    samples, the samples cut into the recording's chunks."""
    yield from session.start()
    events: list[RecordedCommand | RecordedChange] = sorted(
        [*run.commands, *run.changes], key=lambda e: e.sample
    )
    k = 0
    for first, n in run.chunks:
        end = first + n
        blocks = []
        while session.sample_index < end:
            at = session.sample_index
            while k < len(events) and events[k].sample <= at:
                yield from _apply(session, run, events[k])
                k += 1
            stop = events[k].sample if k < len(events) else end
            try:
                blocks.append(session.advance(min(stop, end) - at))
            except SimulationError:
                raise ResimError(
                    f"non-finite or missing samples between samples {first} and {end}"
                ) from None
        block = blocks[0] if len(blocks) == 1 else SampleBlock.concatenate(blocks)
        comparison.check(next(recorded_chunks), block)
        yield from session.messages(block)
    for event in events[k:]:  # after the last sample: recorded, nothing to step
        yield from _apply(session, run, event)
    yield from session.flush()


def resimulate(
    source: str | os.PathLike[str],
    out: str | os.PathLike[str],
    *,
    preset: str | None = None,
    measured: bool | None = None,
    overwrite: bool = False,
    compression: str = "zstd",
) -> Resimulation:
    """Re-simulate the run recorded in ``source`` into the new MCAP file ``out``.

    Args:
        preset: another solver preset (None: the recorded scenario's).
        measured: run the scenario's sensors and record ~/measured (None: as the run did).
        overwrite: replace an existing ``out`` (never an input, never a link).

    Raises:
        BrakeSimError: one line, nothing written (OutputError, RecordingReadError,
            ResimError, ScenarioError, ...).
    """
    check_outputs([("--out", out, {".mcap": ""})], inputs=[source], overwrite=overwrite)
    cpu0 = time.process_time()
    with open_recording(source) as recording:
        run = read_run(recording)
        scenario = run.scenario
        if preset is not None:
            scenario = scenario.with_solver(preset=preset)
        settings = dict(run.start)
        if measured is not None:
            settings["publish_measured"] = measured
        if settings["publish_measured"]:
            require_measured(scenario, "--measured")
        session = RunSession(
            scenario,
            settings=settings,
            model=run.setup_values,
            run_id=run.run.get("run_id", ""),
        )
        session.settings["duration_s"] = run.samples * session.period_s
        records = dict(run.records)
        records[metadata.SCENARIO] = {  # the settings it now runs with (--preset)
            **records[metadata.SCENARIO],
            "solver": json.dumps(metadata.solver_values(scenario)),
        }
        records[metadata.RUN] = metadata.run_record(
            session,
            mode="resim",
            extra={"resimulated_from": describe_path(source), "recorded_mode": run.mode},
        )
        decode = cdr.decoder(_PIVOT)
        recorded_chunks = (decode(m.data) for m in recording.messages(topics=[run.pivot_topic]))
        comparison = Comparison()
        with atomic_output(
            out, inputs=[source], overwrite=overwrite, suffix=".mcap", option="--out"
        ) as partial:
            recorder = McapRecorder(
                partial,
                records=records,
                options=RecordingOptions(compression=compression, durable=False),
                custom_data=metadata.custom_data(session, "resim"),
            )
            try:
                for change in run.changes:  # for a re-simulation of this one
                    recorder.parameter_change(
                        change.values,
                        change.sample,
                        conversion.stamp_ns(change.sample, session.period_s),
                    )
                for topic, msg, ns in _messages(
                    run, session, recorded_chunks=recorded_chunks, comparison=comparison
                ):
                    recorder.write(topic, msg, ns)
            finally:
                recorder.close()
    return Resimulation(
        path=str(out),
        messages=recorder.stats.messages,
        commands=len(run.commands),
        comparison=comparison,
        cpu_s=time.process_time() - cpu0,
        sim_s=run.samples * session.period_s,
    )
