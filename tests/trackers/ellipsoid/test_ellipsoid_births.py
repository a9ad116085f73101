"""Births: proposals from unexplained foreground, and where people may appear (components by name)."""

import numpy as np
import pytest
from _ellipsoid_seen import one_person_seen

from worldtrack.errors import InputError
from worldtrack.foreground import make_foregrounds
from worldtrack.trackers.ellipsoid import EllipsoidConfig, EllipsoidTracker
from worldtrack.trackers.ellipsoid.args import People
from worldtrack.trackers.ellipsoid.births import BIRTH_PLACES, Anywhere, InEntryRegions, Nowhere


def _proposals(tracker, people=People(np.zeros((0, 2)), np.zeros(0), np.zeros(0)), first_frame=True):
    return tracker.births.propose(dict(tracker.last_masks), people, first_frame)


def test_a_person_nobody_explains_is_proposed_at_their_feet_by_each_camera_once():
    scene, person, bgs, tracker, images, real = one_person_seen(seed=3)
    proposals = _proposals(tracker)
    # Both cameras' blobs point at the same person: the second is within min_separation_m of the
    # first and is dropped. The proposer is recorded.
    assert len(proposals) == 1
    xy, cid, _ = proposals[0]
    assert cid in scene.cameras and np.hypot(*(xy - person)) < 0.35
    # A person already there explains the blob: nothing proposed.
    assert _proposals(tracker, People(person[None], np.array([1.65]), np.array([0.4]))) == []


def test_stepping_records_the_proposing_camera_on_the_person_not_in_the_output():
    scene, person, bgs, tracker, images, real = one_person_seen(seed=3)
    for config in (EllipsoidConfig(), EllipsoidConfig.paper()):
        fresh = EllipsoidTracker(scene, make_foregrounds(scene, bgs, "colour"), config)
        reported = fresh.step(images, 0.0)
        assert reported and all(tr.extra == {} for tr in reported)
        assert all(p.birth_camera in scene.cameras for p in fresh.position_map)


def test_where_people_may_appear_is_a_component_chosen_by_name():
    assert isinstance(BIRTH_PLACES["anywhere"](), Anywhere)
    assert isinstance(BIRTH_PLACES["entry"](), InEntryRegions) and isinstance(BIRTH_PLACES["none"](), Nowhere)
    with pytest.raises(InputError, match=r"^ellipsoid\.births\.where: expected one of anywhere, entry, none, got 'door'$"):
        BIRTH_PLACES["door"]
    scene, person, bgs, tracker, images, real = one_person_seen(seed=3)
    never = EllipsoidTracker(scene, make_foregrounds(scene, bgs, "colour"), EllipsoidConfig(births={"where": "none"}))
    assert never.step(images, 0.0) == [] and len(never.position_map) == 0
    # Only in entry regions after the first frame: this scene has none, so anywhere.
    entry = EllipsoidTracker(scene, make_foregrounds(scene, bgs, "colour"), EllipsoidConfig(births={"where": "entry"}))
    entry.last_masks = tracker.last_masks
    assert len(_proposals(entry, first_frame=False)) == 1


def test_entry_regions_keep_only_proposals_inside_them_after_the_first_frame():
    class Scene:
        entry_regions = ["door"]

        @staticmethod
        def entry_region_index(points):
            return np.array([0 if p[0] > 0 else -1 for p in points])

    proposals = [(np.array([1.0, 0.0]), "c1"), (np.array([-1.0, 0.0]), "c2")]
    entry = InEntryRegions()
    assert entry.keep(proposals, Scene, first_frame=True) == proposals
    assert [cid for _, cid in entry.keep(proposals, Scene, first_frame=False)] == ["c1"]


