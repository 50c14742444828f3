"""Named speed/accuracy presets of the fixed-step stepper, from the work-precision study.

A preset chooses accuracy, not the sample rate: it names a scheme and the largest physics
step it may take. The output sample rate belongs to the scenario (``sample_rate_hz``); the
stepper divides each sample interval into the fewest whole substeps that keep the step
within both the preset's largest step and the step limit of the current parameters
(:mod:`brake_sim_ros.solvers.fixed_step`). Where the limit is the smaller, the step is
smaller than the preset's and the result more accurate than its bounds.

The error bounds are the guarantee for the symmetric scenario (7.5 s event) at the default
sample rate against the DOP853 reference: the values measured by ``brake-sim bench
accuracy`` at the preset's largest step (``docs/work_precision.md``, all runs
deterministic), rounded up with a margin of 1.4x to 50x. ``tests/test_presets.py`` runs
every preset at the default sample rate against the reference and checks these bounds. The
real-time factor is measured at the default sample rate on one core of the project's 2-core
machine while shared with other jobs; cost is checked by the benchmark, not by a test.
"""

from __future__ import annotations

from dataclasses import dataclass

from brake_sim_ros.errors import ParameterError


@dataclass(frozen=True)
class Preset:
    """A scheme and largest step with its guaranteed error (relative, fractions) and cost.

    Attributes:
        name: preset name.
        scheme: fixed-step scheme (``solvers.fixed_step.FIXED_STEP_SCHEMES``).
        max_step_s: largest physics step, s (an accuracy bound, not the sample period).
        max_err_first_peak: first-impact peak pivot force, worse shoe.
        max_err_period: first impact period, worse shoe.
        max_err_stop_time: stopping time.
        max_err_contact_force: contact-regime mean pivot force, worse shoe.
        max_impact_count_diff: impacts missed or added, summed over the shoes
            (``analysis.comparison.impact_count_diff``).
        measured_x_real_time: real-time factor of the symmetric event at the default
            sample rate (25.6 kHz), recording every sample (``brake-sim bench core``).
        purpose: when to choose it.
    """

    name: str
    scheme: str
    max_step_s: float
    max_err_first_peak: float
    max_err_period: float
    max_err_stop_time: float
    max_err_contact_force: float
    max_impact_count_diff: int
    measured_x_real_time: float
    purpose: str


PRESETS: dict[str, Preset] = {
    p.name: p
    for p in (
        Preset(
            name="fast",
            scheme="semi-implicit-euler",
            max_step_s=4e-5,
            max_err_first_peak=0.01,  # measured 0.39 %
            max_err_period=0.02,  # measured 1.46 %
            max_err_stop_time=1e-5,  # measured 5.4e-7
            max_err_contact_force=1e-6,  # measured 3e-11
            max_impact_count_diff=0,
            measured_x_real_time=194.0,
            purpose="many long runs where the impact period may be off by up to 2 %",
        ),
        Preset(
            name="balanced",
            scheme="rk4-located",
            max_step_s=6e-5,
            max_err_first_peak=1e-3,  # measured 0.019 %
            max_err_period=5e-4,  # measured 0.0052 %
            max_err_stop_time=1e-6,  # measured 6.2e-10
            max_err_contact_force=1e-6,  # measured 3e-11
            max_impact_count_diff=0,
            measured_x_real_time=102.0,
            purpose="the default: impact and stop figures well inside 0.1 % at 100x real time",
        ),
        Preset(
            name="accurate",
            scheme="rk4-located",
            max_step_s=2e-5,
            max_err_first_peak=1e-5,  # measured 9.9e-7
            max_err_period=1e-5,  # measured 1.6e-6
            max_err_stop_time=1e-6,  # measured 6.1e-10
            max_err_contact_force=1e-6,  # measured 3e-11
            max_impact_count_diff=0,
            measured_x_real_time=34.0,
            purpose="reference-grade figures (1e-5) at 50 kHz output, still faster than real time",
        ),
    )
}
DEFAULT_PRESET = "balanced"


def get_preset(name: str) -> Preset:
    """The preset called ``name``; ParameterError naming the allowed ones otherwise."""
    try:
        return PRESETS[name]
    except KeyError:
        raise ParameterError(
            f"unknown solver preset {name!r}: allowed one of {list(PRESETS)}"
        ) from None
