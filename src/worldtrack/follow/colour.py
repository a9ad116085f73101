"""Colour model (seed 001 §2.4, eq. 1): hue–saturation histograms, the Bhattacharyya distance, and
undoing the camera's white balance before either (von Kries).

**Gains.** A camera multiplies raw R and B by ``r_gain/512`` and ``b_gain/512`` (integer gains
0…1023, 512 = ×1, as the Bumblebee2 of the paper reports them). Dividing them out again gives the
raw image, whatever the white balance did — a diagonal (von Kries) correction with known factors.
Raw colour still carries the light's colour (sun vs. skylight), so ``gains+greyworld`` then balances
it by the grey world of the *background* (every pixel that is not a candidate, neither dark nor
saturated): ``r' = 512·Ḡ/R̄``, ``b' = 512·Ḡ/B̄`` — what an automatic white balance does, measured
every frame instead of jumping now and then. Those gains, in the camera's own steps, are also the
remaining illumination change that α reads (eq. 3).

**Histogram.** OpenCV HSV (hue 0–179, saturation and value 0–255). ``hue_bins × sat_bins`` bins
over (H, S); with ``grey_bins > 0`` pixels too dark or too grey for their hue to mean anything go
to ``grey_bins`` extra bins by value instead (the paper's plain HS histogram has none). Each
histogram sums to 1.

**Distance** (eq. 1): ``RBhat = sqrt(1 − Σ sqrt(H_in·H_tpl))``, which is what
``cv2.compareHist(a, b, cv2.HISTCMP_BHATTACHARYYA)`` returns for histograms that sum to 1.
:func:`bhattacharyya` computes it for all candidate–template pairs at once;
:func:`bhattacharyya_reference` calls OpenCV pair by pair (the tests check they agree).

>>> import numpy as np
>>> from worldtrack.follow.config import FollowConfig
>>> img = np.zeros((4, 4, 3), np.uint8); img[:, :2] = (0, 0, 200); img[:, 2:] = (200, 0, 0)
>>> labels = np.array([[1, 1, 2, 2]] * 4, np.int32)
>>> h = histograms(img, labels, 2, FollowConfig())
>>> round(float(bhattacharyya(h, h[:1])[1, 0]), 3)        # red vs blue: nothing in common
1.0
"""

from __future__ import annotations

import cv2
import numpy as np

from worldtrack.follow.config import FollowConfig

WB_UNITY = 512.0


def gain_lut(factors_bgr: np.ndarray) -> np.ndarray:
    """(1, 256, 3) uint8 look-up table multiplying each channel by its factor (rounded, clipped)."""
    ramp = np.arange(256, dtype=np.float64)[:, None] * np.asarray(factors_bgr, dtype=np.float64)[None, :]
    return np.clip(np.rint(ramp), 0, 255).astype(np.uint8)[None]


def undo_gains(image: np.ndarray, gains_rb: tuple[float, float]) -> np.ndarray:
    """The raw image: B divided by ``b/512``, R by ``r/512`` (``gains_rb`` = (r, b), 0…1023).

    >>> px = np.array([[[100, 50, 200]]], np.uint8)
    >>> undo_gains(px, (1024, 256))[0, 0].tolist()           # R was doubled, B halved
    [200, 50, 100]
    """
    r, b = (max(float(g), 1.0) for g in gains_rb)
    return cv2.LUT(image, gain_lut(np.array([WB_UNITY / b, 1.0, WB_UNITY / r])))


def grey_world_gains(raw: np.ndarray, exclude: np.ndarray | None = None, step: int = 4) -> tuple[float, float]:
    """(r, b) gains in camera steps that make the mean of the usable background grey.

    ``raw`` (H, W, 3) uint8 BGR; ``exclude`` (H, W) bool marks pixels not to use (people).
    Every ``step``-th pixel both ways; dark (≤ 8) and saturated (≥ 250) ones left out.
    """
    sub = raw[::step, ::step].reshape(-1, 3).astype(np.float64)
    ok = np.all((sub > 8) & (sub < 250), axis=1)
    if exclude is not None:
        ok &= ~exclude[::step, ::step].ravel()
    if ok.sum() < 50:
        return WB_UNITY, WB_UNITY
    b, g, r = sub[ok].mean(axis=0)
    return float(np.clip(WB_UNITY * g / max(r, 1e-3), 0, 1023)), float(np.clip(WB_UNITY * g / max(b, 1e-3), 0, 1023))


