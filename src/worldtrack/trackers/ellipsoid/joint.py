"""The joint simulated image of one frame: everybody's ellipses in every camera, one person moved.

Paper 000 §5: with several people, all are rendered into one simulated image (a nearer person
hides a farther one) and each is moved in turn with the others fixed — 9·N evaluations instead of
9^N. :class:`JointImage` holds the people's floor positions and their ellipses in every camera
for one frame, scores candidate places of one person against the ternary real images with eq. 5
summed over the cameras (:meth:`JointImage.score`), and moves a person to a chosen candidate
(:meth:`JointImage.move`). The matching rounds (:mod:`.match`) and the searches (:mod:`.search`)
work on it.

With several cameras a candidate's E is Σ num / Σ den over the cameras; for a tracked person each
camera is weighed as at the person's current place (``held``, :func:`.match.held_scores`), so a
candidate cannot gain by sliding out of the view of a camera that fits the person badly. With
``score.fixed_pixels`` each camera's denominator also counts the pixels counted at the current
place (:mod:`.fixed_pixels`), so neither can it gain by shrinking its sliver past a nearer person.
"""

from __future__ import annotations

from typing import Callable, Mapping

import numpy as np

from worldtrack.trackers.ellipsoid.args import Forms, People, ScoreArgs, Scoring, Walkable
from worldtrack.trackers.ellipsoid.cameras import CameraView, ray_direction
from worldtrack.trackers.ellipsoid.fixed_pixels import dropped_pixels
from worldtrack.trackers.ellipsoid.match import held_scores
from worldtrack.trackers.ellipsoid.score import score_camera


