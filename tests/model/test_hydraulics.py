"""The service brake's hydraulic circuit (model/service.py): one wheel cylinder with two
pistons, one line pressure fed through the line's resistance into the circuit's compliance.
Each figure a test expects is a hand calculation from the documented laws and the
parameters (piston area, R, C, the shoe's lever), never read off a run."""

from __future__ import annotations

import dataclasses
import itertools
import math

import numpy as np
import pytest

from brake_sim_ros.analysis.energy import line_pressure_pa
from brake_sim_ros.model import kernel
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.actuation import Actuation, ForceProfile
from brake_sim_ros.model.assembly import contact_arms
from brake_sim_ros.model.defects import Defects, DrumDefect, DrumHarmonic, ShoeDefect
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.placement import place_shoe
from brake_sim_ros.model.run_setup import BrakeSetup
from brake_sim_ros.model.service_parameters import WHEEL_CYLINDER_BORE_M
from brake_sim_ros.sensing.kinds import LINE_PRESSURE_LOCATION, PA_PER_BAR
from brake_sim_ros.sensing.sensors import SensorBank, SensorChannel, SensorSet
from brake_sim_ros.solvers import stability
from brake_sim_ros.solvers.fixed_step import FixedStepStepper

FS = 25600.0
SERVICE = BrakeParameters.of_brake("service")
SPEC = SERVICE.service
AREA = math.pi * WHEEL_CYLINDER_BORE_M**2 / 4.0
R = SPEC.line_resistance_pa_s_per_m3
C = SPEC.line_compliance_m3_per_pa
SIDES = ("left", "right")


def _stepper(
    actuation: Actuation, defects: Defects | None = None, contact: str = "point"
) -> FixedStepStepper:
    """The service brake at :data:`FS` with its point contact, or with its lining over the
    arc (``contact`` "arc": ``distributed_lining``)."""
    params = SERVICE
    if contact == "arc":
        params = dataclasses.replace(
            SERVICE, service=dataclasses.replace(SPEC, distributed_lining=True)
        )
    setup = BrakeSetup(params=params, defects=defects or Defects(), actuation=actuation)
    return FixedStepStepper(setup, 1.0 / FS)


def _held(force_n: float) -> Actuation:
    """``force_n`` on both shoes from t = 0: a step of the source from the residual pressure
    the line starts at."""
    return Actuation(ForceProfile.constant(force_n), ForceProfile.constant(force_n))


def test_the_circuits_figures_are_the_documented_ones():
    assert math.isclose(AREA, SPEC.piston_area_m2, rel_tol=1e-15)
    assert 0.02 <= R * C <= 0.05  # a rise time constant of tens of ms
    stiffness = AREA**2 / C  # the circuit's at a tip: the shoe follows the drum
    assert stiffness < 0.01 * SERVICE.contact_stiffness_n_per_m


def test_a_held_force_gives_its_static_pressure_and_the_sensor_reads_it():
    """1000 N per shoe, held: after 15 R C the line sits at F / A (35.1 bar), each piston
    pushes 1000 N, and the line-pressure sensor (the pistons' mean force over the bore)
    reads the modelled pressure."""
    stepper = _stepper(_held(1000.0))
    stepper.run(15 * R * C)
    pressure = stepper.state[L.Y_LINE_PRESSURE]
    assert pressure == pytest.approx(1000.0 / AREA, rel=1e-6)
    block = stepper.run(1.0 / FS)  # its one row is the state above
    for side in SIDES:
        assert block[f"{side}_actuation_force_n"][0] == pytest.approx(1000.0, rel=1e-6)
    channel = SensorChannel("p", "line_pressure", LINE_PRESSURE_LOCATION)
    frame = SensorBank(SensorSet(channels=(channel,)), FS, seed=1).advance(block)
    assert frame["p"].values[0] * PA_PER_BAR == pytest.approx(pressure, rel=1e-12)


def test_the_pressure_rises_with_the_time_constant_r_c():
    """A step of 40 N per shoe, below the springs' 60 N preload: the shoes stay on their
    stops, no fluid moves but what the stops' give takes (2 A^2 / k_st, 2 % of C), and the
    pressure approaches F / A as ``exp(-t / R C)``: the slope of ``log(p_s - p)``."""
    force = 40.0
    stepper = _stepper(_held(force))
    block = stepper.run(3 * R * C)
    source = force / AREA
    pressure = line_pressure_pa(block, stepper.packed_parameters)
    gap = source - pressure
    assert gap[0] == pytest.approx(source - SPEC.residual_force_n / AREA, rel=1e-9)
    window = (gap < 0.8 * gap[0]) & (gap > 0.1 * gap[0])
    slope = np.polyfit(block.time_s[window], np.log(gap[window]), 1)[0]
    assert -1.0 / slope == pytest.approx(R * C, rel=0.10)
    for side in SIDES:
        assert np.all(block[f"{side}_normal_force_n"] == 0.0)


