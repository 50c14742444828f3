"""The 2-D brake drawing (:mod:`.drawing`) under ``drawing/``, in metres in frame
``brake_backing_plate``: drum with its angle marker, linings, shoes, pivots, actuation
and pivot-force arrows, contact points with their normal and friction forces (arrows
scaled by :data:`.drawing.FORCE_SCALE_M_PER_N`). A frame is drawn at a BrakeState, at
most ``drawing_rate_hz`` frames per simulated second.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import rerun as rr

from brake_sim_ros.errors import ParameterError
from brake_sim_ros.model.defects import Defects, ShoeDefect
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.viz import entities as E
from brake_sim_ros.viz.drawing import FORCE_SCALE_M_PER_N, BrakeDrawing, contact_force_vectors
from brake_sim_ros.viz.pivot_samples import RecentPivotForces
from brake_sim_ros.viz.styles import COLORS
from brake_sim_ros.viz.timeline import NS_PER_S, log_event, set_sim_time

_DRUM_COLOR = (70, 70, 70)
_ACTUATION_COLOR = (120, 120, 120)
_CONTACT_COLOR = (200, 40, 40)  # contact points and friction arrows


class BrakeScene:
    """Draws the brake at the BrakeStates.

    Args:
        rec: where to log.
        params: the brake's parameters (geometry).
        defects: defects at the start (:meth:`set_defects` updates them).
        drawing_rate_hz: frames per simulated second at most.
        pivot_forces: where the pivot-force arrows take their values.
    """

    def __init__(
        self,
        rec: rr.RecordingStream,
        *,
        params: BrakeParameters,
        defects: Defects,
        drawing_rate_hz: float,
        pivot_forces: RecentPivotForces,
    ) -> None:
        self._rec = rec
        self._params = params
        self._drawing = BrakeDrawing(params, defects)
        self._frame_ns = round(NS_PER_S / drawing_rate_hz)
        self._pivot_forces = pivot_forces
        self._next_frame_ns = 0

    def restart(self) -> None:
        """The simulation restarted: draw at the next state."""
        self._next_frame_ns = 0

    def set_defects(self, shoes: dict[str, ShoeDefect], ns: int) -> None:
        """Draw the shoes with the defects ``shoes`` (per side) from now on; defects the
        model refuses keep the previous drawing, with a warning at ``ns``."""
        try:
            self._drawing = BrakeDrawing(self._params, Defects(**shoes))
        except ParameterError as exc:
            log_event(self._rec, ns, f"defects not drawn: {exc}", "WARN")

    def on_state(self, msg: Any, ns: int) -> None:
        """A BrakeState stamped ``ns``: a frame if one is due."""
        if ns >= self._next_frame_ns:
            self._draw(msg, ns, int(msg.sample_index))
            self._next_frame_ns = ns + self._frame_ns

    def _draw(self, msg: Any, ns: int, index: int) -> None:
        actuation = (float(msg.left_actuation_force_n), float(msg.right_actuation_force_n))
        frame = self._drawing.frame(
            shoe_angles_rad=(float(msg.left_shoe_angle_rad), float(msg.right_shoe_angle_rad)),
            drum_angle_rad=float(msg.drum_angle_rad),
            actuation_n=actuation,
        )
        colors = [COLORS[s] for s in E.SIDES]
        set_sim_time(self._rec, ns)
        log = self._rec.log
        d = E.DRAWING
        log(f"{d}/drum", rr.LineStrips2D([frame.drum, frame.drum_marker], colors=[_DRUM_COLOR]))
        log(f"{d}/linings", rr.LineStrips2D(list(frame.linings), colors=colors, radii=0.0015))
        log(f"{d}/shoes", rr.LineStrips2D(list(frame.tables), colors=colors, radii=0.0008))
        log(
            f"{d}/pivots",
            rr.Points2D(frame.pivots, radii=0.005, colors=colors, labels=["pivot L", "pivot R"]),
        )
        log(
            f"{d}/actuation",
            rr.Arrows2D(
                origins=frame.actuation_origins,
                vectors=frame.actuation_vectors,
                colors=[_ACTUATION_COLOR],
                labels=[f"{f:.0f} N" for f in actuation],
            ),
        )
        pivot = self._pivot_forces.at(index)
        if pivot is not None:
            vectors = np.array([pivot[s] for s in E.SIDES]) * FORCE_SCALE_M_PER_N
            log(
                f"{d}/pivot_forces",
                rr.Arrows2D(
                    origins=frame.pivots,
                    vectors=vectors,
                    colors=colors,
                    labels=[f"{np.hypot(*pivot[s]):.0f} N" for s in E.SIDES],
                ),
            )
        self._draw_contacts(msg)

    def _draw_contacts(self, msg: Any) -> None:
        points, origins, vectors, cols = [], [], [], []
        for side in E.SIDES:
            if bool(getattr(msg, f"{side}_in_contact")):
                p = (
                    float(getattr(msg, f"{side}_contact_x_m")),
                    float(getattr(msg, f"{side}_contact_y_m")),
                )
                normal, friction = contact_force_vectors(
                    p,
                    float(getattr(msg, f"{side}_normal_force_n")),
                    float(getattr(msg, f"{side}_friction_force_n")),
                )
                points.append(p)
                origins += [p, p]
                vectors += [normal, friction]
                cols += [COLORS[side], _CONTACT_COLOR]
        self._rec.log(
            f"{E.DRAWING}/contact_points",
            rr.Points2D(np.array(points).reshape(-1, 2), radii=0.004, colors=[_CONTACT_COLOR]),
        )
        self._rec.log(
            f"{E.DRAWING}/contact_forces",
            rr.Arrows2D(
                origins=np.array(origins).reshape(-1, 2),
                vectors=np.array(vectors).reshape(-1, 2),
                colors=cols or None,
            ),
        )
