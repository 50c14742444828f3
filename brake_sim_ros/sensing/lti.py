"""Linear time-invariant systems sampled exactly: the one rule the structure and the sensor
dynamics share.

A continuous system ``x' = A x + B u``, ``y = C x + D u`` driven by samples ``u[k]`` taken
every ``T`` seconds is advanced from sample to sample with the exact first-order-hold
(FOH) solution: between two samples the input is the straight line joining them, and
``x[k] = Phi x[k-1] + G_prev u[k-1] + G_next u[k]`` with ``Phi``, ``G_prev``, ``G_next``
from one matrix exponential (:func:`foh_discretise`, once per parameter set). FOH, not a
zero-order hold: the inputs (pivot forces, accelerations) are samples of continuous
signals, and a hold would delay them by half a sample. FOH, not the bilinear transform:
the bilinear transform folds a resonance above the Nyquist frequency (a 21 kHz mounted
accelerometer resonance sampled at 25.6 kHz) back into the band; the exact solution keeps
its low-frequency tail right.

White noise entering at the input (a sensor's input-referred noise) is discretised exactly
too (:func:`with_input_noise`): its effect over one sample is a Gaussian state increment
whose covariance comes from one more matrix exponential (Van Loan's method), realised in
innovations form with one draw per sample, so the sampled output has the continuous
system's noise spectrum and variance, whatever its bandwidth against the sample rate.
Treating noise samples as a straight-line input would not: interpolation smooths white
samples and removes a quarter of the noise of a sensor whose bandwidth is near the
Nyquist frequency.

The recursion (:func:`lti_advance`) is a compiled loop over samples that sums each row's
products in column order; the state and the last input are carried in :class:`LtiState`,
so a stream processed in blocks gives the same bits as one long block (the same operations
in the same order for every sample).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit
from scipy.linalg import expm, matrix_balance

from brake_sim_ros.model.compiled import JIT_ALLOCATING


@dataclass(frozen=True)
class SampledLti:
    """A continuous LTI system and its exact FOH recursion at one sample period.

    Attributes:
        a, b, c, d: the continuous system, shapes (n, n), (n, m), (p, n), (p, m).
        phi, g_prev, g_next: the recursion ``x[k] = phi x[k-1] + g_prev u[k-1] + g_next u[k]``.
        sample_period_s: T, s.
    """

    a: np.ndarray
    b: np.ndarray
    c: np.ndarray
    d: np.ndarray
    phi: np.ndarray
    g_prev: np.ndarray
    g_next: np.ndarray
    sample_period_s: float

    @property
    def n_inputs(self) -> int:
        return int(self.b.shape[1])

    @property
    def n_outputs(self) -> int:
        return int(self.c.shape[0])

    def static_state(self, u: np.ndarray) -> np.ndarray:
        """The equilibrium ``x = -A^-1 B u`` under a constant input ``u`` (shape (m,))."""
        return -np.linalg.solve(self.a, self.b @ u)

    def static_output(self, u: np.ndarray) -> np.ndarray:
        """The steady output under a constant input: ``(D - C A^-1 B) u``."""
        return self.c @ self.static_state(u) + self.d @ u


def foh_discretise(
    a: np.ndarray, b: np.ndarray, c: np.ndarray, d: np.ndarray, sample_period_s: float
) -> SampledLti:
    """The exact first-order-hold recursion of ``(A, B, C, D)`` at period ``T``.

    With ``z = [x, u, u']`` and ``u'`` constant over the interval,
    ``z' = [[A, B, 0], [0, 0, I], [0, 0, 0]] z``; one matrix exponential of that block over
    ``T`` gives ``x(T) = E11 x0 + E12 u0 + E13 (u1 - u0) / T``.
    """
    a, b, c, d = (np.ascontiguousarray(m, dtype=np.float64) for m in (a, b, c, d))
    n, m = b.shape
    big = np.zeros((n + 2 * m, n + 2 * m))
    big[:n, :n] = a
    big[:n, n : n + m] = b
    big[n : n + m, n + m :] = np.eye(m)
    e = expm(big * sample_period_s)
    phi = e[:n, :n]
    e12 = e[:n, n : n + m]
    e13 = e[:n, n + m :] / sample_period_s
    return SampledLti(
        a=a,
        b=b,
        c=c,
        d=d,
        phi=np.ascontiguousarray(phi),
        g_prev=np.ascontiguousarray(e12 - e13),
        g_next=np.ascontiguousarray(e13),
        sample_period_s=float(sample_period_s),
    )


# The innovations gain is the fixed point of the Riccati recursion below; its poles are the
# path's own (the slowest a lightly damped resonance decaying ~20 % per sample), so it
# converges in tens of iterations: this many means it will not (then one draw per state).
_RICCATI_MAX_ITERATIONS = 10_000


def with_input_noise(
    system: SampledLti, noise_density_per_sqrt_hz: float, *, per_state: bool = False
) -> SampledLti:
    """``system`` (single input, single output) with white noise of one-sided density
    ``N`` added to its input, realised with one unit normal draw per sample.

    Exact discretisation first: over one sample the noise adds to the state a Gaussian
    increment of covariance ``Q_d = int_0^T e^(A s) B q B^T e^(A^T s) ds``, intensity
    ``q = N^2 / 2`` (two-sided), from one matrix exponential (Van Loan). Drawing that
    increment takes one draw per state. The output's noise is a stationary process whose
    second-order statistics are fixed by ``(Phi, Q_d, C)``; its innovations form
    ``x[k+1] = Phi x[k] + K e[k]``, ``y[k] = C x[k] + e[k]`` (``e`` white, variance
    ``R_e``) has exactly the same autocovariance at every lag with a single draw
    ``e[k] = sqrt(R_e) z[k]``: ``K`` and ``R_e`` come from the steady state of the
    Kalman predictor's Riccati recursion ``P <- Phi P Phi^T + Q_d - Phi P C^T (C P
    C^T)^-1 C P Phi^T``, ``R_e = C P C^T``, ``K = Phi P C^T / R_e``. The output carries
    the continuous sensor's noise (its spectrum, its variance) at an eighth of the draws
    for an 8-state path; only the state's noise, which nothing reads, is not the same.

    The noise is one extra input column ``z``: in ``G_prev`` (``K sqrt(R_e)``: the draw
    of sample ``k`` moves the state at ``k + 1``) and in ``D`` (``sqrt(R_e)``: it is in
    the output at once); ``B`` gains a zero column (the equilibrium ignores the noise).
    ``D`` must be 0 on the signal for white noise to have a finite variance.

    Where the recursion does not settle (a path far faster than the sample rate leaves
    ``Q_d`` at the edge of rounding), and with ``per_state``, the exact increment is drawn
    instead: one draw per state (``n`` extra input columns in ``G_next``,
    ``L L^T = Q_d``). Both forms give the same output statistics; they are different
    draws.

    Raises:
        ValueError: several inputs or outputs, or a feedthrough.
    """
    a, b, c, t = system.a, system.b, system.c, system.sample_period_s
    if b.shape[1] != 1 or c.shape[0] != 1 or np.any(system.d != 0.0):
        raise ValueError("input noise needs a single-input single-output system, no feedthrough")
    n = a.shape[0]
    # in balanced coordinates x = D x_b: the cascaded filters' states span tens of orders
    # of magnitude, which the covariance and the recursion could not resolve
    _, (scale, _) = matrix_balance(a, permute=False, separate=True)
    a_b = a * scale[None, :] / scale[:, None]
    b_b = b / scale[:, None]
    c_b = c * scale[None, :]
    phi_b, q_b = _noise_increment(a_b, b_b, 0.5 * noise_density_per_sqrt_hz**2, t)
    # as computed: the output reads its smallest entries, which a semi-definite repair of
    # rounding-level negative eigenvalues would change by far more than they are
    form = None if per_state else _innovations(phi_b, q_b, c_b)
    if form is None:
        values, vectors = np.linalg.eigh(q_b)
        root_b = vectors * np.sqrt(np.clip(values, 0.0, None))  # a root needs q_d >= 0
        columns, zero_in = root_b * scale[:, None], np.zeros((n, n))
        return SampledLti(
            a=a,
            b=np.hstack([b, zero_in]),
            c=c,
            d=np.hstack([system.d, np.zeros((1, n))]),
            phi=system.phi,
            g_prev=np.ascontiguousarray(np.hstack([system.g_prev, zero_in])),
            g_next=np.ascontiguousarray(np.hstack([system.g_next, columns])),
            sample_period_s=t,
        )
    gain_b, root = form
    zero = np.zeros((n, 1))
    return SampledLti(
        a=a,
        b=np.hstack([b, zero]),
        c=c,
        d=np.hstack([system.d, [[root]]]),
        phi=system.phi,
        g_prev=np.ascontiguousarray(np.hstack([system.g_prev, gain_b * scale[:, None]])),
        g_next=np.ascontiguousarray(np.hstack([system.g_next, zero])),
        sample_period_s=t,
    )


def _noise_increment(
    a: np.ndarray, b: np.ndarray, q: float, t: float
) -> tuple[np.ndarray, np.ndarray]:
    """``(Phi, Q_d)`` over ``t`` of ``x' = A x + B w``, ``w`` white of two-sided intensity
    ``q``: ``Phi = e^(A t)``, ``Q_d = int_0^t e^(A s) B q B^T e^(A^T s) ds``.

    Van Loan's matrix exponential over ``h = t / 2^m`` short enough that ``|A| h <= 1``
    (over a long sample its ``e^(-A t)`` block would overflow for a fast path), then ``m``
    doublings ``Q(2h) = Q(h) + Phi(h) Q(h) Phi(h)^T``, ``Phi(2h) = Phi(h)^2``: sums of
    semi-definite terms, exact up to rounding."""
    n = a.shape[0]
    norm = float(np.max(np.sum(np.abs(a), axis=1)))
    m = max(0, math.ceil(math.log2(norm * t))) if norm * t > 1.0 else 0
    h = t / 2.0**m
    big = np.zeros((2 * n, 2 * n))
    big[:n, :n] = -a
    big[:n, n:] = q * (b @ b.T)
    big[n:, n:] = a.T
    e = expm(big * h)
    phi = e[n:, n:].T
    q_d = phi @ e[:n, n:]
    q_d = 0.5 * (q_d + q_d.T)
    for _ in range(m):
        q_d = q_d + phi @ q_d @ phi.T
        q_d = 0.5 * (q_d + q_d.T)
        phi = phi @ phi
    return phi, q_d


def _innovations(
    phi: np.ndarray, q_d: np.ndarray, c: np.ndarray
) -> tuple[np.ndarray, float] | None:
    """``(K sqrt(R_e), sqrt(R_e))`` of the innovations form (:func:`with_input_noise`), or
    None when the Riccati recursion does not settle to a positive ``R_e``.

    Settled means ``R_e`` and ``K`` no longer change (to rounding): ``P`` itself is a poor
    test, its entries spanning tens of orders of magnitude even in balanced coordinates,
    the output reading the smallest of them."""
    p = q_d.copy()
    previous: tuple[float, np.ndarray] | None = None
    for _ in range(_RICCATI_MAX_ITERATIONS):
        r_e = (c @ p @ c.T).item()
        if not (math.isfinite(r_e) and r_e > 0.0):
            return None
        k = (phi @ p @ c.T) / r_e
        if not np.all(np.isfinite(k)):
            return None
        if previous is not None:
            r_old, k_old = previous
            if abs(r_e - r_old) <= 1e-14 * r_e and np.max(np.abs(k - k_old)) <= 1e-12 * max(
                np.max(np.abs(k)), 1e-300
            ):
                root = math.sqrt(r_e)
                return k * root, root
        previous = (r_e, k)
        p = phi @ p @ phi.T + q_d - k @ (c @ p @ phi.T)
        p = 0.5 * (p + p.T)
    return None


class LtiState:
    """The state of one sampled system in a stream: ``x`` at the last sample and that
    sample's input. Before the first sample the system rests at the equilibrium of the
    first input (a brake that starts loaded starts with its structure deflected).

    ``outputs`` (indices into the system's outputs, in the order wanted; default all)
    selects the outputs computed: a caller that reads two of eight pays for two.

    The recursion reads the matrices transposed (:func:`transposed`), so that it adds one
    column's products to every row at once (:func:`lti_advance`), and the sizes as
    :func:`size_token` tuples."""

    def __init__(self, system: SampledLti, outputs: tuple[int, ...] | None = None) -> None:
        self.system = system
        rows = list(range(system.n_outputs)) if outputs is None else list(outputs)
        self.c = np.ascontiguousarray(system.c[rows])
        self.d = np.ascontiguousarray(system.d[rows])
        self.x = np.zeros(system.a.shape[0])
        self.u_prev = np.zeros(system.n_inputs)
        self.started = False
        self.sizes = (
            size_token(self.x.shape[0]),
            size_token(system.n_inputs),
            size_token(len(rows)),
        )
        self.transposed = transposed(system.phi, system.g_prev, system.g_next, self.c, self.d)

    def advance(self, u: np.ndarray, y: np.ndarray | None = None) -> np.ndarray:
        """Outputs for the input samples ``u`` (shape (k, m)), in place into ``y`` (k, p)
        when given; carries the state to the next call."""
        s = self.system
        u = np.ascontiguousarray(u, dtype=np.float64)
        if y is None:
            y = np.empty((u.shape[0], self.c.shape[0]))
        if u.shape[0] == 0:
            return y
        start = 0
        if not self.started:
            self.x[:] = s.static_state(u[0])
            self.u_prev[:] = u[0]
            self.started = True
            y[0] = self.c @ self.x + self.d @ u[0]
            start = 1
        lti_advance(*self.sizes, *self.transposed, self.x, self.u_prev, u[start:], y[start:])
        return y


def size_token(n: int) -> tuple[int, ...]:
    """``n`` as a type: a tuple of ``n`` zeros. A compiled recursion takes its sizes as such
    tuples (``len`` of one is a constant of its type), so numba compiles one version per
    size with every loop's trip count known: tiny loops of a length known only at run time
    cost more than their arithmetic (the structure's 8 states, 4 inputs and 2 outputs per
    sample in about half the time)."""
    return (0,) * n


def transposed(*matrices: np.ndarray) -> tuple[np.ndarray, ...]:
    """Each matrix transposed on its last two axes, C-contiguous: the layout
    :func:`lti_advance` and :func:`brake_sim_ros.sensing.paths.analog_advance` read."""
    return tuple(np.ascontiguousarray(np.swapaxes(m, -1, -2)) for m in matrices)


@njit(**JIT_ALLOCATING)
def lti_advance(
    x_size, u_size, y_size, phi_t, g_prev_t, g_next_t, c_t, d_t, x, u_prev, u, y
):  # pragma: no cover
    """Advance ``x`` over the input rows ``u`` (k, m), writing outputs into ``y`` (k, p);
    ``x`` and ``u_prev`` are updated in place to the last sample. The sizes n, m, p come
    as :func:`size_token` tuples. The matrices come transposed (:func:`transposed`):
    ``phi_t`` (n, n), ``g_prev_t``, ``g_next_t`` (m, n), ``c_t`` (n, p), ``d_t`` (m, p).

    Every row's sum is ``0 + phi[i, 0] x[0] + ... + (g_prev[i, 0] u_prev[0] + g_next[i, 0]
    u[0]) + ...`` in column order, the order of the plain row-by-row product, so the bits
    are those of the full products. The loops run column by column, each adding one
    column's products to all rows: the inner loop has no dependence between its
    iterations and runs in vector registers (twice as fast for the modal structure as a
    row-by-row loop that skipped the zeros, with the same bits)."""
    n_x = len(x_size)
    n_u = len(u_size)
    n_y = len(y_size)
    x_new = np.empty(n_x)
    out = np.empty(n_y)
    for k in range(u.shape[0]):
        for i in range(n_x):
            x_new[i] = 0.0
        for j in range(n_x):
            xj = x[j]
            for i in range(n_x):
                x_new[i] += phi_t[j, i] * xj
        for j in range(n_u):
            before = u_prev[j]
            now = u[k, j]
            for i in range(n_x):
                x_new[i] += g_prev_t[j, i] * before + g_next_t[j, i] * now
        for i in range(n_x):
            x[i] = x_new[i]
        for j in range(n_u):
            u_prev[j] = u[k, j]
        for i in range(n_y):
            out[i] = 0.0
        for j in range(n_x):
            xj = x[j]
            for i in range(n_y):
                out[i] += c_t[j, i] * xj
        for j in range(n_u):
            now = u[k, j]
            for i in range(n_y):
                out[i] += d_t[j, i] * now
        for i in range(n_y):
            y[k, i] = out[i]
