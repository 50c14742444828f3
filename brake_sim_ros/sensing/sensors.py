"""Sensor models as data: what a monitoring algorithm receives from a brake.

A :class:`SensorSet` is the structure (:mod:`.structure`) and a tuple of
:class:`SensorChannel`; a :class:`SensorBank` turns a stream of sample blocks into the
channels' measured values, their per-sample sensor-fault labels and the tone-ring edge
times. Pure: numpy, scipy and numba only; deterministic.

**Kinds of channel** (``SensorChannel.kind``):

* ``accelerometer``: acceleration along ``axis`` (x or y, frame brake_backing_plate) at a
  mount point of the structure, m/s^2.
* ``load_pin``: the force on the structure at one pivot pin (``location`` left or right)
  along ``axis``, N: the opposite of the pivot columns, what the plate receives.
* ``line_pressure``: brake line pressure, bar: the mean of the two actuation forces (one
  wheel cylinder pushes both shoes; a share defect keeps their sum) over the piston area
  ``pi d^2 / 4``.
* ``wheel_speed``: an ABS tone ring of ``tone_ring_teeth`` teeth read from the drum angle:
  a pulse channel (1 while a tooth is under the sensor, half of each pitch), a
  once-per-revolution index channel ``<name>_index`` (1 for half a tooth pitch after
  angle 0 of each revolution) and the rising-edge times (interpolated between samples).

**The analog signal path** of the other kinds, in order, every step at the scenario's
sample rate ``fs``:
``true x sensitivity_ratio x (gain faults) + noise`` -> mounted resonance (a lightly damped
2nd-order peak) -> 3 dB bandwidth (2nd-order Butterworth low-pass, designed once with
``scipy.signal.butter``) -> the DAQ's anti-alias filter (where the preset has one) ->
``+ bias drift`` -> range (clipping at ``range_min``/``range_max`` and at an active
saturation fault) -> ADC (``adc_bits`` over the range: step ``(range_max - range_min) /
2^bits``) -> stuck / dropout -> every ``fs / rate_hz``-th sample. Resonance and filters are
one continuous system integrated exactly per sample (:mod:`.lti`), so a resonance above
the Nyquist frequency keeps its true tail in band.

**Noise.** White, input-referred, of one-sided density ``noise_density`` (the datasheet's
figure), shaped by the path's own resonance and bandwidth. Through a path with dynamics it
is discretised exactly and realised in innovations form (:func:`.lti.with_input_noise`:
one standard normal draw per sample), so the recorded noise has the continuous sensor's
spectrum and variance
``N^2 int_0^inf |H(f)|^2 df`` even with a bandwidth near the Nyquist frequency; a path without
dynamics adds ``N sqrt(fs / 2)`` times one standard normal draw per sample (white to the
Nyquist frequency). Each channel has its own generator,
``np.random.Generator(np.random.PCG64(np.random.SeedSequence([seed, key])))`` with ``key``
the first 8 bytes of SHA-256 of the channel's name, and draws for every sample of the
scenario rate, in sample order, block after block. So: one seed gives the same bits; two
seeds, or two channels, independent noise; a stream in blocks the same bits as one block;
adding or reordering channels does not change another channel's noise.

**Preset classes** (each kind's ``presets``, :mod:`.sensor_kinds`; figures from TESTBED.md
where it gives them):

* accelerometer ``adxl1002_class`` (industrial MEMS, ADXL1002 datasheet): 25 ug/sqrt(Hz),
  +-50 g, 3 dB bandwidth 11 kHz, mounted resonance 21 kHz; damping ratio of the resonance
  0.05 (assumed: Q = 10); a DAQ with 24 bits over the range (TESTBED: 16-24 bits) and an
  anti-alias filter (4th-order Butterworth at 0.45 of the output rate, assumed: what a
  condition-monitoring DAQ does below its Nyquist frequency). Without it the noise of the
  21 kHz resonance folds into the band at 25.6 kHz.
* accelerometer ``adxl1001_class``: the same family's +-100 g part (ADXL1001 datasheet:
  30 ug/sqrt(Hz), 11 kHz, 21 kHz resonance), with the same DAQ: for mounts whose impacts
  exceed 50 g, at 1.2 times the noise.
* accelerometer ``consumer_imu_class`` (MPU-9250-like): 300 ug/sqrt(Hz), about 1 kHz
  bandwidth, +-16 g with 16 bits (that IMU's widest range and its ADC); no resonance in band.
* ``pressure_transducer``: 0-250 bar, bandwidth 1 kHz (TESTBED), noise 0.003 bar/sqrt(Hz)
  (assumed: about 0.1 bar rms over 1 kHz, 0.04 % of the span), 16 bits (assumed).
* ``strain_gauge_pin``: +-20 kN, bandwidth 2 kHz, noise 0.2 N/sqrt(Hz), 16 bits (all
  assumed: a research-rig load pin with its amplifier).
* ``ideal`` for every kind: the true value, no noise, no dynamics, no range, no ADC.

The default set (:func:`default_sensor_set`): an ``adxl1002_class`` accelerometer per
in-plane axis at the backing plate, the wheel speed (48 teeth: TESTBED 40-50) and the line
pressure (a 19.05 mm, 3/4 in, wheel-cylinder piston: a common passenger-car rear drum size,
assumed; the published 1300 N is then 46 bar).

What they give in the published event (``brake-sim bench sensors``, tests/sensing/test_sensors.py):
a noise floor of about 2.8 mg rms per accelerometer axis; first impacts that exceed the
+-50 g range at the backing plate (the y axis reaches about 93 g before the sensor), so
they are reported clipped for a few samples, as a real ADXL1002 there would (the
``adxl1001_class`` preset keeps them, at 1.2 times the noise); below the actuation the
line pressure reads a few hundredths of a bar, its noise clipped at 0 bar.
"""

