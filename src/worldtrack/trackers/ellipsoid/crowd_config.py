"""Settings for crowds one camera sees (:mod:`worldtrack.trackers.ellipsoid.prediction`,
:mod:`~worldtrack.trackers.ellipsoid.coast`); a section of
:class:`~worldtrack.trackers.ellipsoid.config.EllipsoidConfig`, kept apart so the two stay light.

>>> CrowdConfig().predict_along_ray
1.0
"""

from __future__ import annotations

from typing import ClassVar

from pydantic import Field

from worldtrack.config import Section


class CrowdConfig(Section):
    """People one camera alone shows, in a crowd: what the motion between frames may trust."""

    path: ClassVar[str] = "ellipsoid.crowd"

    predict_along_ray: float = Field(
        1.0, ge=0, le=1, description="share of the velocity along the line of sight the prediction uses for a person "
        "one camera alone shows (across it: all). One camera places people worst along its ray, and a slide of the "
        "match, read as velocity, carried tracks on: 1 = the full velocity, as before (default); 0 = across the ray "
        "only: for dense crowds (one-camera crowd of 50, held-out seeds 103-108 started on everyone: 11.7 -> 17.2 "
        "of 50 held), not sparse scenes, where walkers along the ray need it (PETS 2009 MOTA 0.927 -> 0.804)")
    predict_along_ray_measured: bool = Field(
        False, description="the prediction keeps, of the velocity along a lone camera's line of sight, only the share "
        "measured while a camera saw the person's feet (in the image, in front of obstacles and of everybody nearer: "
        "depth observed) - the same running average as the velocity's: a walker seen whole keeps their velocity into "
        "a crossing, a velocity made of slides in a merged crowd is dropped (times predict_along_ray). Off by default: "
        "crowd 50 held-out seeds 113-118 from the true places 13.0 -> 17.5 of 49 held, cold 7.3 -> 10.3 (as "
        "predict_along_ray=0: 17.0, 10.7), but PETS 2009 MOTA 0.926 -> 0.917 over 8 starts (predict_along_ray=0: "
        "0.801 over 3)")
    hold_along_ray_unobserved: bool = Field(
        False, description="with predict_along_ray_measured: in a frame where the person's depth was not observed, "
        "their velocity along the lone camera's line of sight keeps its value from before the frame (the slide of "
        "the match is not read as a walk), so the prediction carries the walk measured before the cover, damped by "
        "the measured share. Off by default: PETS 2009 over 8 starts MOTA 0.922 (0.917 without it, 0.926 default), "
        "crowd 50 held-out 113-118 true places 16.3 of 49 held, MOTA 0.479 (17.5, 0.492 without it)")
    alone_behind_obstacles: bool = Field(
        False, description="with predict_along_ray_measured: obstacles do not hide the feet (the depth counts as "
        "observed) of a person nobody else overlaps (own_share >= 1 - support.min_own_share): alone behind a sign, "
        "the match has no neighbour's silhouette to slide into. Off by default: PETS 2009 over 8 starts MOTA 0.922, "
        "IDF1 0.802, 4.25 switches (measured alone 0.917, 0.816, 6.62; default 0.926, 0.830, 2.75: the walker behind "
        "the sign is kept on starts 0, 3, 5, not on 4, 6); crowd 50 held-out 113-118 cold 9.5 held / MOTA 0.392, true "
        "places 18.7 / 0.489 (default 7.3 / 0.330, 13.0 / 0.431), never-used 125-128 13.0 / 0.390, 16.0 / 0.479 "
        "(default 8.0 / 0.312, 12.0 / 0.397)")
    births_past_people: bool = Field(
        False, description="a birth blob's end on the ellipses of people already known is hidden, as one on an "
        "obstacle (a head band above a tracked person is placed by its head, not by its lower end), and the size "
        "test expects only the pixels those ellipses leave unexplained (:mod:`.people_edges`). Off by default: crowd 50 "
        "dev 110-112 cold 9.0 -> 8.3 held (MOTA 0.353 -> 0.363), true places 9.7 -> 12.7 (0.390 -> 0.410), with "
        "predict_along_ray_measured 12.7 / 0.406, 16.7 / 0.475 (without it 12.3 / 0.409, 15.3 / 0.486); PETS 2009 "
        "over 8 starts MOTA 0.926 -> 0.924, switches 2.75 -> 4.88")
    births_head_bands: bool = Field(
        False, description="a birth blob too small for a person is still one where it is the top of one above "
        "people already known: nothing above it, its lower end on their ellipses, at least a quarter of a head's square "
        "there; placed by its top at the default height (:mod:`.head_bands`). Off by default: crowd 50 dev 110-112 "
        "alone cold 9.0 -> 9.7 held but MOTA 0.353 -> 0.313 (false positives), true places 9.7 -> 14.0 / 0.390 -> "
        "0.417; with predict_along_ray_measured, alone_behind_obstacles, births_past_people and "
        "births.people_occlude (against the first two) dev cold 14.7 -> 13.3 / 0.420 -> 0.408, true 14.3 -> 18.0 / "
        "0.468 -> 0.488, held-out 113-118 cold 9.5 -> 12.5 / 0.392 -> 0.424, true 18.7 -> 17.3 / 0.489 -> 0.485")
    births_in_front: float = Field(
        0.0, ge=0, description="a person in front of a confirmed one, whose ellipse hides them down to its feet: where "
        "the foreground in a strip down from those feet goes on for at least this share of their length in the image "
        "(the nearer person's legs), a person of the default size is proposed with the feet at its lowest row "
        "(:mod:`.in_front`), unless somebody known covers that row. 0 = off (the default). At 0.15 with "
        "predict_along_ray_measured, alone_behind_obstacles, births_head_bands, births_past_people and "
        "births.people_occlude, crowd 50 dev 110-112: 16 proposals in 6 runs, cold 13.3 -> 12.3 held, MOTA 0.408 -> "
        "0.433, true places 18.0 -> 18.0, 0.488 -> 0.495; without the cover test 177 on seed 110 alone and worse; "
        "held-out 113-118 cold 12.5 -> 12.0 / 0.424 -> 0.428, true 17.3 -> 17.2 / 0.485 -> 0.488, 119-124 cold 11.8 -> "
        "12.0, true 16.8 -> 18.2, 133-136 cold 14.8 -> 14.2, true 19.2 -> 19.2: neutral")
    head_bands_confirmed: bool = Field(
        False, description="with births_head_bands: a head band is one only above confirmed people (its lower end on "
        "their ellipses, not on candidates'; :func:`.head_bands.confirmed_images`). Off by default: with the settings "
        "above crowd 50 dev 110-112 kept 718 of 771 bands, cold 13.3 -> 13.7 held (MOTA 0.408 -> 0.412), true "
        "places 18.0 -> 17.7 (0.488 -> 0.477)")
    head_bands_tallest_m: float = Field(
        0.0, ge=0, description="with head_bands_confirmed: a band's top must also be above those people's ellipses "
        "drawn at least this tall, m (a person taller than their track's height shows their own head there, not "
        "somebody behind). 0 = not tested (the default); at 2.1 (height.range_m's maximum) crowd 50 dev 110-112 kept "
        "143 of 771 bands, cold 13.3 -> 13.3 held (0.408 -> 0.404), true places 18.0 -> 14.7 (0.488 -> 0.490)")
    births_heights_clear: bool = Field(
        False, description="with births_heights: a birth blob gives the new person's height only where the mask "
        "is background just beyond both its ends (:func:`.head_bands.blob_clear`, the head band's test): a blob "
        "the known people's ellipses or a neighbour cut is not a whole person. Off by default: with the settings "
        "above crowd 50 dev 110-112 cold 13.3 -> 13.0 held (0.408 -> 0.405), true places 18.0 -> 17.3 (0.488 -> 0.494)")
    births_heights: bool = Field(
        True, description="a birth blob with feet and head in view gives the new person's height and, shorter than "
        "height.range_m's minimum, is placed by its head (:func:`.births.blob_position`), as with height.measure "
        "on (the default). false: births read no height (blobs placed by their lower end, people born at the "
        "default height) while the tracker still measures heights: in a crowd one camera sees, the blob left "
        "by the known people's ellipses is rarely a whole person (crowd 50 dev 110-112 cold 9.0 -> 11.7 held, "
        "MOTA 0.353 -> 0.385; true places 9.7 -> 10.0, 0.390 -> 0.403; with predict_along_ray_measured + "
        "alone_behind_obstacles cold 14.7 -> 12.3 / 0.420 -> 0.409, true 14.3 -> 16.3 / 0.468 -> 0.478)")
    height_max_beside: float = Field(
        1.0, ge=0, le=1, description="a person is measured for height (:mod:`.height`) only in a frame where some "
        "view shows at most this share of the band beside their body (the ellipse three times as wide, less theirs) "
        "as foreground: in a crowd an untracked person behind makes the silhouette tall, and the tall ellipse then "
        "hides them (:mod:`.height_gate`). 1 = off (the default): the share is ~0.31 in crowd 50, ~0.05 in "
        "crowd 10; at 0.2 crowd 50 dev 110-112 cold 9.0 -> 10.0 held, MOTA 0.353 -> 0.346, true places 9.7 -> 11.7, "
        "0.390 -> 0.410; with predict_along_ray_measured + alone_behind_obstacles cold 14.7 -> 10.0 (0.420 -> "
        "0.374), true 14.3 -> 15.3 (0.468 -> 0.490)")
    coast_behind_obstacles_s: float = Field(
        0.0, ge=0, description="a track the scene's obstacles wholly hide from a camera that has it in its image is "
        "kept this long unseen, carried by the prediction, instead of ending after end.leave_after_s as one that "
        "left the view (0 = off, the default; PETS 2009 unchanged at 2)")


__all__ = ["CrowdConfig"]
