"""The ``worldtrack`` program's entry point (``[project.scripts]``).

Ctrl-C while the command line is still being imported ends the program as Ctrl-C does later on:
``interrupted`` on standard error and exit status 130, not a traceback. Nothing is written before
:func:`worldtrack.cli.main` runs, so there is nothing to flush. This module and ``worldtrack``'s
``__init__`` import next to nothing, so the moments left uncovered are the interpreter's own start.
"""

import sys


def run() -> None:
    """Import the command line and run it; exit with its status (``worldtrack …`` on a shell)."""
    try:
        from worldtrack.cli import main
    except KeyboardInterrupt:
        print("interrupted", file=sys.stderr)
        sys.exit(130)
    sys.exit(main())


if __name__ == "__main__":  # pragma: no cover
    run()
