"""What the simulated sensors measured (MeasuredChunk): one scalar series per channel,
``measured/<channel>`` (its unit in the series name), and an event whenever a channel's
sensor-fault label changes (ground truth: a sensor fault, not a brake defect).

From each wheel-speed channel's tone-ring edges, ``measured/<channel>_from_edges``: the
speed an ABS controller computes, ``(2 pi / teeth) / (t[k] - t[k-1])`` rad/s, logged at
each edge time ``t[k]`` (the previous edge carried from chunk to chunk; an interval that
spans a dropout, with its edges missing, reads low, as it would in the controller).

Every sample is sent to files; with ``envelope_hz`` (live viewers) only the smallest and
largest value of each ``1 / envelope_hz`` bucket, at their own times, as for the pivot
forces. Values are sent as columns, one ``send_columns`` per channel and chunk.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import rerun as rr

from brake_sim_ros.sensing.faults import FAULT_BIT
from brake_sim_ros.viz import entities as E
from brake_sim_ros.viz.series import envelope_positions
from brake_sim_ros.viz.timeline import NS_PER_S, log_event, send_scalar_columns, stamp_ns


def fault_names(label: int) -> str:
    """The fault kinds of a label (OR of FAULT_BIT), or "none"."""
    return ", ".join(k for k, bit in FAULT_BIT.items() if label & bit) or "none"


def edge_speed_path(channel: str) -> str:
    """Entity of the speed from a wheel-speed channel's edges, rad/s."""
    return f"{E.MEASURED}/{channel}_from_edges"


class MeasuredSeries:
    """Logs MeasuredChunks; remembers each channel's last fault label and styles sent."""

    def __init__(self, rec: rr.RecordingStream, *, envelope_hz: float | None = None) -> None:
        self.rec = rec
        self.envelope_hz = envelope_hz
        self._styled: set[str] = set()
        self._labels: dict[str, int] = {}
        self.samples_logged = 0  # values received, every channel
        self._last_edge_s: dict[str, float] = {}

    def restart(self) -> None:
        """A reset: fault labels start again from healthy; edge intervals start afresh."""
        self._labels.clear()
        self._last_edge_s.clear()

    def on_chunk(self, msg: Any) -> None:
        rate = float(msg.sample_rate_hz)
        first = int(msg.first_sample_index)
        values = np.asarray(msg.values, dtype=np.float64)
        labels = np.frombuffer(bytes(msg.fault_labels), dtype=np.uint8)
        start = 0
        for name, unit, decimation, count in zip(
            msg.channel_names, msg.units, msg.decimation, msg.channel_sample_counts, strict=True
        ):
            count, decimation = int(count), int(decimation)
            chunk_values = values[start : start + count]
            chunk_labels = labels[start : start + count]
            start += count
            if count == 0:
                continue
            path = f"{E.MEASURED}/{name}"
            if name not in self._styled:
                self._styled.add(name)
                self.rec.log(path, rr.SeriesLines(names=[f"{name} ({unit})"]), static=True)
            first_index = first + (-first) % decimation  # the first multiple of decimation
            index = first_index + decimation * np.arange(count)
            ns = np.round(index * (NS_PER_S / rate)).astype(np.int64)
            keep = np.arange(count)
            if self.envelope_hz:
                bucket = max(1, round(rate / decimation / self.envelope_hz))
                keep = envelope_positions(chunk_values, bucket)
            send_scalar_columns(self.rec, path, ns[keep], chunk_values[keep])
            self.samples_logged += count
            self._fault_events(name, chunk_labels, ns)
        self._edge_speeds(msg)
        if start != values.size or start != labels.size:
            log_event(
                self.rec,
                stamp_ns(msg),
                f"measured chunk at sample {first}: {values.size} values, {labels.size}"
                f" labels, its channel counts say {start}",
                "WARN",
            )

    def _edge_speeds(self, msg: Any) -> None:
        """``measured/<channel>_from_edges``: rad/s from consecutive tone-ring edges."""
        times = np.asarray(msg.edge_times_s, dtype=np.float64)
        counts = [int(c) for c in msg.edge_counts]
        if sum(counts) != times.size:
            log_event(
                self.rec,
                stamp_ns(msg),
                f"measured chunk at sample {int(msg.first_sample_index)}: {times.size} edge"
                f" times, its edge counts say {sum(counts)}",
                "WARN",
            )
            return
        start = 0
        for name, teeth, count in zip(
            msg.edge_channel_names, msg.tone_ring_teeth, counts, strict=True
        ):
            edges = times[start : start + count]
            start += count
            if count == 0:
                continue
            path = edge_speed_path(name)
            if path not in self._styled:
                self._styled.add(path)
                label = f"{name.replace('_', ' ')} from edges (rad/s)"
                self.rec.log(path, rr.SeriesLines(names=[label]), static=True)
            last = self._last_edge_s.get(name)
            joined = edges if last is None else np.concatenate(([last], edges))
            self._last_edge_s[name] = float(edges[-1])
            if joined.size < 2:
                continue
            speed = (2.0 * np.pi / int(teeth)) / np.diff(joined)
            ns = np.round(joined[1:] * NS_PER_S).astype(np.int64)
            send_scalar_columns(self.rec, path, ns, speed)

    def _fault_events(self, name: str, labels: np.ndarray, ns: np.ndarray) -> None:
        last = self._labels.get(name, 0)
        changes = np.flatnonzero(np.diff(labels, prepend=np.uint8(last)))
        for k in changes:
            label = int(labels[k])
            level = "WARN" if label else "INFO"
            log_event(self.rec, int(ns[k]), f"sensor {name}: fault {fault_names(label)}", level)
        self._labels[name] = int(labels[-1])
