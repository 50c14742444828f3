"""Colours of the shoes and the static styles (names with units, markers) of every plot."""

from __future__ import annotations

import rerun as rr

from brake_sim_ros.viz import entities as E

COLORS = {"left": (230, 120, 30), "right": (40, 120, 220)}  # RGB per shoe, in every view


def log_series_styles(rec: rr.RecordingStream) -> None:
    """Log, static, the line and marker styles of every scalar entity the sink logs."""
    log = rec.log
    step = rr.components.InterpolationMode.StepAfter
    for side in E.SIDES:
        color = COLORS[side]
        for series in E.PIVOT_SERIES:
            unit = "|F|" if series == "magnitude" else series
            log(
                E.pivot_path(side, series),
                rr.SeriesLines(colors=[color], names=[f"{side} {unit} (N)"], widths=[1.0]),
                static=True,
            )
        log(
            f"{E.IMPACTS}/{side}",
            rr.SeriesPoints(
                colors=[color], names=[f"{side} impact"], markers=["Cross"], marker_sizes=[6]
            ),
            static=True,
        )
        log(
            E.impact_peak_path(side),
            rr.SeriesPoints(
                colors=[color],
                names=[f"{side} impact peak"],
                markers=["Diamond"],
                marker_sizes=[5],
            ),
            static=True,
        )
        for path, name, mode in (
            (f"{E.SHOE_ANGLE}/{side}", f"{side} (deg)", None),
            (f"{E.INDENTATION}/{side}", f"{side} (um)", None),
            (f"{E.CONTACT_FORCE}/{side}/normal", f"{side} normal (N)", None),
            (f"{E.CONTACT_FORCE}/{side}/friction", f"{side} friction (N)", None),
            (f"{E.ACTUATION}/{side}", f"{side} applied (N)", step),
            (f"{E.CONTACT}/{side}", f"{side} in contact (0/1)", step),
        ):
            log(
                path,
                rr.SeriesLines(colors=[color], names=[name], interpolation_mode=mode),
                static=True,
            )
        log(
            f"{E.ACTUATION}/command/{side}",
            rr.SeriesPoints(colors=[color], names=[f"{side} command (N)"], markers=["Circle"]),
            static=True,
        )
    log(f"{E.SPEED}/flywheel", rr.SeriesLines(names=["flywheel (rad/s)"]), static=True)
    log(f"{E.SPEED}/drum", rr.SeriesLines(names=["drum (rad/s)"]), static=True)
    log(
        f"{E.CONTACT}/regime",
        rr.SeriesLines(
            colors=[(90, 90, 90)],
            names=["regime (0 free, 1 impacting, 2 contact, 3 stopped)"],
            interpolation_mode=step,
        ),
        static=True,
    )
