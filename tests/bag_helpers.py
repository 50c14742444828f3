"""Reading a recording back with rosbags alone: the independent reader of the tests."""

from __future__ import annotations

from pathlib import Path

from rosbags.rosbag2.storage_mcap import McapReader
from rosbags.typesys import Stores, get_types_from_msg, get_typestore


def rosbags_timed(path: Path) -> dict[str, list[tuple[int, object]]]:
    """topic -> ``(log time ns, decoded message)`` in file order, by rosbags alone (the
    message definitions from the file's own schemas)."""
    reader = McapReader(path)
    reader.open()
    try:
        store = get_typestore(Stores.EMPTY)
        for conn in reader.connections:
            store.register(get_types_from_msg(conn.msgdef.data, conn.msgtype))
        out: dict[str, list[tuple[int, object]]] = {}
        for conn, ns, data in reader.messages(reader.connections):
            out.setdefault(conn.topic, []).append((ns, store.deserialize_cdr(data, conn.msgtype)))
        return out
    finally:
        reader.close()


def rosbags_decoded(path: Path) -> dict[str, list]:
    """topic -> decoded messages in file order, by rosbags alone (:func:`rosbags_timed`)."""
    return {topic: [m for _ns, m in msgs] for topic, msgs in rosbags_timed(path).items()}
