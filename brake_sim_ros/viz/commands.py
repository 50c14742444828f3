"""The Rerun parts of the command line: ``simulate --rerun ...``, ``view``, node ``--rerun``.

Kept here so the CLI (``cli/simulate.py``, ``cli/recordings.py``) and the node's ``main``
only add an option and a call; imported lazily (Rerun is only loaded when it is used).
"""

from __future__ import annotations

import argparse
import functools
import sys
import time
from pathlib import Path

from brake_sim_ros.scenarios import Scenario
from brake_sim_ros.viz.targets import (
    RerunTarget,
    RerunTargetError,
    check_target,
    has_display,
    open_sink,
    parse_target,
)


def parse_targets(option: list[list[str]] | None) -> list[RerunTarget]:
    """The parsed ``--rerun`` options (RerunTargetError for a bad one)."""
    targets = [parse_target(tokens) for tokens in option or []]
    for target in targets:
        check_target(target)
    return targets


def scenario_markdown(scenario: Scenario) -> str:
    """The run's description for the recording: name, source, scenario file."""
    text = [
        f"### Scenario **{scenario.name}**",
        "",
        scenario.description,
        f"source `{scenario.source}`",
    ]
    if scenario.text:
        text += ["", "```toml", scenario.text.rstrip(), "```"]
    return "\n".join(text)


def serve_until_interrupted(targets: list[RerunTarget]) -> None:
    """Keep a ``serve`` target's server up after the run, until Ctrl-C."""
    if any(t.kind == "serve" for t in targets):
        print("rerun: run logged; serving until Ctrl-C", file=sys.stderr)
        try:
            while True:
                time.sleep(1.0)
        except KeyboardInterrupt:
            pass


def open_simulation_sinks(scenario: Scenario, targets: list[RerunTarget]) -> list:
    """One Rerun sink per target for the offline stream of ``scenario``."""
    setup = scenario.setup
    return [
        open_sink(
            t, params=setup.params, defects=setup.defects, run_text=scenario_markdown(scenario)
        )
        for t in targets
    ]


def finish_simulation_sinks(sinks: list, targets: list[RerunTarget]) -> str:
    """Close ``sinks`` (serving until Ctrl-C for ``serve``); one line on what was logged where."""
    for sink in sinks:
        sink.close()
    serve_until_interrupted(targets)
    where = ", ".join(t.kind + (f" {t.arg}" if t.arg else "") for t in targets)
    first = sinks[0]
    return (
        f"rerun: {first.samples_logged} pivot-force samples, {first.states_logged} states,"
        f" impacts seen left {first.impacts['left']} right {first.impacts['right']} -> {where}"
    )


def cmd_view(args: argparse.Namespace) -> int:
    """``brake-sim view FILE.mcap [--save FILE.rrd [--overwrite]]``.

    The output is checked before the recording is read (not an existing file without
    ``--overwrite``, not a link, not the recording), the recording is checked whole before
    anything is shown, and the .rrd file appears only once complete
    (:func:`~brake_sim_ros.recording.output.atomic_output`).
    """
    from brake_sim_ros.recording.output import atomic_output, check_output
    from brake_sim_ros.recording.reader import open_recording
    from brake_sim_ros.viz.mcap_view import read_info, replay

    path = Path(args.recording)
    save_rules = {
        "inputs": [path],
        "overwrite": args.overwrite,
        "suffix": ".rrd",
        "option": "--save",
    }
    if args.save:
        check_output(args.save, **save_rules)
    elif not has_display():
        raise RerunTargetError(
            f"view {path}: no display here (DISPLAY/WAYLAND_DISPLAY unset) to open a viewer;"
            f" use --save FILE.rrd and open the file where there is one (rerun FILE.rrd)"
        )
    with open_recording(path) as recording:
        info = read_info(recording)
        opened = {"params": info.params, "defects": info.defects, "run_text": info.run_text}
        if args.save:
            with atomic_output(args.save, **save_rules) as partial:
                sink = open_sink(parse_target(["save", str(partial)]), **opened)
                summary = replay(recording, [sink])
        else:
            summary = replay(recording, [open_sink(parse_target(["spawn"]), **opened)])
    span = (
        f"{summary.first_s:.3f} s to {summary.last_s:.3f} s"
        if summary.first_s is not None and summary.last_s is not None
        else "no timed messages"
    )
    where = args.save or "a spawned viewer"
    print(
        f"{path}: {summary.messages} messages, {summary.samples} pivot-force samples,"
        f" {summary.states} states, {span} -> {where}"
    )
    return 0


def rerun_openers(targets: list[RerunTarget]) -> list:
    """Sink openers for :class:`~brake_sim_ros.ros.node.BrakeSimNode` (``sink_openers``),
    one Rerun sink per target.

    Each is called with the node once it is set up, before its first message; the drawing
    uses the model in force (the node's model parameters, ``--ros-args`` overrides included).
    Each sink logs on a thread of its own (:class:`~brake_sim_ros.stream.background.
    BackgroundSink`): its drawing would otherwise hold up the node's real-time ticks.
    """
    from brake_sim_ros.stream import parameters as ros_params
    from brake_sim_ros.stream.background import BackgroundSink

    def opener(node, target: RerunTarget):
        base = ros_params.model_values(node.scenario.setup.params, node.scenario.setup.defects)
        values = {name: node.get_parameter(name).value for name in base}
        params, defects = ros_params.build_model(values)
        sink = open_sink(
            target, params=params, defects=defects, run_text=scenario_markdown(node.scenario)
        )
        return BackgroundSink(sink)

    return [functools.partial(opener, target=target) for target in targets]
