"""A recorded channel's QoS: the first profile of rosbag2's ``offered_qos_profiles`` YAML
(:func:`offered_qos`), read as hostile text (its size, nesting, keys and policy names
bounded), by the checked reader and by recovery.
"""

from __future__ import annotations

import yaml

from brake_sim_ros.recording.mcap_format import MalformedError
from brake_sim_ros.stream.topics import (
    DURABILITY_POLICIES,
    HISTORY_POLICIES,
    RELIABILITY_POLICIES,
    QosSpec,
)

MAX_QOS_YAML_BYTES = 4096  # the recorder writes about 330 bytes per profile
MAX_QOS_YAML_NESTING = 32  # "[" and "{": block YAML has none; deep nesting makes PyYAML slow
MAX_QOS_DEPTH = 100_000
_QOS_KEYS = frozenset(
    {
        "history", "depth", "reliability", "durability", "deadline", "lifespan", "liveliness",
        "liveliness_lease_duration", "avoid_ros_namespace_conventions",
    }
)  # fmt: skip


def _qos_policy(profile: dict, key: str, allowed: tuple[str, ...], default: str) -> str:
    """A policy name of ``allowed`` from its name or its rmw enum value (the index)."""
    value = profile.get(key, default)
    if isinstance(value, str) and value.lower() in allowed:
        return value.lower()
    if isinstance(value, int) and not isinstance(value, bool) and 0 <= value < len(allowed):
        return allowed[value]
    raise MalformedError(f"offered_qos_profiles {key}: allowed {', '.join(allowed)}")


def offered_qos(text: str) -> QosSpec | None:
    """The first profile of rosbag2's ``offered_qos_profiles`` YAML (None when empty).

    Only history, depth, reliability and durability are used (the recorder writes the
    other policies at their defaults). The YAML must be a list of mappings with rosbag2's
    keys and known policy names (or their enum values, as older rosbag2 wrote them).

    Raises:
        MalformedError: anything else, without quoting the text.
    """
    if not text.strip():
        return None
    if len(text) > MAX_QOS_YAML_BYTES:
        raise MalformedError(f"offered_qos_profiles over {MAX_QOS_YAML_BYTES} bytes")
    if text.count("[") + text.count("{") > MAX_QOS_YAML_NESTING:
        raise MalformedError(f"offered_qos_profiles with more than {MAX_QOS_YAML_NESTING} brackets")
    try:
        profiles = yaml.safe_load(text)
    except (yaml.YAMLError, RecursionError, ValueError):
        raise MalformedError("offered_qos_profiles is not YAML") from None
    if not isinstance(profiles, list) or not profiles or not isinstance(profiles[0], dict):
        raise MalformedError("offered_qos_profiles: allowed a list of QoS mappings")
    profile = profiles[0]
    unknown = [k for k in profile if k not in _QOS_KEYS]
    if unknown:
        raise MalformedError(
            f"offered_qos_profiles has {len(unknown)} unknown keys; allowed "
            + ", ".join(sorted(_QOS_KEYS))
        )
    depth = profile.get("depth", 10)
    if isinstance(depth, bool) or not isinstance(depth, int) or not 0 <= depth <= MAX_QOS_DEPTH:
        raise MalformedError(f"offered_qos_profiles depth: allowed an integer 0..{MAX_QOS_DEPTH}")
    history = _qos_policy(profile, "history", HISTORY_POLICIES, "keep_last")
    return QosSpec(
        reliability=_qos_policy(profile, "reliability", RELIABILITY_POLICIES, "reliable"),
        durability=_qos_policy(profile, "durability", DURABILITY_POLICIES, "volatile"),
        depth=depth or 10,
        history="keep_last" if history == "system_default" else history,
    )
