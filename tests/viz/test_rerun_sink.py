"""The Rerun adapter: real .rrd files, checked by ``rerun rrd verify`` and read back.

Offline runs (``brake-sim simulate --rerun save``), a live-style envelope, impacts against
the analysis module's onsets, and ``brake-sim view FILE.mcap --save FILE.rrd`` of an MCAP
written here from the node's offline stream.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from tests.rerun_helpers import read, verify

pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_(parse|constants)' is deprecated")

rr = pytest.importorskip("rerun")
pytest.importorskip("brake_sim_msgs", reason="ROS interfaces not built (run scripts/setup.sh)")

from brake_sim_ros import stream  # noqa: E402
from brake_sim_ros.analysis.onsets import contact_changes, in_contact  # noqa: E402
from brake_sim_ros.cli import main  # noqa: E402
from brake_sim_ros.scenarios import load_scenario  # noqa: E402
from brake_sim_ros.stream import conversion  # noqa: E402
from brake_sim_ros.stream import parameters as ros_params  # noqa: E402
from brake_sim_ros.stream.offline import StreamSettings, offline_messages  # noqa: E402
from brake_sim_ros.stream.run import run_scenario  # noqa: E402
from brake_sim_ros.viz import entities as E  # noqa: E402
from brake_sim_ros.viz.rerun_sink import (  # noqa: E402
    LIVE_SETTINGS,
    RerunSink,
    SinkSettings,
    envelope_positions,
)
from brake_sim_ros.viz.targets import RerunTargetError, parse_target  # noqa: E402

SAMPLE_RATE_HZ = 25_600.0  # the built-in scenarios' sample rate
PERIOD_NS = 1e9 / SAMPLE_RATE_HZ  # 39062.5 ns
RUN_S = 1.0
N_SAMPLES = round(RUN_S * SAMPLE_RATE_HZ)
DRAWING = [
    f"{E.DRAWING}/{p}"
    for p in ("drum", "linings", "shoes", "pivots", "actuation", "pivot_forces", "contact_points")
]


def expected_paths() -> set[str]:
    pivot = {E.pivot_path(s, c) for s in E.SIDES for c in E.PIVOT_SERIES}
    return pivot | set(E.state_paths()) | set(DRAWING) | {E.EVENTS, f"{E.DEFECTS}/ground_truth"}


def stamp(index: int) -> int:
    """Simulated time of sample ``index`` as the stream stamps it, ns."""
    return conversion.stamp_ns(index, 1 / SAMPLE_RATE_HZ)


def check_run(path: Path, *, n_samples: int, n_states: int) -> None:
    """A verified file holding the whole run at full rate, plus states and the rest."""
    verify(path)
    c = read(path)
    assert c.blueprints == 1, "the default blueprint travels with the file"
    missing = expected_paths() - c.timed_paths
    assert not missing, f"entities missing: {sorted(missing)}"
    assert f"{E.RUN}/scenario" in c.static
    for side in E.SIDES:
        for series in E.PIVOT_SERIES:
            t = c.times(E.pivot_path(side, series))
            # every simulated sample, once, at its own time
            assert t.size == n_samples
            np.testing.assert_array_equal(t, [stamp(k) for k in range(n_samples)])
    speed = c.times(f"{E.SPEED}/drum")
    assert speed.size == n_states
    assert speed[0] == 0 and speed[-1] == stamp(n_samples - n_samples // n_states)
    assert c.texts[f"{E.DEFECTS}/ground_truth"], "the ground truth is shown"


def test_simulate_rerun_save_holds_every_sample(tmp_path: Path, capsys):
    out = tmp_path / "sub" / "symmetric.rrd"
    out.parent.mkdir()  # simulate writes into existing directories only
    code = main(
        ["simulate", "symmetric", "--duration", str(RUN_S), "--quiet", "--rerun", "save", str(out)]
    )
    assert code == 0
    assert f"rerun: {N_SAMPLES} pivot-force samples, 100 states" in capsys.readouterr().out
    check_run(out, n_samples=N_SAMPLES, n_states=100)
    assert "**healthy**" in read(out).texts[f"{E.DEFECTS}/ground_truth"][0]


def test_bad_targets_are_refused_before_the_run(tmp_path: Path, capsys, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    for argv, reason in (
        (["--rerun", "save", str(tmp_path / "x.txt")], "ending in .rrd"),
        (["--rerun", "spawn"], "no display here"),
        (["--rerun", "connect", "http://x"], "rerun+http://"),
        (["--rerun", "show"], "allowed --rerun spawn"),
        (["--rerun", "save", "a.rrd", "--method", "reference"], "--method reference"),
    ):
        assert main(["simulate", "symmetric", "--quiet", *argv]) == 2
        err = capsys.readouterr()
        assert reason in err.err
        assert "scenario symmetric" not in err.out, "refused before simulating"
    with pytest.raises(RerunTargetError, match="at most one URL"):
        parse_target(["connect", "rerun://a", "rerun://b"])


def test_envelope_keeps_every_extreme():
    rng = np.random.default_rng(3)
    values = rng.normal(size=1003)
    keep = envelope_positions(values, 50)
    assert np.all(np.diff(keep) > 0)
    for start in range(0, values.size, 50):
        seg = values[start : start + 50]
        picked = values[keep[(keep >= start) & (keep < start + 50)]]
        assert seg.max() in picked and seg.min() in picked
        assert picked.size <= 2


def test_live_settings_decimate_and_keep_peaks(tmp_path: Path):
    """The viewer stream: about 2 points per 2 ms bucket, the largest force still there."""
    scenario = load_scenario("symmetric")
    full_path, live_path = tmp_path / "full.rrd", tmp_path / "live.rrd"
    sinks = []
    for path, settings in ((full_path, SinkSettings()), (live_path, LIVE_SETTINGS)):
        rec = rr.RecordingStream("brake_sim_test")
        rec.save(path)
        sinks.append(RerunSink(rec, params=scenario.setup.params, settings=settings))
    for topic, msg, ns in offline_messages(scenario, duration_s=0.5):
        for sink in sinks:
            sink.write(topic, msg, ns)
    for sink in sinks:
        sink.close()
    verify(live_path)
    full, live = read(full_path), read(live_path)
    path = E.pivot_path("left", "magnitude")
    n_full, n_live = full.times(path).size, live.times(path).size
    buckets = math.ceil(n_full / round(SAMPLE_RATE_HZ / LIVE_SETTINGS.force_envelope_hz))
    assert buckets <= n_live <= 2 * buckets
    assert live.values(path).max() == full.values(path).max()
    assert live.values(path).min() == full.values(path).min()
    # frames every 40 ms of simulated time in [0, 0.5 s)
    assert live.times(f"{E.DRAWING}/drum").size == math.ceil(0.5 * LIVE_SETTINGS.drawing_rate_hz)


IMPACTING_S = 0.3  # the impacting regime of the symmetric event ends at 0.27 s


def test_impacts_match_the_analysis_at_the_default_state_rate(tmp_path: Path):
    """From the ContactEvents: every onset of the analysis, at its exact sample; the peaks."""
    scenario = load_scenario("symmetric")
    rec = rr.RecordingStream("brake_sim_test")
    rec.save(tmp_path / "impacts.rrd")
    sink = RerunSink(rec, params=scenario.setup.params)
    messages = list(offline_messages(scenario, duration_s=IMPACTING_S))
    assert sum(topic is stream.STATE for topic, _, _ in messages) == 30  # 100 Hz
    for topic, msg, ns in messages:
        sink.write(topic, msg, ns)
    sink.close()
    verify(tmp_path / "impacts.rrd")
    run = run_scenario(scenario, duration_s=IMPACTING_S)
    period = run.samples.sample_period_s
    c = read(tmp_path / "impacts.rrd")
    for side in E.SIDES:
        metrics = run.metrics.shoe(side)
        assert metrics.n_impacts >= 7, "more bounces than 100 Hz states can resolve"
        assert sink.impacts[side] == metrics.n_impacts
        # the onset sample is the first one after the interpolated crossing
        onset_index = np.searchsorted(run.samples.time_s, metrics.onsets_s, side="right")
        onset_ns = [conversion.stamp_ns(int(k), period) for k in onset_index]
        np.testing.assert_array_equal(c.times(f"{E.IMPACTS}/{side}"), onset_ns)
        # one peak per finished episode (the last contact lasts past the end of the run)
        n_closed = metrics.separations_s.size
        assert n_closed == metrics.n_impacts - 1
        peaks = c.values(E.impact_peak_path(side))
        assert c.times(E.impact_peak_path(side)).size == n_closed
        np.testing.assert_allclose(
            np.sort(peaks), np.sort(metrics.impact_peaks_n[:n_closed]), rtol=0.01
        )
        onset_texts = [t for t in c.texts[E.EVENTS] if t.startswith(f"impact: {side}")]
        assert len(onset_texts) == metrics.n_impacts


def test_impacts_without_contact_events_at_full_state_rate(tmp_path: Path):
    """A stream without ContactEvents (older recordings) falls back to the states: with a
    BrakeState per sample, every contact onset of the analysis is an event."""
    scenario = load_scenario("symmetric")
    duration = IMPACTING_S
    rec = rr.RecordingStream("brake_sim_test")
    rec.save(tmp_path / "impacts.rrd")
    sink = RerunSink(rec, params=scenario.setup.params)
    every_sample = StreamSettings(state_rate_hz=SAMPLE_RATE_HZ)
    for topic, msg, ns in offline_messages(scenario, duration_s=duration, settings=every_sample):
        if topic is not stream.CONTACT_EVENTS:
            sink.write(topic, msg, ns)
    sink.close()
    run = run_scenario(scenario, duration_s=duration)
    metrics = run.metrics
    for side in E.SIDES:
        assert metrics.shoe(side).n_impacts >= 7
        assert sink.impacts[side] == metrics.shoe(side).n_impacts
    c = read(tmp_path / "impacts.rrd")
    for side in E.SIDES:
        onsets_ns = np.asarray(metrics.shoe(side).onsets_s) * 1e9
        marks = c.times(f"{E.IMPACTS}/{side}")
        assert marks.size == onsets_ns.size
        # each marker sits at the sample where the onset is first seen (the next sample;
        # its stamp rounded to the ns)
        assert np.all((marks >= onsets_ns - 0.5) & (marks - onsets_ns <= PERIOD_NS + 0.5))
        # ... which is the onset sample of the shared definition (a run starts out of contact)
        shared = contact_changes(in_contact(run.samples[f"{side}_indentation_m"]), before=False)
        np.testing.assert_array_equal(
            marks, [stamp(run.samples.first_index + k) for k in shared.onsets]
        )


# -- brake-sim view FILE.mcap --------------------------------------------------------------
def _schema_text(type_name: str) -> str:
    """ros2msg schema: the message's definition and those it uses (Header, Time)."""
    package, _, name = type_name.split("/")
    root = Path(__file__).resolve().parents[2] / "msg_defs" / "msg"
    if package == "brake_sim_msgs":
        text = (root / f"{name}.msg").read_text()
    else:
        raise AssertionError(type_name)
    sep = "=" * 80
    return (
        f"{text}\n{sep}\nMSG: std_msgs/Header\nbuiltin_interfaces/Time stamp\nstring frame_id\n"
        f"{sep}\nMSG: builtin_interfaces/Time\nint32 sec\nuint32 nanosec\n"
    )


