"""``brake-sim bench core``: cost and accuracy of the fixed-step stepper against the reference.

Prints nanoseconds per right-hand-side evaluation; the scenario's own stepper
(:func:`stepper_for`: its sample rate, its preset) with its physics step, substeps,
nanoseconds per sample and real-time factor of the whole event on one core (against its
target, 50x, and its goal for the balanced preset at 25.6 kHz, 100x); then every
preset at the scenario's sample rate, and one scheme over a range of physics steps, each
with its real-time factor and its error of first-impact peak pivot force, impact period
and stop time against the adaptive reference.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np
from numba import njit

from brake_sim_ros.analysis.impacts import EventMetrics, event_metrics
from brake_sim_ros.command_line import Parser
from brake_sim_ros.model import kernel
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.layout import SIDES
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.solvers.presets import PRESETS
from brake_sim_ros.stream.build import stepper_for
from brake_sim_ros.stream.run import run_scenario

TARGET_RTF = 50.0
GOAL_RTF = 100.0  # the balanced preset's goal at 25.6 kHz (issue 31)
TARGET_IMPACT_REL = 0.01
TARGET_STOP_REL = 0.001


@njit(cache=True)
def _rhs_loop(y, p, n):
    dydt = np.empty(y.shape[0])
    out = np.empty((0, L.N_COLUMNS))
    acc = 0.0
    for i in range(n):
        y[L.Y_LEFT_ANGLE] = 0.0215 + 1e-12 * i  # in contact, so the whole contact path runs
        kernel.evaluate(y, p, 600.0, 600.0, 0, L.CONTACT_AUTO, L.CONTACT_AUTO, dydt, out, -1, 0.0)
        acc += dydt[L.Y_LEFT_SPEED]
    return acc


def _best_cpu(fn, repeats: int) -> float:
    best = float("inf")
    for _ in range(repeats):
        start = time.process_time()
        fn()
        best = min(best, time.process_time() - start)
    return best


def _errors(m: EventMetrics, ref: EventMetrics) -> tuple[list[float], list[float], float]:
    """Relative errors, %: first-impact peak and period per shoe (left, right), stop time."""
    sides = SIDES
    peak = [
        100 * (m.shoe(s).first_impact_peak_n / ref.shoe(s).first_impact_peak_n - 1) for s in sides
    ]
    period = [100 * (m.shoe(s).period_s / ref.shoe(s).period_s - 1) for s in sides]
    return peak, period, 100 * (m.stop_time_s / ref.stop_time_s - 1)


def _timed_run(make: Callable[[], FixedStepStepper], duration: float, repeats: int):
    """Best CPU time of stepping a whole event recording every sample (building the stepper
    and its step-limit analysis outside the timed region), and the last run's samples."""
    best, stepper, samples = float("inf"), None, None
    for _ in range(repeats):
        stepper = make()
        start = time.process_time()
        samples = stepper.run(duration)
        best = min(best, time.process_time() - start)
    return best, stepper, samples


