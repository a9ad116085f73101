"""The ``worldtrack`` program's entry point (``[project.scripts]``).

Ctrl-C while the command line is still being imported ends the program as Ctrl-C does later on:
``interrupted`` on standard error and exit status 130, not a traceback; SIGTERM there ends it with
``terminated`` and 143 (Python's default would end it silently with status -15). Nothing is
written before :func:`worldtrack.cli.main` runs, so there is nothing to flush. This module and
``worldtrack``'s ``__init__`` import next to nothing, so the moments left uncovered are the
interpreter's own start.
"""

import sys


class _TerminatedWhileImporting(KeyboardInterrupt):
    """SIGTERM before :func:`worldtrack.cli.main` installs its own handlers."""


def _raise_terminated(signum, frame) -> None:
    raise _TerminatedWhileImporting()


def run() -> None:
    """Import the command line and run it; exit with its status (``worldtrack …`` on a shell)."""
    import signal

    signal.signal(signal.SIGTERM, _raise_terminated)     # main() puts its own handlers in at once
    try:
        from worldtrack.cli import main
    except KeyboardInterrupt as interrupt:
        terminated = isinstance(interrupt, _TerminatedWhileImporting)
        print("terminated" if terminated else "interrupted", file=sys.stderr)
        sys.exit(143 if terminated else 130)
    sys.exit(main())


if __name__ == "__main__":  # pragma: no cover
    run()
