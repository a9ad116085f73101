"""real_data's second convention for PETS's truth: rows moved along the camera's line of sight (--truth-beyond-m)."""

import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from real_data import beyond_along_ray, main  # noqa: E402

from worldtrack.io.tracks import TrackTable  # noqa: E402


def test_each_row_moves_away_from_the_camera_along_its_own_line_of_sight():
    table = TrackTable.from_arrays([0, 0, 1], [1, 2, 1], [3.0, 1.0, -2.0], [4.0, 1.0, 0.0], time=[0.0, 0.0, 0.1])
    moved = beyond_along_ray(table, np.array([1.0, 1.0]), 0.1)
    assert np.allclose(moved.x, [3.0 + 0.1 * 2 / np.sqrt(13), 1.0, -2.0 - 0.3 / np.sqrt(10)])
    assert np.allclose(moved.y, [4.0 + 0.1 * 3 / np.sqrt(13), 1.0, -0.1 / np.sqrt(10)])   # (1, 1): under the camera, stays
    assert list(moved.frame) == [0, 0, 1] and list(moved.id) == [1, 2, 1]
    assert beyond_along_ray(table, np.zeros(2), 0.0) is table


def test_a_distance_that_is_not_a_number_is_one_line_and_exit_2(capsys):
    with pytest.raises(SystemExit) as e:
        main(["--truth-beyond-m", "nan"])
    assert e.value.code == 2
    assert "--truth-beyond-m" in capsys.readouterr().err
