"""What the stream says besides the physics: the defect ground truth (markdown under
``defects/ground_truth`` and scalars ``defects/<side>/<field>``), the accepted actuation
commands (``actuation/command/<side>``, N) and the diagnostics (``events/diagnostics``).
"""

from __future__ import annotations

from typing import Any

import rerun as rr

from brake_sim_ros.model import catalogue
from brake_sim_ros.model.defects import ShoeDefect
from brake_sim_ros.viz import entities as E
from brake_sim_ros.viz.timeline import NS_PER_S, log_event, set_sim_time

_DIAG_LEVELS = {0: "INFO", 1: "WARN", 2: "ERROR", 3: "WARN"}  # DiagnosticStatus level


def shoe_defects(msg: Any) -> dict[str, ShoeDefect]:
    """The shoes' defects of a DefectState (its catalogue list, per side)."""
    return {
        side: ShoeDefect.from_severities(
            {d.kind: float(d.severity) for d in msg.defects if d.location == side}
        )
        for side in E.SIDES
    }


def log_defects(rec: rr.RecordingStream, msg: Any, ns: int, shoes: dict[str, ShoeDefect]) -> None:
    """A DefectState stamped ``ns`` with its shoes' defects ``shoes``: the ground-truth
    table (one row per defect in force), a scalar per catalogue kind and location
    (``defects/<location>/<kind>``, in its unit, 0 when absent) and an event."""
    labels = list(msg.labels)
    lines = [
        f"### Defect ground truth — scenario `{msg.scenario}`, seed {msg.seed}",
        "",
        "**healthy**" if msg.healthy else "**active:** " + "; ".join(labels),
        "",
        "| kind | location | severity | unit | onset (s) | growth |",
        "|---|---|---|---|---|---|",
        *(
            f"| {d.kind} | {d.location} | {d.severity:+g} | {d.unit} | {d.onset_s:g} | {d.growth} |"
            for d in msg.defects
        ),
        "",
        f"applies from t = {ns / NS_PER_S:.6f} s",
    ]
    set_sim_time(rec, ns)
    rec.log(
        f"{E.DEFECTS}/ground_truth",
        rr.TextDocument("\n".join(lines), media_type=rr.MediaType.MARKDOWN),
    )
    now = {(d.location, d.kind): float(d.severity) for d in msg.defects}
    for kind in catalogue.KINDS:
        for location in kind.locations:
            value = now.get((location, kind.name), 0.0)
            rec.log(f"{E.DEFECTS}/{location}/{kind.name}", rr.Scalars(value))
    text = "healthy" if msg.healthy else ", ".join(labels)
    log_event(rec, ns, f"defect ground truth ({msg.scenario}): {text}")


def log_actuation_command(rec: rr.RecordingStream, msg: Any, ns: int) -> None:
    """An accepted ActuationCommand at ``ns``: a point per shoe (N)."""
    set_sim_time(rec, ns)
    for side in E.SIDES:
        rec.log(f"{E.ACTUATION}/command/{side}", rr.Scalars(float(getattr(msg, f"{side}_force_n"))))


def log_diagnostics(rec: rr.RecordingStream, msg: Any, ns: int) -> None:
    """A DiagnosticArray at ``ns``: a text log line per status, at its level."""
    set_sim_time(rec, ns)
    for status in msg.status:
        level = _DIAG_LEVELS.get(
            int.from_bytes(status.level, "little")
            if isinstance(status.level, bytes)
            else int(status.level),
            "INFO",
        )
        rec.log(
            f"{E.EVENTS}/diagnostics", rr.TextLog(f"{status.name}: {status.message}", level=level)
        )
