"""A scenario's ``[parameters.service]`` and ``[parameters.service.tyre]``: the service
brake's springs, stops, hydraulics and tyre set from the file, packed into the model,
carried by the node's flat parameter values and refused in one line when wrong (or given to
the study brake, which reads none of them)."""

from __future__ import annotations

import dataclasses

import pytest

from brake_sim_ros.errors import ParameterError, ScenarioError
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.assembly import pack
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.scenarios.loader import parse_scenario
from brake_sim_ros.stream import parameters as ros_params
from brake_sim_ros.stream.build import stepper_for

SERVICE = (
    'name = "t"\nbrake = "service"\nroad_friction = 0.5\n'
    "[parameters.service]\nreturn_spring_preload_n = 90.0\nline_compliance_m3_per_pa = 1.6e-12\n"
    "wheel_cylinder_bore_m = 0.022\n"
    "[[sensors]]\n"  # the line-pressure sensor on the same bore
    'name = "p"\nkind = "line_pressure"\nlocation = "wheel_cylinder"\npiston_diameter_m = 0.022\n'
    "[parameters.service.tyre]\npresliding_stiffness_per_m = 55.0\npeak_ratio = 1.3\n"
)


def test_the_service_table_sets_the_service_brake_and_leaves_the_rest_at_its_defaults():
    params = parse_scenario(SERVICE).setup.params
    default = BrakeParameters.of_brake("service").service
    spec = params.service
    assert (spec.return_spring_preload_n, spec.line_compliance_m3_per_pa) == (90.0, 1.6e-12)
    assert spec.wheel_cylinder_bore_m == 0.022
    assert (spec.tyre.presliding_stiffness_per_m, spec.tyre.peak_ratio) == (55.0, 1.3)
    assert spec.tyre.road_friction == 0.5  # the top-level key's, kept under the tyre table
    assert spec.residual_force_n == default.residual_force_n
    assert spec.tyre.stribeck_speed_m_s == default.tyre.stribeck_speed_m_s
    # what the kernel reads: the spring's preload and the tread's stiffness as given
    p = pack(params, parse_scenario(SERVICE).setup.defects)
    assert p[L.P_SPRING_BASE + L.R_PRELOAD] == 90.0
    assert p[L.P_TYRE_STIFFNESS] == 55.0


SCENARIO_POINT = parse_scenario('name = "t"\nbrake = "service"\n')


def test_the_lining_over_its_arc_is_the_scenarios_choice():
    """``distributed_lining = true`` packs the lining's nodes (model/lining.py) and the
    stepper takes the physics steps its stiffer contact needs; the default keeps the
    point contact; the flat values carry the switch and rebuild it."""
    text = 'name = "t"\nbrake = "service"\n[parameters.service]\ndistributed_lining = true\n'
    setup = parse_scenario(text).setup
    assert setup.params.service.distributed_lining is True
    assert pack(setup.params, setup.defects)[L.P_LINING_NODE_STIFFNESS] > 0.0
    point = SCENARIO_POINT.setup
    assert pack(point.params, point.defects)[L.P_LINING_NODE_STIFFNESS] == 0.0
    # its step limit (3.6e-5 s at the default force) is below the 25.6 kHz sample's period
    assert (stepper_for(parse_scenario(text)).substeps, stepper_for(SCENARIO_POINT).substeps) == (
        2,
        1,
    )
    values = ros_params.model_values(setup.params, setup.defects)
    assert values["service.distributed_lining"] is True
    assert ros_params.build_model(values)[0] == setup.params


def test_the_flat_values_carry_the_service_brake_and_rebuild_it():
    """The node's parameters and a recording's model record: every service field under
    ``service.`` / ``service.tyre.``, rebuilt to the same parameters (the study brake has
    none of them, so its record is as before)."""
    setup = parse_scenario(SERVICE).setup
    values = ros_params.model_values(setup.params, setup.defects)
    assert values["service.return_spring_preload_n"] == 90.0
    assert values["service.tyre.road_friction"] == 0.5
    assert ros_params.build_model(values)[0] == setup.params
    study = parse_scenario('name = "s"\n').setup
    study_values = ros_params.model_values(study.params, study.defects)
    assert not [k for k in study_values if k.startswith("service.")]
    # the bore is fixed while the brake runs (the line-pressure sensors read with it)
    with pytest.raises(ParameterError, match="while it runs") as info:
        ros_params.changed_setup(setup, {**values, "service.wheel_cylinder_bore_m": 0.02})
    assert "\n" not in str(info.value)
    # a change of the road under a running service brake, and one refused by the core
    wet = ros_params.changed_setup(setup, {**values, "service.tyre.road_friction": 0.3})
    assert wet.params.service.tyre.road_friction == 0.3
    with pytest.raises(ParameterError) as info:
        ros_params.changed_setup(setup, {**values, "service.residual_force_n": 95.0})
    assert "residual_force_n" in str(info.value) and "\n" not in str(info.value)
    # the service brake's values on a study brake: refused, never a brake switched
    with pytest.raises(ParameterError) as info:
        ros_params.changed_setup(study, {**study_values, **_service_only(values)})
    assert "study brake" in str(info.value) and "\n" not in str(info.value)
    # some of them but not all: refused in one line
    partial = dict(values)
    del partial["service.tyre.peak_ratio"]
    with pytest.raises(ParameterError, match=r"service\.tyre\.peak_ratio"):
        ros_params.build_model(partial)


