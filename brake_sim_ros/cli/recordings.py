"""``brake-sim view``, ``recover`` and ``resim``: what is done with an MCAP recording (show
it in Rerun, keep its intact chunks, re-simulate the run it holds)."""

from __future__ import annotations

import argparse

from brake_sim_ros.cli.common import Command


def cmd_view(args: argparse.Namespace) -> int:
    from brake_sim_ros.viz.commands import cmd_view as view

    return view(args)


def view_options(p: argparse.ArgumentParser) -> None:
    """``view``'s options."""
    p.add_argument("recording", help="MCAP file recorded from the simulator")
    p.add_argument("--save", metavar="FILE.rrd", help="write a Rerun file instead of a viewer")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --save file")
    p.set_defaults(func=cmd_view)


def cmd_recover(args: argparse.Namespace) -> int:
    from brake_sim_ros.recording.recover import recover

    print(recover(args.broken, args.fixed, overwrite=args.overwrite).describe())
    return 0


def recover_options(p: argparse.ArgumentParser) -> None:
    """``recover``'s options."""
    p.add_argument("broken", help="the damaged .mcap file (only read)")
    p.add_argument("fixed", help="the .mcap file to write (not the input, not a link)")
    p.add_argument("--overwrite", action="store_true", help="replace FIXED if it exists")
    p.set_defaults(func=cmd_recover)


def cmd_resim(args: argparse.Namespace) -> int:
    from brake_sim_ros.app.resim import resimulate

    done = resimulate(
        args.recording,
        args.out,
        preset=args.preset,
        measured=args.measured,
        overwrite=args.overwrite,
        compression=args.compression,
    )
    print(f"brake-sim resim: {done.describe()}")
    return 0


def resim_options(p: argparse.ArgumentParser) -> None:
    """``resim``'s description and options."""
    from brake_sim_ros.solvers.presets import PRESETS

    p.description = (
        "Re-simulate the run a brake-sim recording holds (brake-sim node --record,"
        " live, simulate --mcap) from the recording alone: its scenario text, unit, seed,"
        " model and settings, and every actuation and drive command at the sample it took"
        " effect at. Writes the node's stream to a new MCAP file (never the input, never"
        " through a link, whole or not at all) and says whether the samples equal the"
        " recording's bit for bit (they do with the same preset and sensors)."
    )
    p.add_argument("recording", help="the .mcap file recorded (only read)")
    p.add_argument("--out", required=True, metavar="NEW.mcap", help="the .mcap file to write")
    p.add_argument(
        "--preset",
        choices=tuple(PRESETS),
        help="another solver preset (default: the recorded scenario's)",
    )
    p.add_argument(
        "--measured",
        action=argparse.BooleanOptionalAction,
        default=None,
        help="run the scenario's sensors and record ~/measured, or not (default: as the run)",
    )
    p.add_argument("--compression", choices=("zstd", "none"), default="zstd")
    p.add_argument("--overwrite", action="store_true", help="replace an existing --out")
    p.set_defaults(func=cmd_resim)


VIEW = Command("view", "show an MCAP recording in Rerun, or convert it to .rrd", view_options)
RECOVER = Command(
    "recover", "keep every intact chunk of a cut-short or damaged MCAP recording", recover_options
)
RESIM = Command(
    "resim",
    "re-simulate a recorded run offline, its commands at their recorded samples",
    resim_options,
)
