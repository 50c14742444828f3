"""``brake-sim severity``: each defect of the catalogue swept from healthy to a size seen
in service, and how a few signal features move, so a user sees what is detectable and
from what size.

For every kind the brake carries (:data:`~brake_sim_ros.model.catalogue.KINDS`; the line's
and the seized adjuster's on the service brake) and location, the symmetric scenario on
the ``--brake`` named (default the service brake, the product's; ``study`` for the
published brake) is run with that one defect at :data:`STEPS` fractions of the kind's
service limit (0, 20, ..., 100 %; ``Defects.single``), for ``--duration`` simulated
seconds. A size the brake cannot be assembled with (on the service brake, a pin moved out
by half its limit or more starts the lining inside the drum of its 0.3 mm clearance) is
not run: its features are NaN, the report lists it with the refusal's one line, and the
command counts the refused sizes in one line. Features:

* at the defective shoe, from the pivot force (the model's own signal): the first-impact
  peak ``|F_pivot|`` (N), the first-to-second impact period (ms), the number of impacts,
  the actuation force at the first impact (N), and the contact-regime mean ``|F_pivot|``
  (N; the run must reach 1 s past the impacts, so from ``--duration`` 6.6 s only);
* the order-2 line (twice the drum's rotation frequency, by order analysis on the drum
  angle, :mod:`..analysis.orders`) of that shoe's ``|F_pivot|`` over 0.8-1.9 s, the
  contact regime with the actuation held (N; from ``--duration`` 1.9 s); for the drum the
  leading (left) shoe's; and the order-1 line (once per revolution: a drum flat's);
* the braking torque: the mean friction torque of both shoes on the drum over the same
  window (N m; from ``--duration`` 1.9 s): what a friction change or a weak actuation
  moves first;
* what a sensor gives (the default set, one noise seed, :mod:`..analysis.measured_features`):
  the rms of the backing-plate acceleration x and y in the drum-brake noise band over the
  impacts (m/s^2), and the first-impact time seen by the accelerometers (ms).

The report (``report.md``, one figure per kind, ``severity.json``) gives each feature's
value and its change against the healthy brake. One deterministic brake: a change is what
the signal carries, not a detection rate.
"""

from __future__ import annotations

import functools
import json
import math
import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np

from brake_sim_ros.analysis import measured_features as mf
from brake_sim_ros.analysis.orders import order_amplitude
from brake_sim_ros.command_line import Parser
from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model import catalogue
from brake_sim_ros.model.catalogue import DefectKind
from brake_sim_ros.model.defects import Defects
from brake_sim_ros.model.layout import SIDES
from brake_sim_ros.model.parameters import BRAKES
from brake_sim_ros.recording.output import (
    check_output,
    output_directory,
    probe_output,
    replace_output,
)
from brake_sim_ros.scenarios import Scenario, load_scenario, on_brake
from brake_sim_ros.sensing.sensors import SensorBank, SensorSet
from brake_sim_ros.stream.run import run_scenario

STEPS = (0.0, 0.2, 0.4, 0.6, 0.8, 1.0)  # fractions of the service limit
BASE_SCENARIO = "symmetric"
DEFAULT_BRAKE = "service"  # the product's brake; "study" for the published one
DEFAULT_DURATION_S = 2.0
ORDER_WINDOW_S = (0.8, 1.9)  # contact regime with the actuation held (published event)
SEED = 0
FEATURES: dict[str, str] = {  # key: label (unit)
    "first_impact_peak_n": "first-impact peak of the pivot force magnitude (N)",
    "period_ms": "impact period (ms)",
    "impacts": "impacts",
    "first_impact_actuation_n": "actuation at first impact (N)",
    "contact_regime_force_n": "contact-regime mean pivot force magnitude (N)",
    "band_rms_x": "band rms accel x (m/s^2)",
    "band_rms_y": "band rms accel y (m/s^2)",
    "first_impact_ms": "first impact, accelerometers (ms)",
    "order_2_line_n": "order-2 line of the pivot force magnitude (N)",
    "order_1_line_n": "order-1 line (once per revolution) of the pivot force magnitude (N)",
    "braking_torque_n_m": "mean braking torque, 0.8-1.9 s (N m)",
}
# features whose healthy value is zero (up to rounding): reported as values, not changes
ABSOLUTE = frozenset({"order_2_line_n", "order_1_line_n"})


@functools.cache
def base_scenario(brake: str = DEFAULT_BRAKE) -> Scenario:
    """:data:`BASE_SCENARIO` on the brake ``brake`` (:data:`BRAKES`), parsed once (a frozen
    Scenario: each run takes its own copy with its defects)."""
    return on_brake(load_scenario(BASE_SCENARIO), brake)


