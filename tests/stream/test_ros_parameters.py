"""ROS parameter declarations of the node, generated from the core: pure logic, no rclpy."""

from __future__ import annotations

import dataclasses

import pytest

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.parameters import PARAMETER_GROUPS, POSES, BrakeParameters
from brake_sim_ros.scenarios import builtin_names, load_scenario
from brake_sim_ros.stream import parameters as ros_params


def test_every_core_field_is_a_parameter():
    names = ros_params.model_values(BrakeParameters(), Defects())
    expected = {
        f"defects.{side}.{f.name}"
        for side in ros_params.SIDES
        for f in ros_params.defect_fields(side)
    }
    expected |= {
        f"{group}.{f.name}"
        for group, cls in PARAMETER_GROUPS.items()
        for f in dataclasses.fields(cls)
    }
    expected |= {f"defects.drum.{f.name}" for f in ros_params.defect_fields("drum")}
    # the hydraulic line's, declared on either brake (the study brake refuses a value)
    expected |= {f"defects.line.{f.name}" for f in ros_params.defect_fields("line")}
    # the drum's flat, written once (its catalogue entry), is what the drum takes
    assert {f.name for f in ros_params.defect_fields("drum")} == {
        "flat_depth_um",
        "flat_centre_deg",
        "flat_width_deg",
    }
    assert set(names) == expected
    for required in (
        "defects.left.pivot_radius_change_pct",
        "defects.right.actuation_share",
        "friction.coefficient",
        "friction.smoothing_speed_m_s",
        "contact.damping_n_s_per_m",
        "shoe.running_clearance_m",
    ):
        assert required in names


@pytest.mark.parametrize("name", builtin_names())
def test_round_trip_and_ranges_for_every_builtin_scenario(name):
    setup = load_scenario(name).setup
    values = ros_params.model_values(setup.params, setup.defects)
    params, defects = ros_params.build_model(values)
    # growth laws are not parameters (the node keeps a scenario's across value changes)
    assert params == setup.params
    assert dataclasses.replace(defects, growth=setup.defects.growth) == setup.defects
    for spec in ros_params.model_parameter_specs(setup.params, setup.defects):
        assert spec.description and "(" in spec.description
        if isinstance(spec.default, bool):  # a switch (the lining over its arc): no range
            assert spec.range is None, spec.name
            continue
        if isinstance(spec.default, str):  # a name (the shoe's pose): the names allowed
            assert spec.range is None and all(p in spec.description for p in POSES), spec.name
            continue
        assert spec.range is not None, spec.name
        assert spec.range[0] <= spec.default <= spec.range[1], spec.name


@pytest.mark.parametrize(
    ("field", "low", "high"),
    [
        ("pivot_radius_change_pct", -20.0, 20.0),
        ("initial_angle_deg", -10.0, 10.0),
    ],
)
def test_defect_ranges_equal_the_core_bounds(field, low, high):
    specs = {s.name: s for s in ros_params.model_parameter_specs(BrakeParameters(), Defects())}
    assert specs[f"defects.left.{field}"].range == (low, high)
    for ok in (low, high):
        ShoeDefect(**{field: ok})
    for bad in (low - 1e-6, high + 1e-6):
        with pytest.raises(ParameterError):
            ShoeDefect(**{field: bad})


def test_invalid_values_raise_the_core_message():
    values = ros_params.model_values(BrakeParameters(), Defects())
    with pytest.raises(ParameterError, match="coefficient"):
        ros_params.build_model({**values, "friction.coefficient": 1.5})
    with pytest.raises(ParameterError, match="allowed a sum of exactly 1"):
        ros_params.build_model({**values, "defects.left.actuation_share": 0.6})


def test_a_lone_actuation_share_change_is_completed():
    assert ros_params.complete_actuation_share({"defects.left.actuation_share": 0.6}) == {
        "defects.left.actuation_share": 0.6,
        "defects.right.actuation_share": pytest.approx(0.4),
    }
    both = {"defects.left.actuation_share": 0.6, "defects.right.actuation_share": 0.3}
    assert ros_params.complete_actuation_share(both) == both
    assert ros_params.complete_actuation_share({"friction.coefficient": 0.3}) == {
        "friction.coefficient": 0.3
    }


def test_initial_conditions_are_documented():
    specs = {s.name: s for s in ros_params.model_parameter_specs(BrakeParameters(), Defects())}
    for name in ros_params.INITIAL_CONDITIONS:
        assert "next ~/reset" in specs[name].description


