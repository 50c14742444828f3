"""The sensors' per-sample loops, compiled: one call per channel and block.

The rules are those of :mod:`.sensors` (the analog signal path, the tone ring) and
:mod:`.faults` (what each fault kind does, its label bit); this module is where
they are carried out, sample by sample, so that a live node pays one compiled call per
channel and block instead of dozens of small array operations. Carried state lives in
small arrays the caller keeps between blocks (:class:`PathState`), so a stream in blocks
gives the same bits as one block: every sample goes through the same operations in the
same order whatever the block boundaries.

Faults come as a table (:func:`fault_table`): per fault its kind code (index in
``faults.FAULT_KINDS``), onset, end (onset + duration) and size, all in seconds
of simulated time and the channel's unit. A fault is active at ``t`` when
``onset <= t < end``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from brake_sim_ros.model.compiled import JIT, JIT_ALLOCATING
from brake_sim_ros.sensing import faults as sf
from brake_sim_ros.sensing.lti import SampledLti, transposed

KIND_CODE: dict[str, int] = {kind: i for i, kind in enumerate(sf.FAULT_KINDS)}
BIAS_DRIFT, GAIN_ERROR, DROPOUT, STUCK, SATURATION, LOOSE_MOUNT = (
    KIND_CODE[k]
    for k in ("bias_drift", "gain_error", "dropout", "stuck", "saturation", "loose_mount")
)
# HOLD carried between blocks: the value reported at the last sample before stuck and
# dropout were applied, whether a stuck fault was active there (0/1), the value it holds
LAST_VALUE, WAS_STUCK, HELD = 0, 1, 2


def fault_table(
    faults: tuple[sf.SensorFault, ...],
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(kind code, onset s, end s, size)`` arrays of ``faults``, in their order."""
    return (
        np.array([KIND_CODE[f.kind] for f in faults], dtype=np.int64),
        np.array([f.onset_s for f in faults], dtype=np.float64),
        np.array([f.onset_s + f.duration_s for f in faults], dtype=np.float64),
        np.array([f.size for f in faults], dtype=np.float64),
    )


class PathState:
    """What one channel carries from block to block: the hold of stuck faults and, for a
    path with dynamics, the state ``x`` and last input ``u`` of its sampled system."""

    def __init__(self, n_states: int = 0, n_inputs: int = 0) -> None:
        self.hold = np.zeros(3)
        self.x = np.zeros(n_states)
        self.u_prev = np.zeros(n_inputs)
        self.started = False


def stack_systems(systems: list[SampledLti]) -> tuple[np.ndarray, ...]:
    """``(phi_t, g_prev_t, g_next_t, c, d)`` of same-shaped systems stacked on a first axis
    (the nominal mounting first, then a loose mount's); the recursion's matrices
    transposed (:func:`.lti.transposed`), as :func:`analog_advance` reads them."""
    phi, g_prev, g_next, c, d = (
        np.stack([getattr(s, a) for s in systems]) for a in ("phi", "g_prev", "g_next", "c", "d")
    )
    return (*transposed(phi, g_prev, g_next), np.ascontiguousarray(c), np.ascontiguousarray(d))


def unit_equilibria(systems: list[SampledLti]) -> np.ndarray:
    """Each system's equilibrium state under a unit signal input (noise inputs at 0),
    stacked like :func:`stack_systems`: a path starts at rest, ``x = u x_unit``."""
    out = []
    for system in systems:
        unit = np.zeros(system.n_inputs)
        unit[0] = 1.0
        out.append(system.static_state(unit))
    return np.ascontiguousarray(np.stack(out))


def no_systems() -> tuple[np.ndarray, ...]:
    """The placeholder of :func:`stack_systems` and :func:`unit_equilibria` for a path
    without dynamics."""
    return (*(np.zeros((1, 0, 0)) for _ in range(5)), np.zeros((1, 0)))