def test_a_shoes_actuation_defect_is_its_pistons_own():
    """A per-shoe defect acts on its own piston, the line on both: with the left shoe's
    command delayed by 20 ms and its gain 20 % down, the pistons' difference is the two
    shoes' commanded difference at every sample (``0.8 F(t - 0.02) - F(t)``), their mean
    the line pressure on the area; held, each pushes its own commanded force and the line
    sits at their mean over the area (the sensor reads 9 % less than the healthy brake's)."""
    ramp = ForceProfile((0.0, 0.05), (0.0, 1000.0))
    defects = Defects(left=ShoeDefect(actuation_delay_ms=20.0, actuation_gain_change_pct=-20.0))
    stepper = _stepper(Actuation(ramp, ramp), defects)
    block = stepper.run(0.1 + 15 * R * C)
    t = block.time_s
    commanded = 0.8 * np.interp(t - 0.02, ramp.times_s, ramp.forces_n) - ramp(t)
    left, right = block["left_actuation_force_n"], block["right_actuation_force_n"]
    free = (left > SPEC.residual_force_n) & (right > SPEC.residual_force_n)
    assert free.mean() > 0.8  # all but the start, where a piston is still at its floor
    np.testing.assert_allclose((left - right)[free], commanded[free], rtol=1e-9, atol=1e-9)
    assert left[-1] == pytest.approx(800.0, rel=1e-6)
    assert right[-1] == pytest.approx(1000.0, rel=1e-6)
    assert stepper.state[L.Y_LINE_PRESSURE] == pytest.approx(900.0 / AREA, rel=1e-6)


def _order(signal: np.ndarray, drum_angle: np.ndarray, time_s: np.ndarray, k: int) -> complex:
    """The complex amplitude ``X`` of the order-``k`` line of ``signal`` in the drum's
    angle: ``signal ~ c0 + c1 t + c2 t^2 + Re(X exp(-i k phi))`` by least squares."""
    t = time_s - time_s[0]
    basis = np.column_stack(
        [np.ones_like(t), t, t * t, np.cos(k * drum_angle), np.sin(k * drum_angle)]
    )
    coef = np.linalg.lstsq(basis, signal, rcond=None)[0]
    return complex(coef[3], coef[4])


def _tip_travel(side: str, theta: np.ndarray) -> np.ndarray:
    """The tip's outward travel along the cylinder axis, m (model/service.py's coordinate,
    from the placement of the healthy shoe)."""
    s = place_shoe(SERVICE, side, Defects().left)
    phi = s.sign * theta
    d = np.array(s.tip_xy_m) - np.array(s.pivot_xy_m)
    tx = np.cos(phi) * d[0] - np.sin(phi) * d[1]
    ty = np.sin(phi) * d[0] + np.cos(phi) * d[1]
    ex, ey = s.actuation_dir
    return (tx - d[0]) * ex + (ty - d[1]) * ey


PULSE_FORCE_N = 1000.0
SETTLE_S = 0.25  # > 8 R C: the step's transient has gone
PULSE_S = 0.55


@pytest.fixture(scope="module", params=("point", "arc"))
def pulsation(request):
    """Order-2 runs (an oval drum) at 0, 25 and 50 um under a held 1000 N, on the point
    contact or the lining over its arc: by runout, the order-2 complex amplitudes of the
    line pressure (Pa) and of the tips' summed travel (m), the mean order-2 frequency
    (rad/s) and each shoe's mean contact angle (rad); and the contact."""
    out = {"contact": request.param}
    for runout in (0.0, 25.0, 50.0):
        drum = DrumDefect((DrumHarmonic(2, runout, 0.0),)) if runout else DrumDefect()
        stepper = _stepper(_held(PULSE_FORCE_N), Defects(drum=drum), request.param)
        block = stepper.run(PULSE_S)
        w = block.time_s >= SETTLE_S
        phi, t = block["drum_angle_rad"][w], block.time_s[w]
        pressure = line_pressure_pa(block, stepper.packed_parameters)[w]
        travel = sum(_tip_travel(side, block[f"{side}_angle_rad"][w]) for side in SIDES)
        angles = [
            float(np.mean(np.arctan2(block[f"{s}_contact_y_m"][w], block[f"{s}_contact_x_m"][w])))
            for s in SIDES
        ]
        omega = 2.0 * float(np.mean(block["drum_speed_rad_s"][w]))
        out[runout] = (_order(pressure, phi, t, 2), _order(travel, phi, t, 2), omega, angles)
    return out


