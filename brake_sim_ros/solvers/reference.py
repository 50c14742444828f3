"""Adaptive high-accuracy reference: scipy DOP853 with every discontinuity located.

The Kelvin-Voigt force jumps when a lining touches the drum (the damping term), the
actuation profile has kinks at its knots, and the drum sticks and breaks away at
standstill (:mod:`brake_sim_ros.model.standstill`, the same rule as the fixed-step kernel).
The integration is split at each of these instants so that no step straddles one: contact
onsets and separations, the stick and the breakaway are located as events (root-finding
on the dense output), knots are segment ends. Within a segment each shoe's contact state
and the drum's stick state are fixed, so the right-hand side is smooth there and DOP853
keeps its order.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np

from brake_sim_ros.errors import ParameterError, SimulationError
from brake_sim_ros.model import kernel, standstill
from brake_sim_ros.model import layout as L
from brake_sim_ros.model.assembly import indentation_at, initial_state, pack
from brake_sim_ros.model.layout import SIDES
from brake_sim_ros.model.run_setup import BrakeSetup, SampleBlock
from brake_sim_ros.model.thermal import pack_thermal
from brake_sim_ros.solvers.kernel_parts import ensure_compiled, register

SHOE_BASES = (L.P_SHOE_BASE, L.P_SHOE_BASE + L.SHOE_STRIDE)
# A shoe in contact is declared separated only once the lining is this far off the drum.
# A linear Kelvin-Voigt contact under a steady load has a speed-independent coefficient of
# restitution, so its bounces accumulate in finite time (Zeno); this band ends the
# sequence once bounces are smaller than a nanometre (contact force error < k_c x 1 nm,
# about 0.04 N).
SEPARATION_HYSTERESIS_M = 1e-9


@dataclass
class ReferenceResult:
    """Reference trajectory.

    Attributes:
        samples: recorded samples at ``sample_times`` (SampleBlock, non-uniform allowed).
        onsets_s / separations_s: located contact onsets and separations per shoe, s.
        stop_time_s: located instant the vehicle came to rest (model/standstill.py; None
            if it did not).
        wheel_lock_time_s: located instant the drum first stuck (None if it did not).
        breakaways_s: located instants the held drum broke away again.
        n_rhs: right-hand-side evaluations.
    """

    samples: SampleBlock
    onsets_s: dict[str, list[float]] = field(default_factory=dict)
    separations_s: dict[str, list[float]] = field(default_factory=dict)
    stop_time_s: float | None = None
    wheel_lock_time_s: float | None = None
    breakaways_s: list[float] = field(default_factory=list)
    n_rhs: int = 0


def default_sample_times(
    duration_s: float, fine_dt_s: float = 1e-5, fine_until_s: float = 1.0, coarse_dt_s: float = 1e-3
) -> np.ndarray:
    """Dense sampling over the impacting regime, coarse after it, s."""
    fine_end = min(fine_until_s, duration_s)
    fine = np.arange(0.0, fine_end, fine_dt_s)
    coarse = np.arange(fine_end, duration_s + 0.5 * coarse_dt_s, coarse_dt_s)
    return np.concatenate([fine, coarse])


def run_reference(
    setup: BrakeSetup,
    duration_s: float,
    *,
    rtol: float = 1e-9,
    sample_times: np.ndarray | None = None,
    method: str = "DOP853",
    cpu_budget_s: float | None = None,
) -> ReferenceResult:
    """Integrate ``setup`` over ``[0, duration_s]`` and sample it at ``sample_times``.

    Args:
        rtol: relative tolerance; the absolute tolerances (1e-10 rad, 1e-8 rad/s, 1e-6 J
            at rtol 1e-9) scale with it.
        method: any :func:`scipy.integrate.solve_ivp` method (DOP853 for the reference;
            RK45, Radau, BDF, LSODA for the work-precision study), always with the contact
            switches and the lock located as events.
        cpu_budget_s: give up (SimulationError) after this much process CPU time, s.
    """
    _refuse_unsupported(setup)
    ensure_compiled(parts=("reference",))  # compiled at first use, saying how far
    times = default_sample_times(duration_s) if sample_times is None else np.asarray(sample_times)
    deadline = None if cpu_budget_s is None else time.process_time() + cpu_budget_s
    # imported here: every physics command imports this module (its compiled part is
    # registered on import), few run the reference solver
    from scipy.integrate import solve_ivp

    run = _ReferenceRun(setup, times, deadline, f"{method} at rtol {rtol:g}", cpu_budget_s)
    knots = sorted({float(k) for k in np.concatenate([run.tl, run.tr]) if 0.0 < k < duration_s})
    bounds = [*knots, duration_s]
    # absolute tolerances per component: angles rad, speeds rad/s, energies J
    atol = np.array([1e-10] * 4 + [1e-8] * 4 + [1e-6] * (L.N_STATE - 8)) * (rtol / 1e-9)
    t = 0.0
    segment_end = bounds.pop(0)
    while t < duration_s:
        events = run.events()
        sol = solve_ivp(
            run.fun,
            (t, segment_end),
            run.y,
            method=method,
            rtol=rtol,
            atol=atol,
            events=events,
            dense_output=True,
        )
        if sol.status == -1:
            raise SimulationError(
                f"reference solver failed at t = {sol.t[-1]:.6f} s: {sol.message}"
            )
        t = float(sol.t[-1])
        run.sample(sol, t, duration_s)
        run.y = sol.y[:, -1].copy()
        if sol.status == 1:  # an event fired
            run.on_events(sol, events, t)
        elif t >= segment_end and bounds:
            segment_end = bounds.pop(0)
    times = run.times
    run.result.samples = SampleBlock(
        run.out, 0, float(times[1] - times[0]) if times.size > 1 else 0.0
    )
    run.result.n_rhs = run.n_rhs
    return run.result


def _refuse_unsupported(setup: BrakeSetup) -> None:
    """Refuse, in one line, what the reference solver does not model: a road load, drive
    or cycle, a thermal state, defects that change during the run, a shaped actuation."""
    if setup.driven:
        raise ParameterError(
            "the reference solver has no road load, drive or cycle controller: a scenario"
            " with [vehicle] or [cycle] is allowed with a fixed-step method (rk4-located,"
            " rk4, semi-implicit-euler)"
        )
    if setup.params.service is not None:
        raise ParameterError(
            'the reference solver does not locate the rest stops\' contacts: brake = "service"'
            " is allowed with a fixed-step method (rk4-located, rk4, semi-implicit-euler)"
        )
    if setup.thermal is not None:
        raise ParameterError(
            "the reference solver has no thermal state: a scenario with [thermal] is allowed"
            " with a fixed-step method (rk4-located, rk4, semi-implicit-euler)"
        )
    if not setup.defects.is_static:
        raise ParameterError(
            f"the reference solver holds the defects fixed: the defect"
            f" {setup.defects.growing_kinds[0]!r} changes during the run (an onset after 0 s"
            " or a growth law): allowed with a fixed-step method (rk4-located, rk4,"
            " semi-implicit-euler)"
        )
    shaped = [
        s
        for s in SIDES
        if getattr(setup.defects, s).actuation_shaped
        or getattr(setup.defects, s).return_spring_weakening_pct
    ]
    if shaped:
        raise ParameterError(
            f"the reference solver takes the actuation history as commanded: the {shaped[0]}"
            " shoe's actuation is delayed, lagging, pulsating or has a weak return spring:"
            " allowed with a fixed-step"
            " method (rk4-located, rk4, semi-implicit-euler)"
        )


class _ReferenceRun:
    """One reference integration between its segments: the packed model, the commanded
    actuation, each shoe's contact mode and the drum's stick state (fixed within a
    segment), the samples written so far and what was located."""

    def __init__(
        self,
        setup: BrakeSetup,
        times: np.ndarray,
        deadline: float | None,
        name: str,
        cpu_budget_s: float | None,
    ) -> None:
        self.p = p = pack(setup.params, setup.defects, setup.options)
        pack_thermal(p, setup)  # the temperature the run is held at, recorded
        self.y = y = initial_state(setup.params, setup.defects)
        self.tl, self.fl, self.tr, self.fr = setup.actuation.as_arrays()
        self.gains = (p[SHOE_BASES[0] + L.S_ACTUATION_GAIN], p[SHOE_BASES[1] + L.S_ACTUATION_GAIN])
        self.times = times
        self.out = np.zeros((times.size, L.N_COLUMNS))
        self.deadline, self.name, self.cpu_budget_s = deadline, name, cpu_budget_s
        self.modes = [
            L.CONTACT_ON
            if indentation_at(p, base, y[L.Y_LEFT_ANGLE + i], y[L.Y_DRUM_ANGLE]) > 0
            else L.CONTACT_OFF
            for i, base in enumerate(SHOE_BASES)
        ]
        self.stuck = 0
        self.lock_loss = 0.0
        self.result = ReferenceResult(
            SampleBlock(self.out, 0, 0.0), {"left": [], "right": []}, {"left": [], "right": []}
        )
        self.dydt = np.zeros(L.N_STATE)
        self.n_rhs = 0
        self.sample_pos = 0

    def fun(self, t: float, yy: np.ndarray) -> np.ndarray:
        """The right-hand side in this segment's contact and stick states."""
        self.n_rhs += 1
        if (
            self.deadline is not None
            and self.n_rhs % 1000 == 0
            and time.process_time() > self.deadline
        ):
            raise SimulationError(
                f"{self.name} gave up at t = {t:.4f} s: over its CPU budget"
                f" of {self.cpu_budget_s:g} s"
            )
        fe = (
            self.gains[0] * np.interp(t, self.tl, self.fl),
            self.gains[1] * np.interp(t, self.tr, self.fr),
        )
        kernel.rhs(yy, self.p, fe[0], fe[1], self.stuck, self.modes[0], self.modes[1], self.dydt)
        return self.dydt.copy()

    def events(self) -> list:
        """The events that end this segment: each enabled shoe's contact switch; a held
        drum's breakaway (and, before the stop, its coming to rest); a sliding drum in
        contact, its stick."""
        p, modes = self.p, self.modes
        events = []
        for i, base in enumerate(SHOE_BASES):
            if p[base + L.S_ENABLED] <= 0:
                continue
            ev = _shoe_event(
                p, base, i, 0.0 if modes[i] == L.CONTACT_OFF else SEPARATION_HYSTERESIS_M
            )
            ev.terminal = True
            ev.direction = 1.0 if modes[i] == L.CONTACT_OFF else -1.0
            events.append(ev)
        if self.stuck:

            def breakaway_event(_t: float, yy: np.ndarray) -> float:
                coupling, capacity = standstill.hold_torques_call(p, yy)
                if p[L.P_RIGID_COUPLING] > 0.0:
                    return -capacity
                return abs(coupling) - capacity

            breakaway_event.terminal = True
            breakaway_event.direction = 1.0
            events.append(breakaway_event)
            if self.result.stop_time_s is None:

                def rest_event(_t: float, yy: np.ndarray) -> float:
                    return 0.5 if standstill.at_rest(p, yy) else -0.5

                rest_event.terminal = True
                rest_event.direction = 1.0
                events.append(rest_event)
        elif L.CONTACT_ON in modes:
            radius = p[L.P_DRUM_RADIUS]
            v_lock = p[L.P_FRICTION_SMOOTHING_SPEED]

            def stick_event(_t: float, yy: np.ndarray) -> float:
                return abs(yy[L.Y_DRUM_SPEED]) * radius - v_lock

            stick_event.terminal = True
            stick_event.direction = -1.0
            events.append(stick_event)
        return events

    def sample(self, sol, t_end: float, duration_s: float) -> None:
        """Write every sample inside ``[t, t_end)`` from this segment's dense output."""
        times, pos = self.times, self.sample_pos
        stop = np.searchsorted(times, t_end, side="left")
        if t_end >= duration_s:
            stop = times.size
        if stop > pos:
            tk = times[pos:stop]
            yk = np.ascontiguousarray(sol.sol(np.minimum(tk, t_end)).T)
            fel = self.gains[0] * np.interp(tk, self.tl, self.fl)
            fer = self.gains[1] * np.interp(tk, self.tr, self.fr)
            kernel.evaluate_rows(yk, tk, self.p, fel, fer, self.stuck, self.out[pos:stop])
            self.out[pos:stop, L.C_LOCK_LOSS] = self.lock_loss
            self.out[pos:stop, L.C_REGIME] = L.REGIME_STOPPED if self.stuck else -1
        self.sample_pos = stop

    def on_events(self, sol, events: list, t: float) -> None:
        """Act on the events that ended the segment at ``t``: stick (where the fixed-step
        rule sticks), rest, breakaway, a shoe's contact switch; then re-sync every shoe's
        mode with the geometry."""
        p, y, result = self.p, self.y, self.result
        for ev_index, ev_times in enumerate(sol.t_events):
            if ev_times.size == 0:
                continue
            ev = events[ev_index]
            if ev.__name__ == "stick_event":
                # the crossing of v_s is where the fixed-step rule sticks, if it holds
                coupling, capacity = standstill.hold_torques_call(p, y)
                rigid = p[L.P_RIGID_COUPLING] > 0.0
                if capacity > 0.0 and (rigid or abs(coupling) <= capacity):
                    self.stuck = 1
                    self.lock_loss += standstill.stick(p, y)
                    if result.wheel_lock_time_s is None:
                        result.wheel_lock_time_s = t
                    if result.stop_time_s is None and standstill.at_rest(p, y):
                        result.stop_time_s = t
                continue
            if ev.__name__ == "rest_event":
                result.stop_time_s = t
                continue
            if ev.__name__ == "breakaway_event":
                self.stuck = 0
                result.breakaways_s.append(t)
                continue
            _flip(self.modes, ev.shoe_index, t, result)
        # Simultaneous events (a symmetric brake's shoes touch at the same instant) may
        # be reported one at a time; re-sync every shoe with the geometry.
        for i, base in enumerate(SHOE_BASES):
            eps = indentation_at(p, base, y[L.Y_LEFT_ANGLE + i], y[L.Y_DRUM_ANGLE])
            mode = self.modes[i]
            if (mode == L.CONTACT_OFF and eps > 0.0) or (
                mode == L.CONTACT_ON and eps < -SEPARATION_HYSTERESIS_M
            ):
                _flip(self.modes, i, t, result)


