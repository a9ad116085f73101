"""The ``worldtrack`` command: one entry point, one sub-command per verb.

Each verb lives in its own module of this package with a ``register(subparsers)`` function that
adds its parser and sets ``func`` to the function that runs it; verb modules import NumPy, OpenCV
and the rest inside the functions that run, so ``--help`` answers at once. A user's mistake (an
:class:`~worldtrack.errors.InputError`) prints one line, ``error: …``, and exits with status 2.
Ctrl-C prints ``interrupted`` and exits with 130 (SIGTERM: ``terminated``, 143), wherever it lands
(:mod:`worldtrack.interrupts`); a closed pipe on standard output (``worldtrack … | head``) ends the
command quietly. FFmpeg's own messages about damaged video stay off the terminal unless
``--verbose`` is given.
"""

from __future__ import annotations

import argparse
import importlib
import os
import sys

from worldtrack import __version__
from worldtrack.errors import InputError
from worldtrack.interrupts import (exit_status, install_terminate_handler, interrupt_in, received_signal,
                                   signal_of)

# Verb modules, in the order ``worldtrack --help`` lists them, with the one line it shows for each
# (each module's own ``register`` repeats it; tests/cli/test_cli_startup.py checks they agree).
COMMANDS = {
    "demo": "synthesise a scene, track it, evaluate against ground truth (the README's first command)",
    "scene": "check a scene file and draw its floor plan",
    "calibrate": "fit a camera to point pairs (CSV) or import a calibration file",
    "synth": "render a synthetic multi-camera sequence with exact ground truth",
    "track": "track people in videos of a calibrated scene",
    "smooth": "estimate head trajectories across cameras that do not share views (paper 002)",
    "pose": "track the pose of a face, an upper body or a rigid object (paper 003)",
    "eval": "score tracks against ground truth (MOTA, MOTP in metres, IDF1, HOTA, errors)",
    "background": "estimate an empty-scene background image from a video",
    "gt": "ground-truth tools: import image-box GT (CVML, MOTChallenge) as world GT",
    "follow": "follow one person with a moving stereo / RGB-D camera (paper 001)",
    "replay": "rebuild tracks.csv, the floor plan and a plan video from a shared map",
    "map": "a shared map on Redis: status, fusion, reset",
    "serve": "a floor-plan view in the browser: a finished run (worldtrack serve out/) or the live map",
}
_COMMANDS = tuple(COMMANDS)


def build_parser(verb: str | None = None) -> argparse.ArgumentParser:
    """The command line's parser; with ``verb``, only that verb's module is imported and registered
    (the others are listed by name and help line), so ``--help`` needs no heavy import."""
    parser = argparse.ArgumentParser(
        prog="worldtrack",
        description="Track people in world coordinates (metres on the floor) from calibrated cameras.")
    parser.add_argument("--version", action="version", version=f"worldtrack {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="<command>")
    for name, line in COMMANDS.items():
        if verb is not None and name != verb:
            sub.add_parser(name, help=line, add_help=False)
            continue
        try:
            module = importlib.import_module(f"worldtrack.cli.{name}")
        except ModuleNotFoundError as e:
            if e.name == f"worldtrack.cli.{name}":
                continue  # verb not built yet
            raise
        module.register(sub)
    return parser


def _verb(argv: list[str]) -> str:
    """The verb named on the command line ('' when none: only the listing is built)."""
    first = next((a for a in argv if not a.startswith("-")), "")
    return first if first in COMMANDS else ""


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit status (0 ok, 2 bad input, 130 interrupted, 143
    terminated, 141 when standard output is a closed pipe)."""
    args_in = sys.argv[1:] if argv is None else list(argv)
    if "--verbose" not in args_in:
        # FFmpeg (inside OpenCV) prints every damaged packet; read before cv2 opens a video.
        os.environ.setdefault("OPENCV_FFMPEG_LOGLEVEL", "-8")
    install_terminate_handler()
    try:
        parser = build_parser(_verb(args_in))
        args = parser.parse_args(args_in)
        args.command_line = ["worldtrack", *args_in]
        if not getattr(args, "func", None):
            parser.print_help()
            return 2
        status = int(args.func(args) or 0)
        sys.stdout.flush()          # a reader that went away (| head) is met here, not at exit
        swallowed = received_signal(forget=True)     # raised where a library dropped it: still honoured
        if swallowed is not None and status == 0:
            print("terminated" if swallowed == 15 else "interrupted", file=sys.stderr)
            return 128 + swallowed
        return status
    except InputError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except BrokenPipeError:
        _silence_stdout()
        return 141
    except BaseException as e:
        interrupt = interrupt_in(e)
        if interrupt is None:
            raise
        print("terminated" if signal_of(interrupt) == 15 else "interrupted", file=sys.stderr)
        return exit_status(interrupt)


def _silence_stdout() -> None:
    """Point standard output at /dev/null so the interpreter's last flush does not fail again."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