def test_run_parameters():
    specs = {s.name: s for s in ros_params.run_parameter_specs()}
    assert specs["chunk_rate_hz"].default == 100.0
    assert specs["state_rate_hz"].default == 100.0
    assert specs["real_time_factor"].default == 1.0
    assert specs["paused"].default is False
    assert specs["publish_clock"].default is True
    assert specs["command_timeout_s"].default == 0.2
    assert specs["on_command_timeout"].default == "profile"
    assert set(specs) >= ros_params.FIXED_AT_START


def test_auto_max_force_is_twice_the_peak_whatever_the_step():
    """The default command ceiling does not depend on the physics step any more: the
    stepper re-picks its substeps for any accepted force."""
    assert ros_params.auto_max_actuation_force(load_scenario("symmetric").setup) == 2 * 1300.0
    case2 = load_scenario("case2_left_pivot_in")  # a 9 us step limit at 1300 N
    assert ros_params.auto_max_actuation_force(case2.setup) == 2 * 1300.0


def test_descriptors():
    pytest.importorskip("rcl_interfaces")
    from rcl_interfaces.msg import ParameterType

    from brake_sim_ros.ros.descriptors import descriptor

    spec = ros_params.ParamSpec("friction.coefficient", 0.3, "text", (0.0, 1.0))
    desc = descriptor(spec)
    assert desc.type == ParameterType.PARAMETER_DOUBLE
    assert desc.floating_point_range[0].from_value == 0.0
    assert desc.floating_point_range[0].to_value == 1.0
    flag = descriptor(ros_params.ParamSpec("paused", False, "t"))
    assert flag.type == ParameterType.PARAMETER_BOOL


def test_the_drums_flat_is_a_node_parameter_and_the_scenarios_harmonics_are_kept():
    from brake_sim_ros.model.defects import Defects as _Defects
    from brake_sim_ros.model.defects import DrumDefect as _DrumDefect
    from brake_sim_ros.model.parameters import BrakeParameters as _Params
    from brake_sim_ros.stream import parameters as _p

    oval = _DrumDefect.from_orders((2, 20.0, 0.0))
    values = _p.model_values(_Params(), _Defects(drum=oval))
    assert values["defects.drum.flat_depth_um"] == 0.0
    values["defects.drum.flat_depth_um"] = 40.0
    values["defects.drum.flat_centre_deg"] = 90.0
    _params, defects = _p.build_model(values, drum=oval)
    assert defects.drum.harmonics == oval.harmonics
    assert (defects.drum.flat_depth_um, defects.drum.flat_centre_deg) == (40.0, 90.0)
    values["defects.drum.flat_depth_um"] = 1500.0
    with pytest.raises(ParameterError, match="flat_depth_um=1500 is invalid: allowed 0 to 1000"):
        _p.build_model(values, drum=oval)


def test_the_live_drives_settings_are_parameters_fixed_at_start():
    """max_drive_torque_n_m and speed_time_constant_s: 0 = the scenario's [vehicle], an
    envelope up to the vehicle's limits (which check the rest), fixed at start."""
    from brake_sim_ros.model.vehicle import DRIVE_LIMITS

    specs = {s.name: s for s in ros_params.run_parameter_specs()}
    for name, _lo, hi in DRIVE_LIMITS:
        assert specs[name].default == 0.0 and specs[name].range == (0.0, hi)
        assert name in ros_params.FIXED_AT_START and "[vehicle]" in specs[name].description


def test_the_nodes_start_up_setup_keeps_a_growing_defects_law():
    """node_setup (the node at start, and resim of its recordings): the parameters set the
    final values; the onset and growth law stay the scenario's, as on a ~/reset to it."""
    from brake_sim_ros.scenarios import parse_scenario

    scenario = parse_scenario(
        'name = "g"\n[defects.left]\npivot_radius_change_pct = {value = 2.0, onset_s = 0.1,'
        ' growth = "linear", rate_per_s = 4.0}\n'
    )
    setup = scenario.setup
    values = ros_params.model_values(setup.params, setup.defects)
    assert ros_params.node_setup(setup, values, {}) == setup
    values["defects.left.pivot_radius_change_pct"] = 0.0  # no defect: no growth of it
    assert ros_params.node_setup(setup, values, {}).defects.growth == ()