def normalise_colour(image: np.ndarray, gains_rb: tuple[float, float] | None, mode: str,
                     people: np.ndarray | None = None) -> tuple[np.ndarray, tuple[float, float]]:
    """Apply the colour normalisation ``mode`` (see :data:`~worldtrack.follow.config.NORMALISATIONS`).

    Returns the image the histograms are taken from and the white balance (r, b) that α reads:
    the camera's gains for ``none`` and ``gains``, the grey world's for ``gains+greyworld``.
    Without known gains (``None``) the image is taken as raw.
    """
    cam = gains_rb if gains_rb is not None else (WB_UNITY, WB_UNITY)
    if mode == "none":
        return image, cam
    raw = undo_gains(image, cam) if gains_rb is not None else image
    if mode == "gains":
        return raw, cam
    r, b = grey_world_gains(raw, people)
    balanced = cv2.LUT(raw, gain_lut(np.array([b / WB_UNITY, 1.0, r / WB_UNITY])))
    return balanced, (r, b)


def bin_index(image: np.ndarray, config: FollowConfig) -> np.ndarray:
    """Histogram bin (int32) of every pixel of the BGR ``image`` (..., 3) — an image or a list of pixels."""
    pixels = np.ascontiguousarray(image, dtype=np.uint8).reshape(-1, 1, 3)
    hsv = cv2.cvtColor(pixels, cv2.COLOR_BGR2HSV).reshape(image.shape)
    h = hsv[..., 0].astype(np.int32)
    s = hsv[..., 1].astype(np.int32)
    v = hsv[..., 2].astype(np.int32)
    idx = (h * config.hue_bins // 180) * config.sat_bins + (s * config.sat_bins // 256)
    if config.grey_bins > 0:
        grey = (s < config.achromatic_sat) | (v < config.achromatic_val)
        grey_idx = config.hue_bins * config.sat_bins + v * config.grey_bins // 256
        idx = np.where(grey, grey_idx, idx)
    return idx


def n_bins(config: FollowConfig) -> int:
    """Length of one histogram."""
    return config.hue_bins * config.sat_bins + config.grey_bins


def histograms(image: np.ndarray, labels: np.ndarray, n: int, config: FollowConfig) -> np.ndarray:
    """(n, B) float32 histograms, each summing to 1 (zeros for an empty silhouette).

    ``labels`` (H, W) int32: 0 background, i + 1 a pixel of candidate i (see
    :func:`worldtrack.follow.silhouette.silhouettes`).
    """
    B = n_bins(config)
    if n == 0:
        return np.zeros((0, B), np.float32)
    flat = labels.ravel()
    px = np.flatnonzero(flat)
    bins = bin_index(image.reshape(-1, 3)[px], config)             # only the silhouettes' pixels
    counts = np.bincount((flat[px] - 1).astype(np.int64) * B + bins, minlength=n * B)[:n * B].reshape(n, B)
    total = counts.sum(axis=1, keepdims=True)
    return (counts / np.maximum(total, 1)).astype(np.float32)


def bhattacharyya(hists: np.ndarray, templates: np.ndarray) -> np.ndarray:
    """(N, T) RBhat of eq. 1 between every histogram (N, B) and template (T, B), each summing to 1.

    An empty histogram (all zeros) is 1 from everything.
    """
    bc = np.sqrt(np.maximum(hists, 0)).astype(np.float64) @ np.sqrt(np.maximum(templates, 0)).astype(np.float64).T
    return np.sqrt(np.clip(1.0 - bc, 0.0, 1.0))


def bhattacharyya_reference(hists: np.ndarray, templates: np.ndarray) -> np.ndarray:
    """:func:`bhattacharyya` by ``cv2.compareHist(…, HISTCMP_BHATTACHARYYA)``, pair by pair."""
    out = np.ones((len(hists), len(templates)))
    for i, h in enumerate(hists):
        for j, t in enumerate(templates):
            if h.sum() > 0 and t.sum() > 0:
                out[i, j] = cv2.compareHist(np.ascontiguousarray(h, np.float32), np.ascontiguousarray(t, np.float32),
                                            cv2.HISTCMP_BHATTACHARYYA)
    return out