def _column_blob(view, xy, z0, z1, half_width=0.2):
    """A boolean image of a person-like column (floor place ``xy``, from height z0 to z1, m) in
    ``view``: the crop, its top-left pixel and its centroid, as the births see a blob."""
    cam = view.camera
    ray = xy - cam.centre[:2]
    side = np.array([-ray[1], ray[0]]) / np.hypot(*ray) * half_width
    corners = [(*(xy + s * side), z) for s, z in ((-1, z0), (1, z0), (1, z1), (-1, z1))]
    px = cam.project(np.array(corners, float))
    image = np.zeros((cam.height, cam.width), np.uint8)
    import cv2
    cv2.fillConvexPoly(image, np.round(px).astype(np.int32), 1)
    vs, us = np.nonzero(image)
    crop = image[vs.min():vs.max() + 1, us.min():us.max() + 1].astype(bool)
    return crop, (int(us.min()), int(vs.min())), np.array([us.mean(), vs.mean()])


def test_a_blob_from_feet_to_head_gives_the_persons_height_and_one_without_legs_is_placed_by_its_head():
    from worldtrack.trackers.ellipsoid.births import blob_position
    scene, person, bgs, tracker, images, real = one_person_seen(seed=3)
    view = tracker.views[sorted(tracker.views)[0]]
    whole = blob_position(view, *_column_blob(view, person, 0.0, 1.80), 1.65)
    assert whole is not None
    p, shown, share = whole
    assert share == 1.0
    assert np.hypot(*(p[:2] - person)) < 0.1 and abs(shown - 1.80) < 0.04
    # Legs the colour of the floor: the blob starts at the waist. Its lower end would put the
    # person metres too far along the line of sight; the head puts them within 0.2 m (1.65 m).
    torso = blob_position(view, *_column_blob(view, person, 0.9, 1.65), 1.65)
    assert torso is not None
    p, shown, share = torso
    assert shown is None and np.hypot(*(p[:2] - person)) < 0.2
    assert abs(share - (1.65 - 0.9) / 1.65) < 0.1   # the area test asks only for the part shown


def _known_beside(blob, origin, below: bool, rows: int = 6) -> np.ndarray:
    """An image reaching just past ``blob`` (a crop whose top-left pixel is ``origin``), nonzero on
    ``rows`` rows just above its top (or below its bottom) across its columns: a known person there."""
    crop, (u0, v0) = blob, origin
    known = np.zeros((v0 + crop.shape[0] + rows + 2, u0 + crop.shape[1] + 2), np.uint8)
    v = v0 + crop.shape[0] if below else max(0, v0 - rows)
    known[v:v + rows, u0:u0 + crop.shape[1]] = 1
    return known


def test_a_blob_whose_top_a_known_person_covers_is_placed_by_its_feet():
    from worldtrack.trackers.ellipsoid.births import blob_position
    scene, person, bgs, tracker, images, real = one_person_seen(seed=3)
    view = tracker.views[sorted(tracker.views)[0]]
    # The legs of a person in front of a known one, whose ellipse hides their upper body: read as a
    # whole person, the blob is too short and its top puts them far along the line of sight.
    legs = _column_blob(view, person, 0.0, 0.8)
    alone = blob_position(view, *legs, 1.65)
    assert alone is not None and np.hypot(*(alone[0][:2] - person)) > 1.0
    cut = blob_position(view, *legs, 1.65, known=_known_beside(legs[0], legs[1], below=False))
    assert cut is not None
    p, shown, share = cut
    assert shown is None and np.hypot(*(p[:2] - person)) < 0.1
    assert abs(share - 0.8 / 1.65) < 0.1          # the area test asks only for the part shown
    # The feet against a known person are not read as hidden: the blob is placed as without one.
    top = _column_blob(view, person, 0.6, 1.65)
    np.testing.assert_array_equal(blob_position(view, *top, 1.65, known=_known_beside(*top[:2], below=True))[0],
                                  blob_position(view, *top, 1.65)[0])
    far = np.zeros_like(_known_beside(legs[0], legs[1], below=False))
    np.testing.assert_array_equal(blob_position(view, *legs, 1.65, known=far)[0], alone[0])


