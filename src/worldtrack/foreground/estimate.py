"""An empty-scene background image estimated from frames that contain people (``worldtrack background``).

Three methods (:func:`estimate_background`): a two-pass temporal median that drops people standing
still for up to half the samples, a histogram mode for people who stand still longer, and OpenCV
MOG2's background image.
"""

from __future__ import annotations

import cv2
import numpy as np

from worldtrack.errors import InputError

BACKGROUND_METHODS = ("median", "mode", "adaptive")


def estimate_background(frames, method: str = "median", threshold: float = 30.0,
                        dilate_px: int = 2) -> np.ndarray:
    """Background image from frames that contain people, robust to people standing still.

    A plain temporal median fails where someone stands still for a large part of the sample:
    their samples crowd the background's and pull the median onto them (or between the two).
    The methods:

    ``"median"`` (two-pass median, the default)
        1. ``B₀`` = per-pixel temporal median of the samples.
        2. In every sample, mark as foreground the pixels whose colour is more than
           ``threshold`` (largest channel difference, grey levels) from ``B₀``, grown by
           ``dilate_px`` so the soft edges of people go too.
        3. ``B`` = per-pixel median of the samples not marked (``B₀`` where none is left).

        A person standing still for up to about half the samples is removed: pass 1 still lands
        on the background (or on its edge), pass 2 drops their samples. It also removes the
        faint trails that passers-by leave in a plain median.
    ``"mode"`` (histogram mode)
        Per pixel, the most frequent grey level — the bin of 8 levels whose window of three
        bins (±12 levels) holds the most samples — then the median colour of the samples in that
        window. Keeps working when
        someone stands still for *more* than half the samples, as long as the background is
        still the single most frequent appearance of that pixel; less precise than the median
        where the background itself varies (shadows, noise spread over several bins).
    ``"adaptive"``
        OpenCV MOG2 run over the samples in order; its ``getBackgroundImage()``.

    Parameters
    ----------
    frames : sequence of (H, W, 3) uint8 images
        A sample spread over the video (e.g. 50 to 100 frames), BGR.
    method : {"median", "mode", "adaptive"}
    threshold : float
        ``"median"``: foreground threshold of pass 2, grey levels (0–255).
    dilate_px : int
        ``"median"``: radius by which the pass-2 foreground grows, pixels.

    Returns
    -------
    (H, W, 3) uint8

    Raises
    ------
    InputError
        No frames, frames of different sizes or not colour, or an unknown method.
    """
    frames = list(frames)
    if not frames:
        raise InputError("background estimate: no frames")
    shapes = {np.shape(f) for f in frames}
    if len(shapes) > 1:
        raise InputError(f"background estimate: frames of different sizes {sorted(shapes)}")
    stack = np.stack(frames)
    if stack.ndim != 4 or stack.shape[-1] != 3 or stack.dtype != np.uint8:
        raise InputError(f"background estimate: expected (H, W, 3) uint8 colour frames, got shape "
                         f"{stack.shape[1:]} {stack.dtype}")
    if method not in BACKGROUND_METHODS:
        raise InputError(f"background estimate: unknown method {method!r} (expected "
                         f"{', '.join(BACKGROUND_METHODS)})")
    if method == "adaptive":
        return _mog2_background(stack)
    everything = np.ones(stack.shape[:3], dtype=bool)
    first = _masked_median(stack, everything, fallback=None)           # B₀, (H, W, 3)
    if method == "median":
        far = np.abs(stack.astype(np.int16) - first.astype(np.int16)).max(axis=3) > threshold
        if dilate_px > 0:
            kernel = cv2.getStructuringElement(cv2.MORPH_ELLIPSE, (2 * dilate_px + 1, 2 * dilate_px + 1))
            far = np.stack([cv2.dilate(m.astype(np.uint8), kernel) for m in far]).astype(bool)
        keep = ~far
    else:
        keep = _mode_members(stack)
    return _masked_median(stack, keep, fallback=first)


def _masked_median(stack: np.ndarray, keep: np.ndarray, fallback: np.ndarray | None) -> np.ndarray:
    """Per-pixel median over the samples with ``keep`` (N, H, W); ``fallback`` where none.

    Vectorised: dropped samples become 256 so a sort puts them last; the median of the
    ``n`` kept ones is then the mean of sorted entries ``(n − 1) // 2`` and ``n // 2``.
    """
    values = np.where(keep[..., None], stack.astype(np.uint16), np.uint16(256))
    values.sort(axis=0)
    n = keep.sum(axis=0)                                               # (H, W)
    lo = np.clip((n - 1) // 2, 0, None)[None, :, :, None]
    hi = np.clip(n // 2, 0, None)[None, :, :, None]
    shape = (1,) + values.shape[1:]
    med = (np.take_along_axis(values, np.broadcast_to(lo, shape), 0)[0].astype(np.float64)
           + np.take_along_axis(values, np.broadcast_to(hi, shape), 0)[0]) / 2.0
    if fallback is not None:
        med = np.where((n > 0)[..., None], med, fallback)
    return np.clip(np.round(med), 0, 255).astype(np.uint8)


def _mode_members(stack: np.ndarray, bin_width: int = 8, tolerance: float = 12.0) -> np.ndarray:
    """(N, H, W) bool: samples whose grey level lies near the pixel's most frequent grey level."""
    grey = np.stack([cv2.cvtColor(f, cv2.COLOR_BGR2GRAY) for f in stack])   # (N, H, W)
    n_bins = 256 // bin_width
    N, H, W = grey.shape
    bins = (grey // bin_width).astype(np.int64)                       # (N, H, W)
    flat = bins.reshape(N, -1) * (H * W) + np.arange(H * W)[None, :]
    counts = np.bincount(flat.ravel(), minlength=n_bins * H * W).reshape(n_bins, H, W).astype(np.float32)
    window = counts.copy()                                             # samples within ±1 bin
    window[1:] += counts[:-1]
    window[:-1] += counts[1:]
    mode = np.argmax(window, axis=0)                                   # (H, W) bin index
    centre = (mode + 0.5) * bin_width
    return np.abs(grey - centre[None]) <= tolerance


def _mog2_background(stack: np.ndarray) -> np.ndarray:
    model = cv2.createBackgroundSubtractorMOG2(history=max(len(stack), 2), detectShadows=False)
    for image in stack:
        model.apply(image)
    bg = model.getBackgroundImage()
    if bg is None:
        raise InputError("background estimate: MOG2 returned no background image")
    return bg