def features(
    defects: Defects, location: str, duration_s: float, brake: str = DEFAULT_BRAKE
) -> dict[str, float]:
    """The :data:`FEATURES` of the base scenario on ``brake`` with ``defects``, at shoe
    ``location`` (the leading, left, shoe for the drum).

    Raises:
        ParameterError: the brake cannot be assembled with ``defects`` (one line).
    """
    scenario = base_scenario(brake).with_defects(defects)
    run = run_scenario(scenario, duration_s=duration_s)
    side = location if location in SIDES else SIDES[0]
    shoe = run.metrics.shoe(side)
    b = run.samples
    order_line = once_line = torque = math.nan
    if duration_s >= ORDER_WINDOW_S[1]:  # twice the drum's rotation, by order analysis
        magnitude = np.hypot(b[f"{side}_pivot_fx_n"], b[f"{side}_pivot_fy_n"])
        order_line = order_amplitude(b.time_s, b["drum_angle_rad"], magnitude, 2.0, ORDER_WINDOW_S)
        # once per revolution: what a drum flat (a crack's edge) gives
        once_line = order_amplitude(b.time_s, b["drum_angle_rad"], magnitude, 1.0, ORDER_WINDOW_S)
        window = (b.time_s >= ORDER_WINDOW_S[0]) & (b.time_s < ORDER_WINDOW_S[1])
        torque = float(
            sum(
                (
                    b[f"{s}_friction_force_n"]
                    * np.hypot(b[f"{s}_contact_x_m"], b[f"{s}_contact_y_m"])
                )[window].mean()
                for s in SIDES
            )
        )
    sensors = SensorSet()
    frame = SensorBank(sensors, scenario.sample_rate_hz, SEED).advance(run.samples)
    measured = mf.features(frame, mf.noise_rms(frame), sensors)
    return {
        "first_impact_peak_n": shoe.first_impact_peak_n,
        "period_ms": 1e3 * shoe.period_s,
        "impacts": float(shoe.n_impacts),
        "first_impact_actuation_n": shoe.first_impact_actuation_n,
        "contact_regime_force_n": shoe.contact_regime_force_n,
        "band_rms_x": measured[mf.BAND_RMS[0]],
        "band_rms_y": measured[mf.BAND_RMS[1]],
        "first_impact_ms": measured[mf.FIRST_IMPACT],
        "order_2_line_n": order_line,
        "order_1_line_n": once_line,
        "braking_torque_n_m": torque,
    }


def sweep(
    kind: DefectKind,
    location: str,
    duration_s: float,
    healthy: dict[str, float],
    progress: Callable[[str], None] | None = None,
    steps: tuple[float, ...] = STEPS,
    brake: str = DEFAULT_BRAKE,
) -> dict[str, object]:
    """One kind at one location at ``steps`` (fractions of its service limit, 0 first) on
    ``brake``: severities, each feature's values (the first is ``healthy``; NaN at a size
    the brake refuses) and the refused sizes with the refusal's line."""
    severities = [f * kind.service_limit + 0.0 for f in steps]
    rows = [healthy]
    refused: list[list[object]] = []
    for severity in severities[1:]:
        if progress:
            progress(f"{location} {kind.name} {severity:+g} {kind.unit}")
        defects = Defects.single(kind.name, location, severity)
        try:
            rows.append(features(defects, location, duration_s, brake))
        except ParameterError as exc:  # not assembled: no run, its features missing
            refused.append([severity, str(exc)])
            rows.append(dict.fromkeys(FEATURES, math.nan))
    return {
        "kind": kind.name,
        "location": location,
        "unit": kind.unit,
        "severities": severities,
        "values": {k: [r[k] for r in rows] for k in FEATURES},
        "refused": refused,
    }


def brake_kinds(brake: str) -> tuple[DefectKind, ...]:
    """Every catalogue kind ``brake`` carries."""
    return catalogue.brake_kinds(base_scenario(brake).setup.params.service is not None)


def sweeps(
    duration_s: float,
    progress: Callable[[str], None] | None = None,
    kinds: tuple[DefectKind, ...] | None = None,
    steps: tuple[float, ...] = STEPS,
    brake: str = DEFAULT_BRAKE,
) -> list[dict[str, object]]:
    """``kinds`` (default: every kind ``brake`` carries) at every location, healthy runs
    shared per location."""
    if kinds is None:
        kinds = brake_kinds(brake)
    locations = list(dict.fromkeys(loc for k in kinds for loc in k.locations))
    healthy = {loc: features(Defects(), loc, duration_s, brake) for loc in locations}
    return [
        sweep(kind, loc, duration_s, healthy[loc], progress, steps, brake)
        for kind in kinds
        for loc in kind.locations
    ]


def change_pct(value: float, base: float) -> float:
    """Change of ``value`` against ``base``, % (nan where either is missing or base 0)."""
    if not (math.isfinite(value) and math.isfinite(base)) or base == 0.0:
        return math.nan
    return 100.0 * (value - base) / abs(base)


