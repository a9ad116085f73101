"""Columns whose lower part is hidden (behind a nearer object, below the image's edge).

The column kernel reports how many of each column's lowest samples are hidden; per filter,
:func:`order_statistic` picks the number that a share of its columns reach (``k_lo``, read next
frame by ``common_view``, ``pixel_weights="hidden"`` and the coasting of the motion model) — the
value ``np.quantile(..., method="higher")`` picks, by counting (tested equal to ``np.partition``).

>>> order_statistic(np.array([[5, 1, 3, 3, 0]], dtype=np.int32), 2).tolist()
[3]
"""

from __future__ import annotations

import functools

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


__all__ = ["order_statistic", "quantile_rank"]
