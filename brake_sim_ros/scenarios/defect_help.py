"""``brake-sim defects``: the defect catalogue as text, generated from its entries.

Per kind its locations, unit, valid range and why, the scenario key and node parameter
that set it, its attributes, the growth laws it takes and what it changes; then the
growth laws and their parameters (:data:`.catalogue.LAW_PARAMETERS`). A kind registered
in the catalogue is listed here with no edit.

Pure logic: no files.
"""

from __future__ import annotations

from brake_sim_ros.model.catalogue import (
    GROWTH_LAWS,
    KINDS,
    LAW_PARAMETERS,
    DefectKind,
    label_column,
)


def _where(k: DefectKind) -> str:
    location = k.locations[0] if len(k.locations) == 1 else "<location>"
    table = f"[defects.{location}]"
    if k.table:
        return f"{table} (no node parameter: the scenario's)"
    return f"{table} or the node's parameter defects.{location}.{k.scenario_key}"


def _kind_lines(k: DefectKind) -> list[str]:
    h = k.healthy_value
    lines = [
        f"  {k.name} [{k.unit}] at {', '.join(k.locations)}: {k.description}",
        f"    range {k.minimum:g} to {k.maximum:g} {k.unit} ({k.limit});"
        f" set by {k.scenario_key} = {h:g} + severity in a scenario's {_where(k)};"
        f" column {label_column(k, k.locations[0])}",
    ]
    for f in k.attributes:
        low = f"> {f.low:g}" if f.low_open or f.needed else f"{f.low:g}"
        lines.append(
            f"    attribute {f.name} (default {f.default:g}; allowed {low} to {f.high:g}"
            f" {f.unit}): {f.description}"
        )
    if k.initial_condition:
        growth = "only from t = 0 (an initial condition)"
    elif k.growth_id is None:
        growth = "only from t = 0 (the model cannot change it during a run)"
    else:
        growth = f"growth {', '.join(k.laws)}"
        if k.tied:
            growth += "; a growing one moves the other shoe's the opposite way"
    lines.append(f"    {growth}; fidelity levels {', '.join(sorted(k.levels))}")
    return lines


def catalogue_text() -> str:
    """The defect catalogue: a block per kind (:func:`_kind_lines`), then the growth laws."""
    lines = [
        "defect catalogue (ground truth: DefectState.defects; Parquet/NPZ label columns"
        " defect:<kind>:<location> [<unit>], 0 where absent)"
    ]
    for k in KINDS:
        lines += _kind_lines(k)
    params = "; ".join(
        f"{p.name} ({p.law}: {p.what}"
        + (f", default {p.default:g}" if p.default is not None else "")
        + ")"
        for p in LAW_PARAMETERS
    )
    lines.append(
        f"growth laws: {', '.join(GROWTH_LAWS)}; a key's value is the final severity, or a"
        f" table {{value, onset_s, growth, and the law's parameters: {params}}}"
        " ([defects.drum]: the same keys beside harmonics, in um of peak runout; any other"
        " drum key takes the table itself); without them a defect is in force from t = 0"
    )
    return "\n".join(lines)