@njit(**JIT)
def _hold(value, stuck, dropped, hold):  # pragma: no cover - compiled
    """Stuck, then dropout, on one reported value; updates ``hold`` (module HOLD)."""
    out = value
    if stuck:
        if hold[WAS_STUCK] == 0.0:
            hold[HELD] = hold[LAST_VALUE]  # the value before the run began
        out = hold[HELD]
    hold[LAST_VALUE] = value
    hold[WAS_STUCK] = 1.0 if stuck else 0.0
    if dropped:
        out = np.nan
    return out


@njit(inline="always", **JIT)
def _faults_at(t, f_kind, f_onset, f_end, f_size):  # pragma: no cover - compiled
    """What the active faults do at time ``t``: (label bits, gain factor, bias, saturation
    limit, loose mount 0/1, stuck, dropped) (``faults`` module docstring)."""
    gain = 1.0
    bias = 0.0
    limit = np.inf
    loose = 0
    stuck = False
    dropped = False
    label = 0
    for i in range(f_kind.shape[0]):
        if not (t >= f_onset[i] and t < f_end[i]):
            continue
        kind = f_kind[i]
        label |= 1 << kind
        if kind == GAIN_ERROR:
            gain *= 1.0 + f_size[i]
        elif kind == BIAS_DRIFT:
            bias += f_size[i] * (t - f_onset[i])
        elif kind == SATURATION:
            limit = min(limit, f_size[i])
        elif kind == LOOSE_MOUNT:
            loose = 1
        elif kind == STUCK:
            stuck = True
        elif kind == DROPOUT:
            dropped = True
    return label, gain, bias, limit, loose, stuck, dropped


@njit(**JIT_ALLOCATING)
def analog_advance(  # pragma: no cover - compiled
    x_size,
    draw_size,
    time_s,
    true,
    sensitivity,
    f_kind,
    f_onset,
    f_end,
    f_size,
    phi,
    g_prev,
    g_next,
    c,
    d,
    x_unit,
    x,
    u_prev,
    first,
    draws,
    white_gain,
    range_min,
    range_max,
    adc_step,
    adc_top,
    hold,
    values,
    labels,
):
    """One block of an analog channel (``sensors`` module docstring, in that order):
    ``true`` (k,) in the channel unit at ``time_s`` (k,) -> ``values`` (k,), ``labels``
    (k,) uint8.

    ``x_size`` and ``draw_size``: the number of the systems' states and of draws per sample,
    as :func:`.lti.size_token` tuples (one compiled version per path shape, its loops of
    constant length). ``phi ... d`` hold the path's sampled systems (index 1: loose mount),
    of zero size for a path without dynamics, ``phi``, ``g_prev`` and ``g_next`` transposed
    (:func:`stack_systems`); ``x_unit`` their equilibrium states under a unit input; ``x``
    and ``u_prev`` (the last sample's inputs: scaled true value, then its noise draw) their
    carried state. On the ``first`` block sample 0 starts at rest under its input (``x = v
    x_unit``), output, not advanced to. ``draws`` (k, m): the block's unit normal draws (m =
    0 without noise), the systems' last inputs (``lti.with_input_noise``); ``white_gain``
    their scale without dynamics. ``adc_step`` 0: no ADC.
    ``hold`` is updated in place.

    The state's rows are summed in column order, one column added to every row at once
    (as :func:`.lti.lti_advance`); the output's sum skips the terms whose coefficient is
    exactly 0 (it reads one state of eight): an exact zero product changes no sum that
    starts at +0.0, so the bits are those of the full products."""
    n_x = len(x_size)
    n_draw = len(draw_size)
    n_u = 1 + n_draw if n_x > 0 else 1
    x_new = np.empty(n_x)
    u = np.empty(n_u)
    for k in range(time_s.shape[0]):
        label, gain, bias, limit, loose, stuck, dropped = _faults_at(
            time_s[k], f_kind, f_onset, f_end, f_size
        )
        labels[k] = label
        v = true[k] * sensitivity * gain
        if n_x > 0:
            u[0] = v
            for j in range(n_draw):
                u[j + 1] = draws[k, j]
            s = loose if phi.shape[0] > 1 else 0
            if first and k == 0:  # at rest under the first input: x = v x_unit
                for i in range(n_x):
                    x[i] = v * x_unit[s, i]
            else:
                for i in range(n_x):
                    x_new[i] = 0.0
                for j in range(n_x):
                    xj = x[j]
                    for i in range(n_x):
                        x_new[i] += phi[s, j, i] * xj
                for j in range(n_u):
                    before = u_prev[j]
                    now = u[j]
                    for i in range(n_x):
                        x_new[i] += g_prev[s, j, i] * before + g_next[s, j, i] * now
                for i in range(n_x):
                    x[i] = x_new[i]
            for j in range(n_u):
                u_prev[j] = u[j]
            acc = 0.0
            for j in range(n_x):
                if c[s, 0, j] != 0.0:
                    acc += c[s, 0, j] * x[j]
            for j in range(n_u):
                if d[s, 0, j] != 0.0:
                    acc += d[s, 0, j] * u[j]
            v = acc
        elif n_draw > 0:
            v = v + white_gain * draws[k, 0]
        v = v + bias
        lo = max(range_min, -limit)
        hi = min(range_max, limit)
        if v < lo:
            v = lo
        if v > hi:
            v = hi
        if adc_step > 0.0:
            code = np.rint((v - range_min) / adc_step)
            if code < 0.0:
                code = 0.0
            if code > adc_top:
                code = adc_top
            v = range_min + code * adc_step
        values[k] = _hold(v, stuck, dropped, hold)


