"""Studies and benchmarks: code that uses the library and prints or writes figures.

Nothing in the library imports this package. Each study is registered below by name with
what it measures; ``brake-sim bench NAME`` runs one (``brake-sim validate`` runs
:mod:`.validation`, ``python -m brake_sim_ros.studies.calibration`` the calibration).
A study's module is imported only when it runs: the node benchmark needs rclpy, the
plots need matplotlib.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass


@dataclass(frozen=True)
class Study:
    """One registered study.

    Attributes:
        name: what ``brake-sim bench`` calls it.
        measures: one line, for ``--help``.
        run: its ``main(argv) -> exit code``.
    """

    name: str
    measures: str
    run: Callable[[list[str]], int]


def _core(argv: list[str]) -> int:
    from brake_sim_ros.studies import core_bench

    return core_bench.main(argv)


def _accuracy(argv: list[str]) -> int:
    from brake_sim_ros.studies import work_precision

    return work_precision.main(argv)


def _presets(argv: list[str]) -> int:
    from brake_sim_ros.studies import presets

    return presets.main(argv)


def _node(argv: list[str]) -> int:
    from brake_sim_ros.studies import node_bench

    return node_bench.main(argv)


def _recording(argv: list[str]) -> int:
    from brake_sim_ros.studies import recording_bench

    return recording_bench.main(argv)


def _realtime(argv: list[str]) -> int:
    from brake_sim_ros.studies import realtime_bench

    return realtime_bench.main(argv)


def _sensors(argv: list[str]) -> int:
    from brake_sim_ros.studies import sensors_bench

    return sensors_bench.main(argv)


def _fidelity(argv: list[str]) -> int:
    from brake_sim_ros.studies import fidelity

    return fidelity.main(argv)


def _drum(argv: list[str]) -> int:
    from brake_sim_ros.studies import drum_defect

    return drum_defect.main(argv)


def _detectability(argv: list[str]) -> int:
    from brake_sim_ros.studies import detectability

    return detectability.main(argv)


def _sweep(argv: list[str]) -> int:
    from brake_sim_ros.studies import sweep_bench

    return sweep_bench.main(argv)


def _fleet(argv: list[str]) -> int:
    from brake_sim_ros.studies import fleet_bench

    return fleet_bench.main(argv)


def _units(argv: list[str]) -> int:
    from brake_sim_ros.studies import units

    return units.main(argv)


def _cycle(argv: list[str]) -> int:
    from brake_sim_ros.studies import cycle_bench

    return cycle_bench.main(argv)


BENCHMARKS: dict[str, Study] = {
    s.name: s
    for s in (
        Study("core", "cost and accuracy of the fixed-step stepper", _core),
        Study(
            "accuracy",
            "work-precision study of every solver and preset (table and plot)",
            _accuracy,
        ),
        Study(
            "presets", "each preset's errors over onset phases, against its stated bounds", _presets
        ),
        Study("node", "the ROS node's real-time figures", _node),
        Study(
            "recording",
            "MCAP recording throughput, CPU at real time and size per simulated second",
            _recording,
        ),
        Study(
            "realtime",
            "worst-case cost per streaming chunk, against the real-time budget",
            _realtime,
        ),
        Study(
            "fidelity", "cost and error of each fidelity level against the full model", _fidelity
        ),
        Study(
            "sensors",
            "cost of the structure and sensors; which cases the measured acceleration separates",
            _sensors,
        ),
        Study(
            "drum",
            "severity sweep of drum ovality: the pivot-force line at 2 f_rot per amplitude",
            _drum,
        ),
        Study(
            "sweep",
            "brake-sim sweep: runs per hour and simulated s per wall s on 1 and 2 workers and"
            " a Dask LocalCluster, the parent's work per run, peak memory per worker",
            _sweep,
        ),
        Study(
            "fleet",
            "the 10,000-run campaign (11,680 runs on the service brake) swept and scored with"
            " impact (or a slice, extrapolated): wall time, runs/s, disk",
            _fleet,
        ),
        Study(
            "units",
            "spread of stop time and first-impact force across a fleet of units",
            _units,
        ),
        Study(
            "detectability",
            "per defect, the smallest severity the baselines detect on unseen units at a"
            " stated false-alarm rate (the service brake; --brake study for the study brake)",
            _detectability,
        ),
        Study(
            "cycle",
            "a drive cycle (urban) offline: x real time with and without the default sensors,"
            " its energy books",
            _cycle,
        ),
    )
}
