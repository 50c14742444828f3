"""The CLI as a user runs it: real processes, real files."""

from __future__ import annotations

import json
import os
import re
import subprocess
import sys

import numpy as np
import pytest

from brake_sim_ros.cli.simulate import simulate_summary
from brake_sim_ros.model import catalogue
from brake_sim_ros.scenarios import load_scenario
from brake_sim_ros.scenarios.loader import parse_scenario
from brake_sim_ros.stream.run import run_scenario
from brake_sim_ros.studies.validation_checks import checks
from tests import cli_process


def _cli(*args, cwd=None):
    return cli_process.run(
        [sys.executable, "-m", "brake_sim_ros.cli", *args],
        capture_output=True,
        text=True,
        cwd=cwd,
        timeout=600,
    )


# what starting a command may not import unless the command needs it (each costs the test
# suite's hundreds of CLI processes a start-up)
HEAVY = (
    "numpy", "numba", "scipy.signal", "scipy.stats", "scipy.linalg", "scipy.optimize",
    "scipy.integrate", "rclpy", "dask", "pyarrow", "sklearn", "mcap", "rerun", "matplotlib",
    "brake_sim_ros.sensing", "brake_sim_ros.stream", "brake_sim_ros.scenarios.loader",
    "brake_sim_ros.detection.baselines",
)  # fmt: skip
_IMPORTED = """
import sys
from brake_sim_ros.cli import main
try:
    main(sys.argv[2:])
except SystemExit:
    pass
with open(sys.argv[1], "w") as f:
    f.write("\\n".join(sys.modules))
"""


