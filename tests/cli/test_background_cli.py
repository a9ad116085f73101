"""Background estimation without an empty frame, and ``worldtrack background``.

A synthetic clip: a textured, noisy background; people (coloured blocks) walking across; and one
person standing still at one place for 40 % of the frames. The still person must not appear in
the estimated background.
"""

from __future__ import annotations

import re
from pathlib import Path

import cv2
import numpy as np
import pytest

from worldtrack.cli import main
from worldtrack.foreground.estimate import estimate_background

H, W, N = 72, 96, 50
STILL = (slice(30, 52), slice(40, 52))           # rows, columns of the person standing still


def true_background() -> np.ndarray:
    yy, xx = np.mgrid[0:H, 0:W]
    b = 90 + 60 * xx / W + 10 * np.sin(yy / 5.0)
    g = 120 + 40 * yy / H
    r = 70 + 30 * np.cos(xx / 7.0)
    return np.stack([b, g, r], axis=-1).round().astype(np.uint8)


def clip(still_fraction: float = 0.4, seed: int = 0, crossing_fraction: float | None = None
         ) -> tuple[list[np.ndarray], np.ndarray]:
    """Frames (BGR uint8) and the true background.

    With ``crossing_fraction``, instead of the fast walker, people in dark clothes cover the
    still person's spot in that fraction of the frames (all outside the standing-still ones).
    """
    rng = np.random.default_rng(seed)
    bg = true_background()
    n_still = int(round(still_fraction * N))
    start = (N - n_still) // 2
    frames = []
    for k in range(N):
        img = np.clip(bg + rng.normal(0.0, 3.0, bg.shape), 0, 255)
        if start <= k < start + n_still:
            img[STILL] = (30, 30, 200)                                     # standing still
        x = int(-14 + (W + 14) * k / N)                                    # walking left → right
        img[8:28, max(x, 0):max(x + 12, 0)] = (200, 60, 40)
        if crossing_fraction is None:
            x2 = int(W - (W + 14) * ((3 * k) % N) / N)                     # walking right → left, 3x
            img[34:56, max(x2, 0):max(x2 + 12, 0)] = rng.integers(0, 255, 3)   # crosses the spot
        elif k < start and k < int(round(crossing_fraction * N)):
            img[STILL] = rng.integers(0, 50, 3)                            # someone in dark clothes
        frames.append(img.astype(np.uint8))
    return frames, bg


def still_error(estimate: np.ndarray, bg: np.ndarray) -> float:
    """Mean absolute difference (grey levels) from the true background where the person stood."""
    return float(np.abs(estimate[STILL].astype(int) - bg[STILL].astype(int)).mean())


# ---------------------------------------------------------------------------- the library

@pytest.mark.parametrize("method", ["median", "mode"])
def test_a_person_still_for_40_percent_does_not_appear(method):
    frames, bg = clip(0.4)
    est = estimate_background(frames, method=method)
    assert est.shape == bg.shape and est.dtype == np.uint8
    assert still_error(est, bg) < 3.0
    assert np.abs(est[STILL].astype(int) - bg[STILL].astype(int)).max() < 15
    # The walkers leave no trail anywhere.
    assert np.abs(est.astype(int) - bg.astype(int)).max(axis=2).mean() < 2.0


def test_the_two_pass_median_is_closer_than_a_plain_median():
    frames, bg = clip(0.4)
    plain = np.median(np.stack(frames), axis=0).round().astype(np.uint8)
    two_pass = estimate_background(frames, method="median")
    assert still_error(two_pass, bg) < still_error(plain, bg)


def test_mode_survives_a_spot_covered_most_of_the_time_where_the_median_cannot():
    # Someone stands still for 30 % of the frames and others stand on the same spot in another
    # 30 %: the spot shows the background in only 40 % of the frames, but that is still its most
    # frequent appearance.
    frames, bg = clip(0.3, crossing_fraction=0.3)
    stack = np.stack(frames)[:, STILL[0], STILL[1]].astype(int)
    shows_bg = (np.abs(stack - bg[STILL].astype(int)).max(axis=-1) < 15).mean(axis=0)
    assert 0.35 < shows_bg.mean() < 0.45
    assert still_error(estimate_background(frames, method="mode"), bg) < 3.0
    # A median of samples that are mostly not the background is not the background (the limit
    # the method names in its documentation).
    assert still_error(estimate_background(frames, method="median"), bg) > 20.0


