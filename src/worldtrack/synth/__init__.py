"""Synthetic world: multi-camera sequences of articulated people with exact ground truth.

People are articulated bodies (18 ellipsoid and capsule parts, a walking gait tied to speed,
sitting), ray-cast per pixel through the scene's calibrated cameras (lens distortion included)
into a textured room, lit by ambient and directional light with cast shadows, optional floor
reflections, illumination drift, automatic white balance with jumps, backlight, vignetting, blur
and sensor noise. Cameras can be monocular, stereo (disparity with holes) or RGB-D (Kinect-like
quantised depth), fixed or on a moving robot.

In memory (what tracker tests use):

>>> from worldtrack.synth import make_scenario
>>> sc = make_scenario("two-crossing", size=(160, 120), frames=3, seed=0)
>>> for bundle in sc.frames():
...     view = bundle.views["cam1"]
...     # view.image (120, 160, 3) uint8 BGR, view.depth (120, 160) float32 m, view.instance int32 ids
...     rows = bundle.gt               # dicts with frame, time, id, x, y, z_head, ..., vis_cam1, ...
>>> view.image.shape, view.image.dtype, view.depth.dtype, view.instance.dtype
((120, 160, 3), dtype('uint8'), dtype('float32'), dtype('int32'))
>>> sorted(r["id"] for r in rows)
[1, 2]
>>> sc.background("cam1").shape    # the empty scene (background plate)
(120, 160, 3)

On disk (what ``worldtrack synth SCENARIO --out DIR`` does)::

    from worldtrack.synth import make_scenario, write_sequence
    write_sequence(make_scenario("crowd", people=20, seed=1), "out/crowd", png=False, progress=True)

Scenarios: :func:`list_scenarios` (names → description), :func:`scenario_parameters` (their own
parameters); all accept ``size``, ``frames``, ``seed`` and the options of :class:`Common`.
Same seed → identical arrays and files.
"""

from worldtrack.synth.bodies import BodyShape, PartArrays, body_parts, draw_body_shape
from worldtrack.synth.environment import Environment, Window
from worldtrack.synth.joints import JointAngles, posed
from worldtrack.synth.motion import Track, Waypoint, WalkerSettings, random_walkers, scripted_track
from worldtrack.synth.photometry import Light, LightingSchedule, LightSegment, SensorNoise, WhiteBalance
from worldtrack.synth.render import RenderOptions, Renderer, SynthFrame
from worldtrack.synth.scenarios import Common, list_scenarios, make_scenario, scenario_parameters
# The scenario families register themselves with make_scenario when imported, in this order (list_scenarios).
from worldtrack.synth import kato_lab as _kato_lab  # noqa: F401  (paper 000's experiments)
from worldtrack.synth import halls as _halls  # noqa: F401  (crowd, two rooms, entry)
from worldtrack.synth import following as _following  # noqa: F401  (follow-target)
from worldtrack.synth import office as _office  # noqa: F401  (non-overlapping)
from worldtrack.synth import booth as _booth  # noqa: F401  (face-pose, upper-body)
from worldtrack.synth import unseen as _unseen  # noqa: F401  (line-of-sight)
from worldtrack.synth.sensors import SensorSpec
from worldtrack.synth.sequence import CameraRig, Person, Scenario, SynthBundle
from worldtrack.synth.writer import write_sequence

__all__ = ["BodyShape", "CameraRig", "Common", "Environment", "JointAngles", "Light", "LightSegment",
           "LightingSchedule", "PartArrays", "Person", "RenderOptions", "Renderer", "Scenario", "SensorNoise",
           "SensorSpec", "SynthBundle", "SynthFrame", "Track", "WalkerSettings", "Waypoint", "WhiteBalance",
           "Window", "body_parts", "draw_body_shape", "list_scenarios", "make_scenario", "posed",
           "random_walkers", "scenario_parameters", "scripted_track", "write_sequence"]
