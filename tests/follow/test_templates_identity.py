"""The identity evidence kept open (worldtrack.follow.identity)."""

import numpy as np

from worldtrack.follow.identity import IdentityEvidence


def test_another_track_takes_over_only_when_clearly_and_repeatedly_better():
    ev = IdentityEvidence(tau=0.5, min_frames=3)
    ev.observe(0.1, 0.5, np.array([7, 8]), np.array([0.2, 0.45]))
    ev.observe(0.1, 0.5, np.array([7, 8]), np.array([0.2, 0.45]))
    assert ev.better(0.2) is None                                 # two frames are not enough
    ev.observe(0.1, 0.5, np.array([7]), np.array([0.2]))
    assert ev.better(0.2) == 7 and ev.better(0.35) is None        # 0.3 better: by 0.2 yes, by 0.35 no
    w = 1 - np.exp(-0.1 / 0.5)
    assert ev.mean[ev.ids == 8][0] == 0.45 and ev.target == 0.5   # a running average of equal scores
    ev.observe(0.1, 0.0, np.array([8]), np.array([1.0]))
    assert np.isclose(ev.target, 0.5 * (1 - w)) and np.isclose(ev.mean[ev.ids == 8][0], 0.45 * (1 - w) + w)
    ev.exchange(7)
    assert np.isclose(ev.target, 0.2) and np.isclose(ev.mean[ev.ids == 7][0], 0.5 * (1 - w))
    ev.keep(np.array([8]))
    assert ev.ids.tolist() == [8]
