"""Parsers for command-line values the subcommands share: image sizes and positive numbers.

Each raises :class:`~worldtrack.errors.InputError` naming the flag (or where the value came
from), what was expected with an example, and what was given.
"""

from __future__ import annotations

import math
import re

from worldtrack.errors import InputError

_SIZE = re.compile(r"\s*(\d+)\s*[xX×,]\s*(\d+)\s*")


def parse_size(text: str, flag: str, example: str) -> tuple[int, int]:
    """``"WxH"`` (also ``W×H``, ``W,H``; spaces allowed) → ``(W, H)``, both positive pixels.

    >>> parse_size(" 640 x 480", "--image-size", "640x480")
    (640, 480)
    """
    m = _SIZE.fullmatch(text)
    if not m or min(int(m.group(1)), int(m.group(2))) <= 0:
        raise InputError(f"{flag}: expected WxH in pixels such as {example}, got {text!r}")
    return int(m.group(1)), int(m.group(2))


def positive(text: str, flag: str, example: str) -> float:
    """A finite number > 0.

    >>> positive("0.625", "--scale", "0.625")
    0.625
    """
    try:
        value = float(text)
    except ValueError:
        value = float("nan")
    if not (math.isfinite(value) and value > 0):
        raise InputError(f"{flag}: expected a positive number such as {example}, got {text!r}")
    return value


def positive_int(text: str, flag: str, example: str) -> int:
    """A whole number > 0.

    >>> positive_int("25", "--max-bad-frames", "25")
    25
    """
    try:
        value = int(text)
    except (TypeError, ValueError):
        value = 0
    if value <= 0:
        raise InputError(f"{flag}: expected a whole number > 0 such as {example}, got {text!r}")
    return value
