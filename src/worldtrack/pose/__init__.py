"""Seed 003: face and upper-body pose tracking by particle filter + Levenberg–Marquardt.

Modules follow the paper's steps: ``models`` (point models, rigid pose eqs. 1–2, 8–9),
``render`` (z-buffer, sparse templates §2.2/§4.3), ``cost`` (Geman–McClure eqs. 3–5, eigen-template
§3.1, colour/depth eqs. 16–19), ``lm`` (eqs. 6–7, 20), ``rigid`` (eq. 10, eigen basis),
``particle`` (§2.3–2.4, weighted mean), ``measures`` (eq. 21, failure rule), ``tracker`` (the
per-frame loop), ``body`` (14-DoF upper body, eqs. 11–15), ``baselines`` (KLT + solvePnP, cascade).
"""

from worldtrack.pose.measures import FailureRule, axis_angle_deg, rotation_error_deg
from worldtrack.pose.models import PointModel, box_model, load_obj
from worldtrack.pose.render import Intrinsics
from worldtrack.pose.tracker import PoseEstimate, RigidTracker, TrackerConfig

__all__ = ["FailureRule", "Intrinsics", "PointModel", "PoseEstimate", "RigidTracker", "TrackerConfig",
           "axis_angle_deg", "box_model", "load_obj", "rotation_error_deg"]
