"""The target's colour templates (seed 001 §2.4): long-term and short-term, and when to update them.

* **Long-term** — registered when following starts, with the white balance of that frame. The
  paper's rule refreshes it: every ``update_every`` frames, if α ≥ α_th (the light has changed a
  lot) and the target's D is small (position alone is sure of it), the template becomes the
  target's current histogram and the white balance is registered again (|W| restarts from 0).
* **Short-term** (worldtrack) — an exponential average of the target's recent histograms, time
  constant ``short_term_tau`` seconds, updated only on frames where the target is sure: its D is
  small and nobody else stands within ``clear_radius`` (whose pixels could leak into its
  silhouette). It follows slow changes of the light (backlight, shade) that the long-term one
  does not; a wrong person cannot train it in the moment of a crossing.

RBhat against the templates is the smaller of the two distances; |W| is counted from the white
balance registered with the short-term template when there is one (it moves with it), else with
the long-term one.

>>> import numpy as np
>>> tpl = Templates(np.array([1.0, 0.0]), (512, 512), short_term_tau=2.0)
>>> tpl.learn(np.array([0.0, 1.0]), (600, 512), dt=2.0)       # one time constant
>>> np.round(tpl.short, 2).tolist(), round(tpl.registered_wb[0])
([0.37, 0.63], 568)
"""

from __future__ import annotations

import numpy as np

from worldtrack.follow.colour import bhattacharyya


class Templates:
    """The target's templates; ``hist`` (B,) sums to 1, white balances are (r, b) gain steps."""

    def __init__(self, hist: np.ndarray, wb: tuple[float, float], short_term_tau: float = 0.0):
        self.long = np.asarray(hist, dtype=np.float64).copy()
        self.long_wb = (float(wb[0]), float(wb[1]))
        self.tau = float(short_term_tau)
        self.short: np.ndarray | None = None
        self.short_wb = self.long_wb
        self.frames_since_check = 0
        if self.tau > 0:
            self.short = self.long.copy()

    @property
    def registered_wb(self) -> tuple[float, float]:
        """The white balance |W| is counted from."""
        return self.short_wb if self.short is not None else self.long_wb

    def rbhat(self, hists: np.ndarray) -> np.ndarray:
        """(N,) eq. 1 distance of each histogram (N, B) to the nearer template."""
        tpl = self.long[None] if self.short is None else np.stack([self.long, self.short])
        return bhattacharyya(hists, tpl).min(axis=1)

    def learn(self, hist: np.ndarray, wb: tuple[float, float], dt: float) -> None:
        """Blend ``hist`` into the short-term template with weight ``1 − exp(−dt/τ)``."""
        if self.short is None or hist.sum() <= 0:
            return
        w = 1.0 - np.exp(-max(dt, 0.0) / self.tau)
        self.short = (1 - w) * self.short + w * np.asarray(hist, dtype=np.float64)
        self.short /= max(self.short.sum(), 1e-12)
        self.short_wb = tuple((1 - w) * a + w * float(b) for a, b in zip(self.short_wb, wb))

    def paper_update(self, hist: np.ndarray | None, wb: tuple[float, float], alpha: float, d: float,
                     alpha_th: float, max_d: float, every: int) -> bool:
        """The paper's rule, called once per frame; True when the long-term template was refreshed."""
        self.frames_since_check += 1
        if self.frames_since_check < every:
            return False
        self.frames_since_check = 0
        if hist is None or hist.sum() <= 0 or alpha < alpha_th or d >= max_d:
            return False
        self.long = np.asarray(hist, dtype=np.float64).copy()
        self.long_wb = (float(wb[0]), float(wb[1]))
        if self.short is not None:
            self.short, self.short_wb = self.long.copy(), self.long_wb
        return True
