"""The unit scatter on the service brake (fleet/scatter.py ``SERVICE_SCATTER``): it
spreads what the service brake reads (its 0.3 mm clearance with a self-adjuster's
tolerance, its return spring, its circuit, its tyre) and not the study coupling it does
not read; a key both brakes scatter draws the same uniform for a unit. The study brake's
draws are tests/fleet/test_units.py's (hex floats, unchanged)."""

from __future__ import annotations

import itertools
from dataclasses import replace

import pytest

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.fleet import scatter
from brake_sim_ros.model.assembly import pack
from brake_sim_ros.model.defects import Defects
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.service_parameters import SERVICE_RUNNING_CLEARANCE_M
from brake_sim_ros.scenarios import parse_scenario
from brake_sim_ros.sensing.sensors import default_sensor_set

SERVICE = BrakeParameters.of_brake("service")
SENSORS = default_sensor_set()
COUPLING = (
    "driveline.coupling_stiffness_n_m_per_rad",
    "driveline.coupling_damping_n_m_s_per_rad",
)
OWN = (
    "shoe.running_clearance_m",
    "service.return_spring_preload_n",
    "service.line_compliance_m3_per_pa",
    "service.tyre.presliding_stiffness_per_m",
)


def test_the_service_table_scatters_what_the_service_brake_reads():
    keys = [s.key for s in scatter.SERVICE_SCATTER]
    assert len(keys) == len(set(keys))
    assert not set(COUPLING) & set(keys) and set(OWN) <= set(keys)
    clearance = next(s for s in scatter.SERVICE_SCATTER if s.key == "shoe.running_clearance_m")
    assert (clearance.mode, clearance.limit) == ("absolute", 0.1e-3)
    assert all(s.source for s in scatter.SERVICE_SCATTER)
    # every study entry the service brake reads is kept as it is
    study = {s.key: s for s in scatter.SCATTER}
    for s in scatter.SERVICE_SCATTER:
        if s.key in study and s.key not in OWN:
            assert s == study[s.key]


def test_service_units_move_what_it_reads_within_tolerance_and_keep_the_coupling():
    for i in range(60):
        unit_id = f"svc-{i}"
        unit = scatter.unit_parameters(SERVICE, unit_id, 0)
        assert unit.brake == "service"
        # the coupling, not read: the drawing's (only the drum's inertia scatters)
        inertia = unit.driveline.drum_inertia_kg_m2
        assert unit.driveline == replace(SERVICE.driveline, drum_inertia_kg_m2=inertia)
        gap = unit.shoe.running_clearance_m
        assert gap != SERVICE_RUNNING_CLEARANCE_M
        assert abs(gap - SERVICE_RUNNING_CLEARANCE_M) <= 0.1e-3 * (1 + 1e-9)
        sensors = scatter.unit_sensors(SENSORS, unit_id, 0)
        values = scatter.unit_values(SERVICE, unit, SENSORS, sensors)
        assert {v.key for v in values} >= set(OWN) and not {v.key for v in values} & set(COUPLING)
        for v in values:
            assert v.value != v.nominal, v.key  # every parameter of the table scatters
            if v.scatter.mode == "relative":
                assert abs(v.value / v.nominal - 1.0) <= v.scatter.limit * (1 + 1e-12), v.key
        # the residual force, the stop and the tyre's road stay the drawing's
        assert unit.service.residual_force_n == SERVICE.service.residual_force_n
        assert unit.service.tyre.road_friction == SERVICE.service.tyre.road_friction
        pack(unit, Defects())  # a valid brake


def test_a_key_of_both_tables_draws_the_same_uniform_for_a_unit():
    """The clearance's tolerance is 3 sigma on both brakes, so the service deviation is the
    study's scaled by 0.1/0.3 mm; every other common key draws the same deviation."""
    for i in range(20):
        study = scatter.deviations(f"u{i}", 5)
        service = scatter.deviations(f"u{i}", 5, "service")
        gap = "shoe.running_clearance_m"
        assert service[gap] == pytest.approx(study[gap] / 3.0, rel=1e-9, abs=1e-18)
        for key in set(study) & set(service) - {gap}:
            assert service[key] == study[key], key


def test_the_corners_of_the_service_tolerance_box_are_valid_brakes():
    """Every corner of the service brake's own tolerances and its geometry's."""
    corners = [s for s in scatter.SERVICE_SCATTER if s.key in OWN or s.key.startswith("shoe.")]
    for signs in itertools.product((-1.0, 1.0), repeat=len(corners)):
        drawn = {s.key: sign * s.limit for s, sign in zip(corners, signs, strict=True)}
        pack(scatter.with_deviations(SERVICE, drawn), Defects())


def test_a_scenario_unit_of_the_service_brake_scatters_around_the_files_values():
    text = (
        'name = "svc"\nbrake = "service"\nunit_id = "VIN-3"\nfleet_seed = 2\n'
        "[parameters.service]\nreturn_spring_preload_n = 80.0\n"
    )
    scenario = parse_scenario(text)
    d = scatter.deviations("VIN-3", 2, "service")["service.return_spring_preload_n"]
    assert scenario.setup.params.service.return_spring_preload_n == 80.0 * (1.0 + d)
    assert scenario.drawing_params.service.return_spring_preload_n == 80.0
    units = {v.key: v.unit for v in scenario.unit_values()}
    assert units["service.return_spring_preload_n"] == "N"
    assert units["service.tyre.presliding_stiffness_per_m"] == "1/m"  # per metre, not metres
    keys = set(units)
    assert "service.tyre.presliding_stiffness_per_m" in keys
    assert not keys & set(COUPLING)


def test_a_deviation_the_brake_does_not_scatter_is_refused_in_one_line():
    with pytest.raises(ParameterError) as info:
        scatter.with_deviations(SERVICE, {"driveline.coupling_stiffness_n_m_per_rad": 0.1})
    assert "not scattered on the service brake" in str(info.value)
    assert "\n" not in str(info.value)
    with pytest.raises(ParameterError, match="allowed one of"):
        scatter.deviations("u", 0, "racing")