def test_births_pass_the_known_people_to_the_blobs_only_when_asked(monkeypatch):
    from worldtrack.trackers.ellipsoid import births
    scene, person, bgs, tracker, images, real = one_person_seen(seed=3)
    seen = []
    real_position = births.blob_position
    monkeypatch.setattr(births, "blob_position",
                        lambda *a, **k: seen.append(k.get("known")) or real_position(*a, **k))
    known = People(np.array([[person[0] + 3.0, person[1]]]), np.array([1.65]), np.array([0.4]))
    for occlude in (False, True):
        fresh = EllipsoidTracker(scene, make_foregrounds(scene, bgs, "colour"),
                                 EllipsoidConfig(births={"people_occlude": occlude}))
        fresh.last_masks = tracker.last_masks
        seen.clear()
        assert len(_proposals(fresh, known)) == 1    # the person, 3 m from the known one, either way
        assert seen and all((k is not None) == occlude for k in seen)


def test_a_head_band_on_top_of_a_known_person_is_placed_by_its_head_not_by_its_lower_end():
    # Issue 37 (crowd 50): somebody behind a tracked person shows one band of head and shoulders
    # above them. Its lower end is where the tracked person's ellipse begins, not the feet.
    from worldtrack.trackers.ellipsoid.births import blob_position
    scene, person, bgs, tracker, images, real = one_person_seen(seed=3)
    for cid in sorted(tracker.views):
        view = tracker.views[cid]
        crop, origin, centroid = _column_blob(view, person, 1.35, 1.80)
        # Read as a whole person, the band's lower end puts them metres along the line of sight: it is
        # shorter than the tracker's height.min_px (60 px), so it tells no height to find that out.
        alone = blob_position(view, crop, origin, centroid, 1.80, (1.3, 2.1), 60)
        assert alone is not None and np.hypot(*(alone.xy[:2] - person)) > 2.0
        explained = np.zeros((view.camera.height, view.camera.width), np.uint8)
        explained[origin[1] + crop.shape[0]:, :] = 1     # a known person's ellipse right below the band
        band = blob_position(view, crop, origin, centroid, 1.80, (1.3, 2.1), 60, explained=explained)
        assert band is not None and band.height is None
        assert np.hypot(*(band.xy[:2] - person)) < 0.15   # the head, at the default height (here 1.80 m)
        # Legs under a known person's ellipse (somebody in front of them): still placed by the feet.
        crop, origin, centroid = _column_blob(view, person, 0.0, 0.9)
        explained[:] = 0
        explained[:origin[1], :] = 1
        legs = blob_position(view, crop, origin, centroid, 1.80, (1.3, 2.1), 60, explained=explained)
        assert legs is not None and np.hypot(*(legs.xy[:2] - person)) < 0.1


def test_the_size_test_past_people_expects_only_what_the_known_people_leave_unexplained():
    from worldtrack.trackers.ellipsoid.people_edges import unexplained_pixels
    scene, person, bgs, tracker, images, real = one_person_seen(seed=3)
    view = tracker.views[sorted(tracker.views)[0]]
    cam = view.camera
    explained = np.zeros((cam.height, cam.width), np.uint8)
    whole = view.visible_pixels(person, 1.65, 0.4)
    assert whole > 200 and unexplained_pixels(view, person, 1.65, 0.4, explained) == whole
    foot = cam.project(np.array([[*person, 0.0]]))[0]
    explained[:int(round(foot[1])) - 20, :] = 1           # somebody known covers all but the legs' 20 px
    part = unexplained_pixels(view, person, 1.65, 0.4, explained)
    assert 0 < part < 0.5 * whole


def test_births_past_people_is_the_crowd_setting_and_off_by_default():
    scene, person, bgs, tracker, images, real = one_person_seen(seed=3)
    assert tracker.births.past_people is False
    crowd = EllipsoidTracker(scene, make_foregrounds(scene, bgs, "colour"),
                             EllipsoidConfig(crowd={"births_past_people": True}))
    assert crowd.births.past_people is True
    # Nobody known: the same proposals as without it.
    crowd.last_masks = tracker.last_masks
    assert [tuple(np.round(q.xy, 6)) for q in _proposals(crowd)] == [tuple(np.round(q.xy, 6)) for q in _proposals(tracker)]
