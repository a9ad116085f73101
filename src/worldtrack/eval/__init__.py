"""Evaluation against ground truth: MOT metrics (via motmetrics) and the papers' own numbers.

>>> from worldtrack.io import read_tracks                               # doctest: +SKIP
>>> from worldtrack.eval import evaluate, position_errors               # doctest: +SKIP
>>> gt, pred = read_tracks("gt.csv"), read_tracks("tracks.csv")         # doctest: +SKIP
>>> evaluate(gt, pred, gate=0.5)["mota"]                                # doctest: +SKIP
>>> evaluate(gt, pred, gate=0.5)["hota"]                                # doctest: +SKIP
>>> position_errors(gt, pred, gate=0.5).mean_m                          # doctest: +SKIP
"""

from worldtrack.eval.hota import HotaResult, evaluate_hota, hota_available
from worldtrack.eval.causes import CAUSES, error_causes, errors_by_views, views_of
from worldtrack.eval.mot import DEFAULT_GATE_M, MotEvaluation, drop_ignored, evaluate, evaluate_detailed
from worldtrack.eval.tables import (PositionErrors, limb_angle_errors_deg, position_errors,
                                    rotation_errors_deg, target_frame_counts,
                                    target_precision_recall, track_positions,
                                    trajectory_rmse_split)

__all__ = ["HotaResult", "evaluate_hota", "hota_available", "CAUSES", "DEFAULT_GATE_M", "error_causes", "errors_by_views", "views_of", "MotEvaluation", "drop_ignored", "PositionErrors", "evaluate", "evaluate_detailed",
           "limb_angle_errors_deg", "position_errors", "rotation_errors_deg",
           "target_frame_counts", "target_precision_recall", "track_positions",
           "trajectory_rmse_split"]
