"""The service brake's self-adjuster stepping within a run (model/ratchet.py): the ratchet
takes a lining's wear up as it grows, in whole steps, at applications only; a seized one
takes nothing up; the energy books close; the same bits whatever the blocks.

Expected values come from the documented rule and the parameters (the step, the running
clearance) and the lining's own recorded wear, never read off the take-up: the
clearance at rest after a release is ``c0 + w - s floor(w_a / s)``, ``w`` the wear then
and ``w_a`` the wear at the end of the last application (the take-up of all the wear
short of a step)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from brake_sim_ros.analysis.adjuster import takeup_steps
from brake_sim_ros.analysis.energy import energy_balance
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.assembly import pack
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.growth_law import Growth
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.model.run_setup import SampleBlock
from brake_sim_ros.model.service_parameters import SERVICE_RUNNING_CLEARANCE_M
from brake_sim_ros.scenarios.loader import parse_scenario
from brake_sim_ros.stream.build import stepper_for

STEP_M = BrakeParameters.of_brake("service").service.adjuster_step_m
C0 = SERVICE_RUNNING_CLEARANCE_M
FORCE_N = 1000.0
HOLD_S = 0.15  # an application: 10 ms up, held, 10 ms down
SEIZED_MM = 0.01
# a shoe 0.4 s after a release sits within 1 um of its rest angle at the lining (the
# line's pressure still settling): the clearance at rest is read to 2 um (4 % of a step)
AT_REST_M = 2e-6


def _applications(starts: list[float], duration_s: float, wear: str, left: str = "") -> str:
    """A service-brake scenario: both shoes applied to FORCE_N from each of ``starts``
    (s) for HOLD_S, the left lining's wear table ``wear`` (TOML keys), ``left`` more keys
    of the left shoe's defects."""
    times, forces = [0.0], [0.0]
    for a in starts:
        times += [a, a + 0.01, a + 0.01 + HOLD_S, a + 0.02 + HOLD_S]
        forces += [0.0, FORCE_N, FORCE_N, 0.0]
    times.append(duration_s)
    forces.append(0.0)
    knots = f"times_s = {times}\nforces_n = {forces}\n"
    return (
        f'name = "wearing"\nbrake = "service"\nduration_s = {duration_s}\n'
        f'[actuation]\nprofile = "piecewise"\n[actuation.left]\n{knots}'
        f"[actuation.right]\n{knots}[defects.left]\n{left}"
        f"[defects.left.lining_wear_mm]\nvalue = 5.0\n{wear}"
    )


# eight applications 0.6 s apart (the shoes back at rest 0.4 s after each release), the
# left lining wearing with its friction work (about 0.07 mm an application at this rate:
# some ten steps in all); at rest it does not wear
WORK_STARTS = [0.1 + 0.6 * k for k in range(8)]
WORK = _applications(WORK_STARTS, 4.9, 'growth = "friction_work"\nwear_rate_mm_per_mj = 35.0\n')
# three applications 1 s apart, the left lining wearing in time (0.12 mm/s): it wears
# more than two steps while released
TIME_STARTS = [0.1, 1.1, 2.1]
TIME = _applications(TIME_STARTS, 2.8, 'growth = "linear"\nrate_per_s = 0.12\n')


def _run(text: str, chunk: int | None = None):
    scenario = parse_scenario(text)
    stepper = stepper_for(scenario)
    if chunk is None:
        return scenario, stepper, stepper.run(scenario.duration_s)
    total = round(scenario.duration_s / stepper.sample_period_s)
    blocks = []
    while stepper.sample_index < total:
        blocks.append(stepper.advance(min(chunk, total - stepper.sample_index)))
    return scenario, stepper, SampleBlock.concatenate(blocks)


@pytest.fixture(scope="module")
def work():
    return _run(WORK)


@pytest.fixture(scope="module")
def seized():
    return _run(_seized_text())


def _seized_text() -> str:
    return _applications(
        WORK_STARTS,
        4.9,
        'growth = "friction_work"\nwear_rate_mm_per_mj = 35.0\n',
        left=f"adjuster_seized_mm = {SEIZED_MM}\n",
    )


def _row_before(block: SampleBlock, t_s: float) -> int:
    """The last row before ``t_s`` (a shoe at rest before an application or the end)."""
    return int(np.flatnonzero(block.time_s < t_s - 1e-9)[-1])


def _rests(starts: list[float], duration_s: float) -> list[float]:
    """The instants the shoes are at rest: before each application after the first, and
    the end of the run (each at least 0.4 s after a release)."""
    return [*starts[1:], duration_s]


