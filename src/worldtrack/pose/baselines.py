"""Baselines for the pose trackers: KLT + ``cv2.solvePnP`` for rigid objects.

:class:`KltPnpTracker` — corners found in the first frame on the model at its known pose are
lifted to 3-D through the model's z-buffer, followed frame to frame by pyramidal Lucas–Kanade
(forward–backward checked), and the pose is solved by ``cv2.solvePnPRansac`` from the previous
pose and refined by ``cv2.solvePnPRefineLM`` on the inliers. When fewer than half the corners
remain, new ones are found and lifted at the current estimate (which lets drift in, as any
frame-to-frame tracker does).

The body's baseline, the paper's torso → arm cascade, is :func:`worldtrack.pose.body.cascade`.
"""

from __future__ import annotations

import cv2
import numpy as np

from worldtrack.pose.models import PointModel
from worldtrack.pose.render import Intrinsics, splat
from worldtrack.pose.tracker import PoseEstimate, to_grey


class KltPnpTracker:
    """KLT + solvePnP (LM refine) for a rigid model (see the module docstring).

    Parameters
    ----------
    model : PointModel (geometry only is used); intr : Intrinsics
    R0, t0 : pose at ``image0`` (object → camera, m); image0 : the first frame (BGR or grey)
    max_corners : corners kept at once
    """

    def __init__(self, model: PointModel, intr: Intrinsics, R0: np.ndarray, t0: np.ndarray, image0: np.ndarray,
                 max_corners: int = 300):
        self.model, self.intr, self.max_corners = model, intr, int(max_corners)
        self.K = intr.matrix()
        self.reset(R0, t0, image0)

    def reset(self, R: np.ndarray, t: np.ndarray, image: np.ndarray) -> None:
        """Start again at a known pose on ``image``."""
        self.rvec = cv2.Rodrigues(np.asarray(R, float))[0]
        self.tvec = np.asarray(t, float).reshape(3, 1).copy()
        self.prev = to_grey(image).astype(np.uint8)
        self.obj = np.zeros((0, 3), np.float32)
        self.img = np.zeros((0, 1, 2), np.float32)
        self._replenish()

    def _lift(self, corners: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Model points under image corners (n, 2) at the current pose; drops corners off the model."""
        R = cv2.Rodrigues(self.rvec)[0]
        r = splat(self.model.points @ R.T + self.tvec.ravel(), self.intr)
        uv = np.round(corners).astype(int)
        ok = (uv[:, 0] >= 0) & (uv[:, 1] >= 0) & (uv[:, 0] < self.intr.width) & (uv[:, 1] < self.intr.height)
        idx = np.full(len(uv), -1)
        idx[ok] = r.index[uv[ok, 1], uv[ok, 0]]
        keep = idx >= 0
        return self.model.points[idx[keep]].astype(np.float32), corners[keep].astype(np.float32)

    def _replenish(self) -> None:
        R = cv2.Rodrigues(self.rvec)[0]
        r = splat(self.model.points @ R.T + self.tvec.ravel(), self.intr)
        mask = cv2.erode((r.index >= 0).astype(np.uint8) * 255, np.ones((5, 5), np.uint8))
        for p in self.img.reshape(-1, 2):
            cv2.circle(mask, (int(p[0]), int(p[1])), 5, 0, -1)
        need = self.max_corners - len(self.obj)
        if need <= 0:
            return
        c = cv2.goodFeaturesToTrack(self.prev, need, 0.01, 5, mask=mask)
        if c is None:
            return
        obj, img = self._lift(c.reshape(-1, 2))
        self.obj = np.concatenate([self.obj, obj])
        self.img = np.concatenate([self.img, img.reshape(-1, 1, 2)])

    def step(self, image: np.ndarray, depth: np.ndarray | None = None) -> PoseEstimate:
        grey = to_grey(image).astype(np.uint8)
        n_before = len(self.obj)
        if n_before >= 6:
            nxt, st, _ = cv2.calcOpticalFlowPyrLK(self.prev, grey, self.img, None, winSize=(21, 21), maxLevel=3)
            back, st2, _ = cv2.calcOpticalFlowPyrLK(grey, self.prev, nxt, None, winSize=(21, 21), maxLevel=3)
            good = (st.ravel() == 1) & (st2.ravel() == 1) & (np.linalg.norm((back - self.img).reshape(-1, 2), axis=1) < 1.0)
            self.obj, self.img = self.obj[good], nxt[good]
        if len(self.obj) >= 6:
            ok, rvec, tvec, inl = cv2.solvePnPRansac(self.obj, self.img, self.K, None, self.rvec.copy(), self.tvec.copy(),
                                                     useExtrinsicGuess=True, reprojectionError=3.0,
                                                     flags=cv2.SOLVEPNP_ITERATIVE)
            if ok and inl is not None and len(inl) >= 6:
                inl = inl.ravel()
                self.obj, self.img = self.obj[inl], self.img[inl]
                rvec, tvec = cv2.solvePnPRefineLM(self.obj, self.img, self.K, None, rvec, tvec)
                self.rvec, self.tvec = rvec, tvec
        self.prev = grey
        if len(self.obj) < max(self.max_corners // 2, 6):
            self._replenish()
        R = cv2.Rodrigues(self.rvec)[0]
        return PoseEstimate(R, self.tvec.ravel().copy(), float("nan"), len(self.obj))
