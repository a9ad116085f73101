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
    """One person's head: times (T,) s, points (T, 3) m (head top), present (T,) bool, height m."""

    times: np.ndarray
    points: np.ndarray
    present: np.ndarray
    height: float


@dataclass(frozen=True)
class HeadPixels:
    """Head observations, one row each, in time order (then camera order).

    time (N,) s; camera (N,) str; id (N,) int; uv (N, 2) px (noisy); truth (N, 3) m — the head point
    """

    time: np.ndarray
    camera: np.ndarray
    id: np.ndarray
    uv: np.ndarray
    truth: np.ndarray

    def of(self, person_id: int) -> "HeadPixels":
        keep = self.id == person_id
        return HeadPixels(self.time[keep], self.camera[keep], self.id[keep], self.uv[keep], self.truth[keep])


def head_tracks(scenario: Scenario) -> dict[int, HeadTrack]:
    """Every person's head top at every frame (posed body, so the gait's bob and sway are in it)."""
    n = scenario.n_frames
    points = {p.id: np.full((n, 3), np.nan) for p in scenario.people}
    for k in range(n):
        people, parts = scenario.pose_people(k)
        for i, person in enumerate(people):
            points[person.id][k] = parts.head_top[i]
    times = np.arange(n) / scenario.fps
    return {p.id: HeadTrack(times, points[p.id], p.track.present.copy(), float(p.shape.height))
            for p in scenario.people}


def head_pixels(scenario: Scenario, noise_px: float = 2.0, rng: np.random.Generator | int | None = 0,
                margin_px: float = 0.0, occlusion: bool = True,
                tracks: dict[int, HeadTrack] | None = None) -> HeadPixels:
    """The head pixel of every present person in every camera whose image holds it.

    Parameters
    ----------
    noise_px : float — standard deviation of the Gaussian noise added to u and v (pixels)
    rng : Generator or seed
    margin_px : float — a head this close to the image border is not counted as seen
    occlusion : bool — drop heads hidden behind the scene's obstacles (the cameras' depth maps)
    tracks : the scenario's :func:`head_tracks`, if already computed
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
            parts.append((tr.times[k], np.full(len(k), c), np.full(len(k), pid), uv[seen], tr.points[k]))
    time, cam_index, ids, uv, truth = (np.concatenate([p[i] for p in parts]) for i in range(5))
    order = np.lexsort((ids, cam_index, time))
    uv = uv[order] + rng.normal(0.0, noise_px, (len(order), 2))
    cameras = np.array(scenario.camera_ids)[cam_index[order].astype(int)]
    return HeadPixels(time[order], cameras, ids[order].astype(int), uv, truth[order])
