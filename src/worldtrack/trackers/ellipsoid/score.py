"""Eq. 5 of paper 000: how well a candidate's simulated image matches the real one.

The simulated image of a candidate is the union ("joint image") of every person's visible
ellipse: 1 inside, −1 in a ring of ``ring_px`` pixels around it, 0 elsewhere (:mod:`.forms`). The
real image is the same ternary coding of the foreground mask (:mod:`.real`). The score is::

    E = Σ sim(x, y)·real(x, y) / Σ |sim(x, y)|        (eq. 5; sums where sim ≠ 0)

Differences from the paper, all to make it faster or well-defined:

* Only the pixels a candidate can touch are summed: the union of the candidates' bounding boxes
  (ring included), on a grid of stride ``s`` chosen so that about ``target_pixels`` pixels are
  visited however large the person appears (``target_pixels = 0``: every pixel, as published).
* A pixel hidden by an obstacle nearer than the person (floor distance, the paper's §3.3) is 0 for
  that person in both the ellipse and its ring: occluded pixels carry no evidence either way.
* With lens distortion each real pixel is tested at its undistorted position (exact silhouette).

Optionally (``count_unexplained``, worldtrack's default in tracking mode) foreground pixels of the
region that no simulated person covers are added to the denominator. Eq. 5 alone measures only
how much of the simulation is right, not how much of the foreground it explains: an ellipse that
drifts away along the viewing direction, shrinking into the upper body while the feet are left
unexplained, loses little. With the extra term the score is a Jaccard-like overlap of the two
ternary images and such drift costs.

:func:`score_candidates` is the compiled kernel, :func:`score_candidates_reference` the plain
NumPy version (whole-frame masks drawn from :mod:`worldtrack.geometry.quadric`) it is tested
against; :func:`score_camera` draws candidates and scores them in one call.

>>> import numpy as np
>>> from worldtrack.geometry.camera import Camera
>>> from worldtrack.trackers.ellipsoid.args import DrawArgs, People, ScoreArgs, camera_args
>>> from worldtrack.trackers.ellipsoid.forms import ellipse_crop, person_forms
>>> cam = camera_args(Camera.look_at("c", 160, 120, [0.0, -4.0, 2.6], [0.0, 0.0, 0.8], hfov_deg=60.0), 5.0)
>>> draw, person = DrawArgs(0.1, 0.0), np.array([[0.0, 0.0]])
>>> f = person_forms(cam, person, np.array([1.65]), np.array([0.4]), draw)
>>> real = np.zeros((120, 160), np.int8)
>>> u0, u1, v0, v1 = f.box[0]
>>> real[v0:v1, u0:u1] = ellipse_crop(f.inner[0], f.box[0], cam.grid, False)
>>> cand = person + np.array([[0.0, 0.0], [0.3, 0.0]])
>>> num, den, *_ = score_camera(cam, real, cand, np.full(2, 1.65), np.full(2, 0.4), draw, f, 0,
...                             ScoreArgs(False, 0, False))
>>> (num / den).round(2).tolist()        # capture mode (no ring): the right place scores 1
[1.0, 0.14]
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from worldtrack.geometry import quadric
from worldtrack.trackers.ellipsoid.args import DrawArgs, Forms, People, ScoreArgs, Sums, Window, camera_args
from worldtrack.trackers.ellipsoid.forms import ellipse_forms
from worldtrack.trackers.ellipsoid.pixels import pixels_by_rows, pixels_distorted


@njit(cache=True)
def sample_region(cand, shape, target_pixels):
    """The region :func:`score_candidates` samples for candidates ``cand`` (Forms, C) in an image of
    ``shape`` (H, W): the union of their boxes ``u0, u1, v0, v1`` (empty: u0 ≥ u1 or v0 ≥ v1) and
    the stride that visits about ``target_pixels`` pixels of it (1 when ``target_pixels`` is 0)."""
    c_box, c_valid = cand.box, cand.valid
    H, W = shape
    u0, u1, v0, v1 = W, 0, H, 0
    for c in range(cand.inner.shape[0]):
        if c_valid[c] and c_box[c, 0] < c_box[c, 1] and c_box[c, 2] < c_box[c, 3]:
            u0 = min(u0, c_box[c, 0])
            u1 = max(u1, c_box[c, 1])
            v0 = min(v0, c_box[c, 2])
            v1 = max(v1, c_box[c, 3])
    stride = 1
    if target_pixels > 0 and u0 < u1 and v0 < v1:
        stride = max(1, int(math.sqrt((u1 - u0) * (v1 - v0) / target_pixels)))
    return u0, u1, v0, v1, stride


@njit(cache=True)
def score_candidates(cam, real, cand, others, opts):
    """Numerators and denominators of E for C candidates of one person in one camera.

    Parameters
    ----------
    cam : CameraArgs — ``grid``, ``has_dist`` and ``occ`` are read
    real : (H, W) int8 — ternary real image (1 foreground, −1 ring, 0 else)
    cand : Forms — the candidates' ellipses and floor distances (C,)
    others : Forms — the other people's (M,), those with ``valid`` False left out
    opts : ScoreArgs — ``use_ring`` (False in capture mode: no −1 in either image),
        ``target_pixels`` (visit about this many pixels, 0 = all), ``count_unexplained`` (also add
        to the denominator the foreground pixels no simulated person covers: worldtrack's
        symmetric score, see the module notes)

    Returns
    -------
    num, den : (C,) float64 — E = num / den where den > 0
    n_in : (C,) int64 — visited pixels inside the candidate's own visible ellipse
    """
    o_box, o_valid = others.box, others.valid
    C = cand.inner.shape[0]
    M = others.inner.shape[0]
    sums = Sums(np.zeros(C), np.zeros(C), np.zeros(C, dtype=np.int64))
    u0, u1, v0, v1, stride = sample_region(cand, real.shape, opts.target_pixels)
    if u0 >= u1 or v0 >= v1:
        return sums.num, sums.den, sums.n_in
    # Others whose ring box overlaps the region.
    near = np.empty(M, dtype=np.int64)
    n_near = 0
    for m in range(M):
        if (o_valid[m] and o_box[m, 0] < u1 and o_box[m, 1] > u0
                and o_box[m, 2] < v1 and o_box[m, 3] > v0):
            near[n_near] = m
            n_near += 1
    # Align the sampling grid to absolute coordinates so that every candidate sees the same pixels.
    window = Window(v0 + (-v0) % stride, v1, u0 + (-u0) % stride, u1, stride)
    if cam.has_dist:
        pixels_distorted(cam, real, cand, others, near[:n_near], window, opts, sums)
    else:
        pixels_by_rows(cam.occ, real, cand, others, near[:n_near], window, opts, sums)
    return sums.num, sums.den, sums.n_in


@njit(cache=True)
def score_camera(cam, real, cand_xy, heights, widths, draw, others, skip, opts):
    """:func:`~.forms.ellipse_forms` of the candidates then :func:`score_candidates`, in one call.

    Parameters
    ----------
    cam : CameraArgs
    real : (H, W) int8 — this camera's ternary real image
    cand_xy : (C, 2) — candidate floor positions, m; heights, widths : (C,) m
    draw : DrawArgs
    others : Forms — everybody (the person being moved included, at index ``skip``, which is left
        out of the joint image; −1 for none)
    skip : int
    opts : ScoreArgs

    Returns
    -------
    num, den : (C,) and the candidates' forms ``inner, ring, box, valid`` and floor distances, so
    the caller can keep the chosen one.
    """
    ci, cr, cb, cv = ellipse_forms(cam, cand_xy, heights, widths, draw)
    n = cand_xy.shape[0]
    cd = np.empty(n)
    for i in range(n):
        cd[i] = math.hypot(cand_xy[i, 0] - cam.centre[0], cand_xy[i, 1] - cam.centre[1])
    ov = others.valid.copy()
    if skip >= 0:
        ov[skip] = False
    num, den, _ = score_candidates(cam, real, Forms(ci, cr, cb, cv, cd),
                                   Forms(others.inner, others.ring, others.box, ov, others.dist), opts)
    return num, den, ci, cr, cb, cv, cd


def score_candidates_reference(camera, real: np.ndarray, cand: People, others: People, ring_px: float,
                               opts: ScoreArgs, draw: DrawArgs, occ: np.ndarray | None = None
                               ) -> tuple[np.ndarray, np.ndarray]:
    """Plain NumPy version of :func:`~.forms.ellipse_forms` + :func:`score_candidates` for tests.

    Renders each candidate's joint ternary image over the whole frame from
    :func:`worldtrack.geometry.quadric.ellipsoid_conics` and sums eq. 5 on the same pixel grid.

    Parameters
    ----------
    camera : Camera
    real : (H, W) int8
    cand, others : People — candidates (C) and the other people (M); heights and widths may be
        scalars
    ring_px : float
    opts : ScoreArgs; draw : DrawArgs
    occ : (H, W) float, optional — obstacle floor distances (default none)

    Returns
    -------
    num, den : (C,) float64
    """
    H, W = real.shape
    occ = np.full((H, W), np.inf) if occ is None else occ
    cand_xy = np.asarray(cand.xy, float).reshape(-1, 2)
    c_in, c_rg = _reference_masks(camera, occ, cand, ring_px, draw)
    o_in, o_rg = _reference_masks(camera, occ, others, ring_px, draw)
    other_in = np.zeros((H, W), bool)
    other_rg = np.zeros((H, W), bool)
    for a, b in zip(o_in, o_rg):
        other_in |= a
        other_rg |= b
    # The sampled region: union of the candidates' boxes, from the optimised kernel's forms.
    n = len(c_in)
    _, _, box, valid = ellipse_forms(camera_args(camera, ring_px), cand_xy,
                                     np.broadcast_to(np.asarray(cand.heights, float), (n,)).copy(),
                                     np.broadcast_to(np.asarray(cand.widths, float), (n,)).copy(), draw)
    sel = valid & (box[:, 0] < box[:, 1]) & (box[:, 2] < box[:, 3])
    num = np.zeros(n)
    den = np.zeros(n)
    if not sel.any():
        return num, den
    u0, u1 = box[sel, 0].min(), box[sel, 1].max()
    v0, v1 = box[sel, 2].min(), box[sel, 3].max()
    target = opts.target_pixels
    stride = 1 if target <= 0 else max(1, int(np.sqrt((u1 - u0) * (v1 - v0) / target)))
    vv = np.arange(v0 + (-v0) % stride, v1, stride)
    uu = np.arange(u0 + (-u0) % stride, u1, stride)
    R = real[np.ix_(vv, uu)].astype(float)
    if not opts.use_ring:
        R = np.maximum(R, 0)
    for c in range(n):
        if not valid[c]:
            continue
        within = (c_in[c] | other_in)[np.ix_(vv, uu)]
        ring = ((c_rg[c] | other_rg) if opts.use_ring else np.zeros((H, W), bool))[np.ix_(vv, uu)] & ~within
        sim = within.astype(float) - ring.astype(float)
        num[c] = (sim * R).sum()
        den[c] = np.abs(sim).sum()
        if opts.count_unexplained:
            den[c] += ((sim == 0) & (R > 0)).sum()
    return num, den


def _reference_masks(camera, occ: np.ndarray, people: People, ring_px: float,
                     draw: DrawArgs) -> tuple[list[np.ndarray], list[np.ndarray]]:
    """Full-image (H, W) bool masks of each person's ellipse and ring ellipse, pixels hidden by
    nearer obstacles removed: the reference's drawing, from the quadric module's conics."""
    P, H, W = camera.P, camera.height, camera.width
    pxy = np.asarray(people.xy, float).reshape(-1, 2)
    cen, rad = quadric.person_ellipsoid(pxy, people.heights, people.widths)
    ctr, axes, ang = quadric.ellipse_parameters(quadric.ellipsoid_conics(P, cen, rad))
    dist = np.hypot(pxy[:, 0] - camera.centre[0], pxy[:, 1] - camera.centre[1])
    depth_c = cen @ P[2, :3] + P[2, 3]
    ext = np.sqrt((rad[:, 0] * P[2, 0]) ** 2 + (rad[:, 1] * P[2, 1]) ** 2 + (rad[:, 2] * P[2, 2]) ** 2)
    ok = (depth_c - ext >= draw.min_depth) & np.isfinite(axes).all(axis=1)
    if camera.has_distortion:
        grid = camera.ideal_pixel_grid
        u, v = grid[..., 0].astype(float), grid[..., 1].astype(float)
    else:
        v, u = np.mgrid[0:H, 0:W].astype(float)
    ins, rng = [], []
    for k in range(len(ctr)):
        if not ok[k]:
            ins.append(np.zeros((H, W), bool))
            rng.append(np.zeros((H, W), bool))
            continue
        du, dv = u - ctr[k, 0], v - ctr[k, 1]
        ca, sa = np.cos(ang[k]), np.sin(ang[k])
        p1 = du * ca + dv * sa
        p2 = -du * sa + dv * ca
        vis = occ >= dist[k]
        r = min(ring_px, max(1.0, draw.ring_fraction * axes[k, 1])) if draw.ring_fraction > 0 else ring_px
        ins.append(vis & ((p1 / axes[k, 0]) ** 2 + (p2 / axes[k, 1]) ** 2 < 1))
        rng.append(vis & ((p1 / (axes[k, 0] + r)) ** 2 + (p2 / (axes[k, 1] + r)) ** 2 < 1))
    return ins, rng


__all__ = ["sample_region", "score_camera", "score_candidates", "score_candidates_reference"]
