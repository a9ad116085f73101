"""The ``worldtrack`` program's entry point (``[project.scripts]``).

Ctrl-C while the command line is still being imported ends the program as Ctrl-C does later on:
``interrupted`` on standard error and exit status 130, not a traceback; SIGTERM there ends it with
``terminated`` and 143 (Python's default would end it silently with status -15). Nothing is
written before :func:`worldtrack.cli.main` runs, so there is nothing to flush. This module and
``worldtrack``'s ``__init__`` import next to nothing, so the moments left uncovered are the
interpreter's own start.

An interrupted run (130, 143) ends without the interpreter's finalisation, once standard output and
error are flushed: every output was closed by ``main`` already, and finalising while a native
library's thread is still inside a call has aborted the program (``make test``: exit -6, "Fatal
Python error: PyEval_RestoreThread … Python runtime state: finalizing", once in ~40 signalled
start-ups under load).
"""

import os
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
        _exit(143 if terminated else 130)
    _exit(main())


def _exit(status: int) -> None:
    """Exit with ``status``; after an interrupt (130 or 143) without finalising the interpreter."""
    if status in (130, 143):
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):       # a closed pipe or stream: nothing more to say on it
                pass
        os._exit(status)
    sys.exit(status)


if __name__ == "__main__":  # pragma: no cover
    run()
