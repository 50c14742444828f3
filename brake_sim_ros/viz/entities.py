"""Entity paths of the Rerun recording, shared by the sink, the blueprint and the tests.

One timeline, ``sim_time`` (a duration: simulated time since the start of the run, from
the messages' stamps, never the wall clock). Units are in the series names.
"""

from __future__ import annotations

from brake_sim_ros.model.layout import SIDES

TIMELINE = "sim_time"

# full rate in files, a min/max envelope live (see settings.SinkSettings)
PIVOT_FORCE = "pivot_force"
PIVOT_SERIES = ("magnitude", "fx", "fy")  # N, frame brake_backing_plate
PIVOT_MESSAGE_FIELDS = {"magnitude": "magnitude_n", "fx": "fx_n", "fy": "fy_n"}


def pivot_path(side: str, series: str) -> str:
    return f"{PIVOT_FORCE}/{side}/{series}"


# impacts/<side>: a marker per contact onset at its sample, valued |F_pivot| there (N);
# impacts/<side>/peak: a marker per contact episode at its largest |F_pivot| (N)
IMPACTS = "pivot_force/impacts"


def impact_peak_path(side: str) -> str:
    return f"{IMPACTS}/{side}/peak"


# at the state rate (BrakeState)
SPEED = "speed"  # speed/flywheel, speed/drum, rad/s
SHOE_ANGLE = "shoe_angle"  # shoe_angle/<side>, deg
INDENTATION = "indentation"  # indentation/<side>, um (negative = gap)
CONTACT_FORCE = "contact_force"  # contact_force/<side>/{normal,friction}, N
ACTUATION = "actuation"  # actuation/<side> applied (N); actuation/command/<side> accepted
CONTACT = "contact"  # contact/<side> flag 0/1, contact/regime 0..3

# what the sensors measured (MeasuredChunk): measured/<channel>, in the channel's unit
MEASURED = "measured"

# events, ground truth, drawing
EVENTS = "events"  # TextLog: impacts, regime changes, resets, lost samples, diagnostics
DEFECTS = "defects"  # defects/ground_truth (markdown), defects/<location>/<kind> scalars
RUN = "run"  # run/scenario (markdown): what was simulated
DRAWING = "drawing"  # 2-D, metres in brake_backing_plate


def state_paths() -> list[str]:
    """Every scalar entity logged from BrakeState."""
    paths = [f"{SPEED}/flywheel", f"{SPEED}/drum", f"{CONTACT}/regime"]
    for side in SIDES:
        paths += [
            f"{SHOE_ANGLE}/{side}",
            f"{INDENTATION}/{side}",
            f"{CONTACT_FORCE}/{side}/normal",
            f"{CONTACT_FORCE}/{side}/friction",
            f"{ACTUATION}/{side}",
            f"{CONTACT}/{side}",
        ]
    return paths