def test_the_ratchet_holds_the_clearance_within_a_step_as_the_lining_wears(work):
    """Over eight applications the lining wears about ten steps; after every release the
    clearance at rest is ``c0 + w - s floor(w / s)``: within one step above 0.3 mm (the
    wear does not grow at rest: it follows the friction work). Without the ratchet it
    would be ``c0 + w``, more than half a millimetre by the end."""
    scenario, _stepper, block = work
    wear = block["left_lining_wear_m"]
    gap = -block["left_indentation_m"]
    assert wear[-1] > 8 * STEP_M
    for t in _rests(WORK_STARTS, scenario.duration_s):
        r = _row_before(block, t)
        w = float(wear[r])
        hand = C0 + w - STEP_M * math.floor(w / STEP_M + 1e-9)
        assert gap[r] == pytest.approx(hand, abs=AT_REST_M), (t, gap[r], hand)
        assert C0 - AT_REST_M <= gap[r] < C0 + STEP_M


def test_a_seized_adjuster_leaves_the_growing_wear_in_the_clearance(seized):
    """Seized (by 0.01 mm), the adjuster takes nothing up, at the start or within the run:
    the clearance at rest is ``c0 + y + w`` after every release, growing with the wear."""
    scenario, stepper, block = seized
    assert stepper.packed_parameters[L.P_ADJUSTER_STEP] == 0.0
    wear = block["left_lining_wear_m"]
    gap = -block["left_indentation_m"]
    assert wear[-1] > 8 * STEP_M
    for t in _rests(WORK_STARTS, scenario.duration_s):
        r = _row_before(block, t)
        hand = C0 + SEIZED_MM * 1e-3 + float(wear[r])
        assert gap[r] == pytest.approx(hand, abs=AT_REST_M), (t, gap[r], hand)
    assert stepper.adjuster_takeup_m == (0.0, 0.0)
    with pytest.raises(ValueError, match=r"left shoe's self-adjuster does not step"):
        takeup_steps(block, stepper.packed_parameters, "left")


@pytest.fixture(scope="module")
def timed():
    return _run(TIME)


def test_the_ratchet_steps_at_applications_only(timed):
    """A wear that grows in time grows while the shoes are released too: the clearance at
    rest opens past a step (nothing is taken up while released) and the next application
    takes it up to within a step of 0.3 mm, the wear at the end of that application's
    ``floor(w / s)`` steps in all. The take-up read from the recorded columns changes
    only from an application's start to 0.5 s after its release (the shoe back at rest)."""
    _scenario, stepper, block = timed
    wear = block["left_lining_wear_m"]
    gap = -block["left_indentation_m"]
    t = block.time_s
    taken = takeup_steps(block, stepper.packed_parameters, "left")
    for k, start in enumerate(TIME_STARTS):
        before = _row_before(block, start)
        end = _row_before(block, start + 0.02 + HOLD_S)  # the release
        if k:  # released since the last: the wear it added is not taken up
            assert gap[before] > C0 + STEP_M
        after = _row_before(block, start + 0.02 + HOLD_S + 0.5)
        # the wear when the lining last touched the drum (the run starts unworn: nothing
        # taken up at the start)
        touching = np.flatnonzero(block["left_normal_force_n"][: after + 1] > 0.0)
        assert touching[-1] > end - 0.05 / block.sample_period_s
        applied = float(wear[touching[-1]])
        assert taken[after] == math.floor(applied / STEP_M + 1e-9)
        # at rest after it: the wear since the release stays open
        w = float(wear[after])
        hand = C0 + w - STEP_M * taken[after]
        assert gap[after] == pytest.approx(hand, abs=AT_REST_M)
    changes = t[1:][np.diff(taken) != 0]
    assert len(changes) > 0
    for when in changes:
        assert any(a <= when <= a + 0.02 + HOLD_S + 0.5 for a in TIME_STARTS), when
    assert stepper.adjuster_takeup_m[0] == pytest.approx(taken[-1] * STEP_M, abs=1e-15)
    assert stepper.adjuster_pending_m == (0.0, 0.0)
    assert stepper.adjuster_takeup_m[1] == 0.0  # the right lining does not wear: no ratchet