from __future__ import annotations

import hashlib
import math
from dataclasses import dataclass, field, replace

import numpy as np

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model.run_setup import SampleBlock
from brake_sim_ros.sensing import faults as sf
from brake_sim_ros.sensing.faults import SensorFault
from brake_sim_ros.sensing.kinds import (  # noqa: F401 (re-exported: the kinds' figures)
    DEFAULT_PISTON_DIAMETER_M,
    DEFAULT_TONE_RING_TEETH,
    LINE_PRESSURE_LOCATION,
    ON_STRUCTURE,
    PA_PER_BAR,
    SENSOR_KINDS,
    STANDARD_GRAVITY_M_S2,
    TONE_RING_LOCATION,
    SensorKind,
    sensor_kind,
)
from brake_sim_ros.sensing.lti import SampledLti, foh_discretise, size_token, with_input_noise
from brake_sim_ros.sensing.paths import (
    PathState,
    analog_advance,
    fault_table,
    gather_columns,
    no_systems,
    stack_systems,
    tone_ring_advance,
    unit_equilibria,
)
from brake_sim_ros.sensing.structure import (
    AXES,
    FORCE_COLUMNS,
    Structure,
    StructureParameters,
    acceleration_output,
)
from brake_sim_ros.sensing.transducers import IDEAL, Transducer
from brake_sim_ros.sensing.transducers import bad as _bad


