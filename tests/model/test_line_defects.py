"""The hydraulic line's defects (catalogue location ``line``, model/line_kinds.py) on the
service brake's circuit: air (an isothermal gas's compliance beside the circuit's) and a
leak (a flow ``G p`` to the reservoir). Each figure a test expects is a hand calculation
from the documented laws and the parameters (R, C, the piston area, the stops' give, the
air's gas law), never read off a run."""

from __future__ import annotations

import math

import numpy as np
import pytest

from brake_sim_ros.analysis.energy import energy_balance, line_pressure_pa
from brake_sim_ros.campaigns.campaign import CampaignError
from brake_sim_ros.campaigns.loader import parse_campaign
from brake_sim_ros.errors import ParameterError, ScenarioError
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.actuation import Actuation, ForceProfile
from brake_sim_ros.model.assembly import pack
from brake_sim_ros.model.defects import Defects, LineDefect
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.run_setup import BrakeSetup
from brake_sim_ros.model.service import ATMOSPHERIC_PA
from brake_sim_ros.scenarios import load_scenario, parse_scenario
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.stream.session import RunSession

FS = 25600.0
SERVICE = BrakeParameters.of_brake("service")
SPEC = SERVICE.service
AREA = SPEC.piston_area_m2
R = SPEC.line_resistance_pa_s_per_m3
C = SPEC.line_compliance_m3_per_pa
# the fluid the two rest stops give per pascal while the shoes sit on them (2 A^2 / k_st)
STOPS = 2.0 * AREA**2 / SPEC.stop_stiffness_n_per_m
RESIDUAL_PA = SPEC.residual_force_n / AREA


def _run(force: ForceProfile, line: LineDefect, duration_s: float):
    setup = BrakeSetup(
        params=SERVICE, defects=Defects(line=line), actuation=Actuation(force, force)
    )
    stepper = FixedStepStepper(setup, 1.0 / FS)
    block = stepper.run(duration_s)
    return block, line_pressure_pa(block, stepper.packed_parameters)


def _time_constant(time_s: np.ndarray, gap: np.ndarray) -> float:
    """``-1 / slope`` of ``log(gap)`` where the gap is between 80 % and 10 % of its start."""
    window = (gap < 0.8 * gap[0]) & (gap > 0.1 * gap[0])
    return -1.0 / np.polyfit(time_s[window], np.log(gap[window]), 1)[0]


def test_air_in_the_line_lengthens_the_pressures_time_constant_to_r_times_its_compliance():
    """1 ml of air, a step of the source from the residual 20 N to 21 N per shoe (the
    shoes stay on their stops, 60 N preload): the pressure settles with ``R C'``, ``C' =
    C + V_a p_a / (p_a + p)^2 + 2 A^2 / k_st`` at the window's middle pressure, about five
    times the healthy line's (the air's compliance at 0.7 bar is 4.3 C)."""
    force = 21.0
    source = force / AREA
    air = 1e-6  # m^3
    middle = source - 0.3 * (source - RESIDUAL_PA)  # log-middle of the 80 %..10 % window
    hand = R * (C + air * ATMOSPHERIC_PA / (ATMOSPHERIC_PA + middle) ** 2 + STOPS)
    assert hand > 4.0 * R * C
    block, pressure = _run(ForceProfile.constant(force), LineDefect(air_in_line_ml=1.0), 2.6 * hand)
    assert _time_constant(block.time_s, source - pressure) == pytest.approx(hand, rel=0.10)
    assert np.all(block["left_normal_force_n"] == 0.0)


def test_more_air_raises_the_pressure_later():
    """An application to 1000 N per shoe in 20 ms: the time the line takes to reach half
    its static pressure ``p_h`` grows with the air in it (0, 0.5, 1, 2 ml). Hand bound with
    1 ml: the source must push at least ``C (p_h - p_r)`` and the air's take-up
    ``V_a p_a (1 / (p_a + p_r) - 1 / (p_a + p_h))`` through R, at most ``p_s(t) / R``
    (the ramp's source against the line's residual pressure or more): the time is at
    least ``t`` with ``integral of p_s / R = `` that volume."""
    peak = 1000.0 / AREA
    ramp = ForceProfile((0.0, 0.02), (0.0, 1000.0))
    half = 0.5 * peak
    times = []
    for ml in (0.0, 0.5, 1.0, 2.0):
        block, pressure = _run(ramp, LineDefect(air_in_line_ml=ml), 0.2)
        reached = np.flatnonzero(pressure >= half)
        assert reached.size, f"{ml} ml: the line never reached half its static pressure"
        times.append(float(block.time_s[reached[0]]))
    assert np.all(np.diff(times) > 0.0), times
    p_a = ATMOSPHERIC_PA
    needed = C * (half - RESIDUAL_PA) + 1e-6 * p_a * (1 / (p_a + RESIDUAL_PA) - 1 / (p_a + half))
    bound = needed * R / peak + 0.01  # the ramp's integral: peak (t - 0.01) past 20 ms
    assert bound > 0.02
    assert times[2] >= bound