def _service_only(values: dict) -> dict:
    return {k: v for k, v in values.items() if k.startswith("service.")}


def test_the_node_parameters_describe_the_service_brake_with_the_cores_bounds():
    setup = parse_scenario(SERVICE).setup
    specs = {s.name: s for s in ros_params.model_parameter_specs(setup.params, setup.defects)}
    road = specs["service.tyre.road_friction"]
    assert road.default == 0.5 and road.range == (0.05, 1.2)
    assert "road_friction" in road.description
    assert specs["service.wheel_cylinder_bore_m"].range == (0.005, 0.05)
    assert specs["service.tyre.peak_ratio"].range == (1.0, 3.0)
    assert specs["service.return_spring_preload_n"].description.startswith(
        "return_spring_preload_n (N): "
    )
    assert "(N/m)" in specs["service.return_spring_rate_n_per_m"].description
    assert "(1/m)" in specs["service.tyre.presliding_stiffness_per_m"].description
    names = set(ros_params.model_values(setup.params, setup.defects))
    assert set(specs) == names


@pytest.mark.parametrize(
    ("text", "words"),
    [
        # the study brake reads none of it: refused, never ignored
        ("[parameters.service]\nreturn_spring_preload_n = 90.0\n", 'only with brake = "service"'),
        ("[parameters.service.tyre]\npeak_ratio = 1.3\n", 'only with brake = "service"'),
        # unknown keys, in either table
        (
            'brake = "service"\n[parameters.service]\nspring_preload_n = 90.0\n',
            "'parameters.service.spring_preload_n'",
        ),
        (
            'brake = "service"\n[parameters.service.tyre]\nstiffness = 55.0\n',
            "'parameters.service.tyre.stiffness'",
        ),
        # wrong types
        (
            'brake = "service"\n[parameters.service]\nreturn_spring_preload_n = "stiff"\n',
            "'parameters.service.return_spring_preload_n' = 'stiff' is invalid: allowed a number",
        ),
        ('brake = "service"\n[parameters.service]\ntyre = 3\n', "allowed a table"),
        (
            'brake = "service"\n[parameters.service]\ndistributed_lining = 1\n',
            "'parameters.service.distributed_lining' = 1 is invalid: allowed true or false",
        ),
        (
            'brake = "service"\n[parameters.service]\nreturn_spring_preload_n = true\n',
            "'parameters.service.return_spring_preload_n' = true is invalid: allowed a number",
        ),
        (
            'brake = "service"\n[parameters.service.tyre]\npeak_ratio = inf\n',
            "'parameters.service.tyre.peak_ratio' = inf is invalid: allowed a finite number",
        ),
        # values the core refuses, named with the table and what is allowed
        (
            'brake = "service"\n[parameters.service]\nresidual_force_n = 70.0\n',
            "[parameters.service]: parameter residual_force_n=70.0 is invalid: allowed >= 0"
            " and below the spring's preload (60 N)",
        ),
        (
            'brake = "service"\n[parameters.service]\nline_compliance_m3_per_pa = 1e-9\n',
            "line_compliance_m3_per_pa=1e-09 is invalid: allowed 1e-16 to 1e-10 m^3/Pa",
        ),
        (
            'brake = "service"\n[parameters.service.tyre]\npresliding_stiffness_per_m = 0.5\n',
            "[parameters.service.tyre]: parameter presliding_stiffness_per_m=0.5 is invalid:"
            " allowed 1 to 1000",
        ),
        # a bore the line-pressure sensor (its own piston diameter) would not read
        (
            'brake = "service"\n[parameters.service]\nwheel_cylinder_bore_m = 0.022\n',
            "key 'parameters.service.wheel_cylinder_bore_m' = 0.022 is invalid: allowed the"
            " piston_diameter_m of line-pressure channel 'line_pressure' (0.01905 m)",
        ),
        (
            'brake = "service"\n[parameters.service]\nwheel_cylinder_bore_m = 0.022\n'
            '[cycle]\nsegments = [{kind = "brake", pressure_bar = 20.0}]\n[[sensors]]\n'
            'name = "p"\nkind = "line_pressure"\nlocation = "wheel_cylinder"\n'
            "piston_diameter_m = 0.022\n",
            "segments give pressure_bar",
        ),
        # the road's friction has one key, the top-level one
        (
            'brake = "service"\n[parameters.service.tyre]\nroad_friction = 0.5\n',
            "top-level road_friction",
        ),
    ],
)
def test_a_bad_service_table_is_refused_in_one_line(text, words):
    with pytest.raises(ScenarioError) as info:
        parse_scenario(f'name = "t"\n{text}', "t.toml")
    message = str(info.value)
    assert words in message and message.startswith("t.toml: ") and "\n" not in message


def test_the_service_table_keeps_the_study_brakes_file_unchanged():
    """The study brake's parameters from a file without the table are the defaults'."""
    params = parse_scenario('name = "s"\n[parameters.friction]\ncoefficient = 0.3\n').setup.params
    assert params == dataclasses.replace(
        BrakeParameters(), friction=dataclasses.replace(BrakeParameters().friction, coefficient=0.3)
    )
