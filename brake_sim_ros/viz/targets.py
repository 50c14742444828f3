"""Where a Rerun recording goes: ``spawn``, ``connect URL``, ``serve``, ``save FILE.rrd``.

Each target gets its own recording stream and :class:`~.rerun_sink.RerunSink`: a file
keeps every sample (``FILE_SETTINGS``), a viewer gets the decimated stream
(``LIVE_SETTINGS``). Memory on long runs:

* ``save``: the file grows with the run; the SDK keeps only a small index per chunk for
  the footer (the sink sends one chunk per entity per ``batch_s``, a few per simulated
  second).
* ``spawn``: the viewer runs with ``--memory-limit`` (default 25 % of RAM) and drops
  the oldest data beyond it.
* ``serve``: the gRPC server in this process buffers for late viewers up to
  ``server_memory_limit`` (default 512 MiB), dropping the oldest data beyond it.
* ``connect``: the SDK's gRPC client buffers without limit while it cannot reach the
  viewer (rerun issue #11519; 0.41 has no option for it). The decimated live stream is
  about 0.4 MB per simulated second (measured as a file, symmetric event), so an hour
  without a viewer costs over 1 GB: start the viewer first, or prefer ``serve``.
"""

from __future__ import annotations

import os
import sys
import uuid
from dataclasses import dataclass
from pathlib import Path

import rerun as rr

from brake_sim_ros.errors import BrakeSimError
from brake_sim_ros.model.defects import Defects
from brake_sim_ros.model.parameters import BrakeParameters
from brake_sim_ros.viz.blueprint import brake_blueprint
from brake_sim_ros.viz.rerun_sink import FILE_SETTINGS, LIVE_SETTINGS, RerunSink

APPLICATION_ID = "brake_sim"
KINDS = ("spawn", "connect", "serve", "save")
DEFAULT_CONNECT_URL = "rerun+http://127.0.0.1:9876/proxy"
USAGE = "--rerun spawn | --rerun connect [URL] | --rerun serve | --rerun save FILE.rrd"


class RerunTargetError(BrakeSimError, ValueError):
    """A --rerun option that cannot be honoured (bad form, no display, bad path)."""


@dataclass(frozen=True)
class RerunTarget:
    """One destination. ``arg``: the URL of ``connect`` or the path of ``save``."""

    kind: str
    arg: str | None = None

    @property
    def live(self) -> bool:
        return self.kind != "save"


def parse_target(tokens: list[str]) -> RerunTarget:
    """``["save", "run.rrd"]`` -> RerunTarget; a clear error for anything else."""
    if not tokens or tokens[0] not in KINDS:
        got = " ".join(tokens) or "nothing"
        raise RerunTargetError(f"--rerun {got}: allowed {USAGE}")
    kind, rest = tokens[0], tokens[1:]
    if kind == "save":
        if len(rest) != 1 or not rest[0].endswith(".rrd"):
            raise RerunTargetError(f"--rerun save needs one FILE ending in .rrd, got {rest}")
        return RerunTarget(kind, rest[0])
    if kind == "connect":
        if len(rest) > 1:
            raise RerunTargetError(f"--rerun connect takes at most one URL, got {rest}")
        url = rest[0] if rest else DEFAULT_CONNECT_URL
        if not url.startswith(("rerun://", "rerun+http://", "rerun+https://")):
            raise RerunTargetError(
                f"--rerun connect {url}: allowed a URL like {DEFAULT_CONNECT_URL}"
                " (rerun://, rerun+http:// or rerun+https://)"
            )
        return RerunTarget(kind, url)
    if rest:
        raise RerunTargetError(f"--rerun {kind} takes no argument, got {rest}")
    return RerunTarget(kind)


def check_target(target: RerunTarget) -> None:
    """Refuse, before anything runs, a target that cannot work here (spawn, no display)."""
    if target.kind == "spawn" and not has_display():
        raise RerunTargetError(
            "--rerun spawn: no display here (DISPLAY/WAYLAND_DISPLAY unset), a viewer"
            " window cannot open; use --rerun save FILE.rrd and open the file elsewhere,"
            " or --rerun serve and open the printed web-viewer address"
        )


def has_display() -> bool:
    """True where a native viewer window can open (Linux needs X11 or Wayland)."""
    if sys.platform != "linux":
        return True
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def open_sink(
    target: RerunTarget,
    *,
    params: BrakeParameters | None,
    defects: Defects | None,
    run_text: str = "",
    memory_limit: str = "25%",
    server_memory_limit: str = "512MiB",
) -> RerunSink:
    """A sink logging to ``target``; prints where to look for live targets (stderr).

    Raises:
        RerunTargetError: ``spawn`` without a display, ``save`` to an unwritable place.
    """
    check_target(target)
    rec = rr.RecordingStream(APPLICATION_ID, recording_id=str(uuid.uuid4()))
    blueprint = brake_blueprint()
    if target.kind == "save":
        path = Path(target.arg or "")
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.touch()
        except OSError as exc:
            raise RerunTargetError(f"--rerun save {path}: cannot write there ({exc})") from None
        rec.save(path, default_blueprint=blueprint)
    elif target.kind == "spawn":
        rec.spawn(memory_limit=memory_limit, default_blueprint=blueprint)
    elif target.kind == "connect":
        rec.connect_grpc(target.arg, default_blueprint=blueprint)
        print(f"rerun: streaming to {target.arg}", file=sys.stderr)
    else:  # serve
        url = rec.serve_grpc(default_blueprint=blueprint, server_memory_limit=server_memory_limit)
        rr.serve_web_viewer(connect_to=url, open_browser=False)
        print(
            f"rerun: serving {url}; web viewer at http://localhost:9090/?url={url}"
            f" (or: rerun {url})",
            file=sys.stderr,
        )
    settings = LIVE_SETTINGS if target.live else FILE_SETTINGS
    return RerunSink(rec, params=params, defects=defects, settings=settings, run_text=run_text)
