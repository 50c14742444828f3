"""``brake-sim bench fidelity``: cost of every fidelity level and its error against the full
model on the same scenario.

For each level (and the one-shoe impact model) the scenario is run with needs that force
that level and ask for everything it delivers; the figures are CPU seconds per simulated
second (best of ``repeats``), the real-time factor, and relative errors against the full
model: stop time, first-impact peak pivot force and impact period (both shoes, the worse
one), contact-regime mean pivot force (both shoes, the worse one), the impact count
difference (impacts missed or added, summed over the shoes), all as
:mod:`brake_sim_ros.analysis.comparison` defines them for the accuracy study too, and the
residual of the level's own energy balance (:mod:`brake_sim_ros.analysis.energy`). NaN
where a level does not deliver that output.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

from brake_sim_ros.analysis.comparison import metric_errors, relative_error
from brake_sim_ros.analysis.energy import ENERGY_COLUMNS, energy_balance
from brake_sim_ros.command_line import Parser
from brake_sim_ros.model.fidelity import LEVELS, Needs
from brake_sim_ros.model.layout import SIDES
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.scenarios.types import Scenario
from brake_sim_ros.stream.run import RunResult, run_scenario

TARGET_CONTACT_X_REAL_TIME = 1000.0
TARGET_CONTACT_REL = 0.01
NAN = float("nan")


def energy_residual(result: RunResult, scenario: Scenario) -> float:
    """The run's energy-balance residual over its initial stored energy
    (:attr:`~brake_sim_ros.analysis.energy.EnergyBalance.relative_residual`); NaN where the
    level did not keep every column of the balance."""
    b = result.samples
    if len(b) == 0 or not b.has(*ENERGY_COLUMNS):
        return NAN
    return energy_balance(b, scenario.setup.params).relative_residual


def _forced(scenario: Scenario, level: str, shoes: tuple[str, ...]) -> Scenario:
    outputs = next(lv for lv in LEVELS if lv.name == level).outputs
    needs = Needs(outputs=tuple(sorted(outputs)), shoes=shoes, level=level)
    return dataclasses.replace(scenario, needs=needs)


def _best_run(scenario: Scenario, repeats: int) -> RunResult:
    best: RunResult | None = None
    for _ in range(repeats):
        r = run_scenario(scenario)
        if best is None or r.cpu_s < best.cpu_s:
            best = r
    assert best is not None
    return best


def _row(
    scheme: str, setting: str, r: RunResult, ref: RunResult, duration: float, scenario: Scenario
) -> dict[str, Any]:
    sides = tuple(s for s in SIDES if s in r.plan.shoes)
    errors = metric_errors(r.metrics, ref.metrics, sides)
    impacts = "impacts" in r.plan.level.outputs
    cpu = r.cpu_s / duration
    return {
        "scheme": scheme,
        "setting": setting,
        "cpu_s_per_sim_s": cpu,
        "x_real_time": 1.0 / cpu if cpu > 0 else math.inf,
        "err_stop_time": errors.stop_time,
        "err_first_peak": errors.first_peak if impacts else NAN,
        "err_period": errors.period if impacts else NAN,
        "impact_count_diff": errors.impact_count_diff if impacts else -1,
        "err_contact_force": errors.contact_force,
        "energy_residual": energy_residual(r, scenario),
        "memory_bytes": r.memory_bytes,
        "model_stop_err": relative_error(r.model_stop_time_s, ref.metrics.stop_time_s),
    }


def fidelity_rows(
    scenario_name: str = "symmetric", *, repeats: int = 3, accuracy: str | None = None
) -> list[dict[str, Any]]:
    """One row per fidelity level on ``scenario_name`` (format shared with the accuracy
    study; ``impact_count_diff`` is -1 where the level has no impacts; extra keys:
    ``memory_bytes``, what the run kept, and ``model_stop_err``, the error of the instant
    the level's model locked even where the level does not deliver the stop time)."""
    scenario = load_scenario(scenario_name)
    duration = scenario.duration_s
    runs: list[tuple[str, str, Scenario]] = []
    for level in reversed(LEVELS):  # full first: it is the reference
        forced = _forced(scenario, level.name, SIDES)
        if accuracy is not None:
            forced = dataclasses.replace(
                forced, needs=dataclasses.replace(forced.needs, accuracy=accuracy)
            )
        runs.append((f"level {level.name}", f"{scenario_name}", forced))
    one_shoe = dataclasses.replace(
        scenario, needs=Needs(outputs=("impacts", "contact_regime_forces"), shoes=("left",))
    )
    runs.append(("level full, left shoe only", scenario_name, one_shoe))
    rows = []
    ref: RunResult | None = None
    for scheme, setting, sc in runs:
        r = _best_run(sc, repeats)
        ref = ref or r
        rows.append(_row(scheme, setting, r, ref, duration, scenario))
    return rows


def _fmt(x: float, pct: bool = True) -> str:
    if isinstance(x, float) and math.isnan(x):
        return "-"
    return f"{100 * x:.2g} %" if pct else f"{x:.2e}"


def main(argv: list[str] | None = None) -> int:
    parser = Parser(prog="brake-sim bench fidelity", description=__doc__)
    parser.add_argument("--scenario", action="append", help="scenario(s); default symmetric")
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--accuracy", choices=("fast", "balanced", "accurate"))
    args = parser.parse_args(argv)
    for name in args.scenario or ["symmetric"]:
        rows = fidelity_rows(name, repeats=args.repeats, accuracy=args.accuracy)
        print(f"\nscenario {name} (errors relative to the full model; - = not delivered)")
        print(
            "level | CPU s per sim s | x real time | stop time err | first peak err |"
            " period err | impact count diff | contact-regime F_r err | energy residual |"
            " kept samples"
        )
        print("---|---|---|---|---|---|---|---|---|---")
        for r in rows:
            count = "-" if r["impact_count_diff"] < 0 else str(r["impact_count_diff"])
            stop = _fmt(r["err_stop_time"])
            if stop == "-" and math.isfinite(r["model_stop_err"]):
                stop = f"- (its model: {_fmt(r['model_stop_err'])})"
            print(
                f"{r['scheme']} | {r['cpu_s_per_sim_s']:.3g} | {r['x_real_time']:.0f} |"
                f" {stop} | {_fmt(r['err_first_peak'])} |"
                f" {_fmt(r['err_period'])} | {count} | {_fmt(r['err_contact_force'])} |"
                f" {_fmt(r['energy_residual'], pct=False)} | {r['memory_bytes'] / 1e6:.2f} MB"
            )
        contact = next(r for r in rows if r["scheme"] == "level contact_regime")
        ok = (
            contact["x_real_time"] >= TARGET_CONTACT_X_REAL_TIME
            and contact["err_stop_time"] <= TARGET_CONTACT_REL
            and contact["err_contact_force"] <= TARGET_CONTACT_REL
        )
        print(
            f"contact-regime target (>= {TARGET_CONTACT_X_REAL_TIME:.0f}x real time, stop time"
            f" and contact-regime F_r within {100 * TARGET_CONTACT_REL:g} %):"
            f" {'met' if ok else 'NOT met'}"
        )
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