@pytest.mark.parametrize("leak_pct", [10.0, 40.0])
def test_a_leak_holds_the_pressure_short_by_its_severity_and_settles_faster(leak_pct):
    """A held 40 N per shoe (the shoes on their stops) with a leak: the line holds
    ``(1 - s) F / A`` (the source's flow through R makes up the leak, ``G = s / ((1 - s)
    R)``) within 1 %, and settles with ``R (C + 2 A^2 / k_st) (1 - s)`` within 10 %."""
    force = 40.0
    s = leak_pct / 100.0
    hand_tau = R * (C + STOPS) * (1.0 - s)
    block, pressure = _run(ForceProfile.constant(force), LineDefect(line_leak_pct=leak_pct), 0.3)
    held = (1.0 - s) * force / AREA
    assert pressure[-1] == pytest.approx(held, rel=0.01)
    gap = held - pressure
    assert _time_constant(block.time_s, gap) == pytest.approx(hand_tau, rel=0.10)


def test_a_leak_held_at_a_braking_force_each_piston_pushes_its_share_of_the_droop():
    """1000 N per shoe held with a 20 % leak: the line sits at 0.8 F / A within 1 %, each
    piston pushes 800 N, and the more leak the lower the held pressure (0, 20, 60 %)."""
    held = []
    for pct in (0.0, 20.0, 60.0):
        block, pressure = _run(ForceProfile.constant(1000.0), LineDefect(line_leak_pct=pct), 0.5)
        held.append(float(pressure[-1]))
        if pct == 20.0:
            assert pressure[-1] == pytest.approx(0.8 * 1000.0 / AREA, rel=0.01)
            for side in ("left", "right"):
                assert block[f"{side}_actuation_force_n"][-1] == pytest.approx(800.0, rel=0.01)
    assert held[0] > held[1] > held[2], held


def test_the_study_brake_refuses_a_line_defect_in_one_line():
    """The study brake has no circuit: a scenario that sets a line's defect is refused
    naming the table, what is wrong and what is allowed; packing refuses it too (the
    node's parameters); the service brake loads it."""
    text = 'name = "x"\nduration_s = 0.5\n[defects.line]\nair_in_line_ml = 1.0\n'
    with pytest.raises(ScenarioError) as caught:
        parse_scenario(text, "x.toml")
    message = str(caught.value)
    assert "\n" not in message
    assert "x.toml: [defects.line]" in message
    assert "air_in_line_ml=1" in message and "study brake" in message
    assert 'allowed only with brake = "service"' in message
    with pytest.raises(ParameterError, match="line_leak_pct=5 is invalid on the study brake"):
        pack(BrakeParameters(), Defects(line=LineDefect(line_leak_pct=5.0)))
    loaded = parse_scenario('brake = "service"\n' + text, "x.toml").setup.defects
    assert loaded.line == LineDefect(air_in_line_ml=1.0)
    assert [d.label for d in loaded.active()] == ["line air_in_line +1 ml"]


def test_a_line_defect_beyond_its_range_is_refused_naming_the_limit():
    with pytest.raises(ParameterError, match=r"air_in_line_ml=12 is invalid: allowed 0 to 10"):
        LineDefect(air_in_line_ml=12.0)
    with pytest.raises(ParameterError, match=r"line_leak_pct=95 is invalid: allowed 0 to 90"):
        LineDefect(line_leak_pct=95.0)


def test_the_line_defects_pack_their_physical_slots():
    """The air's volume in m^3 and the leak's conductance ``s / ((1 - s) R)``; a sound
    line packs zeros there, and the study brake's packed vector is the same length."""
    healthy = pack(SERVICE, Defects())
    assert healthy[L.P_LINE_AIR_VOLUME] == 0.0 == healthy[L.P_LINE_LEAK_CONDUCTANCE]
    p = pack(SERVICE, Defects(line=LineDefect(air_in_line_ml=2.5, line_leak_pct=20.0)))
    assert p[L.P_LINE_AIR_VOLUME] == pytest.approx(2.5e-6, rel=1e-12)
    assert p[L.P_LINE_LEAK_CONDUCTANCE] == pytest.approx(0.2 / (0.8 * R), rel=1e-12)
    assert math.isclose(p[L.P_LINE_COMPLIANCE], C)  # the circuit's own C is not rewritten


def test_a_campaign_on_the_study_brake_sweeps_no_line_defect_and_refuses_one_named():
    """A defect axis "all" over a study-brake base leaves the line's kinds out (the base
    has no circuit); naming one is refused in one line saying why."""
    text = (
        'name = "c"\nbase = "symmetric"\nunits = 3\n[[axes]]\ndefects = {kinds}\n'
        "severities = [1.0]\nhealthy = false\n"
    )
    kinds = {c.kind for c in parse_campaign(text.format(kinds='"all"'), "c.toml").axes[0].choices}
    assert "air_in_line" not in kinds and "line_leak" not in kinds and "drum_flat" in kinds
    with pytest.raises(CampaignError) as caught:
        parse_campaign(text.format(kinds='["line_leak"]'), "c.toml")
    assert "\n" not in str(caught.value)
    assert '(the base is the study brake: the line\'s kinds need brake = "service")' in str(
        caught.value
    )


