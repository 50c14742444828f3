"""The calibration study's bookkeeping: its search vector maps onto the parameters and back,
and a model that hits every published figure has no misfit."""

from __future__ import annotations

import pytest

from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.studies import calibration as cal
from brake_sim_ros.studies.validation_checks import (
    PUBLISHED_CASES,
    PUBLISHED_FIRST_IMPACT_ACTUATION_N,
    PUBLISHED_STOP_TIME_S,
)


def test_search_vector_round_trips_through_the_parameters():
    params = BrakeParameters()
    again = cal.parameters_from(cal.vector_of(params), params)
    for name in (
        "pivot_radius_m",
        "pivot_polar_angle_deg",
        "tip_x_m",
        "tip_y_m",
        "running_clearance_m",
        "mass_kg",
        "mass_centre_x_m",
        "mass_centre_y_m",
        "inertia_about_pivot_kg_m2",
    ):
        assert getattr(again.shoe, name) == pytest.approx(getattr(params.shoe, name), rel=1e-12)
    assert again.friction == params.friction and again.contact == params.contact


def test_the_published_figures_have_no_misfit():
    pub = PUBLISHED_CASES
    fig = {
        "stop_time_s": PUBLISHED_STOP_TIME_S,
        "first_impact_actuation_n": PUBLISHED_FIRST_IMPACT_ACTUATION_N,
        "lead_minus_trail_n": 100.0,
        "1.first_impact_actuation_n": pub["1"]["first_impact_actuation_n"],
        "7.contact_fr_change_pct": pub["7"]["peak_fr_change_pct"],
        **{
            f"{case}.{key}": pub[case][key]
            for case in ("1", "5")
            for key in ("peak_fr_change_pct", "period_change_pct")
        },
    }
    miss = cal.misfits(fig)
    assert miss and all(m == pytest.approx(0.0, abs=1e-12) for m in miss.values())
    assert cal.objective_value(miss) == pytest.approx(0.0, abs=1e-20)
    # the trailing shoe carrying more is a miss
    assert cal.misfits({**fig, "lead_minus_trail_n": -50.0})["lead_minus_trail_n"] < 0
