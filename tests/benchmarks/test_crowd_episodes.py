"""crowd 10's error rows grouped into episodes by cause (benchmarks/crowd_episodes.py)."""

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
from crowd_episodes import episodes  # noqa: E402

from worldtrack.io.tracks import TrackTable  # noqa: E402


def test_a_track_slid_onto_a_neighbour_is_one_missed_person_and_one_duplicate():
    # Person 1 at x = 0, person 2 at x = 2, frames 0-3. Track 7 holds 1 throughout; track 8 holds 2 on
    # frames 0-1, then slides onto 1 (frames 2-3): 2 is missed beside 8, which duplicates 1.
    gt = TrackTable.from_arrays([f for f in range(4) for _ in (1, 2)], [1, 2] * 4, [0.0, 2.0] * 4, [0.0] * 8)
    track8 = [2.0, 2.0, 0.1, 0.1]
    pred = TrackTable.from_arrays([f for f in range(4) for _ in (7, 8)], [7, 8] * 4,
                                  [v for f in range(4) for v in (0.0, track8[f])], [0.0] * 8)
    matched = {(f, 1): 7 for f in range(4)} | {(0, 2): 8, (1, 2): 8}
    eps = episodes(gt, pred, matched)
    # Person 2's nearest track (8, 1.9 m away) is beyond 1 m: "none"; 8 is 0.1 m from person 1, who is held.
    assert sorted((e.kind, e.who, e.frames) for e in eps) == [("fp dup", 8, [2, 3]), ("miss none", 2, [2, 3])]


def test_runs_are_split_by_held_frames_and_named_by_their_commonest_cause():
    # Person 1 missed on frames 0-2 and 4: two episodes. On frames 0-1 a track sits 0.6 m away,
    # holding nobody ("displaced"); on frame 2 it is gone ("none"). Track 9 is far from everyone.
    gt = TrackTable.from_arrays([0, 1, 2, 3, 4], [1] * 5, [0.0] * 5, [0.0] * 5)
    pred = TrackTable.from_arrays([0, 1, 3, 0], [5, 5, 5, 9], [0.6, 0.6, 0.0, 5.0], [0.0] * 4)
    eps = episodes(gt, pred, {(3, 1): 5})
    assert sorted((e.kind, e.who, e.frames) for e in eps) == [
        ("fp displaced", 5, [0, 1]), ("fp ghost", 9, [0]), ("miss displaced", 1, [0, 1, 2]), ("miss none", 1, [4])]
