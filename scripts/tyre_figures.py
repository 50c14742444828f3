"""Print the service brake tyre's figures quoted in ``docs/model.md`` ("The service brake").

A panic stop (20 kN per shoe in 50 ms from 100 km/h) on the dry and the wet road, as
``tests/model/test_tyre.py`` runs it: the wheel lock, the slide's time against the hand
time of the Stribeck curve, its mean deceleration over g, the largest backward speed after
the stop and the energy books; the same stop on the study brake (no tyre); the symmetric
scenario's force on the service brake, dry and wet; the step limit. Usage (half a minute
once the kernels are compiled)::

    PYTHONPATH=. .venv/bin/python scripts/tyre_figures.py
"""

from __future__ import annotations

import numpy as np

from brake_sim_ros.analysis.energy import energy_balance
from brake_sim_ros.model.service_parameters import DRY_ROAD_FRICTION, WET_ROAD_FRICTION
from brake_sim_ros.solvers.stability import step_limit
from tests.model.test_tyre import (  # the runs and hand figures the tests check
    RADIUS_M,
    V0_M_S,
    G,
    _first_rest,
    _hand_slide_time_s,
    _panic,
    _run,
)


def _panic_figures(road: float, duration_s: float) -> None:
    scenario, stepper, block = _run(_panic(road, duration_s))
    t, v = block.time_s, block["flywheel_speed_rad_s"] * RADIUS_M
    lock = stepper.wheel_lock_time_s
    v_lock = float(np.interp(lock, t, v))
    rest = _first_rest(t, v)
    hand = _hand_slide_time_s(v_lock, road, 1.5 * road)
    books = energy_balance(block, scenario.setup.params, packed=stepper.packed_parameters)
    after = t > rest
    print(
        f"panic, road {road:g}: wheel locked at {lock:.4f} s at {v_lock:.3f} m/s; at rest"
        f" {rest:.4f} s (vehicle stop rule {stepper.stop_time_s:.4f} s); slide {rest - lock:.4f}"
        f" s against the hand {hand:.4f} s ({100 * ((rest - lock) / hand - 1):+.2f} %); mean"
        f" deceleration {v_lock / (rest - lock) / G:.4f} g ({v_lock / (rest - lock) / G / road:.4f}"
        f" mu); backward at most {-v[after].min():.4f} m/s ({-100 * v[after].min() / V0_M_S:.2f} %"
        f" of the start), forward after the stop at most {v[after].max():.2e} m/s;"
        f" energy residual {books.residual_j:.2e} J of {books.turnover_j:.4g} J"
    )


def _study_panic() -> None:
    text = _panic(DRY_ROAD_FRICTION, 4.2).replace('brake = "service"\nroad_friction = 0.8\n', "")
    _scenario, _stepper, block = _run(text)
    t, v = block.time_s, block["flywheel_speed_rad_s"] * RADIUS_M
    rest = _first_rest(t, v)
    after = t > rest
    print(
        f"the same panic on the study brake (no tyre): at rest {rest:.4f} s, mean"
        f" {V0_M_S / rest / G:.2f} g; then rocks between {v[after].min():.3f} and"
        f" {v[after].max():.3f} m/s ({100 * np.abs(v[after]).max() / V0_M_S:.1f} % of the start)"
    )


def _gentle() -> None:
    for road in (DRY_ROAD_FRICTION, WET_ROAD_FRICTION):
        text = f'name = "gentle"\nbrake = "service"\nroad_friction = {road}\nduration_s = 7.5\n'
        _scenario, stepper, block = _run(text)
        t, v = block.time_s, block["flywheel_speed_rad_s"] * RADIUS_M
        rest = _first_rest(t, v)
        slip = RADIUS_M * (block["drum_speed_rad_s"] - block["flywheel_speed_rad_s"])
        rolling = t < rest - 0.05
        print(
            f"symmetric force on the service brake, road {road:g}: at rest {rest:.4f} s, wheel"
            f" locked {stepper.wheel_lock_time_s:.4f} s, largest slip speed rolling"
            f" {np.abs(slip[rolling]).max():.4f} m/s, backward after at most"
            f" {-v[t > rest].min():.4f} m/s"
        )
    limit = step_limit(_scenario.setup, _scenario.setup.peak_force_n)
    print(f"step limit (symmetric force, service brake): {limit.max_step_s:.3e} s; {limit.reason}")


if __name__ == "__main__":
    _panic_figures(DRY_ROAD_FRICTION, 4.2)
    _panic_figures(WET_ROAD_FRICTION, 6.6)
    _study_panic()
    _gentle()
