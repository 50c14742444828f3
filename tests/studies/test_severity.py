"""The severity sweep: one defect from healthy toward its service limit, features that
move with it, and the report a user reads. The published event's physics on the study
brake (``brake=STUDY``); the service brake (the command's default) with its own kinds
and the sizes it cannot be assembled with."""

from __future__ import annotations

import json
import math

import pytest

from brake_sim_ros.cli import main
from brake_sim_ros.model.catalogue import KIND_BY_NAME
from brake_sim_ros.model.defects import Defects
from brake_sim_ros.studies import severity

DURATION_S = 0.45  # the first impacts of the published event
STUDY = "study"


def test_a_share_change_keeps_the_total_and_a_bad_location_is_refused():
    d = Defects.single("actuation_share_change", "right", -0.05)
    assert d.right.actuation_share == pytest.approx(0.45)
    assert d.left.actuation_share == pytest.approx(0.55)
    assert Defects.single("pivot_radius_change", "left", 3.0).right.is_healthy
    with pytest.raises(Exception, match="allowed at"):
        Defects.single("pivot_radius_change", "drum", 1.0)


def test_a_pin_moved_out_lowers_its_shoes_first_impact_peak_and_period_monotonically():
    """The published pivot sweep's direction, at three severities of the catalogue's
    service limit: larger moves, larger drops (can fail on a sign or an order)."""
    kind = KIND_BY_NAME["pivot_radius_change"]
    healthy = severity.features(Defects(), "left", DURATION_S, STUDY)
    result = severity.sweep(kind, "left", DURATION_S, healthy, steps=(0.0, 0.5, 1.0), brake=STUDY)
    assert result["severities"] == [0.0, 1.5, 3.0]
    peak = result["values"]["first_impact_peak_n"]
    period = result["values"]["period_ms"]
    assert peak[0] > peak[1] > peak[2] and period[0] > period[1] > period[2]


@pytest.mark.slow
def test_the_report_has_a_table_and_a_figure_per_kind_and_location(tmp_path):
    out = tmp_path / "sev"
    kind = KIND_BY_NAME["actuation_share_change"]
    path, refused = severity.write_report(
        out, DURATION_S, kinds=(kind,), steps=(0.0, 1.0), brake=STUDY
    )
    assert refused == 0
    text = path.read_text()
    for loc in kind.locations:
        assert f"## {loc} actuation_share_change [1]" in text
        assert (out / f"{loc}_actuation_share_change.png").stat().st_size > 10_000
    data = json.loads((out / "severity.json").read_text())
    assert [r["location"] for r in data] == list(kind.locations)
    assert data[0]["severities"] == [0.0, 0.05]
    assert set(data[0]["values"]) == set(severity.FEATURES)
    assert math.isnan(data[0]["values"]["order_2_line_n"][0])  # too short for the window


def test_the_cli_refuses_a_duration_too_short_for_the_features(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["severity", "--duration", "0.1"])
    assert exc.value.code == 2
    assert "--duration 0.1: allowed 0.4 to 60 s" in capsys.readouterr().err


def test_an_oval_drum_shows_in_the_order_2_line_in_proportion_to_its_runout():
    """The drum kind swept like the others: its line at twice the rotation frequency is
    numerically zero on a round drum and doubles with the runout."""
    kind = KIND_BY_NAME["drum_out_of_round"]
    healthy = severity.features(Defects(), "drum", severity.ORDER_WINDOW_S[1], STUDY)
    result = severity.sweep(
        kind, "drum", severity.ORDER_WINDOW_S[1], healthy, steps=(0.0, 0.5, 1.0), brake=STUDY
    )
    line = result["values"]["order_2_line_n"]
    assert result["severities"] == [0.0, 75.0, 150.0]
    assert line[0] < 1e-6 < line[1]
    assert line[2] / line[1] == pytest.approx(2.0, rel=0.02)