def test_the_take_up_leaves_the_energy_books_as_they_were(work, seized):
    """The take-up moves a lining only while it is clear of the drum by more than the
    take-up, and the springs and stops act on the shoe's angle: no energy enters or leaves
    the books by it. Over each take-up (0.2 ms around the row it shows first) the books
    close to 1 uJ (the round-off of the rotors' 89 kJ is 1e-11 J): a take-up that moved
    the shoe by its step at the tip (1.92 times the lining's) against the return spring's
    preload would work over a thousand times more. Over the whole run the books close as
    well, with the adjuster working and seized (nothing taken up): under 2e-9 of the
    turnover (measured 3.4e-10 and 5.1e-10), the strain the wear takes booked
    (``contact.wear_loss``; before it was, both missed it: 1.4e-5 of the turnover)."""
    scenario, stepper, block = work
    packed = stepper.packed_parameters
    params = scenario.setup.params
    taken = takeup_steps(block, packed, "left")
    rows = np.flatnonzero(np.diff(taken) != 0) + 1
    assert len(rows) >= 5
    for r in rows:
        window = SampleBlock(
            block.data[r - 3 : r + 3], block.first_index + r - 3, block.sample_period_s
        )
        assert np.all(window["left_indentation_m"] < 0.0)  # clear of the drum
        books = energy_balance(window, params, packed=packed)
        assert abs(books.residual_j) < 1e-6, (r, books)
    spec = params.service
    assert 1e-3 * spec.return_spring_preload_n * 1.92 * STEP_M > 1e-6
    whole = energy_balance(block, params, packed=packed)
    s_scenario, s_stepper, s_block = seized
    held = energy_balance(s_block, s_scenario.setup.params, packed=s_stepper.packed_parameters)
    assert abs(whole.residual_j) < 2e-9 * whole.turnover_j, whole
    assert abs(held.residual_j) < 2e-9 * held.turnover_j, held


def test_a_run_steps_the_same_bits_whatever_its_blocks(work):
    """The same scenario stepped again in blocks of 77 samples: the same bits, and the
    same take-up, which the recorded columns show (analysis/adjuster.py)."""
    _scenario, stepper, block = work
    _again, stepper2, block2 = _run(WORK, chunk=77)
    assert block2.data.tobytes() == block.data.tobytes()
    assert stepper2.adjuster_takeup_m == stepper.adjuster_takeup_m
    taken = takeup_steps(block, stepper.packed_parameters, "left")
    assert stepper.adjuster_takeup_m[0] == pytest.approx(taken[-1] * STEP_M, abs=1e-15)
    assert taken[-1] >= 8


def test_a_wear_that_grows_in_time_steps_the_same_bits_and_books_whatever_its_blocks(timed):
    """The wear of a law of time steps the lining's radius at each physics step's start,
    and the kernel books the strain each step takes (model/growth_energy.py) from the
    step before, which a block's first step rebuilds: in blocks of 77 samples the same
    bits, the books included. They close under 2e-9 of the turnover (measured 2.1e-10;
    without the booking 0.15 J short, 1.6e-6), through three applications' take-ups."""
    scenario, stepper, block = timed
    _again, stepper2, block2 = _run(TIME, chunk=77)
    assert block2.data.tobytes() == block.data.tobytes()
    assert stepper2.adjuster_takeup_m == stepper.adjuster_takeup_m
    assert stepper.adjuster_takeup_m[0] >= 2 * STEP_M
    books = energy_balance(block, scenario.setup.params, packed=stepper.packed_parameters)
    assert abs(books.residual_j) < 2e-9 * books.turnover_j, books


def test_the_take_up_is_read_only_where_it_steps(work):
    """A bad side and a block that is not the run's are refused in one line."""
    _scenario, stepper, block = work
    with pytest.raises(ValueError, match=r"side 'middle': allowed left, right"):
        takeup_steps(block, stepper.packed_parameters, "middle")
    other = stepper.packed_parameters
    other[L.P_SHOE_BASE + L.S_LINING_RADIUS] += 0.3 * STEP_M  # unused, the radius is rebuilt
    other[L.P_LINING_BASE + L.LN_RADIUS] += 0.3 * STEP_M
    with pytest.raises(ValueError, match=r"not a whole number: the block is not this run's"):
        takeup_steps(block, other, "left")


def test_the_ratchet_is_packed_only_where_a_healthy_adjuster_meets_a_growing_wear():
    """The step goes to the shoe whose wear grows and whose adjuster is not seized; a
    static wear, a seized adjuster and the study brake (no adjuster) pack none, so their
    runs step exactly as before."""
    grows = (("lining_wear", "left", Growth(law="linear", rate_per_s=0.1)),)
    service = BrakeParameters.of_brake("service")
    healthy = pack(service, Defects(left=ShoeDefect(lining_wear_mm=1.0), growth=grows))
    assert (healthy[L.P_ADJUSTER_STEP], healthy[L.P_ADJUSTER_STEP + 1]) == (STEP_M, 0.0)
    assert healthy[L.P_ADJUSTER_FREE_PLAY] == C0
    static = pack(service, Defects(left=ShoeDefect(lining_wear_mm=1.0)))
    stuck = ShoeDefect(lining_wear_mm=1.0, adjuster_seized_mm=0.1)
    held = pack(service, Defects(left=stuck, growth=grows))
    study = pack(BrakeParameters(), Defects(left=ShoeDefect(lining_wear_mm=1.0), growth=grows))
    for p in (static, held, study):
        assert p[L.P_ADJUSTER_STEP] == 0.0 and p[L.P_ADJUSTER_STEP + 1] == 0.0
