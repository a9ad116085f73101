"""Settings of the shared map: time buckets, leases, retention, how people are merged and forgotten.

Set them like any other setting: ``map:`` in a ``--config`` file or ``--set map.bucket_s=0.1``.
"""

from __future__ import annotations

from typing import ClassVar, Literal

from pydantic import Field, model_validator

from worldtrack.config import Section, from_mapping, load_yaml, parse_assignment, with_overrides
from worldtrack.errors import InputError


class MapConfig(Section):
    """How workers, the fusion role and the streams on Redis behave (times in seconds)."""

    path: ClassVar[str] = "map"
    prefix: str = Field("worldtrack", min_length=1, pattern=r"^[A-Za-z0-9_.:-]+$",
                        description="key prefix: several maps can share one Redis database")
    bucket_s: float = Field(0.1, gt=0, le=5, description="fusion time bucket: observations whose capture times "
                                                          "fall in one bucket are merged into one map state")
    max_wait_s: float = Field(0.5, gt=0, le=60, description="a bucket is written once every live camera has "
                                                              "reported it, or this long after its first observation "
                                                              "(a batch worker's camera is waited for while "
                                                              "its lease lives)")
    live_updates: bool = Field(True, description="update the live map (map:current, map:updates) as soon as any "
                                                 "worker's observation of a bucket comes, not only when the "
                                                 "bucket is complete (the record, the map stream, waits)")
    lease_s: float = Field(1.0, gt=0.1, le=60, description="camera and fusion leases expire this long after "
                                                            "their last renewal (a dead worker's cameras are "
                                                            "free again after it)")
    starved_wait_s: float = Field(10.0, ge=0, description="a batch worker's camera whose lease lapsed is still "
                                                          "waited for this long (s) while the worker is connected "
                                                          "to Redis (starved of CPU, not dead: "
                                                          "worldtrack.map.starved; 0 = lapsed is dead)")
    renew_s: float = Field(0.25, gt=0.01, le=20, description="leases are renewed (and standbys try to take "
                                                              "them) this often")
    retention_s: float = Field(3600.0, gt=0, description="streams keep this much capture time (older entries "
                                                         "are trimmed with MINID)")
    share_rule: Literal["information", "support-lead"] = Field(
        "information", description="how workers that see the same person share the work (worldtrack.map.fusion): "
                                   "'information': each starts every frame from the map's estimate and the map "
                                   "adds their measurements by information; 'support-lead': the worker with the "
                                   "best view by share and support continues from its own estimate, the others "
                                   "start from the map's (the rule before issue 39e)")
    weigh_by: Literal["geometry", "tracker"] = Field(
        "geometry", description="what the map weighs each worker's estimate by: 'geometry': support x how finely "
                                "its cameras resolve the floor where the person stands, counting what obstacles "
                                "and other people hide; 'tracker': the inverse of the covariance its tracker "
                                "measured (the ellipsoid tracker's sigma), when every estimate has one")
    negative_evidence: bool = Field(True, description="a worker whose camera shows the place of a map person "
                                                      "clearly and nobody there says so, and the map drops a "
                                                      "person that only views showing less than 60 % of the body "
                                                      "report while another worker's clear view shows the place "
                                                      "empty for refute_after buckets running")
    refute_after: int = Field(3, ge=1, description="see negative_evidence (buckets)")
    own_births_s: float = Field(0.0, ge=0, description="a person another worker started less than this long ago "
                                                       "(s) inside this worker's views is not taken from the map: "
                                                       "this worker finds them in its own images (its new person "
                                                       "takes their id or the map merges the two); 0 = take them "
                                                       "(default: 1 s lost on held-out seeds)")
    confirm_birth_s: float = Field(0.0, ge=0, description="with negative_evidence, a person younger than this "
                                                          "(s) is dropped on another worker's clear empty view "
                                                          "even when the worker that started them shows them well "
                                                          "(a birth one view does not confirm; 0 = off)")
    ray_error_m: float = Field(0.0, ge=0, le=5, description="a model error (m) added along each worker's line of "
                                                            "sight to the floor geometry it is weighed by (a "
                                                            "one-camera tracker's depth slides by tenths of a metre; "
                                                            "worldtrack.map.evidence.with_ray_error); 0 = off "
                                                            "(0.15 on held-out 24-53: 9 seeds better, 6 worse, "
                                                            "28 and 41 -0.24 MOTA)")
    height_by_view: bool = Field(False, description="the map's height of a person weighs each worker's by support x "
                                                    "the share of the body its views show as its own (a worker "
                                                    "that sees a person behind somebody measures no height), not "
                                                    "by support alone (held-out 24-53: 5 seeds better, 9 worse, "
                                                    "MOTA -0.008)")
    head_rays: bool = Field(False, description="each worker publishes per person its cameras' own rays through the "
                                               "top of the head and the bottom of the feet in its foreground, and "
                                               "the map's height of a person two workers see is the median of "
                                               "their last heights from those rays (worldtrack.map.rays; off: "
                                               "held-out 84-113 below one process 8 -> 5 of 30, 10 seeds better, "
                                               "6 worse, seed 84 IDF1 -0.49; never-used 118 MOTA -0.32, 119 +0.30; "
                                               "held-out 124-153 MOTA +0.023, 11 better, 4 worse, 148 IDF1 -0.37)")
    ray_height_deadband_m: float = Field(0.0, ge=0, description="with head_rays: the map's height stays while the "
                                                               "median of the ray heights is within this (m) of "
                                                               "it, the first change from the workers' height "
                                                               "included (worldtrack.map.rays.map_height; 0 = off: "
                                                               "0.03 on 8 seen seeds vs head_rays MOTA +0.026, 4 "
                                                               "better, 2 worse; IDF1 84 +0.49, 148 +0.37, but 20 "
                                                               "-0.17, 137 -0.09)")
    weigh_own: bool = Field(False, description="weigh each worker's estimate (and choose the lead) by support x "
                                              "the share of the body no other person it holds covers in its "
                                              "views, not by support alone: a worker that sees a person behind "
                                              "somebody else does not lead them over one that sees them whole")
    hidden_after_s: float = Field(1.0, ge=0, description="a person only one worker reports, covered by other people "
                                                         "it holds (less than a quarter of the body its own) while "
                                                         "other workers are on the map, leaves the map after this "
                                                         "long (the one-process tracker's rule for a duplicate "
                                                         "behind somebody; 0 = never)")
    affirm_candidates: bool = Field(True, description="a worker publishes the people its tracker proposes but has "
                                                      "not confirmed; another worker whose camera shows somebody "
                                                      "there says so, and the first confirms them (one process "
                                                      "confirms a person two cameras show at once; "
                                                      "worldtrack.map.affirm; false: before issue 39k)")
    crossing_s: float = Field(0.0, ge=0, description="two ids one worker held apart (saw at the same time) less "
                                                     "than this long ago (s) are two people: the map does not fold "
                                                     "them as duplicates, and a worker that holds one puts the other "
                                                     "back on its own map while another worker sees them (a crossing "
                                                     "on the axis two facing cameras share: each shows only the "
                                                     "person in front; worldtrack.map.merges; 0 = off: with "
                                                     "head_rays, 2 s lifted dev 20 MOTA 0.853 -> 0.983, but on "
                                                     "held-out 124-153 MOTA -0.005, 2 seeds better, 4 worse, "
                                                     "133 -0.137; with crossing_gap_m 133 -0.023, IDF1 still -0.45)")
    crossing_apart_m: float = Field(0.5, ge=0, description="with crossing_s: only a pair a worker held at least "
                                                          "this far apart (m) at once is remembered (people that "
                                                          "cross were apart before one hid the other; a tracker's "
                                                          "duplicate is born on top of its twin and is folded as "
                                                          "before; no digest changed on dev 0-8, 20, held-out 133, "
                                                          "148); 0 = every pair held at once (issue 39o)")
    crossing_gap_m: float = Field(0.25, ge=0, description="with crossing_s: a worker puts the other of a pair back "
                                                         "only at least this far (m) from the one it holds (nearer, "
                                                         "its tracker ends it again as a duplicate and both ids ride "
                                                         "one person: held-out 133 MOTA 0.852 -> 0.965, 4 of 13 "
                                                         "seen seeds better, 0 worse); 0 = anywhere (issue 39o)")
    merge_distance_m: float = Field(0.5, gt=0, description="two ids from different workers closer than this "
                                                           "for merge_after_s are one person (the younger id "
                                                           "is folded into the elder)")
    merge_after_s: float = Field(0.2, ge=0, description="see merge_distance_m")
    newborn_gate: float = Field(9.21, ge=0, description="two ids from different workers both younger than "
                                                        "merge_after_s merge at once also beyond merge_distance_m "
                                                        "(up to twice it) when their squared Mahalanobis distance "
                                                        "under their trackers' covariances is below this (9.21: "
                                                        "99 % of two degrees of freedom; 0 = off)")
    same_blob_iou: float = Field(0.5, ge=0, le=1, description="a worker whose camera shows its newborn and another "
                                                             "worker's newborn as one blob (their image boxes overlap "
                                                             "by at least this intersection over union) says so, and "
                                                             "the map folds its id into the other's "
                                                             "(worldtrack.map.same_blob; 0 = off, before issue 39l)")
    same_blob_s: float = Field(0.5, gt=0, description="see same_blob_iou: both ids born less than this long (s) "
                                                      "before the claim")
    forget_after_s: float = Field(3.0, gt=0, description="a person no worker reports for this long leaves the "
                                                         "map (their id may be reclaimed until then)")
    claim_radius_m: float = Field(1.0, gt=0, description="a worker's new person within this distance of a "
                                                         "person the map lost takes that person's id "
                                                         "(plus 1.5 m/s times the time since they were lost)")
    handover_margin_m: float = Field(1.0, ge=0, description="a worker puts the map's people on its own map "
                                                            "when they come this close to its cameras' views")
    pace_files: bool = Field(True, description="play video files as live cameras (in real time from the map's "
                                               "epoch); false: as fast as the worker can (batch runs)")
    fusion_in_worker: bool = Field(True, description="each worker contends for the fusion role in a thread; false: "
                                                     "leave it to `worldtrack map fuse` processes (a fusion thread "
                                                     "shares the worker's interpreter lock with its tracker)")
    wait_for_start: bool = Field(False, description="video files wait for `worldtrack map start` (which sets "
                                                    "the epoch for all at once) instead of the first worker's start")

    @model_validator(mode="after")
    def _renew_within_lease(self) -> "MapConfig":
        if self.renew_s * 2 > self.lease_s:
            raise ValueError(f"renew_s: expected at most half of lease_s ({self.lease_s}), got {self.renew_s}")
        return self


def map_settings(config: str | None = None, sets: list[str] | tuple[str, ...] = ()) -> MapConfig:
    """The map settings of a ``--config`` file's ``map:`` section and ``--set map.NAME=VALUE``.

    >>> map_settings(sets=["map.bucket_s=0.05"]).bucket_s
    0.05
    """
    data = load_yaml(config).get("map") if config else None
    try:
        cfg = from_mapping(MapConfig, data, root="map")
    except InputError as e:
        raise InputError(f"{config}: {e}") from None
    overrides = {}
    for text in sets:
        path, value = parse_assignment(text)
        if not path.startswith("map."):
            raise InputError(f"--set {path}: only the map's settings (map.NAME=VALUE) can be set here")
        overrides[path[4:]] = value
    return with_overrides(cfg, overrides, root="map") if overrides else cfg


__all__ = ["MapConfig", "map_settings"]
