"""``brake-sim bench core``: cost and accuracy of the fixed-step stepper against the reference.

Prints nanoseconds per right-hand-side evaluation and per step, the real-time factor of
the 7.5 s symmetric event on one core, and the error of first-impact peak pivot force,
impact period and stop time against the adaptive reference for a range of steps.
"""

from __future__ import annotations

import argparse
import time

import numpy as np
from numba import njit

from brake_sim_ros.model import kernel
from brake_sim_ros.model import layout as L
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.solvers.run import run_scenario

TARGET_RTF = 50.0
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


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="brake-sim bench core", description=__doc__)
    parser.add_argument("--scenario", default="symmetric")
    parser.add_argument(
        "--steps",
        default="1e-5,2e-5,4e-5,5e-5,6e-5",
        help="comma-separated fixed steps to compare, s",
    )
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    scenario = load_scenario(args.scenario)
    duration = scenario.duration_s

    stepper = FixedStepStepper(scenario.setup, scenario.solver.dt_s)
    p = stepper.packed_parameters
    y = stepper.state
    _rhs_loop(y.copy(), p, 10)
    n_eval = 2_000_000
    rhs_cpu = _best_cpu(lambda: _rhs_loop(y.copy(), p, n_eval), args.repeats)
    print(
        f"right-hand side: {1e9 * rhs_cpu / n_eval:.1f} ns per evaluation (both shoes in contact)"
    )

    def stepping_cpu(dt: float, repeats: int, record: bool = True) -> float:
        """Best CPU time of the stepping alone; building the stepper (and its step-limit
        analysis) happens outside the timed region."""
        n = round(duration / dt)
        best = float("inf")
        for _ in range(repeats):
            st = FixedStepStepper(scenario.setup, dt, check_step=False)
            start = time.process_time()
            if record:
                st.run(duration)
            else:
                st.advance(n, record_every=n)
            best = min(best, time.process_time() - start)
        return best

    dt0 = scenario.solver.dt_s
    n0 = round(duration / dt0)
    stepping_cpu(dt0, 1)  # compile, or load the compiled kernel from the cache
    cpu_rec = stepping_cpu(dt0, args.repeats)
    cpu_norec = stepping_cpu(dt0, args.repeats, record=False)
    print(
        f"fixed step {dt0:g} s ({n0} steps, 4 evaluations each):"
        f" {1e9 * cpu_rec / n0:.0f} ns per step recording every sample,"
        f" {1e9 * cpu_norec / n0:.0f} ns per step without recording"
    )
    print(
        f"  {duration:g} s event in {cpu_rec:.3f} s CPU: {duration / cpu_rec:.0f}x real time"
        f" (target >= {TARGET_RTF:.0f}x)"
    )

    print(
        f"reference: adaptive DOP853, rtol {scenario.solver.rtol:g}, events located ...", flush=True
    )
    start = time.process_time()
    ref = run_scenario(scenario, method="reference")
    ref_cpu = time.process_time() - start
    rm = ref.metrics
    print(f"  {ref_cpu:.2f} s CPU, {ref.n_steps} evaluations, stop {rm.stop_time_s:.6f} s")
    print()
    print(
        "step (s) | x real time | peak F_r err L/R (%) | period err L/R (%) | stop err (%) | meets"
    )
    print("---|---|---|---|---|---")
    limit = stepper.limit.max_step_s
    for dt in (float(s) for s in args.steps.split(",")):
        cpu = stepping_cpu(dt, args.repeats)
        st_res = run_scenario(scenario, method="rk4", dt_s=dt) if dt <= limit else None
        if st_res is None:
            print(f"{dt:g} | - | refused: above the step limit {limit:.3g} s | | |")
            continue
        m = st_res.metrics
        pe = [
            100 * (m.shoe(s).first_impact_peak_n / rm.shoe(s).first_impact_peak_n - 1)
            for s in ("left", "right")
        ]
        te = [100 * (m.shoe(s).period_s / rm.shoe(s).period_s - 1) for s in ("left", "right")]
        se = 100 * (m.stop_time_s / rm.stop_time_s - 1)
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
    print(f"\nstep limit for this scenario: {limit:.3g} s ({stepper.limit.reason})")
    return 0
