"""Every solver behind one small contract, and the registry of their names.

As scipy's ``solve_ivp`` maps ``method="RK45"`` to a class, :data:`METHODS` maps a name to
a :class:`Method`: what kind of solver it is, what its step count counts, and
``integrate(setup, duration_s, options) -> Integration``. The fixed-step schemes also make
a :class:`~brake_sim_ros.solvers.fixed_step.FixedStepStepper`, the one kind that streams in
real time. Names a scenario may choose are :data:`SOLVER_METHODS`; ``contact_regime`` is
chosen by the fidelity plan, never by name.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from brake_sim_ros.model.run_setup import BrakeSetup, SampleBlock
from brake_sim_ros.solvers.contact_regime import run_contact_regime
from brake_sim_ros.solvers.fixed_step import FIXED_STEP_SCHEMES, FixedStepStepper
from brake_sim_ros.solvers.reference import run_reference

CHUNK_SAMPLES = 100_000  # fixed-step runs are stepped (and thinned to columns) in chunks


@dataclass(frozen=True)
class MethodOptions:
    """What a run asks of any solver.

    Attributes:
        sample_period_s: output sample interval, s (the scenario's; the contact-regime
            level samples its own macro step instead).
        max_step_s: largest physics step of a fixed-step scheme, s.
        rtol: relative tolerance of the adaptive reference.
        accuracy: the preset name the contact-regime level picks its macro step from.
        keep: turns each recorded block into what the run keeps (columns), block by block
            so that a long run never holds every column; identity by default.
        progress: called with the fraction done (fixed-step schemes).
    """

    sample_period_s: float
    max_step_s: float
    rtol: float = 1e-9
    accuracy: str | None = None
    keep: Callable[[SampleBlock], SampleBlock] = lambda block: block
    progress: Callable[[float], None] | None = None


@dataclass(frozen=True)
class Integration:
    """What any solver returns.

    Attributes:
        samples: the kept time history.
        stop_time_s: the instant the vehicle came to rest, s (None if it did not).
        n_steps: the solver's unit of work (see :attr:`Method.counts`).
        note: fixed-step schemes: sample rate, physics step, substeps and the limit that
            chose them (one line); empty otherwise.
    """

    samples: SampleBlock
    stop_time_s: float | None
    n_steps: int
    note: str = ""


@dataclass(frozen=True)
class Method:
    """One registered solver.

    Attributes:
        name: its registry name.
        kind: "fixed-step" (compiled, real-time capable), "adaptive" (the DOP853 reference,
            events located) or "reduced" (the contact-regime level's quasi-static shoes).
        counts: what :attr:`Integration.n_steps` counts.
        integrate: ``(setup, duration_s, options) -> Integration``.
    """

    name: str
    kind: str
    counts: str
    integrate: Callable[[BrakeSetup, float, MethodOptions], Integration]

    def stepper(self, setup: BrakeSetup, sample_period_s: float, max_step_s: float):
        """A streaming stepper of this scheme (fixed-step methods only).

        Raises:
            ValueError: not a fixed-step method.
            StepSizeError: a pathological step limit of ``setup``.
        """
        if self.kind != "fixed-step":
            raise ValueError(f"method {self.name!r} does not stream; fixed-step ones do")
        return FixedStepStepper(setup, sample_period_s, scheme=self.name, max_step_s=max_step_s)


def _fixed_step(name: str) -> Method:
    def integrate(setup: BrakeSetup, duration_s: float, options: MethodOptions) -> Integration:
        stepper = METHODS[name].stepper(setup, options.sample_period_s, options.max_step_s)
        total = round(duration_s / stepper.sample_period_s)
        blocks, done = [], 0
        while done < total:
            chunk = min(CHUNK_SAMPLES, total - done)
            blocks.append(options.keep(stepper.advance(chunk)))
            done += chunk
            if options.progress is not None:
                options.progress(done / total)
        if blocks:
            samples = SampleBlock.concatenate(blocks)
        else:
            empty = options.keep(stepper.advance(0))
            samples = SampleBlock(
                np.empty((0, len(empty.columns))), 0, stepper.sample_period_s, empty.columns
            )
        return Integration(
            samples, stepper.stop_time_s, total * stepper.substeps, stepper.describe_step()
        )

    return Method(name, "fixed-step", "physics steps", integrate)


def _reference(setup: BrakeSetup, duration_s: float, options: MethodOptions) -> Integration:
    period = options.sample_period_s
    grid = np.arange(round(duration_s / period)) * period  # the fixed-step schemes' samples
    ref = run_reference(setup, duration_s, rtol=options.rtol, sample_times=grid)
    uniform = SampleBlock(ref.samples.data, 0, period, ref.samples.columns)
    return Integration(options.keep(uniform), ref.stop_time_s, ref.n_rhs)


def _contact_regime(setup: BrakeSetup, duration_s: float, options: MethodOptions) -> Integration:
    qs = run_contact_regime(setup, duration_s, accuracy=options.accuracy)
    return Integration(options.keep(qs.samples), qs.stop_time_s, qs.n_substeps)


METHODS: dict[str, Method] = {
    **{name: _fixed_step(name) for name in FIXED_STEP_SCHEMES},
    "reference": Method("reference", "adaptive", "f-evals", _reference),
    "contact_regime": Method("contact_regime", "reduced", "RK4 steps", _contact_regime),
}
FIXED_STEP_METHODS: tuple[str, ...] = tuple(
    name for name, m in METHODS.items() if m.kind == "fixed-step"
)
# what a scenario's [solver] method (or --method) may name
SOLVER_METHODS: tuple[str, ...] = (*FIXED_STEP_METHODS, "reference")
