"""``brake-sim scenarios``, ``defects`` and ``unit``: what the built-in scenarios, the defect
catalogue and a brake unit's manufacturing scatter hold, printed."""

from __future__ import annotations

import argparse
from typing import TYPE_CHECKING

from brake_sim_ros.cli.common import Command
from brake_sim_ros.errors import BrakeSimError

if TYPE_CHECKING:
    from brake_sim_ros.scenarios.types import Scenario


def cmd_scenarios(args: argparse.Namespace) -> int:
    from brake_sim_ros.scenarios import builtin_names, load_scenario

    if args.channels is not None:
        print(channels_text(load_scenario(args.channels)))
        return 0
    for name in builtin_names():
        print(f"{name:24s} {load_scenario(name).description}")
    return 0


def channels_text(scenario: Scenario) -> str:
    """The measured series of ``scenario``'s sensors: name, unit, rate, what and where,
    the transducer class and any sensor faults, a line each; one line saying why there
    are none when its fidelity plan builds no sensors."""
    from brake_sim_ros.stream.build import measures

    if not measures(scenario):
        return (
            f"scenario {scenario.name}: no measured channels: its [needs] do not ask"
            " 'measured_signals', so its fidelity plan builds no sensors (no structure);"
            " add it to [needs] outputs to measure"
        )
    rate = scenario.sample_rate_hz
    lines = [f"scenario {scenario.name}: sensors at {rate:g} Hz samples (unit, rate, kind)"]
    for c in scenario.sensors.channels:
        where = f"{c.location} {c.axis}".strip()
        faults = ", ".join(f"{f.kind} from {f.onset_s:g} s" for f in c.faults) or "no faults"
        for name in c.output_names:
            lines.append(
                f"  {name:28s} {c.unit:6s} {rate / c.decimation(rate):9g} Hz  {c.kind} at"
                f" {where}, {c.transducer.name}; {faults}"
            )
    return "\n".join(lines)


def scenarios_options(p: argparse.ArgumentParser) -> None:
    """``scenarios``' options."""
    p.add_argument(
        "--channels",
        metavar="NAME",
        help="list the measured sensor channels of scenario NAME (built-in or .toml), with"
        " units and rates",
    )
    p.set_defaults(func=cmd_scenarios)


def cmd_defects(args: argparse.Namespace) -> int:
    from brake_sim_ros.scenarios.defect_help import catalogue_text

    print(catalogue_text())
    return 0


def defects_options(p: argparse.ArgumentParser) -> None:
    """``defects`` takes no options."""
    p.set_defaults(func=cmd_defects)


def cmd_unit(args: argparse.Namespace) -> int:
    from brake_sim_ros.scenarios import load_scenario

    for flag, value in (("--seed", args.seed), ("--fleet-seed", args.fleet_seed)):
        if value is not None and not 0 <= value < 2**63:
            raise BrakeSimError(f"{flag} {value}: allowed an integer from 0 to 2^63 - 1")
    scenario = load_scenario(args.scenario).with_unit(
        args.unit_id, seed=args.seed, fleet_seed=args.fleet_seed
    )
    print(unit_text(scenario, sources=args.sources))
    return 0


def _shown(value: float, unit: str) -> tuple[float, str]:
    """A value in the unit a table shows it in (m as mm, Pa as GPa)."""
    scale = {"m": (1e3, "mm"), "Pa": (1e-9, "GPa")}.get(unit)
    return (value * scale[0], scale[1]) if scale else (value, unit)


def unit_text(scenario: Scenario, *, sources: bool = False) -> str:
    """A scenario's brake unit against the scenario's own values: per scattered parameter
    its nominal value, the unit's, the change and the tolerance, with units; with
    ``sources``, where each distribution comes from."""
    from brake_sim_ros.fleet.scatter import NOMINAL_UNIT

    values = scenario.unit_values()
    lines = [
        f"unit {scenario.unit_id} (fleet seed {scenario.fleet_seed}) of scenario {scenario.name}:"
        " manufacturing scatter, each a normal truncated at its tolerance"
        + (
            " (the nominal unit: the scenario's brake itself)"
            if scenario.unit_id == NOMINAL_UNIT
            else ""
        ),
        f"  {'parameter':46s} {'nominal':>12s} {'this unit':>12s} {'change':>10s}"
        f"  {'in':9s}  tolerance",
    ]
    for v in values:
        nominal, shown = _shown(v.nominal, v.unit)
        value, _ = _shown(v.value, v.unit)
        if v.scatter.mode == "relative":
            change = f"{100 * (v.value / v.nominal - 1):+.3f} %" if v.nominal else "-"
        else:
            change = f"{value - nominal:+.4g}"
        lines.append(
            f"  {v.key:46s} {nominal:12.6g} {value:12.6g} {change:>10s}  {shown:9s}"
            f"  {v.scatter.describe(v.unit)}"
        )
        if sources:
            lines.append(f"      {v.scatter.source}")
    if not sources:
        lines.append("  (where each distribution comes from: --sources)")
    for name, truth in scenario.conditions_record().items():
        low, high = truth["range"]
        lines.append(
            f"  condition {name} = {truth['value']:.6g} {truth['unit']} (drawn from"
            f" [{low:g}, {high:g}] with seed {scenario.seed})"
        )
    return "\n".join(lines)


def unit_options(p: argparse.ArgumentParser) -> None:
    """``unit``'s description and options."""
    from brake_sim_ros.identifiers import IDENTIFIER_RULE

    p.description = (
        "Print brake unit UNIT_ID's parameters against the scenario's own"
        " (nominal) values, with units and each distribution's tolerance. A unit is drawn"
        " from its id and the fleet seed (the same brake in every run); 'nominal' is the"
        " scenario's brake itself. The run's seed draws the scenario's [conditions]."
    )
    p.add_argument("unit_id", help=f"the unit's id: {IDENTIFIER_RULE}; or nominal")
    p.add_argument(
        "--fleet-seed",
        type=int,
        help="the fleet's seed, which draws units (default: the scenario's)",
    )
    p.add_argument(
        "--seed", type=int, help="the run's seed: its [conditions] (default: the scenario's)"
    )
    p.add_argument(
        "--scenario", default="symmetric", help="built-in name or .toml path (default symmetric)"
    )
    p.add_argument("--sources", action="store_true", help="say where each distribution comes from")
    p.set_defaults(func=cmd_unit)


SCENARIOS = Command("scenarios", "list the built-in scenarios", scenarios_options)
DEFECTS = Command(
    "defects", "list the defect catalogue: kinds, locations, units, valid ranges", defects_options
)
UNIT = Command(
    "unit",
    "a brake unit's manufacturing scatter: its parameters against the scenario's",
    unit_options,
)
