"""Where a defect kind of the catalogue must reach with no edit of its own: the scenario
loader, the node's parameters, a campaign's defect axis, the label columns, ``brake-sim
defects`` and the packing of the kernels' parameters. Shared by the completeness test over
every entry (tests/model/test_catalogue.py) and the kind a test registers
(tests/model/test_defect_registry.py)."""

from __future__ import annotations

import contextlib
import dataclasses
import io
import tempfile
from pathlib import Path

from pytest import approx

from brake_sim_ros.campaigns.axes import defect_choices, defects_table
from brake_sim_ros.campaigns.campaign import plan_runs
from brake_sim_ros.campaigns.loader import parse_campaign
from brake_sim_ros.cli import main
from brake_sim_ros.model import catalogue
from brake_sim_ros.model.assembly import pack
from brake_sim_ros.model.catalogue import DefectKind, label_column, label_columns
from brake_sim_ros.model.defects import Defects
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.scenarios import parse_scenario
from brake_sim_ros.stream import parameters as ros_params

CAMPAIGN = """
name = "reach"
base = "symmetric"
seed = 3
units = 3
[outputs]
duration_s = 0.2
sample_rate_hz = 2560.0
[[axes]]
defects = ["{kind}"]
severities = [0.5]
healthy = false
"""


def brake_of(kind: DefectKind) -> str:
    """The brake that carries ``kind``: the service brake for a kind only it has (the
    hydraulic line's, the self-adjuster's: the study brake refuses them), else the study
    brake."""
    return "service" if kind.service_only else "study"


def _params(kind: DefectKind) -> BrakeParameters:
    return BrakeParameters.of_brake(brake_of(kind))


def _toml(table: dict, prefix: str) -> str:
    lines = [f"[{prefix}]"]
    nested = []
    for key, value in table.items():
        if isinstance(value, dict):
            nested.append(_toml(value, f"{prefix}.{key}"))
        elif isinstance(value, list):
            for row in value:
                items = ", ".join(f"{k} = {v!r}" for k, v in row.items())
                nested.append(f"[[{prefix}.{key}]]\n" + items.replace(", ", "\n"))
        else:
            lines.append(f"{key} = {float(value)!r}")
    return "\n".join(lines + nested)


def reaches_labels(kind: DefectKind) -> None:
    for location in kind.locations:
        assert label_column(kind, location) in label_columns()


def reaches_the_loader(kind: DefectKind) -> None:
    """A scenario that states the kind at half its service limit, in the keys the
    catalogue gives it, loads to that defect."""
    severity = 0.5 * kind.service_limit
    for location in kind.locations:
        defects = Defects.single(kind.name, location, severity)
        text = f'name = "reach"\nbrake = "{brake_of(kind)}"\nduration_s = 0.2\n'
        text += _toml(defects_table(defects), "defects")
        loaded = parse_scenario(text, "reach.toml").setup.defects
        assert loaded == defects, text
        assert loaded.severities()[label_column(kind, location)] == approx(severity, abs=1e-12)


def reaches_the_node_parameters(kind: DefectKind) -> None:
    """Each of its fields is a node parameter with the field's range, and a value set
    there builds the defect."""
    params = _params(kind)
    specs = {s.name: s for s in ros_params.model_parameter_specs(params, Defects())}
    if kind.table:
        assert not any(kind.scenario_key in name for name in specs)
        return
    for location in kind.locations:
        for f in kind.fields():
            spec = specs[f"defects.{location}.{f.name}"]
            assert spec.range == (f.low, f.high)
            assert kind.name in spec.description
        defects = Defects.single(kind.name, location, 0.5 * kind.service_limit)
        values = ros_params.model_values(params, defects)
        assert ros_params.build_model(values)[1] == defects


def reaches_a_campaign_axis(kind: DefectKind) -> None:
    """A campaign's defect axis over the kind plans runs that carry it and its labels."""
    choices = defect_choices((kind.name,), (0.5,), healthy=False)
    assert {c.location for c in choices} == set(kind.locations)
    with tempfile.TemporaryDirectory() as directory:  # the base scenario on its brake
        base = Path(directory, "base.toml")
        base.write_text(f'name = "base"\nbrake = "{brake_of(kind)}"\nduration_s = 1.0\n')
        text = CAMPAIGN.format(kind=kind.name).replace('"symmetric"', '"base.toml"')
        runs = plan_runs(parse_campaign(text, "reach.toml", Path(directory)))
    assert {r.columns["defect_location"] for r in runs} == set(kind.locations)
    for run in runs:
        column = label_column(kind, run.columns["defect_location"])
        assert run.labels[column] == approx(0.5 * kind.service_limit, abs=1e-12)


def reaches_the_cli_help(kind: DefectKind) -> None:
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        assert main(["defects"]) == 0
    text = out.getvalue()
    assert f"  {kind.name} [{kind.unit}]" in text
    for f in kind.fields():
        assert f.name in text


@contextlib.contextmanager
def _spied(kind: DefectKind) -> list:
    """The kind's entry with its packing recorded: each call's (location, defect)."""
    calls: list = []

    def spy(site) -> None:
        calls.append((site.location, site.defect))
        kind.packing(site)

    at = catalogue.KINDS.index(kind)
    catalogue.KINDS[at] = catalogue.KIND_BY_NAME[kind.name] = dataclasses.replace(kind, packing=spy)
    try:
        yield calls
    finally:
        catalogue.KINDS[at] = catalogue.KIND_BY_NAME[kind.name] = kind


def reaches_the_packing(kind: DefectKind) -> None:
    """Packing a brake that carries the kind calls the entry's packing at its location,
    with that location's defects (what a built-in packing writes: tests/model/test_catalogue.py)."""
    for location in kind.locations:
        defects = Defects.single(kind.name, location, 0.5 * kind.service_limit)
        with _spied(kind) as calls:
            pack(_params(kind), defects)
        assert (location, getattr(defects, location)) in calls, calls


def reaches_everything(kind: DefectKind) -> None:
    reaches_labels(kind)
    reaches_the_loader(kind)
    reaches_the_node_parameters(kind)
    reaches_a_campaign_axis(kind)
    reaches_the_cli_help(kind)
    reaches_the_packing(kind)
