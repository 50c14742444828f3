"""Named speed/accuracy presets of the fixed-step stepper, from the work-precision study.

A preset chooses accuracy, not the sample rate: it names a scheme and the largest physics
step it may take. The output sample rate belongs to the scenario (``sample_rate_hz``); the
stepper divides each sample interval into the fewest whole substeps that keep the step
within both the preset's largest step and the step limit of the current parameters
(:mod:`brake_sim_ros.solvers.fixed_step`). Where the limit is the smaller, the step is
smaller than the preset's and the result more accurate than its bounds.

The error bounds are the guarantee for the symmetric scenario (7.5 s event) against the
DOP853 reference at the default sample rate, 25.6 kHz: the largest error ``brake-sim bench
presets`` measured over five onset phases (the ramp's start moved by 0 to 32 us; the
first-impact error of a scheme depends on where the onset falls inside a step, most of all
for the first-order ``fast``), rounded up with a margin of 1.4x to 50x. All runs are
deterministic. ``tests/solvers/test_presets.py`` runs every preset on the published event against
the reference sampled on the same grid and checks these bounds. The real-time factor is measured
at the default sample rate (``brake-sim bench core``, best of 3) on one core of the
project's 2-core machine while shared with other jobs; cost is checked by the benchmark,
not by a test.
"""

from __future__ import annotations

from dataclasses import dataclass

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model.fidelity import ACCURACY_PRESETS


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
            # largest over the onset phases at 25.6 kHz (one 39.1 us step per sample)
            max_err_first_peak=0.05,  # 3.5 %
            max_err_period=0.03,  # 1.65 %
            max_err_stop_time=1e-5,  # 5.3e-7
            max_err_contact_force=1e-6,  # 8e-12
            max_impact_count_diff=0,
            measured_x_real_time=152.0,
            purpose="many long runs where impact figures may be off by a few per cent",
        ),
        Preset(
            name="balanced",
            scheme="rk4-located",
            max_step_s=6e-5,
            # largest over the onset phases at 25.6 kHz (one 39.1 us step per sample)
            max_err_first_peak=1e-3,  # 4.1e-6
            max_err_period=5e-4,  # 8.7e-6
            max_err_stop_time=1e-6,  # 2.0e-8
            max_err_contact_force=1e-6,  # 8e-12
            max_impact_count_diff=0,
            measured_x_real_time=56.0,
            purpose="the default: impact and stop figures well inside 0.1 % at 50x real time",
        ),
        Preset(
            name="accurate",
            scheme="rk4-located",
            max_step_s=2e-5,
            # largest over the onset phases at 25.6 kHz (two 19.5 us steps per sample)
            max_err_first_peak=1e-5,  # 3.4e-7
            max_err_period=1e-5,  # 8.9e-7
            max_err_stop_time=1e-6,  # 2.0e-8
            max_err_contact_force=1e-6,  # 8e-12
            max_impact_count_diff=0,
            measured_x_real_time=29.0,
            purpose="reference-grade figures (1e-5), still faster than real time",
        ),
    )
}
DEFAULT_PRESET = "balanced"
if tuple(PRESETS) != ACCURACY_PRESETS:  # the names are the fidelity plan's, defined once
    raise ImportError(f"presets {list(PRESETS)} differ from the names {ACCURACY_PRESETS}")


def get_preset(name: str) -> Preset:
    """The preset called ``name``; ParameterError naming the allowed ones otherwise."""
    try:
        return PRESETS[name]
    except KeyError:
        raise ParameterError(
            f"unknown solver preset {name!r}: allowed one of {list(PRESETS)}"
        ) from None
