"""Following one person with a moving stereo / RGB-D camera under changing light (seed 001).

A robot's camera sees colour and depth; one person — the target — is to be followed among
others while the sun, the shade and the camera's white balance change the colours. The whole loop
a user needs:

>>> from worldtrack.synth import make_scenario
>>> from worldtrack.follow import FollowTracker, PIDFollower, frame_from_synth
>>> sc = make_scenario("follow-target", size=(160, 120), frames=5, seed=0)
>>> tracker, pid = FollowTracker(scene=sc.scene), PIDFollower()
>>> for b in sc.frames():
...     start = (b.gt[0]["x"], b.gt[0]["y"]) if b.frame == 0 else None
...     step = tracker.follow(frame_from_synth(b), b.views["robot"].camera, start_xy=start)
...     v, omega = pid.command(step, b.views["robot"].camera, b.time)
>>> bool(step.found)
True

Modules, one per step of the paper: :mod:`planview` (detection from depth), :mod:`silhouette`,
:mod:`colour` (eq. 1, gain undo), :mod:`kalman`, :mod:`dissimilarity` (eqs. 2–3, the decision),
:mod:`templates`, :mod:`others` (tracking the other people), :mod:`tracker` (one frame),
:mod:`pid` (the follower's commands), :mod:`loop` (the closed loop in the synthetic world),
:mod:`stereo` (disparity from a stereo pair); :mod:`config` holds the parameters and presets.
"""

from worldtrack.follow.config import PRESETS, FollowConfig
from worldtrack.follow.pid import PIDFollower
from worldtrack.follow.tracker import FollowStep, FollowTracker, frame_from_synth

__all__ = ["PRESETS", "FollowConfig", "FollowStep", "FollowTracker", "PIDFollower", "frame_from_synth"]