def main(argv: list[str] | None = None) -> int:
    parser = Parser(prog="brake-sim bench core", description=__doc__)
    parser.add_argument("--scenario", default="symmetric")
    parser.add_argument(
        "--steps",
        default="1e-5,2e-5,4e-5,5e-5,6e-5",
        help="comma-separated physics steps for the step table (one sample per step), s",
    )
    parser.add_argument("--scheme", default="rk4", help="scheme of the step table")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    scenario = load_scenario(args.scenario)
    duration = scenario.duration_s

    stepper = stepper_for(scenario)
    p = stepper.packed_parameters
    y = stepper.state
    _rhs_loop(y.copy(), p, 10)
    n_eval = 2_000_000
    rhs_cpu = _best_cpu(lambda: _rhs_loop(y.copy(), p, n_eval), args.repeats)
    print(
        f"right-hand side: {1e9 * rhs_cpu / n_eval:.1f} ns per evaluation (both shoes in contact)"
    )

    stepper.run(0.01)  # compile, or load the compiled kernel from the cache
    n = round(duration / stepper.sample_period_s)
    cpu_rec, stepper, _ = _timed_run(lambda: stepper_for(scenario), duration, args.repeats)

    def no_record() -> None:
        st = stepper_for(scenario)
        st.advance(n, record_every=n)

    cpu_norec = _best_cpu(no_record, args.repeats)  # includes the step-limit analysis (ms)
    print(f"scenario {scenario.name}, preset {scenario.solver.preset}: {stepper.describe_step()}")
    print(
        f"  {n} samples: {1e9 * cpu_rec / n:.0f} ns per sample recording every sample,"
        f" {1e9 * cpu_norec / n:.0f} ns without recording"
    )
    print(
        f"  {duration:g} s event in {cpu_rec:.3f} s CPU: {duration / cpu_rec:.0f}x real time"
        f" (target >= {TARGET_RTF:.0f}x; goal >= {GOAL_RTF:.0f}x:"
        f" {'met' if duration / cpu_rec >= GOAL_RTF else 'not met'})"
    )

    print(
        f"reference: adaptive DOP853, rtol {scenario.solver.rtol:g}, events located ...", flush=True
    )
    start = time.process_time()
    ref = run_scenario(scenario, method="reference")
    ref_cpu = time.process_time() - start
    rm = ref.metrics
    print(f"  {ref_cpu:.2f} s CPU, {ref.n_steps} evaluations, stop {rm.stop_time_s:.6f} s")

    print(f"\npresets at the scenario's sample rate ({1 / stepper.sample_period_s:g} Hz):\n")
    print(
        "preset | scheme | physics step (us) | substeps | x real time | peak F_r err L/R (%)"
        " | period err L/R (%) | stop err (%)"
    )
    print("---|---|---|---|---|---|---|---")
    for name in PRESETS:
        chosen = scenario.with_solver(preset=name)
        cpu, st, samples = _timed_run(lambda c=chosen: stepper_for(c), duration, args.repeats)
        pe, te, se = _errors(event_metrics(samples, stop_time_s=st.stop_time_s), rm)
        print(
            f"{name} | {st.scheme} | {1e6 * st.physics_step_s:.4g} | {st.substeps} |"
            f" {duration / cpu:.0f} | {pe[0]:+.4f} / {pe[1]:+.4f} | {te[0]:+.4f} / {te[1]:+.4f}"
            f" | {se:+.6f}"
        )

    print(f"\n{args.scheme} over physics steps (one sample per step):\n")
    print(
        "step (s) | x real time | peak F_r err L/R (%) | period err L/R (%) | stop err (%) | meets"
    )
    print("---|---|---|---|---|---")
    table_limit = FixedStepStepper(scenario.setup, 1e-3, scheme=args.scheme, check_step=False).limit
    limit = table_limit.max_step_s
    for dt in (float(s) for s in args.steps.split(",")):
        if dt > limit:
            print(f"{dt:g} | - | above the step limit {limit:.3g} s | | |")
            continue
        cpu, st, samples = _timed_run(
            lambda dt=dt: FixedStepStepper(
                scenario.setup, dt, scheme=args.scheme, check_step=False
            ),
            duration,
            args.repeats,
        )
        pe, te, se = _errors(event_metrics(samples, stop_time_s=st.stop_time_s), rm)
        ok = (
            max(map(abs, pe)) <= 100 * TARGET_IMPACT_REL
            and max(map(abs, te)) <= 100 * TARGET_IMPACT_REL
            and abs(se) <= 100 * TARGET_STOP_REL
            and duration / cpu >= TARGET_RTF
        )
        print(
            f"{dt:g} | {duration / cpu:.0f} | {pe[0]:+.3f} / {pe[1]:+.3f} |"
            f" {te[0]:+.3f} / {te[1]:+.3f}"
            f" | {se:+.5f} | {'yes' if ok else 'no'}"
        )
    print(f"\n{args.scheme} step limit for this scenario: {limit:.3g} s ({table_limit.reason})")
    return 0
