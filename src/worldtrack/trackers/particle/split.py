"""Splitting a particle cloud in two (worldtrack's answer to seed 004's open problem, §6: objects that
enter together and then part).

:func:`bimodal_split` — is a particle cloud two objects side by side? Its projection on the
principal axis must have two peaks with a deep valley between them, and each side enough of the
particles. :func:`splittable` is its cheap first test, for many clouds at once. The compiled parts
(:func:`_valley`, :func:`_sides`, :func:`_covariance_axes`) have NumPy references (tested equal).

>>> rng = np.random.default_rng(0)
>>> two = np.vstack([rng.normal([0, 0], 0.06, (250, 2)), rng.normal([0.6, 0], 0.06, (250, 2))])
>>> side = bimodal_split(two, 0.35, 0.5, 0.2)
>>> side is not None and 230 <= int(side.sum()) <= 270
True
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING, Mapping, Sequence

import numpy as np
from numba import njit

from worldtrack.trackers.base import Person
from worldtrack.trackers.lifecycle import counts_for, frames_for
from worldtrack.trackers.particle.cloud import Cloud, CloudStack
from worldtrack.trackers.particle.likelihood.boxes import overlap
from worldtrack.trackers.particle.likelihood.camera import CameraLikelihood
from worldtrack.trackers.particle.region import cloud_mean

if TYPE_CHECKING:
    from worldtrack.trackers.particle.config import ParticleConfig


class Splitter:
    """Which clouds are two objects: split tracking filters, and the lumps a detection filter fires on.

    Parameters
    ----------
    cfg : ParticleConfig — its ``split`` section, and ``merge.overlap`` (lumps whose boxes overlap
        more are one object seen along a line of sight)
    person_size : (height, width) metres — the scene's person
    cameras : {camera_id: CameraLikelihood}
    """

    def __init__(self, cfg: "ParticleConfig", person_size: tuple[float, float],
                 cameras: Mapping[str, CameraLikelihood]):
        s = cfg.split
        self.distance, self.dip, self.min_mass, self.after_s = s.distance_m, s.dip, s.min_mass, s.after_s
        self.overlap = cfg.merge.overlap
        self.height, self.width = person_size
        self.cameras = cameras

    def two_objects(self, xy: np.ndarray, principal: tuple | None = None) -> np.ndarray | None:
        """Which side of a two-lump cloud ``xy`` (N, 2) each particle is on, or None for one object.

        Two lumps (:func:`bimodal_split`) are two objects only if the cameras can tell them apart:
        their image boxes must overlap less than ``merge.overlap`` in some camera that sees both
        (lumps one behind the other on a single camera's line of sight are the depth ambiguity of one
        object, not two objects). ``principal``: the cloud's row of :func:`splittable`'s, if at hand.
        """
        side = bimodal_split(xy, self.distance, self.dip, self.min_mass, principal=principal)
        if side is None:
            return None
        lumps = np.array([xy[~side].mean(axis=0), xy[side].mean(axis=0)])
        for cl in self.cameras.values():
            p, q = cl.boxes(lumps, self.width, self.height, 0.0)
            if p is not None and q is not None and overlap(p, q) < self.overlap:
                return side
        return None

    def lumps(self, xyz: np.ndarray, idx: np.ndarray, depth: int = 2) -> list[np.ndarray]:
        """Split particle indices ``idx`` into lumps on the floor, recursively (up to 2^depth)."""
        side = self.two_objects(xyz[idx, :2])
        if side is None or depth == 0:
            return [idx]
        return self.lumps(xyz, idx[~side], depth - 1) + self.lumps(xyz, idx[side], depth - 1)

    def due(self, clouds: Sequence[Cloud], persons: Sequence[Person], stack: CloudStack, t: float,
            dt: float) -> list[tuple[Cloud, np.ndarray]]:
        """The tracking filters to split now, with their sides: those whose particles have been two
        lumps for ``after_s`` seconds (counted on the person, frame interval ``dt``). The cheap first
        test of the two-lump check (:func:`splittable`) runs for all of them at once."""
        if not clouds:
            return []
        wide, principal = splittable(stack.stacked(clouds, "xyz")[:, :, :2], self.distance, self.min_mass,
                                     principal=True)
        need = frames_for(self.after_s, dt)
        out = []
        for c, p, w, pc in zip(clouds, persons, wide.tolist(), principal):
            side = self.two_objects(c.xyz[:, :2], pc) if w else None
            if counts_for(p, "split", t, side is not None) >= need:
                p.reset("split", t)
                out.append((c, side))
        return out


def bimodal_split(xy: np.ndarray, min_separation: float, max_dip: float, min_mass: float,
                  bin_m: float = 0.04, smooth_m: float = 0.05,
                  principal: tuple | None = None) -> np.ndarray | None:
    """Split a floor cloud of particles into two objects side by side, if it is two.

    The cloud is projected on its principal axis; the projection's histogram (``bin_m`` bins,
    Gaussian smoothing ``smooth_m``) must have two peaks at least ``min_separation`` apart whose
    valley is at most ``max_dip`` times the lower peak, and each side of the valley must hold at
    least ``min_mass`` of the particles.

    Parameters
    ----------
    xy : (N, 2) float, metres — equally weighted particles
    min_separation : float, metres
    max_dip : float in (0, 1)
    min_mass : float in (0, 0.5)
    principal : tuple, optional — this cloud's row of :func:`splittable`'s ``principal`` (the
        centred cloud and its covariance, computed for many clouds at once), not to compute it again

    Returns
    -------
    (N,) bool or None
        Which side of the valley each particle is on; ``None`` for a single object.
    """
    xy = np.asarray(xy, dtype=float)
    if len(xy) < 8:
        return None
    if principal is None:
        c, (sxx, syy, sxy, lam) = _principal(xy[None])
        principal = c[0], float(sxx[0]), float(syy[0]), float(sxy[0]), float(lam[0])
    c, sxx, syy, sxy, lam = principal
    # _wide_enough of one float: the same IEEE operations (max keeps NaN and −0.0 as np.maximum does).
    if not math.sqrt(max(lam, 0.0)) >= min_separation * math.sqrt(min_mass * (1 - min_mass)):
        return None
    # The principal axis: the eigenvector of the covariance's largest eigenvalue.
    axis = np.array([sxy, lam - sxx]) if abs(sxy) > 1e-15 else (np.array([1.0, 0.0]) if sxx >= syy
                                                                   else np.array([0.0, 1.0]))
    axis /= np.linalg.norm(axis)
    s = c @ axis
    side = np.empty(len(s), dtype=np.bool_)
    return side if _sides(s, s.min(), bin_m, smooth_m, min_separation, max_dip, min_mass, side) else None


@njit(cache=True)
def _sides(s, lo, bin_m, smooth_m, min_separation, max_dip, min_mass, side):
    """The end of :func:`bimodal_split` in one call: ``side = s > lo + (valley + 0.5)·bin_m`` (in
    place) and True if :func:`_valley` finds a valley and each side holds at least ``min_mass`` of the
    particles (``side.mean()``, as a count over N)."""
    valley = _valley(s, lo, bin_m, smooth_m, min_separation, max_dip)
    if valley < 0:
        return False
    cut = lo + (valley + 0.5) * bin_m
    n = 0
    for i in range(s.shape[0]):
        side[i] = s[i] > cut
        n += side[i]
    m = n / s.shape[0]
    return not min(m, 1 - m) < min_mass


@njit(cache=True)
def _valley(s: np.ndarray, lo: float, bin_m: float, smooth_m: float, min_separation: float,
            max_dip: float) -> int:
    """The valley bin between the two peaks of the smoothed histogram of ``s`` (N,) metres, from
    ``lo`` in ``bin_m`` bins; −1 if there are no two peaks ``min_separation`` apart with a valley at
    most ``max_dip`` times the lower. The compiled kernel of :func:`bimodal_split` (the NumPy calls
    on these ~20-bin arrays cost more than the work); :func:`_valley_reference` is the same in NumPy."""
    nb = int(math.ceil((s.max() - lo) / bin_m)) + 1
    h = np.zeros(nb)
    for v in s:
        h[min(int((v - lo) / bin_m), nb - 1)] += 1.0
    r = max(1, int(math.ceil(3 * smooth_m / bin_m)))
    kernel = np.empty(2 * r + 1)
    for k in range(2 * r + 1):
        kernel[k] = math.exp(-0.5 * (((k - r) * bin_m) / smooth_m) ** 2)
    hs = np.zeros(nb)
    for i in range(nb):                      # np.convolve(np.pad(h, r), kernel, "valid")
        acc = 0.0
        for k in range(2 * r + 1):
            j = i + r - k
            if 0 <= j < nb:
                acc += h[j] * kernel[k]
        hs[i] = acc
    peaks = np.empty(nb, np.int64)
    n_peaks, p1 = 0, -1
    for i in range(nb):
        left = hs[i - 1] if i > 0 else -1.0
        right = hs[i + 1] if i < nb - 1 else -1.0
        if hs[i] >= left and hs[i] > right and hs[i] > 0:
            peaks[n_peaks] = i
            n_peaks += 1
            if p1 < 0 or hs[i] > hs[p1]:
                p1 = i
    if n_peaks < 2:
        return -1
    p2 = -1
    for i in peaks[:n_peaks]:
        if abs(i - p1) * bin_m >= min_separation and (p2 < 0 or hs[i] > hs[p2]):
            p2 = i
    if p2 < 0:
        return -1
    a, b = min(p1, p2), max(p1, p2)
    valley = a
    for i in range(a, b + 1):
        if hs[i] < hs[valley]:
            valley = i
    if hs[valley] > max_dip * min(hs[p1], hs[p2]):
        return -1
    return valley


def _valley_reference(s: np.ndarray, lo: float, bin_m: float, smooth_m: float, min_separation: float,
                      max_dip: float) -> int:
    """:func:`_valley` in NumPy."""
    nb = int(np.ceil((s.max() - lo) / bin_m)) + 1
    h = np.bincount(np.minimum(((s - lo) / bin_m).astype(np.int64), nb - 1), minlength=nb).astype(float)
    r = max(1, int(np.ceil(3 * smooth_m / bin_m)))
    kx = np.arange(-r, r + 1) * bin_m
    kernel = np.exp(-0.5 * (kx / smooth_m) ** 2)
    hs = np.convolve(np.pad(h, r), kernel, mode="valid")
    left = np.concatenate([[-1.0], hs[:-1]])
    right = np.concatenate([hs[1:], [-1.0]])
    peaks = np.flatnonzero((hs >= left) & (hs > right) & (hs > 0))
    if len(peaks) < 2:
        return -1
    p1 = peaks[np.argmax(hs[peaks])]
    far = peaks[np.abs(peaks - p1) * bin_m >= min_separation]
    if len(far) == 0:
        return -1
    p2 = far[np.argmax(hs[far])]
    a, b = min(p1, p2), max(p1, p2)
    valley = a + int(np.argmin(hs[a:b + 1]))
    if hs[valley] > max_dip * min(hs[p1], hs[p2]):
        return -1
    return valley


def _sides_reference(s: np.ndarray, lo: float, bin_m: float, smooth_m: float, min_separation: float,
                     max_dip: float, min_mass: float) -> np.ndarray | None:
    """:func:`_sides` in NumPy (:func:`bimodal_split`'s former end): the sides, or None."""
    valley = _valley_reference(s, lo, bin_m, smooth_m, min_separation, max_dip)
    if valley < 0:
        return None
    side = s > lo + (valley + 0.5) * bin_m
    m = side.mean()
    if min(m, 1 - m) < min_mass:
        return None
    return side


def splittable(xy: np.ndarray, min_separation: float, min_mass: float, principal: bool = False):
    """Which of F clouds :func:`bimodal_split` could split at all: the cheap test it starts with
    (at least 8 particles, wide enough along the principal axis), for many clouds at once.

    Parameters
    ----------
    xy : (F, N, 2) float, metres
    min_separation, min_mass : as in :func:`bimodal_split`
    principal : bool — also return each cloud's centred particles and covariance, for
        :func:`bimodal_split` (the same values as it computes for one cloud: the matrix products
        run per cloud)

    Returns
    -------
    wide : (F,) bool — False: :func:`bimodal_split` returns None for that cloud
    principal : list of F tuples, with ``principal`` — each cloud's ``principal`` argument of
        :func:`bimodal_split` (None for clouds of fewer than 8 particles)
    """
    xy = np.asarray(xy, dtype=float)
    if xy.shape[1] < 8:
        wide, rows = np.zeros(len(xy), dtype=bool), [None] * len(xy)
    else:
        c = xy - cloud_mean(xy)[:, None, :]
        out = np.empty((4, len(xy)))
        wide = np.empty(len(xy), dtype=np.bool_)
        _covariance_axes(c.transpose(0, 2, 1) @ c, xy.shape[1], out, float(min_separation), float(min_mass), wide)
        rows = list(zip(c, *out.tolist())) if principal else None
    return (wide, rows) if principal else wide


def _principal(xy: np.ndarray) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """The clouds ``xy`` (F, N, 2) centred, and per cloud the covariance ``sxx, syy, sxy`` and its
    largest eigenvalue (the variance along the principal axis), each (F,), m²."""
    c = xy - cloud_mean(xy)[:, None, :]
    out = np.empty((4, len(xy)))
    _covariance_axes(c.transpose(0, 2, 1) @ c, xy.shape[1], out, 0.0, 0.0, np.empty(0, dtype=np.bool_))
    return c, (out[0], out[1], out[2], out[3])


@njit(cache=True)
def _covariance_axes(products, n, out, min_separation, min_mass, wide):
    """``out`` (4, F), in place: ``sxx, syy, sxy`` of the (F, 2, 2) sums of products over ``n`` and the
    largest eigenvalue ``(sxx + syy)/2 + hypot((sxx − syy)/2, sxy)`` — :func:`_principal_reference`'s
    arithmetic; and, if ``wide`` is not empty, :func:`_wide_enough` of the eigenvalues into it."""
    limit = min_separation * math.sqrt(min_mass * (1 - min_mass))
    for f in range(products.shape[0]):
        sxx = products[f, 0, 0] / n
        syy = products[f, 1, 1] / n
        sxy = products[f, 0, 1] / n
        out[0, f], out[1, f], out[2, f] = sxx, syy, sxy
        lam = 0.5 * (sxx + syy) + math.hypot(0.5 * (sxx - syy), sxy)
        out[3, f] = lam
        if wide.shape[0]:
            wide[f] = math.sqrt(lam if not lam < 0.0 else 0.0) >= limit


def _principal_reference(xy: np.ndarray) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """:func:`_principal` in NumPy (its former code)."""
    c = xy - cloud_mean(xy)[:, None, :]
    cov = c.transpose(0, 2, 1) @ c / xy.shape[1]
    sxx, syy, sxy = cov[:, 0, 0], cov[:, 1, 1], cov[:, 0, 1]
    return c, (sxx, syy, sxy, 0.5 * (sxx + syy) + np.hypot(0.5 * (sxx - syy), sxy))


def _wide_enough(lam, min_separation: float, min_mass: float):
    """Two lumps d apart holding m and 1 − m of the particles have a std of at least d·sqrt(m(1 − m))
    along the axis joining them: a cloud of principal variance ``lam`` narrower than that cannot be
    split."""
    return np.sqrt(np.maximum(lam, 0.0)) >= min_separation * np.sqrt(min_mass * (1 - min_mass))


__all__ = ["Splitter", "bimodal_split", "splittable"]