@dataclass(frozen=True)
class SensorChannel:
    """One sensor.

    Attributes:
        name: the channel's name (unique in a set).
        kind: one of :data:`KINDS`.
        location: a mount point of the structure (accelerometer), a side (load pin),
            ``wheel_cylinder`` (line pressure) or ``tone_ring`` (wheel speed).
        axis: x or y (accelerometer, load pin), frame brake_backing_plate; "" otherwise.
        transducer: the signal path (a preset of its kind, :mod:`.sensor_kinds`, possibly
            with fields changed).
        rate_hz: output rate, Hz; a whole fraction of the scenario's (None: the scenario's).
        sensitivity_ratio: reported per true value (1.0: calibrated), dimensionless.
        tone_ring_teeth: teeth of the tone ring (wheel speed).
        piston_diameter_m: wheel-cylinder piston diameter, m (line pressure).
        faults: sensor faults injected on this channel.
    """

    name: str
    kind: str
    location: str
    axis: str = ""
    transducer: Transducer = IDEAL
    rate_hz: float | None = None
    sensitivity_ratio: float = 1.0
    tone_ring_teeth: int = DEFAULT_TONE_RING_TEETH
    piston_diameter_m: float = DEFAULT_PISTON_DIAMETER_M
    faults: tuple[SensorFault, ...] = ()

    def __post_init__(self) -> None:
        name = self.name
        if not name or not isinstance(name, str):
            raise _bad(name, "name", name, "a non-empty string")
        kind = sensor_kind(self.kind, name)
        if kind.axis:
            if self.axis not in AXES:
                raise _bad(name, "axis", self.axis, f"one of {list(AXES)}")
        elif self.axis:
            raise _bad(name, "axis", self.axis, f"none for a {self.kind} channel")
        if kind.locations != ON_STRUCTURE and self.location not in kind.locations:
            one = len(kind.locations) == 1
            allowed = repr(kind.locations[0]) if one else f"one of {list(kind.locations)}"
            raise _bad(name, "location", self.location, allowed)
        self.transducer.check(name)
        if self.rate_hz is not None and not (math.isfinite(self.rate_hz) and self.rate_hz > 0):
            raise _bad(name, "rate_hz", self.rate_hz, "a rate > 0 Hz, or none")
        if not (math.isfinite(self.sensitivity_ratio) and self.sensitivity_ratio > 0):
            raise _bad(name, "sensitivity_ratio", self.sensitivity_ratio, "> 0")
        if not 1 <= self.tone_ring_teeth <= 1000:
            raise _bad(name, "tone_ring_teeth", self.tone_ring_teeth, "1 to 1000")
        if not (math.isfinite(self.piston_diameter_m) and 1e-3 <= self.piston_diameter_m <= 0.1):
            raise _bad(name, "piston_diameter_m", self.piston_diameter_m, "1 mm to 100 mm")
        for fault in self.faults:
            if fault.kind not in kind.faults:
                raise _bad(name, "fault", fault.kind, f"one of {list(kind.faults)}")
            if fault.kind == "loose_mount" and self.transducer.resonance_hz is None:
                raise _bad(name, "fault", fault.kind, "a transducer with a mounted resonance")
        if len(sf.of_kind(self.faults, "loose_mount")) > 1:
            raise _bad(name, "faults", "loose_mount x2", "at most one loose mount")

    @property
    def unit(self) -> str:
        return sensor_kind(self.kind, self.name).unit

    @property
    def output_names(self) -> tuple[str, ...]:
        """The sampled series this channel gives (a wheel speed also its index)."""
        return sensor_kind(self.kind, self.name).output_names(self.name)

    def decimation(self, sample_rate_hz: float) -> int:
        """Scenario samples per output sample; refuses a rate that does not divide it."""
        if self.rate_hz is None:
            return 1
        ratio = sample_rate_hz / self.rate_hz
        whole = round(ratio)
        if whole < 1 or abs(ratio - whole) > 1e-9 * ratio:
            raise _bad(
                self.name,
                "rate_hz",
                self.rate_hz,
                f"the scenario's rate {sample_rate_hz:g} Hz divided by a whole number",
            )
        return whole

    def with_faults(self, *faults: SensorFault) -> SensorChannel:
        return replace(self, faults=self.faults + faults)


def accelerometer(
    name: str, mount: str, axis: str, preset: str = "adxl1002_class", **changes: object
) -> SensorChannel:
    """An accelerometer channel from a preset class (``changes``: SensorChannel fields)."""
    return SensorChannel(
        name, "accelerometer", mount, axis, SENSOR_KINDS["accelerometer"].presets[preset], **changes
    )


def default_channels() -> tuple[SensorChannel, ...]:
    return (
        accelerometer("backing_plate_accel_x", "backing_plate", "x"),
        accelerometer("backing_plate_accel_y", "backing_plate", "y"),
        SensorChannel("wheel_speed", "wheel_speed", TONE_RING_LOCATION),
        SensorChannel(
            "line_pressure",
            "line_pressure",
            LINE_PRESSURE_LOCATION,
            transducer=SENSOR_KINDS["line_pressure"].presets["pressure_transducer"],
        ),
    )