def test_a_node_on_the_study_brake_refuses_a_line_parameter_and_keeps_its_model():
    """The node's ``defects.line.*`` parameters exist on either brake (a ~/reset may move
    it to the other); on the study brake a value other than healthy is refused in one
    line and the run's model is unchanged."""
    session = RunSession(load_scenario("symmetric"))
    before = session.stepper.packed_parameters.copy()
    with pytest.raises(ParameterError) as caught:
        session.apply({"defects.line.air_in_line_ml": 2.0})
    assert "\n" not in str(caught.value) and "study brake" in str(caught.value)
    assert np.array_equal(session.stepper.packed_parameters, before)
    assert session.model["defects.line.air_in_line_ml"] == 0.0


def test_energy_closes_through_the_lines_air_and_leak():
    """The three applications of the service brake's tests with 1 ml of air and a 20 %
    leak: the books (the air's stored ``V_a p_a (ln(1 + x) - x / (1 + x))``, the leak's
    loss ``G p^2``) close to 1e-6 of the turnover, as the sound line's do."""
    from tests.model.test_service_brake import _run as run_text
    from tests.model.test_service_brake import _three_applications

    line = LineDefect(air_in_line_ml=1.0, line_leak_pct=20.0)
    scenario, stepper, block = run_text(_three_applications(), Defects(line=line))
    assert scenario.setup.defects.line == line
    books = energy_balance(block, scenario.setup.params, packed=stepper.packed_parameters)
    assert abs(books.residual_j) < 1e-6 * books.turnover_j


def test_the_airs_stored_energy_is_the_work_of_the_pressure_on_its_volume():
    """``line_energy`` (the books' circuit term) is ``integral p dV`` from 0 gauge with the
    circuit's and the air's take-up ``dV = (C + V_a p_a / (p_a + p)^2) dp``: at 0.7, 10 and
    100 bar, by the trapezoid rule on a fine grid (1e-6)."""
    from brake_sim_ros.model.service import line_energy

    p = pack(SERVICE, Defects(line=LineDefect(air_in_line_ml=2.0)))
    for bar in (0.7, 10.0, 100.0):
        grid = np.linspace(0.0, bar * 1e5, 200_001)
        take_up = C + 2e-6 * ATMOSPHERIC_PA / (ATMOSPHERIC_PA + grid) ** 2
        work = np.trapezoid(grid * take_up, grid)
        assert line_energy.py_func(p, bar * 1e5) == pytest.approx(work, rel=1e-6)


def test_air_softens_the_pedal_pulsation_of_an_oval_drum_at_a_light_application():
    """A 50 um oval drum under a held 200 N (7 bar): the tips push fluid back at order 2,
    and the line's pressure answers with ``|P/U| = A w R / sqrt(1 + (w R C')^2)``; 1 ml of
    air adds ``V_a p_a / (p_a + p)^2`` (0.2 C at 7 bar) to C', so the pulsation is smaller
    than the sound line's, each within 5 % of its hand gain times the tips' measured U."""
    from brake_sim_ros.model.defects import DrumDefect, DrumHarmonic
    from tests.model.test_hydraulics import PULSE_S, SETTLE_S, SIDES, _held, _order, _tip_travel
    from tests.model.test_hydraulics import _stepper as stepper_with

    drum = DrumDefect((DrumHarmonic(2, 50.0, 0.0),))
    amplitudes = []
    for ml in (0.0, 1.0):
        stepper = stepper_with(_held(200.0), Defects(drum=drum, line=LineDefect(air_in_line_ml=ml)))
        block = stepper.run(PULSE_S)
        w = block.time_s >= SETTLE_S
        phi, t = block["drum_angle_rad"][w], block.time_s[w]
        pressure = line_pressure_pa(block, stepper.packed_parameters)[w]
        travel = sum(_tip_travel(side, block[f"{side}_angle_rad"][w]) for side in SIDES)
        p_amp, u_amp = abs(_order(pressure, phi, t, 2)), abs(_order(travel, phi, t, 2))
        omega = 2.0 * float(np.mean(block["drum_speed_rad_s"][w]))
        mean = float(np.mean(pressure))
        compliance = C + 1e-6 * ml * ATMOSPHERIC_PA / (ATMOSPHERIC_PA + mean) ** 2
        gain = AREA * omega * R / math.sqrt(1.0 + (omega * R * compliance) ** 2)
        assert p_amp == pytest.approx(gain * u_amp, rel=0.05)
        amplitudes.append(p_amp)
    assert amplitudes[1] < 0.9 * amplitudes[0]
