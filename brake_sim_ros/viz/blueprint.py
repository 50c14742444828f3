"""The default Rerun layout: drawing and ground truth on the left, time series on the right."""

from __future__ import annotations

import rerun.blueprint as rrb

from brake_sim_ros.viz import entities as E


def brake_blueprint() -> rrb.Blueprint:
    """Layout shown on first open (the viewer's "reset blueprint" returns to it).

    Left column: the animated 2-D drawing (drum, shoes, pivots, contact points, force
    arrows), the defect ground truth and the event log (impacts, regime changes).
    Right column: pivot force magnitudes with impact markers, pivot force components,
    drum and flywheel speeds, shoe angles and indentations, contact flags and regime,
    contact and actuation forces, defect values and what the sensors measured (tabs).
    """
    left = rrb.Vertical(
        rrb.Spatial2DView(origin=E.DRAWING, name="Brake (backing plate, m)"),
        rrb.Tabs(
            rrb.TextDocumentView(origin=f"{E.DEFECTS}/ground_truth", name="Defect ground truth"),
            rrb.TextDocumentView(origin=E.RUN, name="Run"),
        ),
        rrb.TextLogView(origin=E.EVENTS, name="Events"),
        row_shares=[4, 2, 2],
    )
    right = rrb.Vertical(
        rrb.TimeSeriesView(
            name="Pivot force |F| (N), impacts",
            contents=[E.pivot_path(s, "magnitude") for s in E.SIDES] + [f"{E.IMPACTS}/**"],
        ),
        rrb.TimeSeriesView(
            name="Pivot force components (N)",
            contents=[E.pivot_path(s, c) for s in E.SIDES for c in ("fx", "fy")],
        ),
        rrb.Horizontal(
            rrb.TimeSeriesView(origin=E.SPEED, name="Speeds (rad/s)"),
            rrb.TimeSeriesView(origin=E.SHOE_ANGLE, name="Shoe angles (deg)"),
            rrb.TimeSeriesView(origin=E.INDENTATION, name="Indentation (um)"),
        ),
        rrb.Horizontal(
            rrb.TimeSeriesView(origin=E.CONTACT, name="Contact flags, regime"),
            rrb.Tabs(
                rrb.TimeSeriesView(origin=E.ACTUATION, name="Actuation (N)"),
                rrb.TimeSeriesView(origin=E.CONTACT_FORCE, name="Contact forces (N)"),
                rrb.TimeSeriesView(origin=E.DEFECTS, name="Defect values"),
                rrb.TimeSeriesView(origin=E.MEASURED, name="Measured (sensors)"),
            ),
        ),
        row_shares=[3, 3, 2, 2],
    )
    return rrb.Blueprint(
        rrb.Horizontal(left, right, column_shares=[2, 3]),
        rrb.TimePanel(state="expanded"),
        collapse_panels=False,
    )