def test_adaptive_gives_an_image_of_the_right_size():
    frames, bg = clip(0.0)
    est = estimate_background(frames, method="adaptive")
    assert est.shape == bg.shape and est.dtype == np.uint8
    assert np.abs(est.astype(int) - bg.astype(int)).mean() < 10.0


def test_library_errors():
    from worldtrack.errors import InputError

    with pytest.raises(InputError, match="unknown method 'mean'"):
        estimate_background([true_background()], method="mean")
    with pytest.raises(InputError, match="no frames"):
        estimate_background([])
    with pytest.raises(InputError, match="different sizes"):
        estimate_background([true_background(), true_background()[:10]])


# ---------------------------------------------------------------------------- the command line

@pytest.fixture(scope="module")
def video(tmp_path_factory) -> tuple[Path, np.ndarray]:
    frames, bg = clip(0.4, seed=1)
    path = tmp_path_factory.mktemp("clip") / "clip.avi"
    writer = cv2.VideoWriter(str(path), cv2.VideoWriter_fourcc(*"MJPG"), 10.0, (W, H))
    assert writer.isOpened()
    for f in frames:
        writer.write(f)
    writer.release()
    return path, bg


@pytest.mark.parametrize("method", ["mode", "median"])
def test_cli_writes_a_clean_background(video, tmp_path, capsys, method):
    path, bg = video
    out = tmp_path / "bg.png"
    rc = main(["background", str(path), "--out", str(out), "--samples", "50", "--method", method, "--quiet"])
    text = capsys.readouterr().out
    assert rc == 0
    assert re.search(rf"{N} frames, {N} sampled; method {method}; background {W}x{H}", text)
    est = cv2.imread(str(out))
    assert est.shape == bg.shape
    assert still_error(est, bg) < 6.0                    # MJPG compression adds a few levels


def test_cli_resizes_to_the_camera_size(video, tmp_path, capsys):
    path, _ = video
    out = tmp_path / "bg.png"
    assert main(["background", str(path), "--out", str(out), "--samples", "10", "--camera-size", "48x36",
                 "--quiet"]) == 0
    assert "resized from 96x72" in capsys.readouterr().out
    assert cv2.imread(str(out)).shape == (36, 48, 3)


def test_cli_shows_progress_on_stderr(video, tmp_path, capsys):
    path, _ = video
    assert main(["background", str(path), "--out", str(tmp_path / "bg.png"), "--samples", "5"]) == 0
    assert "reading" in capsys.readouterr().err


@pytest.mark.parametrize("case", ["missing", "not a video", "method", "samples", "extension", "folder",
                                  "threshold", "size"])
def test_cli_errors_are_one_line(case, video, tmp_path, capsys):
    path, _ = video
    junk = tmp_path / "junk.avi"
    junk.write_text("this is not a video\n")
    argv, message = {
        "missing": ([str(tmp_path / "none.avi"), "--out", str(tmp_path / "bg.png")], r"none.avi: no such file"),
        "not a video": ([str(junk), "--out", str(tmp_path / "bg.png")],
                        r"junk.avi: (cannot open as a video|no frames could be decoded)"),
        "method": ([str(path), "--out", str(tmp_path / "bg.png"), "--method", "mean"],
                   r"--method: expected one of median, mode, adaptive, got 'mean'"),
        "samples": ([str(path), "--out", str(tmp_path / "bg.png"), "--samples", "0"],
                    r"--samples: expected a positive whole number"),
        "extension": ([str(path), "--out", str(tmp_path / "bg.txt")], r"expected an image file name"),
        "folder": ([str(path), "--out", str(tmp_path / "no" / "bg.png")], r"does not exist"),
        "threshold": ([str(path), "--out", str(tmp_path / "bg.png"), "--threshold", "300"],
                      r"--threshold: expected grey levels"),
        "size": ([str(path), "--out", str(tmp_path / "bg.png"), "--camera-size", "big"],
                 r"--camera-size: expected WxH"),
    }[case]
    rc = main(["background", *argv, "--quiet"])
    captured = capsys.readouterr()
    lines = captured.err.splitlines()
    assert rc == 2 and len(lines) == 1 and lines[0].startswith("error: "), captured.err
    assert re.search(message, lines[0]), lines[0]
