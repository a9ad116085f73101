"""Columns whose lower part is hidden (behind a nearer object, below the image's edge), and the
pixel weights of their samples.

* :func:`order_statistic` — per filter, the number of lowest samples hidden that a share of its
  columns reach (``k_lo``, read next frame by ``common_view``, ``pixel_weights="hidden"`` and the
  coasting of the motion model);
* :func:`inverse_lengths` — the pixel-weight scale of ``pixel_weights="filter"``: 1 / the image
  length of a body sample of the column at each filter's centre.

Each has a NumPy reference (tested equal).

>>> order_statistic(np.array([[5, 1, 3, 3, 0]], dtype=np.int32), 2).tolist()
[3]
"""

from __future__ import annotations

import functools
import math

import numpy as np
from numba import njit


def order_statistic(x: np.ndarray, rank: int) -> np.ndarray:
    """(F,) the value of rank ``rank`` (0-based, ascending) in each row of ``x`` (F, N) of small
    non-negative integers: ``np.partition(x, rank, axis=1)[:, rank]`` by counting (tested equal)."""
    x = np.ascontiguousarray(x)
    out = np.empty(len(x), dtype=x.dtype)
    if not 0 <= rank < x.shape[1] or not _order_statistic(x, int(rank), out):
        return np.partition(x, rank, axis=1)[:, rank]         # (other values, or rank out of range: its error)
    return out


@njit(cache=True)
def _order_statistic(x, rank, out):
    """False (``out`` not filled) if some value is negative or above 4096."""
    for f in range(x.shape[0]):
        top = 0
        for v in x[f]:
            if v < 0 or v > 4096:
                return False
            top = max(top, v)
        counts = np.zeros(top + 1, dtype=np.int64)
        for v in x[f]:
            counts[v] += 1
        seen = 0
        for v in range(top + 1):
            seen += counts[v]
            if seen > rank:
                out[f] = v
                break
    return True


@functools.lru_cache(maxsize=16)
def quantile_rank(n: int, q: float) -> int:
    """The 0-based rank of the order statistic that ``np.quantile(x, q, method="higher")`` returns
    for ``n`` values (so ``np.partition`` can pick it without the quantile machinery)."""
    return int(np.quantile(np.arange(n), q, method="higher"))


@njit(cache=True)
def inverse_lengths(uv: np.ndarray, steps: int, out: np.ndarray) -> None:
    """``out`` (F,), in place: 1 / (the image length from ``uv[0, f]`` to ``uv[1, f]`` (pixels) over
    ``steps``), 0 where that is not finite and positive — :func:`inverse_lengths_reference`'s
    arithmetic (the pixel scale of ``pixel_weights="filter"``)."""
    for f in range(uv.shape[1]):
        length = math.hypot(uv[1, f, 0] - uv[0, f, 0], uv[1, f, 1] - uv[0, f, 1]) / steps
        out[f] = 1.0 / length if math.isfinite(length) and length > 0 else 0.0


def inverse_lengths_reference(uv: np.ndarray, steps: int) -> np.ndarray:
    """:func:`inverse_lengths` in NumPy (the tracker's former code)."""
    length = np.hypot(*(uv[1] - uv[0]).T) / steps
    ok = np.isfinite(length) & (length > 0)
    return np.where(ok, 1.0 / np.where(ok, length, 1.0), 0.0)


__all__ = ["inverse_lengths", "inverse_lengths_reference", "order_statistic", "quantile_rank"]
