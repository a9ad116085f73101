"""The re-fitted board truths of the cube benchmark recover known board poses from tag corners, also
when the camera has a rolling shutter."""

import json
import sys
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from visp_rolling_shutter import fit_rolling_shutter, moved  # noqa: E402
from visp_truth import load_tags, refit_board_poses  # noqa: E402

SIZE = 0.0955
K = np.array([[607.0, 0, 321.0], [0, 607.0, 242.0], [0, 0, 1]])


def _pose(rotvec, t) -> np.ndarray:
    M = np.eye(4)
    M[:3, :3], M[:3, 3] = Rotation.from_rotvec(rotvec).as_matrix(), t
    return M


def _project(M: np.ndarray, X: np.ndarray) -> np.ndarray:
    p = (X @ M[:3, :3].T + M[:3, 3]) @ K.T
    return p[:, :2] / p[:, 2:]


def _write_sequence(folder: Path, rng: np.random.Generator, readout: float = 0.0,
                    twist=(0.0, 0.0, 0.0, 0.0, 0.0, 0.0)) -> list[np.ndarray]:
    """Six tags on a 2×3 grid, eight camera poses; detections as ViSP stores them: (row, col). With
    ``readout`` > 0 the camera has a rolling shutter: row v is seen ``readout·(v − 240)/480`` frame
    periods after mid-frame, while the camera swings back and forth along ``twist`` (rotation
    vector, m): at time τ (frame periods) by ``3·sin(τ/2)·twist`` from the first board pose."""
    square = np.array([[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]) * SIZE / 2
    layout = {str(i): _pose([0, 0, 0], [0.12 * (i // 3), 0.12 * (i % 3), 0]) for i in range(6)}
    layout = {k: np.linalg.inv(layout["2"]) @ v for k, v in layout.items()}        # board = tag 2's frame
    boards = [_pose([np.pi + 0.1 * np.sin(t), 0.05 * t, 0.02 * t], [-0.1 + 0.01 * t, -0.05, 0.9 + 0.005 * t])
              for t in range(8)]
    swing = lambda b, time: moved(boards[0], np.asarray(twist, float), 3 * np.sin(time / 2))
    if readout:                     # the camera's speed changes, so no layout can absorb the shear
        boards = [swing(None, np.array([t], float))[0] for t in range(8)]
    detections = []
    for t, b in enumerate(boards):
        frame = {}
        for tag, L in layout.items():
            M = b @ L
            uv = _project(M, square)
            for _ in range(3 if readout else 0):                    # each corner at its own row's time
                seen = swing(b, t + readout * (uv[:, 1] - 240) / 480) @ L
                uv = np.array([_project(Mi, X[None])[0] for Mi, X in zip(seen, square)])
            uv = uv + rng.normal(0, 0.05, (4, 2))
            noisy = M @ _pose(rng.normal(0, 0.01, 3), rng.normal(0, 0.002, 3))        # a single tag's pose is rough
            frame[tag] = {"tag_corners": uv[:, ::-1].tolist(), "cMo": noisy.tolist()}
        detections.append(frame)
    _write_sequence.layout = layout
    (folder / "apriltag_data.json").write_text(json.dumps({"tag_size": SIZE, "grid": [b.tolist() for b in boards],
                                                           "detections": detections}))
    (folder / "cam.json").write_text(json.dumps({"px": K[0, 0], "py": K[1, 1], "u0": K[0, 2], "v0": K[1, 2],
                                                       "h": 480}))
    return boards


def test_refit_recovers_the_board_motion(tmp_path):
    truth = _write_sequence(tmp_path, np.random.default_rng(4))
    board, rms = refit_board_poses(tmp_path)
    # Four alternating rounds from rough single-tag poses do not fully converge on 8 frames of small
    # motion (0.16 px, 5 mm, 0.33 deg here; a joint bundle adjustment reached 0.045 px, 2.3 mm): the
    # bounds check the corner order and the fit, not the last millimetre.
    assert rms < 0.25                                                       # pixels (row/col mixed up: > 100)
    for b, t in zip(board, truth):
        rel, rel_true = b @ np.linalg.inv(board[0]), t @ np.linalg.inv(truth[0])
        assert np.linalg.norm(rel[:3, 3] - rel_true[:3, 3]) < 8e-3         # metres
        angle = np.linalg.norm(Rotation.from_matrix(rel[:3, :3] @ rel_true[:3, :3].T).as_rotvec())
        assert np.degrees(angle) < 0.6


def _relative_errors(board, truth) -> tuple[float, float]:
    """Largest error over the frames of the motion relative to frame 0: mm, degrees."""
    mm, deg = [], []
    for b, t in zip(board, truth):
        rel, rel_true = b @ np.linalg.inv(board[0]), t @ np.linalg.inv(truth[0])
        mm.append(1000 * np.linalg.norm(rel[:3, 3] - rel_true[:3, 3]))
        deg.append(np.degrees(np.linalg.norm(Rotation.from_matrix(rel[:3, :3] @ rel_true[:3, :3].T).as_rotvec())))
    return max(mm), max(deg)


def test_rolling_shutter_refit_finds_the_readout_and_removes_the_shear(tmp_path):
    # the camera swings by up to 1 deg and 7 mm per frame; rows are read over one frame period
    twist = (0.001, np.radians(0.67), 0.001, 0.005, 0.0, 0.001)
    truth = _write_sequence(tmp_path, np.random.default_rng(5), readout=1.0, twist=twist)
    tags, layout = load_tags(tmp_path), _write_sequence.layout
    start = fit_rolling_shutter(tags, layout, np.array(truth), readouts=(0.0,)).poses   # a global-shutter fit
    board = fit_rolling_shutter(tags, layout, start)
    assert board.readout == 1.0                               # the corners' residual picks the readout
    assert board.rms_by_readout[1.0] < 0.3 * board.rms_by_readout[0.0]
    global_mm, global_deg = _relative_errors(start, truth)
    rolling_mm, rolling_deg = _relative_errors(board.poses, truth)
    assert global_deg > 0.3                                   # the global-shutter fit is sheared off
    assert rolling_deg < 0.3 * global_deg
    assert rolling_mm < 0.3 * global_mm