@dataclass(frozen=True)
class SensorSet:
    """The structure and the channels measured on it."""

    structure: StructureParameters = field(default_factory=StructureParameters)
    channels: tuple[SensorChannel, ...] = field(default_factory=default_channels)

    def __post_init__(self) -> None:
        names = [n for c in self.channels for n in c.output_names]
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise ParameterError(f"sensor names {dup} are used twice: allowed distinct names")
        for c in self.channels:
            on_structure = SENSOR_KINDS[c.kind].locations == ON_STRUCTURE
            if on_structure and c.location not in self.structure.mounts:
                raise _bad(
                    c.name, "location", c.location, f"a mount point {list(self.structure.mounts)}"
                )

    @property
    def needs_structure(self) -> bool:
        return any(sensor_kind(c.kind, c.name).reads_structure for c in self.channels)


def default_sensor_set() -> SensorSet:
    return SensorSet()


def channel_seed(seed: int, name: str) -> np.random.SeedSequence:
    """The noise seed of channel ``name`` in a run seeded ``seed`` (module docstring)."""
    key = int.from_bytes(hashlib.sha256(name.encode()).digest()[:8], "little")
    return np.random.SeedSequence([seed, key])


# --- the run-time side ----------------------------------------------------------------------
@dataclass(frozen=True)
class ChannelSamples:
    """One output series of one block.

    Attributes:
        name, unit: the series' name and unit.
        time_s: sample times (simulated), s, shape (k,).
        values: measured values, shape (k,); NaN where the channel dropped out.
        fault_label: per-sample OR of ``faults.FAULT_BIT`` (0: healthy), uint8.
    """

    name: str
    unit: str
    time_s: np.ndarray
    values: np.ndarray
    fault_label: np.ndarray


@dataclass(frozen=True)
class SensorFrame:
    """What the sensors give for one sample block.

    Attributes:
        series: every output series by name (:class:`ChannelSamples`).
        edges_s: rising-edge times of each wheel-speed channel in this block, s.
        structure_names, structure: the structure's true accelerations (m/s^2) that the
            accelerometers read (each mount and axis once), shape (n, len(names)), at the
            scenario rate; empty when no accelerometer needs it.
    """

    series: dict[str, ChannelSamples]
    edges_s: dict[str, np.ndarray]
    structure_names: tuple[str, ...]
    structure: np.ndarray

    def __getitem__(self, name: str) -> ChannelSamples:
        return self.series[name]

    @staticmethod
    def concatenate(frames: list[SensorFrame]) -> SensorFrame:
        first = frames[0]
        series = {
            name: ChannelSamples(
                name,
                s.unit,
                *(
                    np.concatenate([getattr(f.series[name], a) for f in frames])
                    for a in ("time_s", "values", "fault_label")
                ),
            )
            for name, s in first.series.items()
        }
        edges = {n: np.concatenate([f.edges_s[n] for f in frames]) for n in first.edges_s}
        structure = np.concatenate([f.structure for f in frames])
        return SensorFrame(series, edges, first.structure_names, structure)