def _circuit_gain(omega: float) -> float:
    """|P / U| of ``C p' = -p / R - A U'`` at the frequency ``omega`` (rad/s), Pa/m."""
    return AREA * omega * R / math.sqrt(1.0 + (omega * R * C) ** 2)


def test_the_pedal_pulsation_of_an_oval_drum_is_the_hand_calculations(pulsation):
    """The tips pushed back by the drum push fluid back: the pressure's order-2 line is
    ``A Omega R |U| / sqrt(1 + (Omega R C)^2)`` of the tips' summed order-2 travel ``U``
    (within 20 %), and ``U`` is the shoes' lever on the runout: each tip travels ``q / d``
    times the drum's radius at its contact (``q``, ``d``: the actuation and normal arms
    about the pivot), the two in the phase of ``2 x`` their contact angles (within 20 %).
    The lining over its arc presses on a patch about the point contact's place (its radius
    is the drum's less the running clearance: under 1000 N, 14 and 10 of its 32 nodes
    press), so its lever is the point's within the same 20 % (4-7 % below it: a patch ``w``
    wide averages the order-2 profile by about ``sin(w) / w``, 0.94 over the leading shoe's
    35 deg)."""
    params_p = _stepper(_held(PULSE_FORCE_N), contact=pulsation["contact"]).packed_parameters
    levers = [contact_arms(params_p, L.P_SHOE_BASE + i * L.SHOE_STRIDE, 0.0) for i in range(2)]
    for runout in (25.0, 50.0):
        p_amp, u_amp, omega, angles = pulsation[runout]
        a = runout * 1e-6
        hand_u = abs(
            sum(
                a * arm.actuation_arm_m / arm.normal_arm_m * np.exp(2j * alpha)
                for arm, alpha in zip(levers, angles, strict=True)
            )
        )
        assert abs(u_amp) == pytest.approx(hand_u, rel=0.20), runout
        assert abs(p_amp) == pytest.approx(_circuit_gain(omega) * abs(u_amp), rel=0.20), runout
        assert abs(p_amp) == pytest.approx(_circuit_gain(omega) * hand_u, rel=0.20), runout


def test_the_pulsation_grows_in_proportion_to_the_runout(pulsation):
    amps = [abs(pulsation[r][0]) for r in (0.0, 25.0, 50.0)]
    assert amps[0] < 0.01 * amps[1]
    assert amps[0] < amps[1] < amps[2]
    assert amps[2] / amps[1] == pytest.approx(2.0, rel=0.10)


def test_the_step_limit_needs_no_hydraulic_mode():
    """The line pressure in the Jacobian (linearised at the sliding point the step limit
    uses) moves its stiffest eigenvalue and fastest oscillation by under 1 %: the
    circuit's spring at the tips is 0.3 % of the contact's."""
    stepper = _stepper(_held(PULSE_FORCE_N))
    p = stepper.packed_parameters
    fe = (PULSE_FORCE_N, PULSE_FORCE_N)
    y = stability._state(p, True, fe)
    for i, base in enumerate((L.P_SHOE_BASE, L.P_SHOE_BASE + L.SHOE_STRIDE)):
        y[L.Y_LEFT_ANGLE + i] = stability._loaded_angle(p, base, PULSE_FORCE_N, 100.0)
    y[L.Y_DRUM_SPEED] = y[L.Y_FLYWHEEL_SPEED] = 100.0
    slots = [*range(8), L.Y_LINE_PRESSURE]
    on = L.CONTACT_ON
    jac = np.zeros((len(slots), len(slots)))
    f_plus, f_minus = np.zeros(y.shape[0]), np.zeros(y.shape[0])
    for col, j in enumerate(slots):
        h = 1e-7 * max(1.0, abs(y[j]))
        yp, ym = y.copy(), y.copy()
        yp[j] += h
        ym[j] -= h
        kernel.rhs(yp, p, fe[0], fe[1], 0, on, on, f_plus)
        kernel.rhs(ym, p, fe[0], fe[1], 0, on, on, f_minus)
        jac[:, col] = (f_plus[slots] - f_minus[slots]) / (2 * h)
    held = np.linalg.eigvals(jac[:8, :8])
    full = np.linalg.eigvals(jac)
    assert np.abs(full).max() == pytest.approx(np.abs(held).max(), rel=0.01)
    assert np.abs(full.imag).max() == pytest.approx(np.abs(held.imag).max(), rel=0.01)
    # and the circuit's own rate is there, near 1 / (R C)
    assert np.any(np.abs(full.real + 1.0 / (R * C)) < 0.2 / (R * C))


