"""Actuation defects per shoe (low pressure, delay, first-order lag, pulsation) in the
compiled model, against the commanded history and the shoe's dynamics."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
from scipy.optimize import brentq

from brake_sim_ros.errors import ParameterError, ScenarioError
from brake_sim_ros.model.actuation import shaped
from brake_sim_ros.model.catalogue import Growth
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.scenarios.loader import load_scenario, parse_scenario
from brake_sim_ros.solvers.reference import run_reference
from brake_sim_ros.stream.build import stepper_for

RATE_HZ = 25_600.0
RAMP = (0.2, 0.7, 1300.0)  # the published actuation: 0 until 0.2 s, 1300 N at 0.7 s


def _run(left: ShoeDefect, duration_s: float, growth=()):
    sc = load_scenario("symmetric").with_defects(Defects(left=left, growth=growth))
    sc = dataclasses.replace(sc, duration_s=duration_s)
    return stepper_for(sc).run(duration_s)


def _commanded(t: np.ndarray) -> np.ndarray:
    return np.interp(t, [0.0, RAMP[0], RAMP[1]], [0.0, 0.0, RAMP[2]])


def _first_impact_s(run, side: str = "left") -> float:
    return float(run.time_s[np.flatnonzero(run[f"{side}_normal_force_n"] > 0.0)[0]])


@pytest.fixture(scope="module")
def healthy():
    return _run(ShoeDefect(), 2.0)


def test_the_lag_of_a_piecewise_linear_history_is_the_first_order_solution():
    """``tau y' + y = u`` for the ramp, integrated by a fine implicit scheme."""
    ts = np.array([0.0, 0.2, 0.7])
    fs = np.array([0.0, 0.0, 1300.0])
    tau, dt = 0.03, 1e-6
    t = np.arange(0.0, 1.0, dt)
    u = np.interp(t, ts, fs)
    y = np.zeros_like(t)
    for i in range(1, t.size):  # trapezoidal rule, second order
        y[i] = (y[i - 1] * (tau / dt - 0.5) + 0.5 * (u[i] + u[i - 1])) / (tau / dt + 0.5)
    for probe in (0.1, 0.21, 0.3, 0.7, 0.72, 0.9):
        i = round(probe / dt)
        assert shaped(t[i], ts, fs, 0.0, tau, 0.0, 0.0) == pytest.approx(y[i], abs=1e-6)


def test_a_low_pressure_scales_the_force_and_the_steady_pivot_force(healthy):
    """-20 %: the shoe's actuation is 0.8 of the commanded at every sample; riding on the
    drum the shoe balances forces proportional to it, so its pivot force is 0.8 too."""
    run = _run(ShoeDefect(actuation_gain_change_pct=-20.0), 2.0)
    assert np.allclose(run["left_actuation_force_n"], 0.8 * _commanded(run.time_s), rtol=1e-12)
    assert np.array_equal(run["right_actuation_force_n"], healthy["right_actuation_force_n"])
    w = (run.time_s > 1.0) & (run.time_s < 2.0)
    ratio = (
        run.pivot_force_magnitude("left")[w].mean()
        / healthy.pivot_force_magnitude("left")[w].mean()
    )
    assert ratio == pytest.approx(0.8, rel=0.01)


def test_a_delay_shifts_the_first_impact_by_the_delay(healthy):
    """Before its first contact a shoe moves under the actuation alone and the drum turns
    freely: the delayed brake is the healthy one later, to the sample."""
    run = _run(ShoeDefect(actuation_delay_ms=40.0), 2.0)
    shift = _first_impact_s(run) - _first_impact_s(healthy)
    assert shift == pytest.approx(0.040, abs=1.0 / RATE_HZ)
    assert _first_impact_s(run, "right") == _first_impact_s(healthy, "right")