class AnalogPath:
    """The analog signal path of one channel (module docstring) with its carried state:
    the dynamics' state, the noise generator, the stuck-value hold. The per-sample work is
    one compiled call (:func:`.paths.analog_advance`)."""

    def __init__(
        self, channel: SensorChannel, sample_period_s: float, seed: int, decimation: int = 1
    ) -> None:
        self.channel = channel
        self.sample_period_s = sample_period_s
        self.rng = np.random.Generator(np.random.PCG64(channel_seed(seed, channel.name)))
        t = channel.transducer
        self.noise = t.noise_density_per_sqrt_hz
        self.faults = fault_table(channel.faults)
        systems: list[SampledLti] = []
        for factor in (1.0, *(f.size for f in sf.of_kind(channel.faults, "loose_mount"))):
            chain = t.continuous(1.0 / (sample_period_s * decimation), factor)
            if chain is not None:
                systems.append(foh_discretise(*chain, sample_period_s))
        if self.noise > 0.0:
            noisy = [with_input_noise(s, self.noise) for s in systems]
            if len({s.n_inputs for s in noisy}) > 1:  # one form for all (they are stacked)
                noisy = [with_input_noise(s, self.noise, per_state=True) for s in systems]
            systems = noisy
        self.systems = systems
        if systems:
            self.matrices = (*stack_systems(systems), unit_equilibria(systems))
            self.state = PathState(systems[0].a.shape[0], systems[0].n_inputs)
            # one per sample (innovations form), or one per state (lti.with_input_noise)
            self.n_draws = systems[0].n_inputs - 1
        else:
            self.matrices = no_systems()
            self.state = PathState()
            self.n_draws = 1 if self.noise > 0.0 else 0
        self.sizes = (size_token(self.state.x.shape[0]), size_token(self.n_draws))
        self.white_gain = self.noise * math.sqrt(0.5 / sample_period_s)

    def advance(self, time_s: np.ndarray, true: np.ndarray) -> np.ndarray:
        """Measured values at the scenario rate for the true values ``true`` (channel unit)
        at ``time_s``."""
        return self.measure(time_s, true)[0]

    def measure(self, time_s: np.ndarray, true: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Measured values and per-sample fault labels (``faults.FAULT_BIT``) for
        the true values ``true`` (channel unit) at ``time_s``."""
        ch, t, state = self.channel, self.channel.transducer, self.state
        k = time_s.shape[0]
        values = np.empty(k)
        labels = np.empty(k, dtype=sf.LABEL_DTYPE)
        if k == 0:
            return values, labels
        draws = self.rng.standard_normal((k, self.n_draws))
        first = not state.started
        state.started = True
        analog_advance(
            *self.sizes,
            np.ascontiguousarray(time_s, dtype=np.float64),
            np.ascontiguousarray(true, dtype=np.float64),
            float(ch.sensitivity_ratio),
            *self.faults,
            *self.matrices,
            state.x,
            state.u_prev,
            first,
            draws,
            self.white_gain,
            float(t.range_min),
            float(t.range_max),
            t.adc_step,
            2.0**t.adc_bits - 1.0 if t.adc_bits is not None else 0.0,
            state.hold,
            values,
            labels,
        )
        return values, labels


class ToneRing:
    """A wheel-speed sensor over a tone ring, with the last sample carried for edges."""

    def __init__(self, channel: SensorChannel) -> None:
        self.channel = channel
        self.faults = fault_table(channel.faults)
        self.last = np.zeros(3)  # [has one, time s, tooth phase] of the last sample
        self.pulse_hold = np.zeros(3)
        self.index_hold = np.zeros(3)

    def advance(
        self, time_s: np.ndarray, drum_angle_rad: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Pulse and index values and the rising-edge times, s, of one block."""
        pulse, index, edges, _ = self.measure(time_s, drum_angle_rad)
        return pulse, index, edges

    def measure(
        self, time_s: np.ndarray, drum_angle_rad: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Pulse, index, rising-edge times (s) and per-sample fault labels of one block."""
        k = time_s.shape[0]
        pulse, index, edges = np.empty(k), np.empty(k), np.empty(k)
        labels = np.empty(k, dtype=sf.LABEL_DTYPE)
        n = tone_ring_advance(
            np.ascontiguousarray(time_s, dtype=np.float64),
            np.ascontiguousarray(drum_angle_rad, dtype=np.float64),
            float(self.channel.tone_ring_teeth),
            *self.faults,
            self.last,
            self.pulse_hold,
            self.index_hold,
            pulse,
            index,
            labels,
            edges,
        )
        return pulse, index, edges[:n].copy(), labels


class SensorBank:
    """A :class:`SensorSet` at a scenario's sample rate and seed, fed sample blocks in order.

    ``advance(block)`` returns the :class:`SensorFrame` of that block; state (structure,
    dynamics, noise generators, holds, tone-ring phase) is carried to the next block, so
    a stream in blocks equals one block bit for bit.
    """

    def __init__(self, sensors: SensorSet, sample_rate_hz: float, seed: int) -> None:
        self.sensors = sensors
        self.sample_rate_hz = float(sample_rate_hz)
        self.sample_period_s = 1.0 / self.sample_rate_hz
        # each channel's kind: its model (a kind without an entry is refused here)
        self.kinds = {c.name: sensor_kind(c.kind, c.name) for c in sensors.channels}
        self.decimation = {c.name: c.decimation(self.sample_rate_hz) for c in sensors.channels}
        # the structure computes what the accelerometers read (each mount and axis once)
        reads = {
            c.name: acceleration_output(c.location, c.axis)
            for c in sensors.channels
            if self.kinds[c.name].reads_structure
        }
        outputs = tuple(dict.fromkeys(reads.values()))
        self.structure = (
            Structure(sensors.structure, self.sample_period_s, outputs)
            if sensors.needs_structure
            else None
        )
        self._structure_column = {name: outputs.index(out) for name, out in reads.items()}
        self.paths: dict[str, AnalogPath | ToneRing] = {}
        for c in sensors.channels:
            self.paths[c.name] = (
                ToneRing(c)
                if self.kinds[c.name].tone_ring
                else AnalogPath(c, self.sample_period_s, seed)
            )
        # Scenario samples per sample of each output series (a wheel speed's index series
        # is sampled with it): series k of a block is taken at the sample indices that are
        # multiples of this.
        self.output_decimation: dict[str, int] = {
            name: self.decimation[c.name] for c in sensors.channels for name in c.output_names
        }
        # the block's columns the channels read, gathered once per block (time first)
        read = ["time_s"]
        for c in sensors.channels:
            read.extend(n for n in self.kinds[c.name].inputs(c) if n not in read)
        self._read_columns = tuple(read)
        self._gather_plans: dict[tuple[str, ...], tuple[np.ndarray, np.ndarray]] = {}

    def _gather(self, block: SampleBlock) -> tuple[np.ndarray, dict[str, np.ndarray]]:
        """The structure's pivot forces (n, 4), N (n, 0 without a structure), and each
        column the channels read as a contiguous array, by name, from one pass over the
        block."""
        plan = self._gather_plans.get(block.columns)
        if plan is None:
            forces = FORCE_COLUMNS if self.structure is not None else ()
            plan = self._gather_plans[block.columns] = (
                np.array([block.index_of(n) for n in forces], dtype=np.int64),
                np.array([block.index_of(n) for n in self._read_columns], dtype=np.int64),
            )
        by_row, by_column = plan
        n = len(block)
        forces_n = np.empty((n, by_row.shape[0]))
        rows = np.empty((by_column.shape[0], n))
        gather_columns(block.data, by_row, forces_n, by_column, rows)
        return forces_n, dict(zip(self._read_columns, rows, strict=True))

    def true_value(
        self, channel: SensorChannel, block: SampleBlock, structure: np.ndarray
    ) -> np.ndarray:
        """What the channel measures, before its signal path, channel unit."""
        columns = {name: block[name] for name in self.kinds[channel.name].inputs(channel)}
        return self._true_value(channel, columns, structure)

    def _true_value(
        self, channel: SensorChannel, columns: dict[str, np.ndarray], structure: np.ndarray
    ) -> np.ndarray:
        """:meth:`true_value` from the block's columns it reads (its kind's ``inputs``), by
        name: its kind's model (:class:`.sensor_kinds.SensorKind`)."""
        kind = self.kinds[channel.name]
        own = structure[:, self._structure_column[channel.name]] if kind.reads_structure else None
        return kind.true_value(channel, columns, own)

    def advance(self, block: SampleBlock) -> SensorFrame:
        forces_n, columns = self._gather(block)
        time_s = columns["time_s"]
        if self.structure is not None:
            structure = self.structure.advance_forces(forces_n)
            names = self.structure.names
        else:
            structure, names = np.empty((len(block), 0)), ()
        series: dict[str, ChannelSamples] = {}
        edges: dict[str, np.ndarray] = {}
        first = block.first_index
        for c in self.sensors.channels:
            path = self.paths[c.name]
            if isinstance(path, ToneRing):
                pulse, idx, edges[c.name], label = path.measure(time_s, columns["drum_angle_rad"])
                outputs: tuple[np.ndarray, ...] = (pulse, idx)
            else:
                values, label = path.measure(time_s, self._true_value(c, columns, structure))
                outputs = (values,)
            step = self.decimation[c.name]
            if step == 1:
                times = time_s
            else:  # the samples whose running index is a multiple of the decimation
                keep = slice((-first) % step, None, step)
                times, label = time_s[keep], label[keep]
                outputs = tuple(o[keep] for o in outputs)
            for name, values in zip(c.output_names, outputs, strict=True):
                series[name] = ChannelSamples(name, c.unit, times, values, label)
        return SensorFrame(series, edges, names, structure)
