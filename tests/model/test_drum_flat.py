"""A local flat of the drum (catalogue ``drum_flat``; the edge of a crack): one event per
revolution, when the flat passes the shoe, growing with its depth.

The flat is a dip of the drum's radius in an angular window of its own frame
(``model/contact.py drum_radius``, the harmonics' code path). Runs are the drum test's:
1.9 s of the published event, the contact regime with the actuation held from 0.8 s.
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest

from brake_sim_ros.errors import FidelityError, ParameterError, ScenarioError
from brake_sim_ros.model import growth
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.assembly import pack
from brake_sim_ros.model.catalogue import FLAT_KIND, Growth
from brake_sim_ros.model.defects import DEFAULT_FLAT_WIDTH_DEG, Defects, DrumDefect
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.run_setup import BrakeSetup, SampleBlock
from brake_sim_ros.scenarios.loader import parse_scenario
from brake_sim_ros.solvers.fixed_step import FixedStepStepper

DT_S = 4e-5
RUN_S = 1.9
WINDOW_S = 0.8  # from here on: the contact regime, actuation held
CENTRE_DEG = 30.0


@functools.cache
def _run(depth_um: float) -> SampleBlock:
    drum = DrumDefect(flat_depth_um=depth_um, flat_centre_deg=CENTRE_DEG)
    return FixedStepStepper(BrakeSetup(defects=Defects(drum=drum)), DT_S).run(RUN_S)


def _flat_angle(block: SampleBlock, side: str) -> np.ndarray:
    """Angle from the flat's centre to the shoe's contact point, in the drum's frame,
    wrapped to [-pi, pi) rad: the drum turns counter-clockwise, so it falls through 0 once a
    revolution as the flat passes the contact."""
    alpha = np.arctan2(block[f"{side}_contact_y_m"], block[f"{side}_contact_x_m"])
    psi = alpha - block["drum_angle_rad"] - math.radians(CENTRE_DEG)
    return np.remainder(psi + math.pi, 2.0 * math.pi) - math.pi


def _events(block: SampleBlock, side: str) -> tuple[np.ndarray, float]:
    """(rows where the shoe's normal force first departs from its steady value by more
    than a quarter of its largest departure, after a quiet quarter revolution; that
    largest departure, N), over the contact window."""
    w = np.flatnonzero(block.time_s >= WINDOW_S)
    fn = block[f"{side}_normal_force_n"][w]
    departure = np.abs(fn - np.median(fn))
    peak = float(departure.max())
    loud = departure > 0.25 * peak
    angle = block["drum_angle_rad"][w]
    events = []
    last = -np.inf
    for i in np.flatnonzero(loud):
        if angle[i] - last > 0.5 * math.pi and (
            not events or angle[i] - angle[events[-1]] > math.pi
        ):
            events.append(i)
        last = angle[i]
    return w[np.array(events, dtype=int)], peak


@pytest.mark.parametrize("side", ["left", "right"])
def test_a_flat_gives_one_event_per_revolution_where_it_passes_the_shoe(side):
    block = _run(50.0)
    rows, _peak = _events(block, side)
    angle = _flat_angle(block, side)
    w = block.time_s >= WINDOW_S
    passes = np.count_nonzero((angle[w][:-1] >= 0.0) & (angle[w][1:] < 0.0))
    assert passes >= 10
    assert abs(len(rows) - passes) <= 1  # one event per passage (a window's edges)
    half = math.radians(0.5 * DEFAULT_FLAT_WIDTH_DEG)
    # each starts while the contact point is on the flat (entering from +half)
    assert np.all(np.abs(angle[rows]) <= half), np.degrees(angle[rows])


def test_the_event_grows_with_the_depth_and_a_round_drum_has_none():
    healthy = _run(0.0)
    w = healthy.time_s >= WINDOW_S
    fn = healthy["left_normal_force_n"][w]
    assert np.ptp(fn) < 1e-6 * fn.mean()  # steady: nothing happens once a revolution
    peaks = [_events(_run(depth), "left")[1] for depth in (5.0, 20.0, 50.0)]
    assert peaks == sorted(peaks)
    # a stiff linear contact: the departure grows nearly in proportion to the depth
    assert peaks[1] / peaks[0] == pytest.approx(4.0, rel=0.1)
    assert peaks[2] / peaks[1] == pytest.approx(2.5, rel=0.1)
    # the pivot force, what reaches the chassis, carries it
    pivot = [
        np.ptp(np.hypot(b["left_pivot_fx_n"], b["left_pivot_fy_n"])[w])
        for b in (healthy, _run(50.0))
    ]
    assert pivot[1] > 1000.0 * max(pivot[0], 1e-6)


def test_a_growing_flat_sets_its_depth_at_each_step():
    d = Defects(
        drum=DrumDefect(flat_depth_um=40.0),
        growth=((FLAT_KIND, "drum", Growth(1.0, "linear", rate_per_s=20.0)),),
    )
    p = pack(BrakeParameters(), d)
    assert p[L.P_FLAT_DEPTH] == pytest.approx(40e-6)
    pw = growth.working_copy(p)
    growth.apply(p, pw, 0.5, np.zeros(L.N_STATE), growth.ALL_ENTRIES)
    assert pw[L.P_FLAT_DEPTH] == 0.0
    growth.apply(p, pw, 1.5, np.zeros(L.N_STATE), growth.ALL_ENTRIES)
    assert pw[L.P_FLAT_DEPTH] == pytest.approx(10e-6, rel=1e-12)
    growth.apply(p, pw, 9.0, np.zeros(L.N_STATE), growth.ALL_ENTRIES)
    assert pw[L.P_FLAT_DEPTH] == pytest.approx(40e-6, rel=1e-12)


@pytest.mark.parametrize(
    ("drum", "message"),
    [
        ("flat_depth_um = 1500", "flat_depth_um=1500 is invalid: allowed 0 to 1000"),
        (
            "flat_depth_um = 600\nflat_width_deg = 2",
            "slope pi d / (2 w R0) = 0.3000, allowed at most 0.05",
        ),
        ("flat_depth_um = 50\nflat_width_deg = 0", "flat_width_deg=0 is invalid: allowed > 0"),
        ("flat_depth_um = 50\nflat_centre_deg = 400", "flat_centre_deg=400 is invalid"),
        ("flat_depth_um = true", "flat_depth_um"),
    ],
)
def test_an_impossible_flat_is_refused_in_one_line(drum, message):
    with pytest.raises((ScenarioError, ParameterError)) as info:
        parse_scenario(f'name = "bad"\n[defects.drum]\n{drum}\n', "bad.toml")
    assert message in str(info.value)
    assert "\n" not in str(info.value)


def test_a_flat_needs_the_impact_levels():
    text = (
        'name = "f"\n[needs]\noutputs = ["stop_time"]\nlevel = "contact_regime"\n'
        "[defects.drum]\nflat_depth_um = 20\n"
    )
    with pytest.raises((FidelityError, ScenarioError), match="cannot represent the defect"):
        parse_scenario(text, "f.toml")
