"""Ground-truth head tracks and per-camera head pixels of a scenario, without rendering.

Seed 002 estimates a head trajectory from the head's pixel in whichever camera sees it. These
functions give, for a synthetic scenario, the exact head point of every person at every frame
(the top of the articulated body's head, gait included) and its pixel in every camera that sees
it — the observations a head detector would make — with optional pixel noise.

>>> from worldtrack.synth import make_scenario
>>> sc = make_scenario("non-overlapping", frames=200, seed=13, people=1)
>>> heads = head_tracks(sc)
>>> heads[1].points.shape
(200, 3)
>>> obs = head_pixels(sc, noise_px=0.0, tracks=heads)
>>> sorted(str(c) for c in set(obs.camera))
['cam2', 'cam4']
>>> seen = obs.camera == "cam2"
>>> bool(np.allclose(sc.scene.cameras["cam2"].project(obs.truth[seen]), obs.uv[seen]))
True
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from worldtrack.synth.sequence import Scenario


@dataclass(frozen=True)
class HeadTrack:
    """One person's head: times (T,) s, points (T, 3) m (head top), present (T,) bool, height m;
    floor (T, 2) m — the person's floor position (midway between the feet: a box's bottom centre)."""

    times: np.ndarray
    points: np.ndarray
    present: np.ndarray
    height: float
    floor: np.ndarray | None = None


@dataclass(frozen=True)
class HeadPixels:
    """Head observations, one row each, in time order (then camera order).

    time (N,) s; camera (N,) str; id (N,) int; uv (N, 2) px (noisy); truth (N, 3) m — the head point;
    feet_uv (N, 2) px (noisy) — the floor point of the person in the same camera, NaN where the feet are
    hidden or outside the image (None: not asked for)
    """

    time: np.ndarray
    camera: np.ndarray
    id: np.ndarray
    uv: np.ndarray
    truth: np.ndarray
    feet_uv: np.ndarray | None = None

    def of(self, person_id: int) -> "HeadPixels":
        keep = self.id == person_id
        return HeadPixels(self.time[keep], self.camera[keep], self.id[keep], self.uv[keep], self.truth[keep],
                          None if self.feet_uv is None else self.feet_uv[keep])


def head_tracks(scenario: Scenario) -> dict[int, HeadTrack]:
    """Every person's head top at every frame (posed body, so the gait's bob and sway are in it)."""
    n = scenario.n_frames
    points = {p.id: np.full((n, 3), np.nan) for p in scenario.people}
    for k in range(n):
        people, parts = scenario.pose_people(k)
        for i, person in enumerate(people):
            points[person.id][k] = parts.head_top[i]
    times = np.arange(n) / scenario.fps
    return {p.id: HeadTrack(times, points[p.id], p.track.present.copy(), float(p.shape.height),
                            np.asarray(p.track.xy, dtype=float).copy())
            for p in scenario.people}


def head_pixels(scenario: Scenario, noise_px: float = 2.0, rng: np.random.Generator | int | None = 0,
                margin_px: float = 0.0, occlusion: bool = True,
                tracks: dict[int, HeadTrack] | None = None, feet: bool = False) -> HeadPixels:
    """The head pixel of every present person in every camera whose image holds it.

    Parameters
    ----------
    noise_px : float — standard deviation of the Gaussian noise added to u and v (pixels)
    rng : Generator or seed
    margin_px : float — a head this close to the image border is not counted as seen
    occlusion : bool — drop heads hidden behind the scene's obstacles (the cameras' depth maps)
    tracks : the scenario's :func:`head_tracks`, if already computed
    feet : bool — also the pixel of each seen head's floor point (the person's floor position, a box's
        bottom centre) in the same camera, NaN where it is hidden or outside the image; its noise is
        drawn after the heads', so the head pixels are the same with and without feet
    """
    rng = np.random.default_rng(rng)
    tracks = tracks or head_tracks(scenario)
    parts = []
    for c, cid in enumerate(scenario.camera_ids):
        if scenario.rigs[cid].poses is not None:
            raise ValueError(f"camera {cid!r} moves; head_pixels handles fixed cameras only")
        cam = scenario.scene.cameras[cid]
        for pid, tr in tracks.items():
            k = np.flatnonzero(tr.present)
            uv, depth = cam.project(tr.points[k], return_depth=True)
            seen = (depth > 0) & cam.in_image(uv, margin_px)
            if occlusion and scenario.scene.obstacles and seen.any():
                hidden = scenario.scene.occlusion(cid).hidden(uv[seen], depth[seen], true_depth=True)
                seen[np.flatnonzero(seen)[hidden]] = False
            k = k[seen]
            foot = _feet_pixels(scenario, cid, tr.floor[k], margin_px, occlusion) if feet else np.zeros((len(k), 2))
            parts.append((tr.times[k], np.full(len(k), c), np.full(len(k), pid), uv[seen], tr.points[k], foot))
    time, cam_index, ids, uv, truth, foot = (np.concatenate([p[i] for p in parts]) for i in range(6))
    order = np.lexsort((ids, cam_index, time))
    uv = uv[order] + rng.normal(0.0, noise_px, (len(order), 2))
    foot = foot[order] + rng.normal(0.0, noise_px, (len(order), 2)) if feet else None
    cameras = np.array(scenario.camera_ids)[cam_index[order].astype(int)]
    return HeadPixels(time[order], cameras, ids[order].astype(int), uv, truth[order], foot)


def _feet_pixels(scenario: Scenario, camera_id: str, floor_xy: np.ndarray, margin_px: float,
                 occlusion: bool) -> np.ndarray:
    """(K, 2) pixels of floor points (K, 2) in one camera, NaN where outside the image or hidden."""
    cam = scenario.scene.cameras[camera_id]
    points = np.column_stack([floor_xy, np.zeros(len(floor_xy))])
    uv, depth = cam.project(points, return_depth=True)
    seen = (depth > 0) & cam.in_image(uv, margin_px)
    if occlusion and scenario.scene.obstacles and seen.any():
        hidden = scenario.scene.occlusion(camera_id).hidden(uv[seen], depth[seen], true_depth=True)
        seen[np.flatnonzero(seen)[hidden]] = False
    uv[~seen] = np.nan
    return uv
