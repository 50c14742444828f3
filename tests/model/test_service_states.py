"""The service brake's state slots (layout.N_STATE_SERVICE): every service run carries them,
the study brake's runs keep their sizes, and a slot the run does not drive stays where it
started (the temperature of a run without a thermal state at the temperature it is held at).
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from brake_sim_ros.model import layout as L
from brake_sim_ros.model.actuation import Actuation, ForceProfile
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.run_setup import BrakeSetup
from brake_sim_ros.model.thermal import Thermal
from brake_sim_ros.scenarios import parse_scenario
from brake_sim_ros.solvers.fixed_step import FixedStepStepper
from brake_sim_ros.stream.build import stepper_for

STEP = 1.0 / 25600.0
SERVICE = BrakeParameters.of_brake("service")
# an application of 0.1 s: the linings rub, heat and (with a wear law) wear
APPLIED = Actuation(*(ForceProfile((0.0, 0.02, 0.1), (0.0, 800.0, 800.0)),) * 2)


def _stepper(params: BrakeParameters, **setup) -> FixedStepStepper:
    return FixedStepStepper(BrakeSetup(params=params, actuation=APPLIED, **setup), STEP)


def test_a_service_run_carries_every_service_state_and_holds_its_temperature():
    stepper = _stepper(SERVICE, held_temperature_c=35.0)
    assert stepper.state.shape == (L.N_STATE_SERVICE,)
    block = stepper.run(0.1)
    y = stepper.state
    assert y.shape == (L.N_STATE_SERVICE,)
    assert block["friction_work_j"][-1] > 0.0  # the linings rubbed: a thermal state would heat
    assert y[L.Y_BRAKE_TEMPERATURE] == 35.0
    assert np.all(block["brake_temperature_c"] == 35.0)
    for slot in (L.Y_LEFT_WEAR, L.Y_RIGHT_WEAR):
        assert y[slot] == 0.0
    assert y[L.Y_TYRE_DEFLECTION] < 0.0  # the tread carries the braking force (model/tyre.py)


def test_a_service_run_with_a_thermal_state_heats_in_its_slot():
    stepper = _stepper(SERVICE, thermal=Thermal(cooling_w_k=0.0, cooling_w_k_per_m_s=0.0))
    block = stepper.run(0.1)
    y = stepper.state
    assert y.shape == (L.N_STATE_SERVICE,)
    heat = Thermal().heat_capacity_j_k * (y[L.Y_BRAKE_TEMPERATURE] - Thermal().start_c)
    assert heat == pytest.approx(y[L.Y_FRICTION_WORK], rel=1e-9)
    assert block["brake_temperature_c"][-1] > Thermal().start_c


# the left lining wears with its friction work, fast enough to see in 0.1 s
WEARING = """name = "wearing"
duration_s = 0.1
[actuation]
profile = "piecewise"
[actuation.left]
times_s = [0.0, 0.02]
forces_n = [0.0, 800.0]
[actuation.right]
times_s = [0.0, 0.02]
forces_n = [0.0, 800.0]
[defects.left.lining_wear_mm]
value = 1.0
growth = "friction_work"
wear_rate_mm_per_mj = 1000.0
"""


def test_a_service_lining_wearing_with_its_work_wears_in_its_slot():
    stepper = stepper_for(parse_scenario('brake = "service"\n' + WEARING))
    stepper.run(0.1)
    y = stepper.state
    assert y.shape == (L.N_STATE_SERVICE,)
    assert y[L.Y_LEFT_WEAR] > 0.0 and y[L.Y_RIGHT_WEAR] == 0.0


def test_the_study_brakes_runs_keep_their_sizes():
    assert _stepper(BrakeParameters()).state.shape == (L.N_STATE,)
    assert _stepper(BrakeParameters(), thermal=Thermal()).state.shape == (L.N_STATE_THERMAL,)
    assert stepper_for(parse_scenario(WEARING)).state.shape == (L.N_STATE_WEAR,)


def test_a_parameter_change_keeps_a_service_runs_states():
    stepper = _stepper(SERVICE, held_temperature_c=35.0)
    stepper.run(0.05)
    before = stepper.state
    changed = dataclasses.replace(stepper.setup, held_temperature_c=25.0)
    stepper.replace_setup(changed)
    after = stepper.state
    assert after.shape == (L.N_STATE_SERVICE,)
    np.testing.assert_array_equal(after[: L.Y_BRAKE_TEMPERATURE], before[: L.Y_BRAKE_TEMPERATURE])
    assert after[L.Y_BRAKE_TEMPERATURE] == 25.0
    stepper.replace_setup(dataclasses.replace(changed, thermal=Thermal(initial_c=60.0)))
    assert stepper.state[L.Y_BRAKE_TEMPERATURE] == 60.0
    assert stepper.state.shape == (L.N_STATE_SERVICE,)
