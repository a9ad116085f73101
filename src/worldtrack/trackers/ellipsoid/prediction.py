"""Where each tracked person is predicted before matching: constant velocity, with the part along
a lone camera's line of sight optionally damped.

Paper 000 moves each person from their last place; worldtrack first predicts them at constant
velocity (``match.predict``), the velocity smoothed from the matching's own moves
(:meth:`~.life.LifeCycle._update_velocity`). With one camera showing a person, the match places
them worst along that camera's line of sight (the ellipse slides along it inside a crowd's
merged silhouette and E hardly changes, :mod:`.uncertainty`). Such a slide is then read as a
velocity, and the prediction carries the track on along the ray the next frame, and the next:
in the one-camera crowd of 50 (``benchmarks/crowd50.py``) a track started on its person had
slid a median 0.3 m along the ray after 1 s and 0.55 m after 1.5 s, against 0.05 m across it.

``crowd.predict_along_ray`` (default 1: the full velocity, as before) is the share of the
velocity's component along the line of sight that the prediction uses when exactly one of the
tracker's cameras showed the person last (the only one it has, or the only one of several);
the component across the ray, which one camera measures well, is kept in full. A person several
cameras show is predicted with the full velocity: another camera measures their depth. The
velocity itself is not changed (it is also what the reported velocity filter starts from).

It is for dense crowds only: on PETS 2009 (one camera, a handful of people who walk along its
rays for seconds) the setting at 0 loses MOTA 0.927 -> 0.804 (also 0.824 when only people whose
image box meets another's are damped): there the match follows a walker along the ray only with
the prediction's help.

``crowd.predict_along_ray_measured`` (default off) damps by whether depth was observed instead
of by a fixed share: the prediction keeps the share of the velocity that was measured while a
camera saw the person's feet (:mod:`.ground_contact`, :class:`MeasuredShare`) — a walker seen
whole keeps their velocity into a brief crossing; a velocity built from slides inside a merged
crowd is dropped. Crowd 50, dev seeds 110–112: from the true places 9.7 -> 15.3 of 50 held (MOTA
0.390 -> 0.486), cold 9.0 -> 12.3 (0.353 -> 0.409); held-out 113–118: 13.0 -> 17.5 (0.431 ->
0.492), cold 7.3 -> 10.3 (0.330 -> 0.389), about what the share 0 gives there (17.0, 10.7). PETS
2009 over 8 start frames: MOTA 0.926 -> 0.917, IDF1 0.830 -> 0.816 (the share 0: 0.801 over 3):
off by default. Tried on the same seeds: "clear" as own_share >= 0.5
instead of the feet (crowd 16.3 / 10.3 held, PETS 0.895), and only nearer people hiding the feet
(obstacles and the image's edge not counted: crowd 11.3 / 10.7, PETS 0.901). (The score's
own curvature along the ray, the reported σ, does not tell the two apart: it is as flat on PETS
as in the crowd, median 0.41 against 0.43 1/m², both below its floor.)

>>> import numpy as np
>>> from worldtrack.geometry.camera import Camera
>>> cam = Camera.look_at("c", 160, 120, [0.0, -4.0, 2.6], [0.0, 0.0, 0.8], hfov_deg=60.0)
>>> xy, v = np.array([[0.0, 0.0]]), np.array([[0.5, 1.0]])      # walking across and away
>>> lone = np.array([True])
>>> predicted_places(xy, v, 0.1, [cam], np.array([0]), lone, 0.0).round(3).tolist()
[[0.05, 0.0]]
>>> predicted_places(xy, v, 0.1, [cam], np.array([0]), lone, 1.0).round(3).tolist()
[[0.05, 0.1]]
"""

from __future__ import annotations

import weakref
from typing import Mapping, Sequence

import numpy as np

from worldtrack.geometry.camera import Camera
from worldtrack.trackers.base import Person
from worldtrack.trackers.ellipsoid.cameras import CameraView
from worldtrack.trackers.ellipsoid.ground_contact import feet_in_view