def report_markdown(
    results: list[dict[str, object]], duration_s: float, brake: str = DEFAULT_BRAKE
) -> str:
    lines = [
        "# Defect severity sweeps",
        "",
        f"Scenario `{BASE_SCENARIO}` on the {brake} brake with one defect, {duration_s:g} s"
        f" simulated, default sensors (seed {SEED}). Severity from healthy to the kind's"
        " service limit (`brake-sim defects`); each cell: value (change against healthy);"
        " nan at a size the brake refuses (listed under its table).",
        "",
    ]
    for r in results:
        sev = r["severities"]
        values = r["values"]
        assert isinstance(sev, list) and isinstance(values, dict)
        lines += [
            f"## {r['location']} {r['kind']} [{r['unit']}]",
            "",
            f"![{r['location']} {r['kind']}]({r['location']}_{r['kind']}.png)",
            "",
            "| feature | " + " | ".join(f"{s:+g}" for s in sev) + " |",
            "|---|" + "---|" * len(sev),
        ]
        for key, label in FEATURES.items():
            row = values[key]
            cells = [
                f"{v:.4g} ({change_pct(v, row[0]):+.1f} %)"
                if i and key not in ABSOLUTE
                else f"{v:.4g}"
                for i, v in enumerate(row)
            ]
            lines.append(f"| {label} | " + " | ".join(cells) + " |")
        lines.append("")
        for severity, reason in r.get("refused", []):
            lines += [f"Refused at {severity:+g} {r['unit']}: {reason}", ""]
    return "\n".join(lines)


def plot(result: dict[str, object], out_dir: Path) -> Path:
    """One figure per kind and location: each feature's change (%) against severity."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    sev = result["severities"]
    values = result["values"]
    assert isinstance(sev, list) and isinstance(values, dict)
    rows = -(-len(FEATURES) // 3)
    fig, axes = plt.subplots(rows, 3, figsize=(14, 3 * rows), sharex=True)
    for ax in axes.flat[len(FEATURES) :]:
        ax.set_visible(False)
    for ax, (key, label) in zip(axes.flat, FEATURES.items(), strict=False):
        base = values[key][0]
        if key not in ABSOLUTE and math.isfinite(base) and base != 0.0:
            ax.plot(sev, [change_pct(v, base) for v in values[key]], "o-")
            ax.set_ylabel("change against healthy (%)", fontsize=8)
        else:  # nothing to compare with on a healthy brake: the values themselves
            ax.plot(sev, values[key], "o-", color="C1")
            ax.set_ylabel("value", fontsize=8)
        ax.axhline(0.0, color="0.6", lw=0.6)
        ax.set_title(label, fontsize=9)
        ax.grid(alpha=0.3)
    for ax in axes[-1]:
        ax.set_xlabel(f"severity ({result['unit']})")
    fig.suptitle(f"{result['location']} {result['kind']}: features against severity")
    fig.tight_layout()
    path = out_dir / f"{result['location']}_{result['kind']}.png"
    replace_output(path, lambda tmp: fig.savefig(tmp, format="png", dpi=100))
    plt.close(fig)
    return path


def write_report(
    out_dir: str | Path,
    duration_s: float,
    progress: Callable[[str], None] | None = None,
    kinds: tuple[DefectKind, ...] | None = None,
    steps: tuple[float, ...] = STEPS,
    brake: str = DEFAULT_BRAKE,
) -> tuple[Path, int]:
    """Run the sweeps on ``brake``; write ``report.md``, a figure per kind and location
    and ``severity.json``. Returns the report's path and how many sizes were refused.

    Every output is checked before the work (the directory made, each file's rules, a file
    created there and removed): a refusal is one line, and no file is written."""
    if kinds is None:
        kinds = brake_kinds(brake)
    out_dir = output_directory(out_dir, "--out")
    names = [f"{loc}_{kind.name}.png" for kind in kinds for loc in kind.locations]
    for name in ("severity.json", *names):
        check_output(out_dir / name, overwrite=True, option="--out")
    probe_output(out_dir / "report.md", overwrite=True, option="--out")
    results = sweeps(duration_s, progress, kinds, steps, brake)
    for r in results:
        plot(r, out_dir)
    text = json.dumps(results, indent=1, allow_nan=True)
    replace_output(out_dir / "severity.json", lambda tmp: tmp.write_text(text, encoding="utf-8"))
    report = report_markdown(results, duration_s, brake)
    path = replace_output(out_dir / "report.md", lambda tmp: tmp.write_text(report, "utf-8"))
    return path, sum(len(r["refused"]) for r in results)


def main(argv: list[str] | None = None) -> int:
    parser = Parser(prog="brake-sim severity", description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="out/severity", help="report directory")
    parser.add_argument(
        "--duration",
        type=float,
        default=DEFAULT_DURATION_S,
        metavar="S",
        help=f"simulated seconds per run (default {DEFAULT_DURATION_S:g}; 6.6 for the"
        " contact-regime force)",
    )
    parser.add_argument(
        "--brake",
        choices=BRAKES,
        default=DEFAULT_BRAKE,
        help=f"the brake (default {DEFAULT_BRAKE})",
    )
    args = parser.parse_args(argv)
    if not mf.IMPACT_WINDOW_S[1] <= args.duration <= 60.0:
        parser.error(f"--duration {args.duration:g}: allowed {mf.IMPACT_WINDOW_S[1]:g} to 60 s")
    path, refused = write_report(
        args.out,
        args.duration,
        lambda what: print(f"running {what}", file=sys.stderr),
        brake=args.brake,
    )
    if refused:
        print(f"refused: {refused} sizes the {args.brake} brake cannot be assembled with (report)")
    print(f"report: {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
