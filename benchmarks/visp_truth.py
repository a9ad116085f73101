"""A second ground truth for the ViSP cube: the board poses re-fitted from the tags' own corners.

The data's ``grid`` poses ``cMg(t)`` are one estimate of the AprilTag board per frame. Here the
board is fitted again from the detected corners of every tag alone: the tags' layout on the board
(each tag's pose relative to tag 2, seen in every frame) and the 99 board poses are estimated in
turn — ``cv2.solvePnP`` of all the frame's tag corners given the layout, then each tag's layout
pose by least squares over all frames given the board poses — four rounds. Nothing here looks at
the cube or at any tracker's output. Where the two truths differ, the board data cannot decide
between them (both reproject the corners to a fraction of a pixel), so the difference is a
measure of the ground truth's own uncertainty at the cube.

The corners in ``apriltag_data.json`` are stored (row, column), ViSP's ``vpImagePoint`` order; in
the tag's frame they are (−s/2, −s/2), (s/2, −s/2), (s/2, s/2), (−s/2, s/2) for tag size s
(checked: projected through each tag's ``cMo`` they land within 2.6 px of the detections).
"""

from __future__ import annotations

import json
from pathlib import Path

import cv2
import numpy as np
from scipy.optimize import least_squares
from scipy.spatial.transform import Rotation

REFERENCE_TAG = "2"


def _pose(v: np.ndarray) -> np.ndarray:
    M = np.eye(4)
    M[:3, :3], M[:3, 3] = Rotation.from_rotvec(v[:3]).as_matrix(), v[3:]
    return M


def _vector(M: np.ndarray) -> np.ndarray:
    return np.r_[Rotation.from_matrix(M[:3, :3]).as_rotvec(), M[:3, 3]]


def _project(K: np.ndarray, M: np.ndarray, X: np.ndarray) -> np.ndarray:
    p = (X @ M[:3, :3].T + M[:3, 3]) @ K.T
    return p[:, :2] / p[:, 2:]


def refit_board_poses(sequence: Path, rounds: int = 4) -> tuple[list[np.ndarray], float]:
    """Board poses (T × 4×4, camera ← board, board = tag 2's frame) and the median per-frame RMS
    corner reprojection error (pixels) of the fit.

    >>> poses, rms = refit_board_poses(Path("visp_rbt/sequence"))   # doctest: +SKIP
    """
    tags_json = json.loads((sequence / "apriltag_data.json").read_text())
    cam = json.loads((sequence / "cam.json").read_text())
    K = np.array([[cam["px"], 0, cam["u0"]], [0, cam["py"], cam["v0"]], [0, 0, 1]])
    half = tags_json["tag_size"] / 2
    square = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]], float) * half
    frames = tags_json["detections"]
    corners = {(t, tag): np.array(x["tag_corners"])[:, ::-1] for t, f in enumerate(frames) for tag, x in f.items()}
    names = sorted({tag for f in frames for tag in f}, key=int)
    board = [np.array(f[REFERENCE_TAG]["cMo"]) for f in frames]
    layout = {tag: _pose(np.median([_vector(np.linalg.inv(board[t]) @ np.array(f[tag]["cMo"]))
                                    for t, f in enumerate(frames) if tag in f], axis=0)) for tag in names}
    layout[REFERENCE_TAG] = np.eye(4)
    for _ in range(rounds):
        rms = []
        for t in range(len(frames)):
            seen = [tag for tag in names if (t, tag) in corners]
            X = np.concatenate([square @ layout[tag][:3, :3].T + layout[tag][:3, 3] for tag in seen])
            x = np.concatenate([corners[(t, tag)] for tag in seen])
            rvec = cv2.Rodrigues(board[t][:3, :3])[0]
            _, rvec, tvec = cv2.solvePnP(X, x, K, None, rvec, board[t][:3, 3].copy(), useExtrinsicGuess=True,
                                         flags=cv2.SOLVEPNP_ITERATIVE)
            board[t] = np.eye(4)
            board[t][:3, :3], board[t][:3, 3] = cv2.Rodrigues(rvec)[0], tvec.ravel()
            rms.append(float(np.sqrt(np.mean((_project(K, board[t], X) - x) ** 2))))
        for tag in names:
            if tag == REFERENCE_TAG:
                continue
            seen = [t for t in range(len(frames)) if (t, tag) in corners]
            residual = lambda v, seen=seen, tag=tag: np.concatenate(
                [(_project(K, board[t] @ _pose(v), square) - corners[(t, tag)]).ravel() for t in seen])
            layout[tag] = _pose(least_squares(residual, _vector(layout[tag]), loss="huber").x)
    return board, float(np.median(rms))
