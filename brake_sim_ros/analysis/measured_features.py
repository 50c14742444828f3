"""Features of the measured backing-plate acceleration, and when one separates a defect
case from the symmetric brake.

One place for both: ``brake-sim bench sensors`` (part 2) and the validation report call
these functions, so they print the same figures by the same rule.

Features, from the backing-plate accelerometers x and y of a sensor set (m/s^2):

* ``first impact``: the first sample, on either axis, whose magnitude exceeds
  :data:`IMPACT_THRESHOLD_X_NOISE` times that channel's noise rms, ms of simulated time
  (inf when none does);
* ``band rms x``, ``band rms y``: rms in the drum-brake noise band :data:`NOISE_BAND_HZ`
  (4th-order Butterworth band-pass, zero phase) over the impacts, :data:`IMPACT_WINDOW_S`,
  m/s^2;
* ``clipped``: samples at either end of the range, both axes (reported, not judged: the
  model's impacts clip the default +-50 g part in every case alike).

The noise rms of each channel is taken from one healthy stop before any force
(``t < IMPACT_WINDOW_S[0]``).

Separation (:class:`SeparationRule`): a feature separates a case when the difference of
its means over noise seeds exceeds :data:`SPREAD_FACTOR` times the seed spread (the
largest standard deviation over seeds of any case, the symmetric one included) and a
floor: two sample periods for the first-impact time; :data:`BAND_REPEATABILITY` of the
symmetric value for a band level. The model is deterministic and has one brake, so the
spread is sensor noise only: a separation says what the signal carries, not that a
detector would generalise to another brake (no unit-to-unit scatter is modelled; the band
floor stands in for it, an assumption, not a measurement).
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
from scipy import signal

from brake_sim_ros.model.run_setup import SampleBlock
from brake_sim_ros.sensing.sensors import SensorBank, SensorFrame, SensorSet

NOISE_BAND_HZ = (850.0, 4600.0)  # drum-brake noise band (shared/TESTBED.md), Hz
IMPACT_WINDOW_S = (0.2, 0.4)  # the impacts of every built-in case fall inside, s
AXES_CHANNELS = ("backing_plate_accel_x", "backing_plate_accel_y")
IMPACT_THRESHOLD_X_NOISE = 10.0
FIRST_IMPACT = "first impact"
CLIPPED = "clipped"
BAND_RMS = tuple(f"band rms {name[-1]}" for name in AXES_CHANNELS)
FEATURES = (FIRST_IMPACT, *BAND_RMS, CLIPPED)
FEATURE_UNITS = {FIRST_IMPACT: "ms", **dict.fromkeys(BAND_RMS, "m/s^2"), CLIPPED: "samples"}

SPREAD_FACTOR = 3.0
# A band level must differ by more than this fraction to count: an assumed stop-to-stop
# repeatability of impact-band levels on one brake (not measured: the model has no scatter).
BAND_REPEATABILITY = 0.05
FIRST_IMPACT_MIN_SAMPLES = 2
# What the bench and the validation report measure by default: each stop's first 0.6 s (the
# impacts of every built-in case and some quiet after them), four noise seeds.
DEFAULT_DURATION_S = 0.6
DEFAULT_SEEDS = 4


def noise_rms(frame: SensorFrame) -> dict[str, float]:
    """Noise rms of each backing-plate channel before any force (``t <
    IMPACT_WINDOW_S[0]``), m/s^2."""
    out = {}
    for name in AXES_CHANNELS:
        s = frame[name]
        out[name] = float(np.std(s.values[s.time_s < IMPACT_WINDOW_S[0]]))
    return out


def features(
    frame: SensorFrame, quiet_rms: Mapping[str, float], sensors: SensorSet
) -> dict[str, float]:
    """The :data:`FEATURES` of one measured stop (module docstring), keyed by name.

    Args:
        frame: the sensors' output over at least ``[0, IMPACT_WINDOW_S[1])``.
        quiet_rms: noise rms per backing-plate channel, m/s^2 (:func:`noise_rms`).
        sensors: the set that measured ``frame`` (for each channel's range and ADC step).
    """
    transducers = {c.name: c.transducer for c in sensors.channels}
    out: dict[str, float] = dict.fromkeys(FEATURES, 0.0)
    out[FIRST_IMPACT] = math.inf
    for name, band_key in zip(AXES_CHANNELS, BAND_RMS, strict=True):
        s = frame[name]
        if s.time_s[-1] < IMPACT_WINDOW_S[1] - 2 * (s.time_s[1] - s.time_s[0]):
            raise ValueError(
                f"{name} ends at {s.time_s[-1]:.3f} s: the features need"
                f" {IMPACT_WINDOW_S[1]:g} s of samples"
            )
        fs = 1.0 / float(s.time_s[1] - s.time_s[0])
        above = np.flatnonzero(np.abs(s.values) > IMPACT_THRESHOLD_X_NOISE * quiet_rms[name])
        if above.size:
            out[FIRST_IMPACT] = min(out[FIRST_IMPACT], 1e3 * float(s.time_s[above[0]]))
        window = (s.time_s >= IMPACT_WINDOW_S[0]) & (s.time_s < IMPACT_WINDOW_S[1])
        sos = signal.butter(4, NOISE_BAND_HZ, btype="bandpass", fs=fs, output="sos")
        band = signal.sosfiltfilt(sos, s.values[window])
        out[band_key] = float(np.sqrt(np.mean(band**2)))
        t = transducers[name]
        at_range = (s.values >= t.range_max - t.adc_step) | (s.values <= t.range_min)
        out[CLIPPED] += float(np.count_nonzero(at_range))
    return out


@dataclass(frozen=True)
class SeparationRule:
    """When a feature's difference separates a case from the symmetric brake.

    Attributes:
        spread_factor: the difference of the means must exceed this many seed spreads.
        min_absolute: ... and this, in the feature's unit.
        min_relative: ... and this fraction of the symmetric value.
    """

    spread_factor: float = SPREAD_FACTOR
    min_absolute: float = 0.0
    min_relative: float = 0.0

    def separates(self, case_mean: float, base_mean: float, spread: float) -> bool:
        """Whether ``case_mean`` differs from ``base_mean`` by more than every floor;
        False when either is not finite (no such feature in one of them: not judged)."""
        if not (math.isfinite(case_mean) and math.isfinite(base_mean) and math.isfinite(spread)):
            return False
        d = abs(case_mean - base_mean)
        return (
            d > self.spread_factor * spread
            and d > self.min_absolute
            and d > self.min_relative * abs(base_mean)
        )


def separation_rules(sample_period_s: float) -> dict[str, SeparationRule]:
    """The rule of each judged feature (``clipped`` is reported, not judged)."""
    return {
        FIRST_IMPACT: SeparationRule(min_absolute=1e3 * FIRST_IMPACT_MIN_SAMPLES * sample_period_s),
        **{k: SeparationRule(min_relative=BAND_REPEATABILITY) for k in BAND_RMS},
    }


@dataclass(frozen=True)
class FeatureComparison:
    """One feature of one case against the symmetric brake.

    Attributes:
        mean, std: the case's mean and standard deviation over noise seeds (feature unit).
        base_mean, base_std: the same for the symmetric brake.
        spread: the seed spread the rule uses (largest std over all cases).
        separates: the rule's verdict; None for a feature that is not judged.
    """

    feature: str
    mean: float
    std: float
    base_mean: float
    base_std: float
    spread: float
    separates: bool | None

    @property
    def difference(self) -> float:
        return self.mean - self.base_mean

    @property
    def relative(self) -> float:
        """Relative difference (dimensionless; nan when the symmetric value is 0 or not
        finite)."""
        if not math.isfinite(self.base_mean) or self.base_mean == 0:
            return math.nan
        return self.mean / self.base_mean - 1.0


@dataclass(frozen=True)
class CaseSeparation:
    """Every case's features against the symmetric brake's.

    Attributes:
        base: the symmetric case's name.
        seeds: the noise seeds measured.
        quiet_rms: noise rms per channel before any force, m/s^2.
        sample_period_s: the samples' period, s.
        duration_s: the symmetric stop's measured duration, s.
        per_seed: each case's features for each seed, in ``seeds`` order.
        comparisons: for each case other than ``base``, each feature's comparison.
    """

    base: str
    seeds: tuple[int, ...]
    quiet_rms: dict[str, float]
    sample_period_s: float
    duration_s: float
    per_seed: dict[str, list[dict[str, float]]]
    comparisons: dict[str, dict[str, FeatureComparison]]

    def separating(self, case: str) -> list[str]:
        """The features that separate ``case`` from the symmetric brake."""
        return [k for k, c in self.comparisons[case].items() if c.separates]

    def verdict(self, case: str) -> str:
        """One line: which features separate ``case``, or that none does."""
        found = self.separating(case)
        if found:
            return "separated by " + ", ".join(found)
        return "**not separated** by any feature of the measured acceleration"


def _stats(rows: Sequence[Mapping[str, float]], key: str) -> tuple[float, float]:
    values = np.array([r[key] for r in rows], dtype=float)
    if not np.all(np.isfinite(values)):
        return math.inf if np.all(np.isinf(values)) else math.nan, math.nan
    return float(np.mean(values)), float(np.std(values))


def compare_cases(
    per_seed: Mapping[str, Sequence[Mapping[str, float]]],
    base: str,
    rules: Mapping[str, SeparationRule],
) -> dict[str, dict[str, FeatureComparison]]:
    """Each case's features against ``base``'s by ``rules`` (module docstring).

    Args:
        per_seed: each case's features for each noise seed (the same seeds for all).
        base: the key of the symmetric brake in ``per_seed``.
        rules: the rule of each judged feature; a feature without one is not judged.
    """
    keys = list(per_seed[base][0])
    stats = {name: {k: _stats(rows, k) for k in keys} for name, rows in per_seed.items()}
    spread = {k: max(s[k][1] for s in stats.values()) for k in keys}
    out: dict[str, dict[str, FeatureComparison]] = {}
    for name in per_seed:
        if name == base:
            continue
        row = {}
        for k in keys:
            (m, sd), (bm, bsd) = stats[name][k], stats[base][k]
            rule = rules.get(k)
            verdict = None if rule is None else rule.separates(m, bm, spread[k])
            row[k] = FeatureComparison(k, m, sd, bm, bsd, spread[k], verdict)
        out[name] = row
    return out


def measure_cases(
    samples: Mapping[str, SampleBlock],
    base: str,
    *,
    sample_rate_hz: float,
    seeds: Sequence[int],
    sensors: SensorSet | None = None,
) -> CaseSeparation:
    """Measure each case's samples with ``sensors`` (default set) for each noise seed and
    compare each with ``base``.

    Args:
        samples: each case's samples from t = 0 over at least ``IMPACT_WINDOW_S[1]`` s.
        base: the key of the symmetric brake in ``samples``.
        sample_rate_hz: the scenarios' sample rate, Hz (the same for all).
        seeds: the noise seeds (at least two, for a spread).
        sensors: the sensor set; its backing-plate channels must be :data:`AXES_CHANNELS`.
    """
    if len(seeds) < 2:
        raise ValueError(f"{len(seeds)} noise seed(s): a spread needs at least two")
    sensors = SensorSet() if sensors is None else sensors
    order = [base, *(n for n in samples if n != base)]
    quiet: dict[str, float] = {}
    per_seed: dict[str, list[dict[str, float]]] = {}
    for name in order:
        frames = [
            SensorBank(sensors, sample_rate_hz, seed).advance(samples[name]) for seed in seeds
        ]
        if not quiet:  # the noise before any force, from the healthy brake
            quiet = noise_rms(frames[0])
        per_seed[name] = [features(f, quiet, sensors) for f in frames]
    period = samples[base].sample_period_s
    return CaseSeparation(
        base,
        tuple(seeds),
        quiet,
        period,
        len(samples[base]) * period,
        per_seed,
        compare_cases(per_seed, base, separation_rules(period)),
    )


def head(block: SampleBlock, duration_s: float) -> SampleBlock:
    """The first ``duration_s`` of ``block`` (a view)."""
    n = min(len(block), round(duration_s / block.sample_period_s))
    return SampleBlock(block.data[:n], block.first_index, block.sample_period_s, block.columns)


def _value(mean: float, std: float, digits: int) -> str:
    if not math.isfinite(mean):
        return "none" if math.isinf(mean) else "n/a"
    return f"{mean:.{digits}f} ± {std:.2g}"


_DIGITS = {FIRST_IMPACT: 2, CLIPPED: 1, **dict.fromkeys(BAND_RMS, 2)}


def describe(result: CaseSeparation) -> str:
    """One paragraph: what was measured and the rule (for a report or a terminal)."""
    rules = separation_rules(result.sample_period_s)
    noise = ", ".join(f"{n[-1]} {v:.4f}" for n, v in result.quiet_rms.items())
    return (
        f"{len(result.seeds)} noise seeds, default backing-plate accelerometers (noise rms"
        f" {noise} m/s^2 before any force); first impact: first sample above"
        f" {IMPACT_THRESHOLD_X_NOISE:g}x the noise rms on either axis; band rms:"
        f" {NOISE_BAND_HZ[0]:g}-{NOISE_BAND_HZ[1]:g} Hz over {IMPACT_WINDOW_S[0]:g}-"
        f"{IMPACT_WINDOW_S[1]:g} s. A feature separates a case when its mean differs from the"
        f" symmetric one's by more than {SPREAD_FACTOR:g}x the seed spread (largest std over"
        f" all cases) and by more than {rules[FIRST_IMPACT].min_absolute:.3f} ms"
        f" ({FIRST_IMPACT_MIN_SAMPLES} samples) for the first impact,"
        f" {100 * BAND_REPEATABILITY:g} % (an assumed stop-to-stop repeatability) for a band"
        " level; clipped samples are reported, not judged. Values are mean ± std over the seeds."
    )


def markdown_table(result: CaseSeparation, labels: Mapping[str, str] | None = None) -> str:
    """One row per case and feature: the case's value, the symmetric value, the difference
    (and its relative size) and whether it separates; ``labels`` renames cases."""
    labels = labels or {}
    lines = [
        "| case | feature | case | symmetric | difference | relative | separates |",
        "|---|---|---|---|---|---|---|",
    ]
    for case, row in result.comparisons.items():
        for k, c in row.items():
            digits, unit = _DIGITS[k], FEATURE_UNITS[k]
            diff = f"{c.difference:+.{digits}f} {unit}" if math.isfinite(c.difference) else "n/a"
            rel = f"{100 * c.relative:+.1f} %" if math.isfinite(c.relative) else "n/a"
            verdict = {True: "**yes**", False: "no", None: "not judged"}[c.separates]
            lines.append(
                f"| {labels.get(case, case)} | {k} ({unit}) | {_value(c.mean, c.std, digits)}"
                f" | {_value(c.base_mean, c.base_std, digits)} | {diff} | {rel} | {verdict} |"
            )
    return "\n".join(lines)


def verdict_lines(result: CaseSeparation, labels: Mapping[str, str] | None = None) -> list[str]:
    """A markdown bullet per case: the features that separate it, or that none does."""
    labels = labels or {}
    return [f"* {labels.get(case, case)}: {result.verdict(case)}" for case in result.comparisons]