def predicted_places(xy: np.ndarray, velocity: np.ndarray, dt: float, cameras: Sequence[Camera],
                     camera_of: np.ndarray, lone: np.ndarray, along_share: float | np.ndarray) -> np.ndarray:
    """Constant-velocity places after ``dt`` s, the velocity's part along a lone camera's ray scaled.

    Parameters
    ----------
    xy : (N, 2) float — floor positions, m
    velocity : (N, 2) float — floor velocities, m/s
    dt : float — time since the last frame, s
    cameras : the tracker's cameras
    camera_of : (N,) int — index into ``cameras`` of the camera that showed each person last
        (read only where ``lone``)
    lone : (N,) bool — exactly one camera showed the person: their depth rests on it alone
    along_share : float or (N,) float — share of the velocity along that camera's ray kept (0..1),
        for everyone or per person (:class:`MeasuredShare`)

    Returns
    -------
    (N, 2) float — the predicted floor positions, m
    """
    xy = np.asarray(xy, float).reshape(-1, 2)
    v = np.array(velocity, float).reshape(-1, 2)
    share = np.broadcast_to(np.asarray(along_share, float), (len(xy),))
    damped = np.asarray(lone, bool) & (share != 1.0)
    if damped.any():
        for c, cam in enumerate(cameras):
            rows = np.flatnonzero(damped & (camera_of == c))
            if rows.size:
                ray = cam.floor_rays(xy[rows], min_distance=0.3)[0]
                along = np.sum(v[rows] * ray, axis=1, keepdims=True)
                v[rows] -= (1.0 - share[rows, None]) * along * ray
    return xy + dt * v


class MeasuredShare:
    """Per person, the share of their velocity that was measured while their depth was observed.

    The tracker's velocity is an exponential average of the frame-to-frame moves, each weighed
    ``smoothing`` (a) and decaying by 1 − a a frame (:meth:`~.life.LifeCycle._update_velocity`).
    Its part along a lone camera's line of sight is only as good as the depths those moves were
    measured from (:func:`depth_observed`): with the feet in view one camera has the depth; a
    person placed by a merged blob slides along the ray, and the slide is no walk. The share kept
    here is the same average of that yes / no: 1 for a person observed in every recent frame,
    ``(1 − a)ⁿ`` n frames into a cover, back towards 1 as soon as they are observed again. The
    prediction keeps that share of the velocity along the ray (``crowd.predict_along_ray_measured``),
    so a walker seen whole keeps their velocity into a brief crossing, while a velocity made of
    slides inside a crowd is dropped.

    >>> from worldtrack.trackers.base import Person
    >>> p = Person(1, 0.0, 0.0, mode="tracking")
    >>> m = MeasuredShare(0.5)
    >>> m.update([p], 0.1, np.array([False])); m.update([p], 0.2, np.array([False]))
    >>> m.shares([p]).tolist()
    [0.25]
    >>> m.update([p], 0.3, np.array([True])); m.shares([p]).tolist()
    [0.625]
    """

    def __init__(self, smoothing: float, hold: bool = False, alone_share: float | None = None) -> None:
        self.smoothing = float(np.clip(smoothing, 0.0, 1.0))
        self.hold = bool(hold)
        self.alone_share = alone_share
        self._share: "weakref.WeakKeyDictionary[Person, float]" = weakref.WeakKeyDictionary()
        self._velocity: "weakref.WeakKeyDictionary[Person, np.ndarray]" = weakref.WeakKeyDictionary()

    @classmethod
    def from_config(cls, config) -> "MeasuredShare":
        """The tracker's: smoothed as its velocity (``match.velocity_smoothing``), ``hold`` from
        ``crowd.hold_along_ray_unobserved``, and with ``crowd.alone_behind_obstacles`` an
        ``alone_share`` of 1 − ``support.min_own_share`` (see :func:`depth_observed`)."""
        alone = 1.0 - config.support.min_own_share if config.crowd.alone_behind_obstacles else None
        return cls(config.match.velocity_smoothing, config.crowd.hold_along_ray_unobserved, alone)

    def update(self, people: Sequence[Person], t: float, observed: np.ndarray, rays: np.ndarray | None = None) -> None:
        """Count this frame (time ``t`` s, once) for each tracked person of ``people``, whose depth
        was ``observed`` (N,) bool or not (call after the life cycle has moved the velocity). With
        ``hold`` (``crowd.hold_along_ray_unobserved``), a person whose depth was not observed gets
        back their velocity's part along ``rays`` (N, 2) — their lone camera's line of sight, NaN
        where several cameras show them — from before this frame: a slide is not read as a walk,
        and the prediction carries the walk measured before the cover, damped by the share."""
        a = self.smoothing
        for k, (p, seen) in enumerate(zip(people, np.asarray(observed, bool))):
            if not (p.mode == "tracking" and p.once("measured_share", t)):
                continue
            before = self._velocity.get(p)
            if self.hold and not seen and rays is not None and before is not None and np.isfinite(rays[k]).all():
                v = np.array([p.vx, p.vy])
                p.vx, p.vy = (float(c) for c in v + ((before - v) @ rays[k]) * rays[k])
            self._velocity[p] = np.array([p.vx, p.vy])
            self._share[p] = (1.0 - a) * self._share.get(p, 1.0) + a * bool(seen)

    def observe(self, people: Sequence[Person], everyone: Sequence[Person], views: Mapping[str, CameraView],
                labelled: Sequence[str], t: float) -> None:
        """:meth:`update` with each of ``people``'s depth judged by :func:`depth_observed` in the
        cameras ``labelled`` (ids of ``views`` with an image this frame) among ``everyone`` on the
        map, and, with ``hold``, their lone camera's rays (:func:`lone_rays`)."""
        cids = list(views)
        rays = lone_rays(people, [v.camera for v in views.values()], cids) if self.hold else None
        self.update(people, t, depth_observed(people, everyone, [views[c] for c in labelled], t, self.alone_share),
                    rays)

    def shares(self, people: Sequence[Person]) -> np.ndarray:
        """(N,) float in [0, 1] — each person's measured share (1 for one not counted yet)."""
        return np.array([self._share.get(p, 1.0) for p in people], dtype=float).reshape(-1)


