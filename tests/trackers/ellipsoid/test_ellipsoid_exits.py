"""A track lost at the image's edge gets no id back by place alone (:mod:`worldtrack.trackers.ellipsoid.exits`)."""

import numpy as np
from _ellipsoid_scenes import drawn_frame, noise_backgrounds, one_camera_scene

from worldtrack.config import with_overrides
from worldtrack.foreground import make_foregrounds
from worldtrack.trackers.base import Frame
from worldtrack.trackers.ellipsoid import EllipsoidConfig, EllipsoidTracker
from worldtrack.trackers.ellipsoid.config import LostConfig
from worldtrack.trackers.ellipsoid.exits import in_image_share, left_the_view
from worldtrack.trackers.ellipsoid.reentry import LostTracks

FPS = 10.0


def _views(**settings):
    scene = one_camera_scene()
    return EllipsoidTracker(scene, make_foregrounds(scene, {"cam": np.zeros((120, 160, 3), np.uint8)}, "colour"),
                            with_overrides(EllipsoidConfig(), settings)).views


def test_the_share_inside_the_image_is_one_in_view_falls_at_the_edge_and_ignores_obstacles():
    view = _views()["cam"]
    # At y = 1.5 m a person is whole in the image from x about -2.8 to 0.8 m, gone past 1.5 m.
    shares = [in_image_share(view, np.array([x, 1.5]), 1.65, 0.4) for x in (-1.0, 1.0, 1.2, 1.6)]
    assert shares[0] > 0.95 and 0.2 < shares[1] < 0.9 and shares[2] < shares[1] and shares[3] == 0.0
    assert in_image_share(view, np.array([-1.0, -1.7]), 1.65, 0.4) < 0.5      # under the camera
    assert left_the_view([view], np.array([1.0, 1.5]), 1.65, 0.4, 0.9)
    assert not left_the_view([view], np.array([-1.0, 1.5]), 1.65, 0.4, 0.9)


def test_a_person_lost_at_the_edge_is_not_given_back_by_place():
    for left_view, back in ((True, None), (False, 4)):
        lost = LostTracks(LostConfig())
        lost.file(4, xy=(0.0, 0.0), v=(1.0, 0.0), t=0.0, left_view=left_view)
        assert lost.claim((0.5, 0.0), t=0.5, taken=lambda pid: False) is back
    # Nor somebody else's id when the one who left is the nearest: the newcomer is as likely them.
    lost = LostTracks(LostConfig(margin_m=0.5))
    lost.file(4, xy=(0.0, 0.0), v=(0.0, 0.0), t=0.0, left_view=True)
    lost.file(5, xy=(1.2, 0.0), v=(0.0, 0.0), t=0.0)
    assert lost.claim((0.1, 0.0), t=0.5, taken=lambda pid: False) is None
    assert lost.claim((1.3, 0.0), t=0.5, taken=lambda pid: False) == 5


def _out_and_in(border_share: float) -> list[list[int]]:
    """Ids per frame: a person walks at 1 m/s out of the image's right edge (gone by frame 25);
    1 s later somebody else stands 0.6 m from where they were last whole in view."""
    scene = one_camera_scene()
    rng = np.random.default_rng(5)
    bg = noise_backgrounds(scene, rng)["cam"]
    cfg = with_overrides(EllipsoidConfig(), {"lost.border_share": border_share, "identity.reid_distance": 0.0})
    tr = EllipsoidTracker(scene, make_foregrounds(scene, {"cam": bg}, "colour"), cfg)
    ids = []
    for i in range(50):
        people = [(-1.0 + i / FPS, 1.5)] if i < 25 else ([] if i < 35 else [(0.6, 2.0)])
        tracks = tr.step({"cam": Frame(drawn_frame(scene, bg, people, rng), i / FPS, i)}, i / FPS)
        ids.append([t.id for t in tracks])
    return ids


def test_somebody_entering_where_a_person_walked_out_of_view_gets_a_new_id():
    default = _out_and_in(0.0)
    assert default[5:15] == [[1]] * 10 and default[-5:] == [[1]] * 5    # main: the id given back by place
    border = _out_and_in(0.9)
    assert border[5:15] == [[1]] * 10 and border[-5:] == [[2]] * 5
