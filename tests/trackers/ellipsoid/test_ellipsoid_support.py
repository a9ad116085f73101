"""Support (how much of each person's ellipse is their own foreground): kernel against reference."""

import numpy as np
import pytest
from _ellipsoid_scenes import lab_scene, person_mask

from worldtrack.trackers.ellipsoid.args import DrawArgs, camera_args
from worldtrack.trackers.ellipsoid.forms import person_forms
from worldtrack.trackers.ellipsoid.support import track_support, track_support_reference


@pytest.mark.parametrize("cam_id", ["cam1", "cam2"])
def test_track_support_equals_the_reference(cam_id):
    lab = lab_scene()
    cam = lab.cameras[cam_id]
    args = camera_args(cam, 5.0, lab.occlusion(cam_id).floor_distance)
    rng = np.random.default_rng(4)
    for trial in range(5):
        xy = np.column_stack([rng.uniform(-2, 0, 4), rng.uniform(0.5, 3.2, 4)])   # some behind the desk
        forms = person_forms(args, xy, rng.uniform(1.5, 1.9, 4), rng.uniform(0.35, 0.5, 4), DrawArgs(0.1, 0.0))
        mask = sum(person_mask(cam, p, 1.65, 0.4) for p in xy[:3]).clip(0, 1).astype(np.uint8)
        mask[rng.random(mask.shape) < 0.05] = 2                    # unsure pixels are nobody's evidence
        covers = rng.random(4) < 0.7
        for target in (0, 200):
            got = track_support(args, mask, forms, target, covers)
            want = track_support_reference(args, mask, forms, target, covers)
            for a, b in zip(got, want):
                np.testing.assert_array_equal(a, b)
    visible, own, own_fg, area, hidden = got
    assert (own <= visible).all() and (own_fg <= own).all() and (visible > 0).any()


def test_a_ghost_beside_a_person_has_no_support_and_one_inside_them_no_own_pixels():
    lab = lab_scene()
    cam = lab.cameras["cam1"]
    args = camera_args(cam, 5.0)
    person, beside, inside = np.array([-1.0, 1.0]), np.array([-0.2, 1.0]), np.array([-1.0, 1.05])
    mask = person_mask(cam, person, 1.65, 0.4)
    forms = person_forms(args, np.array([person, beside, inside]), np.full(3, 1.65), np.full(3, 0.4),
                         DrawArgs(0.1, 0.0))
    visible, own, own_fg, _, _ = track_support(args, mask, forms, 0, np.array([True, False, False]))
    assert own_fg[0] / own[0] > 0.99                  # the person: all their own pixels foreground
    assert own_fg[1] / own[1] < 0.05                  # the ghost beside: its own pixels are floor
    assert own[2] / visible[2] < 0.3                  # the duplicate inside: covered by the person
