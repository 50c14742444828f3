"""What the stream says besides the physics: the defect ground truth (markdown under
``defects/ground_truth`` and scalars ``defects/<side>/<field>``), the accepted actuation
commands (``actuation/command/<side>``, N) and the diagnostics (``events/diagnostics``).
"""

from __future__ import annotations

import math
from typing import Any

import rerun as rr

from brake_sim_ros.model.defects import ShoeDefect
from brake_sim_ros.viz import entities as E
from brake_sim_ros.viz.timeline import NS_PER_S, log_event, set_sim_time

_DIAG_LEVELS = {0: "INFO", 1: "WARN", 2: "ERROR", 3: "WARN"}  # DiagnosticStatus level


def shoe_defects(msg: Any) -> dict[str, ShoeDefect]:
    """The defects of a DefectState per side (angles in the message in rad, here deg)."""
    return {
        side: ShoeDefect(
            pivot_radius_change_pct=float(getattr(msg, f"{side}_pivot_radius_change_pct")),
            initial_angle_deg=math.degrees(float(getattr(msg, f"{side}_initial_angle_rad"))),
            actuation_share=float(getattr(msg, f"{side}_actuation_share")),
        )
        for side in E.SIDES
    }


def log_defects(rec: rr.RecordingStream, msg: Any, ns: int, shoes: dict[str, ShoeDefect]) -> None:
    """A DefectState stamped ``ns`` with its defects ``shoes``: the ground-truth table,
    the defect scalars and an event."""
    labels = list(msg.active_defects)
    lines = [
        f"### Defect ground truth — scenario `{msg.scenario}`",
        "",
        "**healthy**" if msg.healthy else "**active:** " + "; ".join(labels),
        "",
        "| | left | right |",
        "|---|---|---|",
        f"| pivot radius (mm) | {1e3 * msg.left_pivot_radius_m:.2f}"
        f" | {1e3 * msg.right_pivot_radius_m:.2f} |",
        f"| pivot radius change (%) | {msg.left_pivot_radius_change_pct:+.2f}"
        f" | {msg.right_pivot_radius_change_pct:+.2f} |",
        f"| initial angle (deg) | {math.degrees(msg.left_initial_angle_rad):+.3f}"
        f" | {math.degrees(msg.right_initial_angle_rad):+.3f} |",
        f"| actuation share | {msg.left_actuation_share:.3f} | {msg.right_actuation_share:.3f} |",
        "",
        f"applies from t = {ns / NS_PER_S:.6f} s",
    ]
    set_sim_time(rec, ns)
    rec.log(
        f"{E.DEFECTS}/ground_truth",
        rr.TextDocument("\n".join(lines), media_type=rr.MediaType.MARKDOWN),
    )
    for side in E.SIDES:
        d = shoes[side]
        for name, value in (
            ("pivot_radius_change_pct", d.pivot_radius_change_pct),
            ("initial_angle_deg", d.initial_angle_deg),
            ("actuation_share", d.actuation_share),
        ):
            rec.log(f"{E.DEFECTS}/{side}/{name}", rr.Scalars(value))
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
