"""Named speed/accuracy presets of the fixed-step stepper, from the work-precision study.

Each preset names a scheme and a step. Its error bounds are the guarantee for the symmetric
scenario (7.5 s event) against the DOP853 reference: the values measured by
``brake-sim bench accuracy`` (``docs/work_precision.md``, all runs deterministic, so the
measured errors do not vary between runs), rounded up with a margin of 1.4x to 50x.
``tests/test_presets.py`` runs every preset against the reference and checks these bounds.
The real-time factor is what the study measured on one core of the project's 2-core machine
while shared with other jobs; cost is checked by the benchmark, not by a test.

Other scenarios have other errors and step limits: a preset whose step exceeds a scenario's
step limit is refused when the scenario is loaded, naming the limit (choose a smaller
``dt_s`` explicitly); it is never shrunk silently, since the step is also the published
sample period.
"""

from __future__ import annotations

from dataclasses import dataclass

from brake_sim_ros.errors import ParameterError


@dataclass(frozen=True)
class Preset:
    """A scheme and step with its guaranteed error (relative, fractions) and measured cost.

    Attributes:
        name: preset name.
        scheme: fixed-step scheme (``solvers.fixed_step.FIXED_STEP_SCHEMES``).
        dt_s: fixed step, s (the published sample period).
        max_err_first_peak: first-impact peak pivot force, worse shoe.
        max_err_period: first impact period, worse shoe.
        max_err_stop_time: stopping time.
        max_err_contact_force: contact-regime mean pivot force, worse shoe.
        max_impact_count_diff: impacts missed or added, summed over the shoes
            (``analysis.comparison.impact_count_diff``).
        measured_x_real_time: real-time factor measured by the study (recording every sample).
        purpose: when to choose it.
    """

    name: str
    scheme: str
    dt_s: float
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
            dt_s=4e-5,
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
            dt_s=6e-5,
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
            dt_s=2e-5,
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