class JointImage:
    """Everybody's ellipses in every camera for one frame, and eq. 5 for one person's candidates.

    Parameters
    ----------
    views : {camera_id: CameraView} — the cameras with a real image this frame
    real : {camera_id: (H, W) int8} — their ternary real images
    people : People — floor positions (N, 2) m (a copy is kept and updated), heights, widths (N,)
    settings : Scoring
    walkable : callable — (M, 2) floor points → (M,) bool
    walk : Walkable — the same floor as a raster, for the compiled rounds
    """

    def __init__(self, views: Mapping[str, CameraView], real: Mapping[str, np.ndarray], people: People,
                 settings: Scoring, walkable: Callable[[np.ndarray], np.ndarray], walk: Walkable):
        self.cids = list(real)
        self.views = {cid: views[cid] for cid in self.cids}
        self.real = {cid: real[cid] for cid in self.cids}
        xy = np.array(people.xy, dtype=float).reshape(-1, 2)
        self.people = People(xy, np.asarray(people.heights, float), np.asarray(people.widths, float))
        self.settings = settings
        self.walkable = walkable
        self.walk = walk
        #: Forms stacked over the cameras (C, N, …), as the compiled rounds take them.
        self.stacked = Forms(*(np.stack(a) for a in zip(*(self.views[c].forms(*self.people) for c in self.cids))))
        #: Per camera, views into the stacked arrays: updates through either are shared.
        self.state = {cid: Forms(*(a[c] for a in self.stacked)) for c, cid in enumerate(self.cids)}

    @property
    def xy(self) -> np.ndarray:
        """(N, 2) floor positions, metres (updated as people move)."""
        return self.people.xy

    def score(self, k: int, cand: np.ndarray, use_ring: bool,
              current: int | None = None) -> tuple[np.ndarray, np.ndarray, dict[str, Forms]]:
        """E (J,), denominators (J,) and per-camera forms of J candidate places ``cand`` (J, 2) of
        person ``k`` (their size), everybody else fixed in the joint image.

        E is Σ num / Σ den over the cameras (−inf where no camera shows the candidate); with
        ``current`` (the index of the candidate that is the person's place now) and ``held``
        settings, each camera is weighed as it is there (:func:`.match.held_scores`).
        """
        s = self.settings
        num, den, forms = self.camera_sums(k, cand, use_ring)
        if current is not None and s.held and len(self.cids) > 1:
            total = den.sum(axis=0)
            if s.fixed_pixels:
                den = den + self._dropped(k, forms, current, use_ring)
            return held_scores(num, den, current), total, forms  # (one camera: the same)
        num, den = num.sum(axis=0), den.sum(axis=0)
        with np.errstate(invalid="ignore", divide="ignore"):
            e = np.where(den > 0, num / np.maximum(den, 1e-12), -np.inf)
        return e, den, forms

    def camera_sums(self, k: int, cand: np.ndarray, use_ring: bool) -> tuple[np.ndarray, np.ndarray, dict[str, Forms]]:
        """Each camera's Σ sim·real and Σ|sim| (C, J) for J candidate places ``cand`` (J, 2) of
        person ``k``, everybody else fixed, and the candidates' per-camera forms."""
        s = self.settings
        n = len(cand)
        heights, widths = np.full(n, self.people.heights[k]), np.full(n, self.people.widths[k])
        num = np.zeros((len(self.cids), n))
        den = np.zeros((len(self.cids), n))
        forms = {}
        opts = ScoreArgs(use_ring, int(s.target_pixels), use_ring and s.symmetric)
        for i, cid in enumerate(self.cids):
            num[i], den[i], ci, cr, cb, cv, cd = score_camera(self.views[cid].args, self.real[cid], cand, heights,
                                                              widths, s.draw, self.state[cid], k, opts)
            forms[cid] = Forms(ci, cr, cb, cv, cd)
        return num, den, forms

    def _dropped(self, k: int, forms: Mapping[str, Forms], current: int, use_ring: bool) -> np.ndarray:
        """(C, J): per camera, the pixels candidate ``current`` of ``forms`` counts and each
        candidate does not (:func:`.fixed_pixels.dropped_pixels`), everybody else fixed."""
        s = self.settings
        opts = ScoreArgs(use_ring, int(s.target_pixels), use_ring and s.symmetric)
        out = []
        for cid in self.cids:
            st = self.state[cid]
            valid = st.valid.copy()
            valid[k] = False
            out.append(dropped_pixels(self.views[cid].args, self.real[cid], forms[cid], st._replace(valid=valid),
                                      current, opts))
        return np.array(out)

    def move(self, k: int, place: np.ndarray, forms: Mapping[str, Forms], b: int) -> None:
        """Person ``k`` moves to ``place`` (2,), candidate ``b`` of ``forms`` (from :meth:`score`)."""
        self.people.xy[k] = place
        for cid, f in forms.items():
            for dst, src in zip(self.state[cid], f):
                dst[k] = src[b]

    def axes(self, k: int, along_ray: bool = False) -> tuple[np.ndarray, np.ndarray]:
        """Floor axes for person ``k``: the viewing direction of the camera that sees the person
        largest (the paper's), and its normal.

        With ``along_ray`` the direction is that of the camera's ray through the person's
        position projected on the floor — the direction along which one camera cannot tell
        depth — falling back to the optical axis for a person right below the camera.
        """
        best_cam, best_area = self.cids[0], -1
        for cid, st in self.state.items():
            box = st.box[k]
            area = max(0, box[1] - box[0]) * max(0, box[3] - box[2]) if st.valid[k] else 0
            if area > best_area:
                best_cam, best_area = cid, area
        cam = self.views[best_cam].camera
        d = ray_direction(cam, self.xy[k]) if along_ray else cam.floor_direction
        return d, np.array([-d[1], d[0]])

    def ray_directions(self, k: int) -> list[np.ndarray]:
        """Unit floor directions of the rays from each camera that sees person ``k`` through its
        position (the camera's optical axis for a person right below it); one direction at least."""
        out = [ray_direction(self.views[cid].camera, self.xy[k]) for cid, st in self.state.items() if st.valid[k]]
        return out or [self.axes(k, along_ray=True)[0]]


__all__ = ["JointImage"]