def test_the_report_is_never_written_through_a_link(tmp_path, capsys):
    """A report.md that is a symbolic link is refused before any run, in one line, and the
    file it points to is untouched."""
    out = tmp_path / "sev"
    out.mkdir()
    victim = tmp_path / "precious.txt"
    victim.write_text("keep me")
    (out / "report.md").symlink_to(victim)
    assert main(["severity", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "is a symbolic link" in err
    assert victim.read_text() == "keep me" and not list(out.glob("*.png"))


def test_a_fading_lining_lowers_the_braking_torque_monotonically():
    """Friction change swept to its service limit (-50 %): the braking torque over the
    contact regime falls at each step, and less than in proportion (the trailing shoe
    keeps its share)."""
    kind = KIND_BY_NAME["friction_change"]
    healthy = severity.features(Defects(), "left", severity.ORDER_WINDOW_S[1], STUDY)
    result = severity.sweep(
        kind, "left", severity.ORDER_WINDOW_S[1], healthy, steps=(0.0, 0.5, 1.0), brake=STUDY
    )
    assert result["severities"] == [0.0, -25.0, -50.0]
    torque = result["values"]["braking_torque_n_m"]
    assert torque[0] > torque[1] > torque[2] > 0.5 * torque[0]


def test_lining_wear_raises_its_shoes_first_impact_actuation_monotonically():
    """Wear opens the gap: the shoe strikes later on the ramp, at a larger force."""
    kind = KIND_BY_NAME["lining_wear"]
    healthy = severity.features(Defects(), "left", DURATION_S, STUDY)
    result = severity.sweep(kind, "left", DURATION_S, healthy, steps=(0.0, 0.5, 1.0), brake=STUDY)
    assert result["severities"] == [0.0, 1.7, 3.4]
    force = result["values"]["first_impact_actuation_n"]
    assert force[0] < force[1] < force[2]


def test_a_drum_flat_grows_the_once_per_revolution_line():
    kind = KIND_BY_NAME["drum_flat"]
    healthy = severity.features(Defects(), "drum", 1.9, STUDY)
    result = severity.sweep(kind, "drum", 1.9, healthy, steps=(0.0, 0.2, 1.0), brake=STUDY)
    line = result["values"]["order_1_line_n"]
    assert line[0] < 1e-6 * line[1] and line[1] < line[2]


def test_a_size_the_service_brake_cannot_be_assembled_with_is_listed_not_run(tmp_path):
    """On the service brake a pin moved out by half its limit (+1.5 %) starts the lining
    inside the 0.3 mm clearance's drum: that size is not run (its features NaN), the report
    gives the refusal's line and the count says one; the smaller size runs."""
    out = tmp_path / "sev"
    kind = KIND_BY_NAME["pivot_radius_change"]
    path, refused = severity.write_report(
        out, DURATION_S, kinds=(kind,), steps=(0.0, 0.1, 0.5), brake="service"
    )
    assert refused == 2  # +1.5 % at each shoe
    data = json.loads((out / "severity.json").read_text())
    for r in data:
        assert [s for s, _ in r["refused"]] == [1.5]
        assert "inside the drum" in r["refused"][0][1]
        peak = r["values"]["first_impact_peak_n"]
        assert math.isfinite(peak[1]) and math.isnan(peak[2])
    text = path.read_text()
    assert "on the service brake" in text and text.count("Refused at +1.5 %:") == 2


def test_a_seized_adjuster_raises_its_shoes_first_contact_force_on_the_service_brake():
    """The seized adjuster leaves more clearance: the piston takes more fluid before the
    lining lands, later on the rise and at a larger force, at half and at all of its
    limit. (Not on every finer step: the piston's force ripples while the shoe travels,
    and the full sweep gives the left shoe 77.8 N at 0.4 mm and 75.7 N at 0.6 mm,
    docs/scenarios.md.)"""
    kind = KIND_BY_NAME["adjuster_seized"]
    healthy = severity.features(Defects(), "left", DURATION_S, "service")
    result = severity.sweep(
        kind, "left", DURATION_S, healthy, steps=(0.0, 0.5, 1.0), brake="service"
    )
    force = result["values"]["first_impact_actuation_n"]
    assert result["refused"] == [] and force[0] < force[1] < force[2]


def test_the_cli_refuses_an_unknown_brake_in_one_line_before_any_run(tmp_path, capsys):
    out = tmp_path / "sev"
    with pytest.raises(SystemExit) as exc:
        main(["severity", "--brake", "disc", "--out", str(out)])
    assert exc.value.code == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert "--brake: invalid choice: 'disc'" in err and "'service'" in err
    assert not out.exists()