def write_mcap(path: Path, scenario_name: str, duration_s: float, *, with_model: bool) -> None:
    """An MCAP of the node's stream as the recorder writes it (cdr, ros2msg, metadata)."""
    from mcap.writer import Writer
    from rclpy.serialization import serialize_message

    scenario = load_scenario(scenario_name)
    kept = (stream.PIVOT_FORCES, stream.STATE, stream.DEFECTS, stream.CONTACT_EVENTS)
    with path.open("wb") as f:
        writer = Writer(f)
        writer.start(profile="ros2", library="brake-sim-ros tests")
        channels = {}
        for topic in kept:
            schema = writer.register_schema(
                name=topic.type_name,
                encoding="ros2msg",
                data=_schema_text(topic.type_name).encode(),
            )
            channels[topic] = writer.register_channel(
                topic=topic.name, message_encoding="cdr", schema_id=schema
            )
        if with_model:
            values = ros_params.model_values(scenario.setup.params, scenario.setup.defects)
            writer.add_metadata("brake_sim_model", {k: repr(v) for k, v in values.items()})
        writer.add_metadata(
            "brake_sim_scenario",
            {"name": scenario.name, "source": scenario.source, "toml": scenario.text},
        )
        for seq, (topic, msg, ns) in enumerate(offline_messages(scenario, duration_s=duration_s)):
            if topic in channels:
                writer.add_message(
                    channel_id=channels[topic],
                    log_time=ns,
                    publish_time=ns,
                    sequence=seq,
                    data=serialize_message(msg),
                )
        writer.finish()


