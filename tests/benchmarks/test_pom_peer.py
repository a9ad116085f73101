"""What the POM benchmark writes for POM and reads back: person boxes, the config, detections, counts.

POM itself (GPL, built by the benchmark from ../shared/peers/pom) is not needed here.
"""

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from peer_pom import detection_counts  # noqa: E402
from pom_peer import PomRun, detections, person_rectangles  # noqa: E402

from worldtrack.geometry.camera import Camera  # noqa: E402
from worldtrack.io.tracks import TrackTable  # noqa: E402

# A 320×240 camera 3 m up at the origin looking along +Y at a point 5 m away on the floor.
CAM = Camera.look_at("c", 320, 240, [0.0, 0.0, 3.0], [0.0, 5.0, 0.0], hfov_deg=60.0)


def test_person_box_spans_feet_to_head_and_width_across_the_line_of_sight():
    xy = np.array([[0.0, 5.0]])
    rects, visible = person_rectangles(CAM, xy, height=1.7, width=0.4)
    feet, head = CAM.project(np.array([[0.0, 5.0, 0.0], [0.0, 5.0, 1.7]]))
    left, right = CAM.project(np.array([[-0.2, 5.0, 0.0], [0.2, 5.0, 0.0]]))
    assert visible[0]
    xmin, ymin, xmax, ymax = rects[0]
    assert ymax == round(feet[1]) and ymin == round(head[1])      # the camera looks down: feet lower
    assert xmin <= round(left[0]) and xmax >= round(right[0])      # at least the feet's width
    assert (xmin + xmax) / 2 == pytest.approx(feet[0], abs=1.0)    # centred on the person


def test_people_behind_the_camera_or_mostly_outside_the_image_are_not_visible():
    xy = np.array([[0.0, -3.0], [30.0, 5.0], [0.0, 5.0]])
    _, visible = person_rectangles(CAM, xy, height=1.7, width=0.4)
    assert visible.tolist() == [False, False, True]


def test_config_has_a_rectangle_per_camera_and_location_inside_the_image(tmp_path):
    xy = np.array([[0.0, 5.0], [0.0, -3.0]])
    run = PomRun(tmp_path, [CAM, CAM], xy, frames=3)
    path, n_visible = run.write_config(1.7, 0.4, prior=0.01, sigma=0.001)
    lines = path.read_text().splitlines()
    rects = [ln.split() for ln in lines if ln.startswith("RECTANGLE")]
    assert lines[0] == "ROOM -1 -1 2 2" and lines[1] == "CAMERA 0 320 240"
    assert len(rects) == 4 and n_visible == 2
    assert [r[3] for r in rects if r[2] == "1"] == ["notvisible", "notvisible"]
    for r in rects:
        if r[3] != "notvisible":
            x0, y0, x1, y1 = map(int, r[3:])
            assert 0 <= x0 < x1 < 320 and 0 <= y0 < y1 < 240          # POM rejects boxes out of bounds
    assert lines[-1] == "PROCESS 0 3" and "SIGMA_IMAGE_DENSITY 0.001" in lines


def test_detections_are_locations_above_the_threshold_and_counts_pair_them_within_the_gate():
    xy = np.array([[0.0, 0.0], [1.0, 0.0], [5.0, 5.0]])
    prob = np.array([[0.9, 0.2, 0.6],      # frame 10: locations 0 and 2
                     [0.1, 0.95, 0.4]])    # frame 11: location 1
    det = detections(prob, xy, 0.5, np.array([10, 11]))
    assert det.frame.tolist() == [10, 10, 11] and det.xy.tolist() == [[0, 0], [5, 5], [1, 0]]
    gt = TrackTable.from_arrays([10, 11, 11], [1, 1, 2], [0.3, 1.2, 3.0], [0.0, 0.0, 0.0])
    c = detection_counts(gt, det, gate=0.5)
    # frame 10: (0.3, 0) ↔ (0, 0) at 0.3 m, (5, 5) is a false positive; frame 11: (1.2, 0) ↔ (1, 0)
    # at 0.2 m, the person at (3, 0) is missed.
    assert (c["tp"], c["fp"], c["fn"]) == (2, 1, 1) and c["dist"] == pytest.approx(0.5)