@pytest.mark.parametrize(
    ("argv", "needs"),
    [
        (["--help"], ()),
        (["--version"], ()),
        (["nope"], ()),
        (["score", "--help"], ()),
        (["fit", "--help"], ()),
        (["dataset", "info", "--help"], ()),
        (["recover", "--help"], ()),
        (["bench", "--help"], ()),
        (["defects"], ("numpy", "numba")),  # the catalogue is the model's, which sets numba up
        # the scenarios load (their sensors' scatter too) but build no filter and run nothing
        (
            ["scenarios"],
            (
                "numpy",
                "numba",
                "scipy.linalg",
                "scipy.optimize",
                "brake_sim_ros.sensing",
                "brake_sim_ros.scenarios.loader",
            ),
        ),
        # a run into an MCAP file: the physics, its sensors and the recorder, not Rerun
        (
            ["simulate", "symmetric", "--duration", "0.01", "--quiet", "--mcap", "{tmp}/r.mcap"],
            tuple(h for h in HEAVY if h not in ("rerun", "rclpy", "dask", "sklearn")),
        ),
    ],
    ids=" ".join,
)
def test_a_command_imports_only_what_it_needs(tmp_path, argv, needs):
    listing = tmp_path / "modules"
    r = subprocess.run(
        [sys.executable, "-c", _IMPORTED, str(listing), *(a.format(tmp=tmp_path) for a in argv)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert "Traceback" not in r.stderr, r.stderr
    imported = listing.read_text().split()
    heavy = [h for h in HEAVY if h not in needs]
    loaded = {m for m in imported for h in heavy if m == h or m.startswith(h + ".")}
    assert not loaded, sorted(loaded)


@pytest.mark.slow
def test_simulate_writes_a_history_numpy_opens(tmp_path):
    out = tmp_path / "run.npz"
    r = _cli("simulate", "symmetric", "--duration", "1.0", "--out", str(out), "--quiet")
    assert r.returncode == 0, r.stderr
    assert "impacts" in r.stdout and "real time" in r.stdout
    data = np.load(out)
    assert data["time_s"].size == 25_600  # the default sample rate, 25.6 kHz
    np.testing.assert_array_equal(data["time_s"], np.arange(25_600) * (1 / 25_600))
    assert data["left_pivot_fx_n"].shape == data["time_s"].shape
    meta = json.loads(str(data["metadata"]))
    assert meta["scenario"] == "symmetric" and meta["sample_rate_hz"] == 25_600.0


@pytest.mark.slow
def test_simulate_csv(tmp_path):
    out = tmp_path / "run.csv"
    r = _cli("simulate", "case5_left_tilted", "--duration", "0.3", "--out", str(out), "--quiet")
    assert r.returncode == 0, r.stderr
    arr = np.genfromtxt(out, delimiter=",", names=True)
    assert arr["time_s"].size == 7680 and "right_pivot_fy_n" in arr.dtype.names


@pytest.mark.slow
def test_simulate_runs_at_the_scenarios_sample_rate_for_every_preset_and_defect(tmp_path):
    """The sample rate is the scenario's: the preset and a defect that needs a smaller step
    (case 2's leading pivot 3 % inward: limit 9 us) change the physics step, not the rate."""
    for i, args in enumerate(
        (
            ("case2_left_pivot_in", "--preset", "fast"),
            ("case2_left_pivot_in", "--preset", "accurate"),
            ("symmetric", "--preset", "accurate", "--sample-rate", "10000"),
        )
    ):
        out = tmp_path / f"run{i}.npz"  # an existing output is refused without --overwrite
        r = _cli("simulate", *args, "--duration", "0.05", "--out", str(out), "--quiet")
        assert r.returncode == 0, r.stderr
        rate = float(args[-1]) if "--sample-rate" in args else 25_600.0
        time_s = np.load(out)["time_s"]
        np.testing.assert_array_equal(time_s, np.arange(round(0.05 * rate)) * (1 / rate))
        assert f"{rate:g} Hz samples, physics step" in r.stdout


@pytest.mark.slow
def test_errors_are_one_line_and_nonzero(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text('name = "b"\n[parameters.friction]\ncoefficient = -1.0\n')
    for args in (
        ("simulate", str(bad)),
        ("simulate", "nope"),
        ("simulate", "symmetric", "--dt", "1e-3"),  # retired: the rate is the scenario's
        ("simulate", "symmetric", "--sample-rate", "0"),
        ("simulate", "symmetric", "--max-step", "0"),
    ):
        r = _cli(*args)
        assert r.returncode == 2
        lines = r.stderr.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("brake-sim: error:"), r.stderr


@pytest.mark.slow
def test_validate_writes_report_and_json(tmp_path):
    r = _cli("validate", "--out", str(tmp_path / "v"), "--json", str(tmp_path / "f.json"))
    assert r.returncode == 0, r.stderr
    fig = json.loads((tmp_path / "f.json").read_text())
    sym = fig["symmetric"]
    assert set(sym) >= {
        "stop_time_s",
        "first_impact_actuation_n",
        "first_impact_peak_fr_n",
        "period_s",
    }
    assert set(fig["cases"]) == {str(i) for i in range(1, 9)}
    for case in fig["cases"].values():
        assert set(case) >= {
            "shoe",
            "first_impact_actuation_n",
            "peak_fr_change_pct",
            "period_change_pct",
            "contact_fr_change_pct",
            "other_shoe_peak_fr_change_pct",
            "other_shoe_period_change_pct",
        }
    # the study's calibration targets, checked on the figures the command wrote: every
    # check within its band (case 1's too, since the study brake's heel sits in an eye), and
    # every published change keeps its sign
    check_list = checks(fig)
    failed = [c for c in check_list if not c.passed]
    assert not failed, failed
    signs = [c for c in check_list if "sign of" in c.what]
    assert len(signs) == 6 and all(c.passed for c in signs)
    # the pivot sweep: both shoes' actuation at first impact follows the free travel; the
    # eye's even response: a pin moved either way softens the leading shoe's first impact
    sweep = fig["pivot_sweep"]
    assert sweep["left"]["pivot_radius_change_pct"] == [-3.0, -2.0, -1.0, 0.0, 1.0, 2.0, 3.0]
    assert all(sweep[s]["free_travel_miss_pct"] <= 0.5 for s in ("left", "right"))
    peak = sweep["left"]["change_pct"]["first_impact_peak_fr_n"]
    assert peak[0] < 0.0 and peak[-1] < 0.0
    report = (tmp_path / "v" / "report.md").read_text()
    assert "| case 1: peak F_r change | -43.0 % |" in report
    assert "## Pivot-location sweep" in report
    for png in (
        "pivot_forces_event.png",
        "pivot_forces_impacting.png",
        "defects_vs_symmetric.png",
        "drum_speed.png",
        "pivot_sweep.png",
    ):
        assert (tmp_path / "v" / png).stat().st_size > 10_000


# --- the simulate summary: no nan, "none" with the reason ------------------------------------
SLOW_DRUM = """
[parameters.driveline]
initial_speed_rad_s = 3.0
flywheel_inertia_kg_m2 = 0.5
"""


def _summary(text: str) -> str:
    scenario = parse_scenario(f'name = "t"\n{text}')
    return simulate_summary(run_scenario(scenario), scenario)


def _shoe_lines(summary: str) -> list[str]:
    assert "nan" not in summary.lower(), summary
    return [line for line in summary.splitlines() if line.startswith("  ")]


def test_summary_of_a_whole_event_has_every_figure(symmetric_run):
    lines = _shoe_lines(simulate_summary(symmetric_run, load_scenario("symmetric")))
    assert len(lines) == 2
    for line in lines:
        assert "impacts, first at" in line and "period T" in line and "none" not in line
        assert re.search(r"contact-regime \|F_pivot\| \d+ N$", line), line


def test_summary_says_why_a_stop_has_no_contact_regime():
    """The drum locks at 0.22 s, while the shoes still bounce: no contact regime."""
    for line in _shoe_lines(_summary(f"duration_s = 0.5\n{SLOW_DRUM}")):
        assert re.search(
            r"contact-regime \|F_pivot\| none: the drum locked at 0\.2\d+ s during the"
            r" impacting regime, before the contact-regime window \(1-6 s\)$",
            line,
        ), line
    # the quasi-static level has no impacting regime to speak of
    needs = '[needs]\noutputs = ["stop_time", "contact_regime_forces"]'
    for line in _shoe_lines(_summary(f"duration_s = 0.5\n{SLOW_DRUM}\n{needs}")):
        assert re.search(r"none: the drum locked at 0\.\d+ s, before the contact", line), line


def test_summary_of_runs_too_short_for_a_figure():
    lines = _shoe_lines(_summary("duration_s = 0.1"))
    for line in lines:
        assert line.endswith(
            ": no impacts within the run, contact-regime |F_pivot| none: not reached within"
            " the run: it ends at 0.100 s, before the contact-regime window (1-6 s)"
        ), line
    one = _shoe_lines(
        _summary('duration_s = 0.23\n[needs]\noutputs = ["impacts"]\nshoes = ["left"]')
    )
    assert "1 impact, first at" in one[0] and "period T none (a single impact)" in one[0]
    assert one[1] == "  right: not asked for"
    motion = _shoe_lines(_summary('duration_s = 0.1\n[needs]\noutputs = ["shoe_motion"]'))
    assert all(
        line.endswith(
            ": contact-regime |F_pivot| none: its pivot force was not kept (not asked for)"
        )
        for line in motion
    ), motion


def test_node_help_names_the_command_the_user_typed(capsys):
    from brake_sim_ros.cli import main

    with pytest.raises(SystemExit) as exit_info:
        main(["node", "--help"])
    assert exit_info.value.code == 0
    assert capsys.readouterr().out.startswith("usage: brake-sim node ")


@pytest.mark.parametrize("case", ["exists", "link", "input", "rrd exists"])
def test_node_refuses_its_outputs_before_starting(tmp_path, capsys, case):
    """--record / --rerun save: an existing file (without --overwrite), a link (even with
    it), the scenario file under another name (a hard link, even with it) is refused in
    one line before the node starts, and the file is left as it was."""
    from brake_sim_ros.app.node import _parse_cli

    scenario = tmp_path / "s.toml"
    scenario.write_text("keep")
    existing = tmp_path / "old.mcap"
    existing.write_bytes(b"keep")
    (tmp_path / "link.mcap").symlink_to(existing)
    os.link(scenario, tmp_path / "hard.mcap")
    (tmp_path / "old.rrd").write_bytes(b"keep")
    argv = {
        "exists": ["--record", str(existing)],
        "link": ["--record", str(tmp_path / "link.mcap"), "--overwrite"],
        "input": ["--scenario", str(scenario), "--record", str(tmp_path / "hard.mcap"),
                  "--overwrite"],
        "rrd exists": ["--rerun", "save", str(tmp_path / "old.rrd")],
    }[case]  # fmt: skip
    with pytest.raises(SystemExit) as exit_info:
        _parse_cli(argv, "brake-sim node")
    assert exit_info.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith("brake-sim node: error: "), err  # argparse: usage, then one line
    assert existing.read_bytes() == scenario.read_bytes() == b"keep"
    assert (tmp_path / "old.rrd").read_bytes() == b"keep"


def test_node_overwrite_replaces_an_existing_recording_path(tmp_path):
    from brake_sim_ros.app.node import _parse_cli

    existing = tmp_path / "old.mcap"
    existing.write_bytes(b"old")
    args = _parse_cli(["--record", str(existing), "--overwrite"], "brake-sim node")
    assert args.record == str(existing)


@pytest.mark.slow
def test_simulate_parquet_holds_samples_and_the_measured_channels(tmp_path):
    """``--out run.parquet``: read back by pyarrow, every sample, the measured channels
    with units in their names, the same bits as the stream's ~/measured, and the run's
    parameters and seed in the file's metadata."""
    pq = pytest.importorskip("pyarrow.parquet")
    out = tmp_path / "run.parquet"
    r = _cli("simulate", "symmetric", "--duration", "0.2", "--out", str(out), "--quiet")
    assert r.returncode == 0, r.stderr
    table = pq.read_table(out)
    n = round(0.2 * 25_600)
    assert table.num_rows == n
    np.testing.assert_array_equal(table["sample_index"].to_numpy(), np.arange(n))
    assert table["left_pivot_fx_n"].type == "double"
    scenario = load_scenario("symmetric")
    meta = json.loads(table.schema.metadata[b"brake_sim"])
    assert meta["seed"] == scenario.seed and meta["scenario"] == "symmetric"
    assert meta["sample_rate_hz"] == 25_600.0 and meta["fault_bits"]["dropout"] == 4
    field = table.schema.field("measured:line_pressure [bar]")
    assert field.metadata[b"unit"] == b"bar" and field.metadata[b"rate_hz"] == b"25600.0"
    pytest.importorskip("brake_sim_msgs", reason="ROS interfaces not built")
    from brake_sim_ros import stream
    from brake_sim_ros.stream.offline import StreamSettings, offline_messages

    sent: dict[str, list[float]] = {}
    messages = offline_messages(
        scenario, duration_s=0.2, settings=StreamSettings(publish_measured=True)
    )
    for topic, msg, _ns in messages:
        if topic is stream.MEASURED:
            start = 0
            for name, unit, count in zip(
                msg.channel_names, msg.units, msg.channel_sample_counts, strict=True
            ):
                sent.setdefault(f"measured:{name} [{unit}]", []).extend(
                    msg.values[start : start + count]
                )
                start += count
    assert sent and all(name in table.column_names for name in sent)
    for name, values in sent.items():
        assert table[name].to_numpy().tobytes() == np.asarray(values).tobytes(), name


@pytest.mark.slow
def test_simulate_parquet_labels_every_sample_with_the_defects_ground_truth(tmp_path):
    """Per catalogue kind and location a severity column, the scenario's defect on every
    row and 0 for the healthy others; the metadata lists the defects as DefectState does."""
    pq = pytest.importorskip("pyarrow.parquet")
    out = tmp_path / "case7.parquet"
    r = _cli("simulate", "case7_left_actuation", "--duration", "0.05", "--out", str(out))
    assert r.returncode == 0, r.stderr
    table = pq.read_table(out)
    scenario = load_scenario("case7_left_actuation")
    share = scenario.setup.defects.left.actuation_share - 0.5
    right = scenario.setup.defects.right.actuation_share - 0.5
    assert share > 0.0 > right
    columns = [c for c in table.column_names if c.startswith("defect:")]
    assert len(columns) == sum(len(k.locations) for k in catalogue.KINDS)
    for name in columns:
        values = table[name].to_numpy()
        expected = {
            "defect:actuation_share_change:left [1]": share,
            "defect:actuation_share_change:right [1]": right,
        }.get(name, 0.0)
        assert values.shape == (table.num_rows,) and np.all(values == expected), name
    meta = json.loads(table.schema.metadata[b"brake_sim"])
    assert [(d["kind"], d["location"]) for d in meta["defects"]] == [
        ("actuation_share_change", "left"),
        ("actuation_share_change", "right"),
    ]
    assert meta["defects"][0]["severity"] == share and meta["defects"][0]["growth"] == "step"
    assert meta["unit_id"] == "nominal" and all(
        v["value"] == v["nominal"] for v in meta["unit_parameters"]
    )


def test_a_slower_channel_is_null_between_its_samples():
    pytest.importorskip("pyarrow")
    from brake_sim_ros.datasets.parquet import history_table
    from brake_sim_ros.sensing.sensors import SensorBank, SensorSet, accelerometer

    scenario = load_scenario("symmetric")
    run = run_scenario(scenario, duration_s=0.05)
    slow = accelerometer("slow_x", "backing_plate", "x", rate_hz=6400.0)
    bank = SensorBank(SensorSet(channels=(slow,)), scenario.sample_rate_hz, seed=3)
    table = history_table(
        run.samples,
        bank,
        scenario.setup.defects,
        {"seed": 3},
        unit_id=scenario.unit_id,
        unit_values=scenario.unit_values(),
        conditions=scenario.conditions_record(),
    )
    values = table["measured:slow_x [m/s^2]"]
    assert values.null_count == len(run.samples) - len(run.samples) // 4
    assert values.to_pylist()[0] is not None and values.to_pylist()[1] is None
    assert table["fault:slow_x"].null_count == values.null_count


@pytest.mark.slow
def test_scenarios_lists_the_channels_with_units_and_rates():
    r = _cli("scenarios", "--channels", "symmetric")
    assert r.returncode == 0, r.stderr
    lines = {line.split()[0]: line for line in r.stdout.splitlines()[1:]}
    assert "m/s^2" in lines["backing_plate_accel_x"] and "25600 Hz" in lines["line_pressure"]
    assert "bar" in lines["line_pressure"] and "wheel_speed_index" in lines
    r = _cli("scenarios", "--channels", "no_such")
    assert r.returncode != 0 and "unknown scenario" in r.stderr


@pytest.mark.parametrize("kind", ["not toml", "fifo", "binary"])
def test_scenarios_channels_refuses_a_hostile_file_in_one_line(tmp_path, kind):
    """``scenarios --channels FILE`` reads through the checked reader: one line, exit 2,
    nothing of the file quoted, a FIFO refused instead of waited on."""
    path = tmp_path / "x.toml"
    secret = "SECRET-LINE-CONTENT"
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "binary":
        path.write_bytes(b"\xff\xfe" + secret.encode())
    else:
        path.write_text(f"{secret} garbage\n")
    r = _cli("scenarios", "--channels", str(path))
    assert r.returncode == 2, r.stderr
    lines = r.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("brake-sim: error: "), lines
    assert secret not in r.stderr and "Traceback" not in r.stderr


@pytest.mark.slow
def test_simulate_parquet_and_npz_hold_the_tone_ring_edges_on_their_samples(tmp_path):
    """``measured:wheel_speed_edge_time [s]``, read back by pyarrow and by numpy: each edge
    of the run on the row of the first sample at or after it, NaN on every other row, and
    the same column in the NPZ file as in the Parquet one."""
    pq = pytest.importorskip("pyarrow.parquet")
    from brake_sim_ros.stream.build import sensor_bank_for

    name = "measured:wheel_speed_edge_time [s]"
    out = tmp_path / "run.parquet"
    r = _cli("simulate", "symmetric", "--duration", "0.3", "--out", str(out), "--quiet")
    assert r.returncode == 0, r.stderr
    table = pq.read_table(out)
    field = table.schema.field(name)
    assert field.type == "double"
    assert field.metadata[b"unit"] == b"s" and field.metadata[b"tone_ring_teeth"] == b"48"
    column = table[name].to_numpy()
    assert table[name].null_count == 0
    scenario = load_scenario("symmetric")
    run = run_scenario(scenario, duration_s=0.3)
    edges = sensor_bank_for(scenario).advance(run.samples).edges_s["wheel_speed"]
    rows = np.flatnonzero(~np.isnan(column))
    assert edges.size > 50 and rows.size == edges.size
    assert column[rows].tobytes() == edges.tobytes()
    t = table["time_s"].to_numpy()
    assert np.all((t[rows - 1] < column[rows]) & (column[rows] <= t[rows]))
    npz = tmp_path / "run.npz"
    r = _cli("simulate", "symmetric", "--duration", "0.3", "--out", str(npz), "--quiet")
    assert r.returncode == 0, r.stderr
    data = np.load(npz)
    assert data[name].tobytes() == column.tobytes()
    for measured in ("measured:wheel_speed [1]", "measured:backing_plate_accel_y [m/s^2]"):
        assert data[measured].tobytes() == table[measured].to_numpy().tobytes()
    assert data["fault:line_pressure"].dtype == np.uint8


def test_two_edges_in_one_sample_interval_are_refused():
    from brake_sim_ros.datasets.parquet import edges_on_rows

    t = np.arange(5) * 0.1
    np.testing.assert_array_equal(
        edges_on_rows(t, np.array([0.05, 0.3])), [np.nan, 0.05, np.nan, 0.3, np.nan]
    )
    with pytest.raises(ValueError, match="more than one edge"):
        edges_on_rows(t, np.array([0.21, 0.29]))


def test_a_reader_that_closes_the_pipe_gets_no_traceback():
    """``brake-sim defects | head -1``: the reader has closed the pipe (here before the
    CLI writes anything, so the write fails whatever the timing); the CLI stops quietly
    with 141 (128 + SIGPIPE), as a shell tool does, not with a traceback."""
    proc = subprocess.Popen(
        [sys.executable, "-m", "brake_sim_ros.cli", "defects"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        bufsize=0,
    )
    assert proc.stdout is not None and proc.stderr is not None
    proc.stdout.close()  # the reader goes away before the listing is written
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=60) == 141, err
    assert "Traceback" not in err and "BrokenPipe" not in err