def test_view_mcap_save_rrd(tmp_path: Path, capsys):
    mcap_path, rrd = tmp_path / "case5.mcap", tmp_path / "case5.rrd"
    write_mcap(mcap_path, "case5_left_tilted", RUN_S, with_model=True)
    assert main(["view", str(mcap_path), "--save", str(rrd)]) == 0
    assert f"{N_SAMPLES} pivot-force samples, 100 states" in capsys.readouterr().out
    check_run(rrd, n_samples=N_SAMPLES, n_states=100)
    c = read(rrd)
    truth = c.texts[f"{E.DEFECTS}/ground_truth"][0]
    assert "case5_left_tilted" in truth and "| initial_angle | left | -2 | deg |" in truth
    assert not any("built-in brake geometry" in t for t in c.texts[E.EVENTS])
    assert c.values(f"{E.DEFECTS}/left/initial_angle")[0] == pytest.approx(-2.0)
    assert c.values(f"{E.DEFECTS}/right/initial_angle")[0] == 0.0


def test_view_without_model_metadata_says_so(tmp_path: Path):
    mcap_path, rrd = tmp_path / "bare.mcap", tmp_path / "bare.rrd"
    write_mcap(mcap_path, "symmetric", 0.05, with_model=False)
    assert main(["view", str(mcap_path), "--save", str(rrd)]) == 0
    verify(rrd)
    assert any("built-in brake geometry" in t for t in read(rrd).texts[E.EVENTS])


