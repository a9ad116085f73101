"""The ``worldtrack`` command: one entry point, one sub-command per verb.

Each verb lives in its own module of this package with a ``register(subparsers)`` function that
adds its parser and sets ``func`` to the function that runs it. A user's mistake (an
:class:`~worldtrack.errors.InputError`) prints one line, ``error: …``, and exits with status 2.
"""

from __future__ import annotations

import argparse
import importlib
import sys

from worldtrack import __version__
from worldtrack.errors import InputError

# Verb modules, in the order ``worldtrack --help`` lists them.
_COMMANDS = ("demo", "scene", "calibrate", "synth", "track", "smooth", "pose", "eval", "background", "gt", "follow")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="worldtrack",
        description="Track people in world coordinates (metres on the floor) from calibrated cameras.")
    parser.add_argument("--version", action="version", version=f"worldtrack {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="<command>")
    for name in _COMMANDS:
        try:
            module = importlib.import_module(f"worldtrack.cli.{name}")
        except ModuleNotFoundError as e:
            if e.name == f"worldtrack.cli.{name}":
                continue  # verb not built yet
            raise
        module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command line; returns the exit status (0 ok, 2 bad input, 130 interrupted)."""
    parser = build_parser()
    args = parser.parse_args(argv)
    args.command_line = ["worldtrack", *(sys.argv[1:] if argv is None else argv)]
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except InputError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