STROKE_FORCE_N = 63.0  # above the springs' 60 N preload, below the 66 N that closes the gap
STROKE_S = 0.6


def _smoothed(x: np.ndarray, n: int) -> np.ndarray:
    """The running mean of ``x`` over ``n`` samples (valid part, centred)."""
    return np.convolve(x, np.ones(n) / n, mode="valid")


def test_the_shoes_ring_on_the_fluid_through_their_stroke():
    """A held 63 N per shoe, above the return springs' 60 N preload and below the 66 N at
    which the tips (0.6 mm of travel at 10 N/mm) close the 0.3 mm clearance: the shoes lift
    off their stops and move out together, never touching the drum. Both pistons share one
    line, so each tip sits on the fluid's spring ``2 A^2 / C`` beside its return spring's
    rate ``k``, with the shoe's inertia about its pin at the tip's arm, ``m = I / a^2``:

    * they ring in phase at ``f = sqrt((2 A^2 / C + k) / m) / 2 pi`` (within 2 %): the
      ripple of the piston force while a shoe travels (docs/scenarios.md);
    * damped by the line's flow alone (``omega R C >> 1``): ``zeta = (2 A^2 / C) /
      (2 A^2 / C + k) / (2 omega R C)`` (within 10 %);
    * and creep out as the source fills the pistons through the line, with the time
      constant ``R (C + 2 A^2 / k)`` (within 5 %), 21 times the pressure's ``R C``."""
    stepper = _stepper(_held(STROKE_FORCE_N))
    block = stepper.run(STROKE_S)
    assert np.all(block["left_normal_force_n"] == 0.0)
    assert np.all(block["right_normal_force_n"] == 0.0)
    placed = place_shoe(SERVICE, "left", Defects().left)
    arm = abs(
        (placed.tip_xy_m[0] - placed.pivot_xy_m[0]) * placed.actuation_dir[1]
        - (placed.tip_xy_m[1] - placed.pivot_xy_m[1]) * placed.actuation_dir[0]
    )
    mass = placed.inertia_about_pivot_kg_m2 / arm**2
    fluid = 2.0 * AREA**2 / C
    k = SPEC.return_spring_rate_n_per_m
    omega = math.sqrt((fluid + k) / mass)
    zeta = fluid / (fluid + k) / (2.0 * omega * R * C)
    tau = R * (C + 2.0 * AREA**2 / k)

    u = _tip_travel("left", block["left_angle_rad"])
    np.testing.assert_array_equal(u, _tip_travel("right", block["right_angle_rad"]))
    t = block.time_s
    # off the stop once the tip is past the stop's give (4 um: the preload's net 40 N on
    # k_st) by 10 um
    give = (SPEC.return_spring_preload_n - SPEC.residual_force_n) / SPEC.stop_stiffness_n_per_m
    lifted = int(np.argmax(u > give + 1e-5))
    assert 0 < lifted < 0.2 * FS
    period_n = round(FS * 2.0 * math.pi / omega)
    # the ring: the travel less its running mean over a period, zero crossings upward
    mean = _smoothed(u, period_n)
    ring = u[period_n // 2 : period_n // 2 + mean.shape[0]] - mean
    window = slice(lifted, lifted + 10 * period_n)
    ring, tr = ring[window], t[period_n // 2 :][window]
    up = np.flatnonzero((ring[:-1] < 0.0) & (ring[1:] >= 0.0))
    assert up.shape[0] >= 7
    frequency = 1.0 / np.median(np.diff(tr[up]))
    assert frequency == pytest.approx(omega / (2.0 * math.pi), rel=0.02)
    peaks = np.array([ring[a:b].max() for a, b in itertools.pairwise(up)])
    measured_zeta = -np.polyfit(np.arange(peaks.shape[0]), np.log(peaks), 1)[0] / (2 * math.pi)
    assert measured_zeta == pytest.approx(zeta, rel=0.10)
    # the creep: three running means a tenth of a second apart, from 0.2 s on
    i1, i2, i3 = (int((0.2 + 0.1 * j) * FS) for j in range(3))
    creep_tau = 0.1 / math.log((mean[i2] - mean[i1]) / (mean[i3] - mean[i2]))
    assert creep_tau == pytest.approx(tau, rel=0.05)