def depth_observed(people: Sequence[Person], others: Sequence[Person], views: Sequence[CameraView],
                   t: float, alone_share: float | None = None) -> np.ndarray:
    """(N,) bool — whether a camera observed each of ``people``'s depth at time ``t`` (s): it showed
    them then and some camera of ``views`` sees their feet, in its image, in front of obstacles and
    of everybody nearer among ``people`` and ``others`` (:func:`.ground_contact.feet_in_view`).

    With ``alone_share`` (``crowd.alone_behind_obstacles``), obstacles do not hide the feet of a
    person at least this share of whose pixels nobody else covers (``Person.own_share``): behind a
    sign or a pillar but alone, their match has no neighbour's silhouette to slide into (PETS 2009:
    a walker passing behind the sign lost the prediction within 3 frames and the track)."""
    seen = np.array([p.seen_now(t) for p in people], dtype=bool).reshape(-1)
    mine = {id(p) for p in people}
    everyone = list(people) + [q for q in others if id(q) not in mine]
    xy = np.array([[q.x, q.y] for q in everyone], dtype=float).reshape(-1, 2)
    hs = np.array([q.height for q in everyone], dtype=float)
    ws = np.array([q.width for q in everyone], dtype=float)
    feet = np.zeros(len(people), dtype=bool)
    for view in views:
        feet |= feet_in_view(view, xy, hs, ws)[:len(people)]
    if alone_share is not None:
        own = np.array([p.own_share for p in people], dtype=float).reshape(-1)
        alone = np.nan_to_num(own, nan=0.0) >= alone_share
        for view in views:
            feet |= alone & feet_in_view(view, xy, hs, ws, obstacles=False)[:len(people)]
    return seen & feet


def lone_rays(people: Sequence[Person], cameras: Sequence[Camera], camera_ids: Sequence[str]) -> np.ndarray:
    """(N, 2) — unit floor direction of the line of sight of the one camera of ``cameras`` (ids
    ``camera_ids``) that showed each person (:func:`lone_camera`); NaN where none or several did."""
    out = np.full((len(people), 2), np.nan)
    for k, p in enumerate(people):
        c = lone_camera(p.seen_by, camera_ids)
        if c >= 0:
            out[k] = cameras[c].floor_rays(np.array([p.x, p.y]), min_distance=0.3)[0]
    return out


def lone_camera(seen_by: Sequence[str], camera_ids: Sequence[str]) -> int:
    """Index in ``camera_ids`` of the one camera of this tracker in ``seen_by``; −1 when none or
    several of them showed the person (a tracker with one camera: that camera once it has).

    >>> lone_camera(("c1",), ["c1", "c2"]), lone_camera(("c1", "c2"), ["c1", "c2"]), lone_camera((), ["c1"])
    (0, -1, 0)
    """
    if len(camera_ids) == 1:
        return 0
    mine = [camera_ids.index(c) for c in seen_by if c in camera_ids]
    return mine[0] if len(mine) == 1 else -1


__all__ = ["MeasuredShare", "depth_observed", "lone_camera", "lone_rays", "predicted_places"]