def _flip(modes: list[int], shoe: int, t: float, result: ReferenceResult) -> None:
    side = SIDES[shoe]
    if modes[shoe] == L.CONTACT_OFF:
        modes[shoe] = L.CONTACT_ON
        result.onsets_s[side].append(t)
    else:
        modes[shoe] = L.CONTACT_OFF
        result.separations_s[side].append(t)


def _shoe_event(p: np.ndarray, base: int, index: int, offset_m: float):
    def shoe_contact_event(_t: float, yy: np.ndarray) -> float:
        return indentation_at(p, base, yy[L.Y_LEFT_ANGLE + index], yy[L.Y_DRUM_ANGLE]) + offset_m

    shoe_contact_event.shoe_index = index
    return shoe_contact_event


def _compile_part() -> None:
    """The reference solver's right-hand side and sample evaluation, compiled on a tiny event
    (:mod:`brake_sim_ros.solvers.warmup`), and the standstill rules its stick, rest and
    breakaway events call, which a tiny event does not reach (on a copy of its state)."""
    setup = BrakeSetup()
    run_reference(setup, 0.01, rtol=1e-6)
    p = pack(setup.params, setup.defects, setup.options)
    y = initial_state(setup.params, setup.defects)
    standstill.hold_torques_call(p, y)
    standstill.at_rest(p, y)
    standstill.stick(p, y)


# compiled at first use, not at set-up (its ensure_compiled call above)
register("reference", "reference solver", _compile_part)