def test_view_refuses_what_it_cannot_show(tmp_path: Path, capsys, monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    not_mcap = tmp_path / "junk.mcap"
    not_mcap.write_bytes(b"not an mcap file at all")
    assert main(["view", str(not_mcap), "--save", str(tmp_path / "j.rrd")]) == 2
    assert "junk.mcap is not an MCAP file" in capsys.readouterr().err
    good = tmp_path / "ok.mcap"
    write_mcap(good, "symmetric", 0.01, with_model=True)
    assert main(["view", str(good)]) == 2
    assert "use --save FILE.rrd" in capsys.readouterr().err


def test_measured_channels_are_plotted_with_their_sensor_faults(tmp_path: Path):
    """Every measured value at its sample's time under measured/<channel> (a channel at a
    quarter of the rate too), and an event where a sensor fault starts and ends."""
    import dataclasses

    from brake_sim_ros.sensing.faults import SensorFault
    from brake_sim_ros.sensing.sensors import SensorSet, accelerometer, default_channels

    slow = accelerometer("slow_x", "backing_plate", "x", rate_hz=SAMPLE_RATE_HZ / 4)
    pressure = next(c for c in default_channels() if c.kind == "line_pressure")
    faulty = pressure.with_faults(SensorFault("dropout", 0.1, duration_s=0.05))
    base = load_scenario("symmetric")
    scenario = dataclasses.replace(base, sensors=SensorSet(channels=(slow, faulty)))
    path = tmp_path / "measured.rrd"
    rec = rr.RecordingStream("brake_sim_test")
    rec.save(path)
    sink = RerunSink(rec, params=scenario.setup.params)
    sent: dict[str, list[float]] = {"slow_x": [], "line_pressure": []}
    measured = StreamSettings(publish_measured=True)
    for topic, msg, ns in offline_messages(scenario, duration_s=0.3, settings=measured):
        sink.write(topic, msg, ns)
        if topic is stream.MEASURED:
            start = 0
            for name, count in zip(msg.channel_names, msg.channel_sample_counts, strict=True):
                sent[name] += list(msg.values[start : start + count])
                start += count
    sink.close()
    verify(path)
    c = read(path)
    n = round(0.3 * SAMPLE_RATE_HZ)
    np.testing.assert_array_equal(
        c.times(f"{E.MEASURED}/slow_x"), [stamp(k) for k in range(0, n, 4)]
    )
    np.testing.assert_array_equal(
        c.times(f"{E.MEASURED}/line_pressure"), [stamp(k) for k in range(n)]
    )
    for name, values in sent.items():
        got = c.values(f"{E.MEASURED}/{name}")
        np.testing.assert_array_equal(np.sort(got), np.sort(np.asarray(values)))  # NaN last
    dropped = round(0.05 * SAMPLE_RATE_HZ)  # [0.1 s, 0.15 s]: both ends sampled
    assert np.isnan(sent["line_pressure"]).sum() in (dropped, dropped + 1)
    events = c.texts[E.EVENTS]
    assert "sensor line_pressure: fault dropout" in events
    assert "sensor line_pressure: fault none" in events
    assert not any("slow_x: fault" in e for e in events)


def test_wheel_speed_from_edges_is_what_an_abs_controller_computes(tmp_path: Path):
    """measured/wheel_speed_from_edges: one value per tone-ring edge after the first, at
    the edge's time, (2 pi / teeth) / (interval to the previous edge) rad/s, the previous
    edge carried across chunks; it follows the drum speed of the run."""
    from brake_sim_ros.viz.measured import edge_speed_path

    scenario = load_scenario("symmetric")
    path = tmp_path / "edges.rrd"
    rec = rr.RecordingStream("brake_sim_test")
    rec.save(path)
    sink = RerunSink(rec, params=scenario.setup.params)
    chunks = []
    # a measured chunk per 10 ms, so that the edges are carried across many chunks
    measured = StreamSettings(publish_measured=True, measured_rate_hz=100.0)
    for topic, msg, ns in offline_messages(scenario, duration_s=0.4, settings=measured):
        sink.write(topic, msg, ns)
        if topic is stream.MEASURED:
            chunks.append(msg)
    sink.close()
    verify(path)
    c = read(path)
    edges = conversion.measured_edges(chunks)["wheel_speed"]
    teeth = chunks[0].tone_ring_teeth[0]
    entity = edge_speed_path("wheel_speed")
    assert entity == f"{E.MEASURED}/wheel_speed_from_edges"
    assert edges.size > 100 and sum(len(m.edge_times_s) > 0 for m in chunks) > 30
    times = c.times(entity)
    np.testing.assert_array_equal(times, np.round(edges[1:] * 1e9).astype(np.int64))
    values = c.values(entity)
    expected = (2 * np.pi / teeth) / np.diff(edges)
    np.testing.assert_array_equal(np.sort(values), np.sort(expected))
    run = run_scenario(scenario, duration_s=0.4)
    middle = 0.5 * (edges[1:] + edges[:-1])
    true = np.interp(middle, run.samples.time_s, run.samples["drum_speed_rad_s"])
    assert np.max(np.abs(expected / true - 1)) < 0.02