@njit(**JIT)
def tone_ring_advance(  # pragma: no cover - compiled
    time_s,
    drum_angle_rad,
    teeth,
    f_kind,
    f_onset,
    f_end,
    f_size,
    last,
    pulse_hold,
    index_hold,
    pulse,
    index,
    labels,
    edges,
):
    """One block of a wheel-speed channel: ``pulse``, ``index`` and ``labels`` (k,) and
    the rising-edge times into ``edges`` (at most one per sample); returns the number of
    edges. ``last`` = [has a previous sample (0/1), its time s, its tooth phase], updated.
    An edge between two samples is dropped when the later sample is in a dropout."""
    n_edges = 0
    two_pi = 2.0 * math.pi
    for k in range(time_s.shape[0]):
        t = time_s[k]
        label, _, _, _, _, stuck, dropped = _faults_at(t, f_kind, f_onset, f_end, f_size)
        labels[k] = label
        turns = drum_angle_rad[k] / two_pi
        phase = teeth * turns
        p = 1.0 if phase - np.floor(phase) < 0.5 else 0.0
        q = 1.0 if turns - np.floor(turns) < 0.5 / teeth else 0.0
        if last[0] != 0.0:
            t0, p0 = last[1], last[2]
            crossing = np.floor(phase)
            if crossing > np.floor(p0) and not dropped:  # a tooth's leading edge passed
                frac = (crossing - p0) / (phase - p0)
                edges[n_edges] = t0 + frac * (t - t0)
                n_edges += 1
        last[0], last[1], last[2] = 1.0, t, phase
        pulse[k] = _hold(p, stuck, dropped, pulse_hold)
        index[k] = _hold(q, stuck, dropped, index_hold)
    return n_edges


@njit(**JIT)
def gather_columns(data, by_row, by_row_out, by_column, by_column_out):  # pragma: no cover
    """Copy the columns ``by_row`` (int64 indices) of ``data`` (n, c) into ``by_row_out``
    (n, len(by_row)) and the columns ``by_column`` into the rows of ``by_column_out``
    (len(by_column), n), in one pass over ``data``'s rows: what a sensor bank reads of a
    sample block, each channel's input then contiguous, for one read of the block."""
    for k in range(data.shape[0]):
        for j in range(by_row.shape[0]):
            by_row_out[k, j] = data[k, by_row[j]]
        for j in range(by_column.shape[0]):
            by_column_out[j, k] = data[k, by_column[j]]
