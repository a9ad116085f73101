"""Observing filters: this frame's likelihood of every particle of a set of filters, in one call.

The tracking filters hold equal particle counts, so their particles are read as (F·N,) rows of the
stacked arrays, each with its own filter's box, colours, pixel scale and hidden samples; the
detection filters are concatenated. After the call each filter holds ``logpi, likely, col_h``; a
tracking filter also its ``k_lo``: per camera the number of its columns' lowest samples that were
hidden, as the order statistic a share of its particles reach (read next frame by ``common_view``,
the pixel weights and the coasting of the motion model).
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Sequence

import numpy as np

from worldtrack.trackers.particle.cloud import Cloud, CloudStack
from worldtrack.trackers.particle.likelihood.hidden import order_statistic, quantile_rank
from worldtrack.trackers.particle.likelihood.models import FrameView, Likelihood, Readers
from worldtrack.trackers.particle.likelihood.pixel_weights import PIXEL_WEIGHTS
from worldtrack.trackers.particle.region import cloud_mean

if TYPE_CHECKING:
    from worldtrack.trackers.particle.config import ParticleConfig

_OBSERVED = ("logpi", "likely", "col_h")


class Observer:
    """Reads filters' particles with the tracker's likelihood.

    Parameters
    ----------
    cfg : ParticleConfig
    likelihood : Likelihood — the component chosen by ``likelihood.model``
    stack : CloudStack — the tracking filters' stacked arrays
    """

    def __init__(self, cfg: "ParticleConfig", likelihood: Likelihood, stack: CloudStack):
        lk = cfg.likelihood
        self.likelihood, self.stack = likelihood, stack
        self.pixel_weights = PIXEL_WEIGHTS[lk.pixel_weights if likelihood.ratio else "none"](
            likelihood, cfg.column.foot_samples)
        # Hidden samples are collected for whoever reads them next frame (column likelihoods only).
        self.collect_hidden = likelihood.column and (lk.common_view > 0 or cfg.motion.coast_hidden > 0
                                                     or lk.pixel_weights == "hidden")
        self.cut_hidden = likelihood.ratio and lk.common_view > 0
        self.rank_share = lk.common_view or 0.5

    def tracking(self, clouds: Sequence[Cloud], frame: FrameView, centres: np.ndarray | None = None) -> None:
        """This frame's observation of tracking filters ``clouds`` (equal particle counts), with the top
        edge; ``centres`` (F, 2) their particles' mean floor positions, if already at hand."""
        stack, f = self.stack, len(clouds)
        cameras = list(frame.images)
        scales = self.pixel_weights.scales(
            clouds, lambda: cloud_mean(stack.stacked(clouds, "xyz")[:, :, :2]) if centres is None else centres, cameras)
        hidden = k_lo = None
        if self.collect_hidden:
            hidden = {}
            if self.cut_hidden:
                k_lo = {cid: np.array([c.k_lo.get(cid, 0) for c in clouds], dtype=np.int64) for cid in cameras}
        n = len(clouds[0].xyz)                          # equal particle counts: (F, N) as (F·N,)
        xyz, h = stack.stacked(clouds, "xyz").reshape(-1, 3), stack.stacked(clouds, "h").reshape(-1)
        readers = Readers(stack.which(f, n), np.arange(f), [c.colours for c in clouds], scales, k_lo)
        out = self.likelihood(xyz, h, frame, readers, hidden, top_edge=True)
        if hidden:
            # Next frame's k_lo: the share ``common_view`` of the filter's columns see every sample
            # from there up (np.quantile(..., method="higher") of each row, as the order statistic it picks).
            rank = quantile_rank(n, self.rank_share)
            for cid, hid in hidden.items():
                for c, v in zip(clouds, order_statistic(hid.reshape(f, n), rank).tolist()):
                    c.k_lo[cid] = v
        for name, a in zip(_OBSERVED, out):
            stack.set_rows(clouds, name, a.reshape(f, -1))

    def detection(self, clouds: Sequence[Cloud], frame: FrameView) -> None:
        """This frame's observation of detection filters ``clouds`` (any particle counts)."""
        sizes = [len(c.xyz) for c in clouds]
        xyz, h = np.concatenate([c.xyz for c in clouds]), np.concatenate([c.h for c in clouds])
        readers = Readers(np.repeat(np.arange(len(clouds)), sizes), np.arange(len(clouds)),
                          [c.colours for c in clouds])
        out = self.likelihood(xyz, h, frame, readers)
        ends = np.cumsum(sizes).tolist()
        for name, a in zip(_OBSERVED, out):
            for c, start, end in zip(clouds, [0] + ends, ends):
                setattr(c, name, a[start:end])


__all__ = ["Observer"]