def test_a_lag_delays_the_first_impact_by_about_the_lag(healthy):
    """A free shoe turns by the double integral of its force (a nearly constant arm):
    it meets the drum when that integral reaches the healthy shoe's at its first impact.
    For the ramp of slope b from t0 lagged by tau, the integral is
    b (s^3/6 - tau s^2/2 + tau^2 s - tau^3 (1 - exp(-s/tau))), s = t - t0."""
    tau = 0.010
    run = _run(ShoeDefect(actuation_lag_ms=1e3 * tau), 2.0)
    s_healthy = _first_impact_s(healthy) - RAMP[0]

    def reach(s: float) -> float:
        lagged = s**3 / 6 - tau * s**2 / 2 + tau**2 * s - tau**3 * (1 - math.exp(-s / tau))
        return lagged - s_healthy**3 / 6

    expected = brentq(reach, s_healthy, s_healthy + 5 * tau) - s_healthy
    assert 0.5 * tau < expected < tau  # about the lag (all of it once s >> tau)
    shift = _first_impact_s(run) - _first_impact_s(healthy)
    assert shift == pytest.approx(expected, abs=0.05 * tau + 1.0 / RATE_HZ)


def test_a_pulsation_modulates_the_force_and_the_pivot_force_at_its_frequency(healthy):
    run = _run(ShoeDefect(actuation_pulsation_pct=10.0, actuation_pulsation_hz=20.0), 2.0)
    t = run.time_s
    expected = _commanded(t) * (1.0 + 0.1 * np.sin(2 * np.pi * 20.0 * t))
    assert np.allclose(run["left_actuation_force_n"], expected, rtol=1e-12, atol=1e-9)
    # riding on the drum the pivot force follows the actuation: a 20 Hz line of 10 % of it
    w = (t >= 1.0) & (t < 2.0)  # 20 whole periods
    force = run.pivot_force_magnitude("left")[w]
    line = 2 * np.abs(np.mean(force * np.exp(-2j * np.pi * 20.0 * t[w])))
    assert line / force.mean() == pytest.approx(0.1, rel=0.1)
    plain = healthy.pivot_force_magnitude("left")[w]
    assert 2 * np.abs(np.mean(plain * np.exp(-2j * np.pi * 20.0 * t[w]))) < 0.01 * line


def test_a_pressure_loss_that_grows_lowers_the_force_as_it_grows():
    law = Growth(1.0, "linear", rate_per_s=30.0)  # to -30 % at 2 s
    run = _run(
        ShoeDefect(actuation_gain_change_pct=-30.0), 2.5, (("actuation_gain_change", "left", law),)
    )
    t = run.time_s
    factor = 1.0 - np.clip(30.0 * (t - 1.0), 0.0, 30.0) / 100.0
    assert np.allclose(run["left_actuation_force_n"], factor * _commanded(t), rtol=1e-12)


def test_models_that_take_the_history_as_commanded_refuse_a_shaped_one():
    setup = (
        load_scenario("symmetric")
        .with_defects(Defects(left=ShoeDefect(actuation_lag_ms=5.0)))
        .setup
    )
    with pytest.raises(ParameterError, match="reference solver takes the actuation history"):
        run_reference(setup, 0.1)
    with pytest.raises(ScenarioError, match="cannot represent the defect 'actuation_lag'"):
        parse_scenario(
            'name = "x"\n[defects.left]\nactuation_lag_ms = 20.0\n'
            '[needs]\noutputs = ["stop_time"]\nlevel = "contact_regime"\n'
        )


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("actuation_delay_ms = 600.0", "actuation_delay_ms=600 is invalid: allowed 0 to 500"),
        ("actuation_lag_ms = -1.0", "actuation_lag_ms=-1 is invalid: allowed 0 to 500"),
        ("actuation_pulsation_pct = 10.0", "actuation_pulsation_hz=0 is invalid: allowed > 0"),
        (
            "actuation_gain_change_pct = -95.0",
            "actuation_gain_change_pct=-95 is invalid: allowed -90 to 50",
        ),
        (
            'actuation_lag_ms = {value = 20.0, growth = "linear", rate_per_s = 10.0}',
            "actuation_lag at left cannot change during a run in this model",
        ),
    ],
)
def test_a_bad_actuation_defect_is_refused_in_one_line(text, message):
    with pytest.raises(ScenarioError, match=message) as info:
        parse_scenario(f'name = "x"\n[defects.left]\n{text}\n')
    assert "\n" not in str(info.value)
