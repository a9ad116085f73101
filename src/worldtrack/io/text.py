"""Small helpers for reading the text files users hand to worldtrack.

>>> is_number("1e-3"), is_number("x")
(True, False)
"""

from __future__ import annotations

from pathlib import Path

from worldtrack.errors import InputError


def read_text(path: str | Path, what: str, *, directory: str | None = None) -> str:
    """The file's text (UTF-8, a byte-order mark dropped), or one :class:`InputError` line naming it.

    Parameters
    ----------
    path : str or Path
    what : str
        What the file should hold, for the messages: ``"<path>: not a text file (expected <what>)"``.
    directory : str, optional
        What to say instead of ``what`` when ``path`` is a directory
        (``"<path>: is a directory, expected <directory>"``); default ``what``.

    Raises
    ------
    InputError
        No such file, a directory, not UTF-8 text, or unreadable.
    """
    label = str(path)
    try:
        return Path(path).read_text(encoding="utf-8-sig")
    except FileNotFoundError:
        raise InputError(f"{label}: no such file") from None
    except IsADirectoryError:
        raise InputError(f"{label}: is a directory, expected {what if directory is None else directory}") from None
    except UnicodeDecodeError:
        raise InputError(f"{label}: not a text file (expected {what})") from None
    except OSError as e:
        raise InputError(f"{label}: cannot read ({e.strerror})") from None


def is_number(text: str) -> bool:
    """Whether Python's ``float()`` accepts ``text`` (so ``"nan"``, ``"inf"`` and ``"1_000"`` count)."""
    try:
        float(text)
    except ValueError:
        return False
    return True
