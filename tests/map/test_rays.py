"""Each worker's own head and feet rays (map.head_rays): measured in its foreground, carried in the
observation beside format 2, and met by the fusion (pure functions, no server)."""

import math

import numpy as np

from worldtrack.geometry.camera import Camera
from worldtrack.map.config import MapConfig
from worldtrack.map.evidence import people_boxes
from worldtrack.map.fusion import FusionState, fuse_bucket
from worldtrack.map.messages import Estimate, Observation, decode_observation, encode_observation
from worldtrack.map.rays import ViewRay, ray_height, view_rays

WEST = Camera.look_at("west", 320, 240, [0.3, 2.5, 3.0], [6.0, 2.5, 0.0], hfov_deg=60)
EAST = Camera.look_at("east", 320, 240, [11.7, 2.5, 3.0], [6.0, 2.5, 0.0], hfov_deg=60)


def drawn(cam, people):
    """A foreground mask with each person of ``people`` (x, y, height, width) drawn as their box."""
    mask = np.zeros((cam.height, cam.width), np.uint8)
    for u0, v0, u1, v1, _ in people_boxes(cam, np.asarray(people, float)):
        mask[int(round(v0)):int(round(v1)), int(round(u0)):int(round(u1))] = 1
    return mask


def through(ray_o, d, z):
    """Where the ray from ``ray_o`` along ``d`` is at height ``z``: (x, y)."""
    s = (z - ray_o[2]) / d[2]
    return ray_o[:2] + s * d[:2]


def test_the_rays_go_through_the_head_and_feet_the_foreground_shows_not_the_estimates():
    truth = [5.0, 2.5, 1.85, 0.45]
    mask = drawn(WEST, [truth])
    # The worker's tracker slid 0.6 m away along the ray with the map's 1.7 m height.
    r, = view_rays(WEST, mask, np.array([[5.6, 2.5, 1.7, 0.45]]), [7])
    o = np.array([r.ox, r.oy, r.oz])
    head, feet = np.array([r.hx, r.hy, r.hz]), np.array([r.fx, r.fy, r.fz])
    assert r.id == 7 and np.allclose(through(o, head, 1.85), [5.0, 2.5], atol=0.12)
    assert np.allclose(through(o, feet, 0.0), [5.0, 2.5], atol=0.12)


def test_a_person_behind_another_gives_no_feet_ray_and_the_one_in_front_not_the_others_head():
    front, back = [4.0, 2.5, 1.6, 0.45], [6.0, 2.85, 1.9, 0.45]    # the taller one behind, half covered
    rays = {r.id: r for r in view_rays(WEST, drawn(WEST, [front, back]), np.array([front, back]), [1, 2])}
    o = np.array([rays[1].ox, rays[1].oy, rays[1].oz])
    assert np.allclose(through(o, np.array(rays[1][4:7]), 1.6), [4.0, 2.5], atol=0.12)
    assert np.allclose(through(o, np.array(rays[2][4:7]), 1.9), [6.0, 2.85], atol=0.12)
    assert abs(through(o, np.array(rays[2][7:10]), 0.0)[0] - 6.0) < 0.1     # the depth of the feet's visible side
    back[1] = 2.5                                                  # right behind: feet hidden, head above the other's
    rays = {r.id: r for r in view_rays(WEST, drawn(WEST, [front, back]), np.array([front, back]), [1, 2])}
    assert math.isnan(rays[2].fx) and np.allclose(through(o, np.array(rays[2][4:7]), 1.9), [6.0, 2.5], atol=0.12)
    # The one in front: feet shown; above their head the other's silhouette goes on, so no head ray.
    assert math.isnan(rays[1].hx) and np.allclose(through(o, np.array(rays[1][7:10]), 0.0), [4.0, 2.5], atol=0.12)


def test_a_sliver_at_the_image_edge_gives_no_rays():
    mask = np.zeros((240, 320), np.uint8)
    mask[60:200, 0:6] = 1
    xy = WEST.backproject(np.array([[3.0, 200.0]]), 0.0)[0][:2]
    assert view_rays(WEST, mask, np.array([[*xy, 1.7, 0.45]]), [1]) == []


def test_the_rays_travel_in_a_field_of_their_own_that_older_readers_do_not_read():
    r = ViewRay(4, 0.3, 2.5, 3.0, 0.9, 0.0, -0.3, float("nan"), float("nan"), float("nan"))
    o = Observation("west", 1.0, "w1", 10, 1.01, (Estimate(4, 5.0, 2.5, 1.7, 0.45, 0, 0, 0.5, 0.8, True),), rays=(r,))
    fields = encode_observation(o)
    back = decode_observation(fields)
    assert fields["v"] == "2" and back.people[0][:10] == o.people[0][:10]
    assert back.rays[0][:7] == r[:7] and math.isnan(back.rays[0].fx)
    assert decode_observation({k: v for k, v in fields.items() if k != "rays"}).rays == ()    # an older worker
    assert decode_observation(fields | {"rays": '[99, [[1, 2]]]'}).rays == ()                # a later ray format
    assert "rays" not in encode_observation(o.__class__(*[getattr(o, f) for f in ("camera", "t", "worker", "frame",
                                                                                 "sent", "people")]))


def _opposite_workers(truth, west_x, east_x, t=5.0):
    """Both workers see ``truth`` (x, y, h, w); their trackers put it at ``west_x`` / ``east_x``, 1.7 m tall."""
    obs = []
    for cam, x, worker in ((WEST, west_x, "w1"), (EAST, east_x, "w2")):
        e = Estimate(7, x, 2.5, 1.7, 0.45, 0, 0, 0.5, 0.8, True)
        rays = tuple(view_rays(cam, drawn(cam, [truth]), np.array([[x, 2.5, 1.7, 0.45]]), [7]))
        obs.append(Observation(cam.id, t, worker, int(t * 10), t + 0.01, (e,), rays=rays))
    return obs


def test_the_map_takes_the_height_two_facing_workers_head_rays_tell_when_asked():
    truth = [5.3, 2.5, 1.85, 0.45]
    heights = {}
    for on in (False, True):
        state = FusionState()
        for b in range(50, 54):          # both slid along the one axis they share, with the map's 1.7 m
            p, = fuse_bucket(state, b, _opposite_workers(truth, 6.0, 4.9, b / 10), MapConfig(head_rays=on)).people
            heights.setdefault(on, []).append(p.height)
    assert heights[False] == [1.7] * 4                                  # the default: the estimates' height
    assert heights[True][:2] == [1.7, 1.7] and abs(heights[True][-1] - 1.85) < 0.04    # from the third on
    assert len(state.people[7].ray_heights) == 4


def test_head_rays_that_do_not_agree_tell_no_height():
    o1, o2 = np.array([0.3, 2.5, 3.0]), np.array([11.7, 2.5, 3.0])
    unit = lambda v: v / np.linalg.norm(v)        # noqa: E731
    agree = [ViewRay(7, *o, *unit(np.array([5.0, 2.5, 1.85]) - o)) for o in (o1, o2)]
    assert abs(ray_height(agree, np.array([5.2, 2.5, 1.7])) - 1.85) < 0.12
    # East's "top of the head" is somebody else's, 1.5 m farther on: the rays meet 0.7 m off the
    # estimates, or not at all.
    other = [agree[0], ViewRay(7, *o2, *unit(np.array([3.5, 2.5, 1.85]) - o2))]
    assert ray_height(other, np.array([5.2, 2.5, 1.7])) is None
    assert ray_height(agree[:1], np.array([5.2, 2.5, 1.7])) is None          # one camera


def tangent_to_head(o, crown, radius=0.1):
    """The ray from ``o`` over the top of a spherical head (``radius`` m) whose crown is at ``crown``."""
    centre = crown - [0.0, 0.0, radius]
    flat = np.append(centre[:2] - o[:2], 0.0)
    dist, drop = np.linalg.norm(flat), o[2] - centre[2]
    below = math.atan2(drop, dist) - math.asin(radius / math.hypot(dist, drop))    # over the head, not through it
    return ViewRay(7, *o, *(flat / dist * math.cos(below) - [0.0, 0.0, math.sin(below)]))


def test_the_height_from_rays_over_the_head_and_to_the_near_edge_of_the_feet():
    crown, o1, o2 = np.array([4.0, 2.5, 1.85]), np.array([0.3, 2.5, 3.0]), np.array([11.7, 2.5, 3.0])
    rays = [tangent_to_head(o, crown) for o in (o1, o2)]
    assert abs(ray_height(rays, np.array([4.4, 2.5, 1.7])) - 1.85) < 0.001         # exact for a round head
    # With the feet: west's feet ray to the near edge of the feet fits; one 0.6 m beyond does not.
    unit = lambda v: v / np.linalg.norm(v)        # noqa: E731
    edge = ViewRay(7, *o1, *rays[0][4:7], *unit(np.array([4.0 - 0.15, 2.5, 0.0]) - o1))
    beyond = ViewRay(7, *o1, *rays[0][4:7], *unit(np.array([4.6, 2.5, 0.0]) - o1))
    assert abs(ray_height([edge, rays[1]], np.array([4.4, 2.5, 1.7])) - 1.85) < 0.01
    assert ray_height([beyond, rays[1]], np.array([4.4, 2.5, 1.7])) is None


def test_no_height_from_a_camera_that_sees_the_person_from_above():
    o1, o2 = np.array([0.3, 2.5, 3.0]), np.array([11.7, 2.5, 3.0])
    unit = lambda v: v / np.linalg.norm(v)        # noqa: E731

    def seen(crown):                   # head and feet rays of both cameras, as a round head and feet show
        edge = lambda o: crown * [1, 1, 0] + 0.15 * unit((o - crown) * [1, 1, 0])      # noqa: E731
        return [ViewRay(7, *o, *tangent_to_head(o, crown)[4:7], *unit(edge(o) - o)) for o in (o1, o2)]
    crown = np.array([10.2, 2.5, 1.8])                    # 1.5 m from east's foot point, 3 m up
    assert ray_height(seen(crown), crown - [0.3, 0.0, 0.1]) is None
    assert abs(ray_height(seen(crown - [1.0, 0, 0]), crown - [1.3, 0.0, 0.1]) - 1.8) < 0.01      # 2.5 m: counted


def test_the_ray_heights_are_handed_over_and_without_them_the_hand_over_is_as_before():
    state = FusionState()
    for b in range(50, 53):
        fuse_bucket(state, b, _opposite_workers([5.3, 2.5, 1.85, 0.45], 6.0, 4.9, b / 10), MapConfig(head_rays=True))
    back = FusionState.from_json(state.to_json())
    assert back.people[7].ray_heights == state.people[7].ray_heights and len(back.people[7].ray_heights) == 3
    plain = FusionState()
    fuse_bucket(plain, 50, _opposite_workers([5.3, 2.5, 1.85, 0.45], 6.0, 4.9), MapConfig())
    assert "ray_heights" not in plain.to_json() and FusionState.from_json(plain.to_json()).people[7].ray_heights == []


def test_the_map_height_holds_while_the_ray_heights_stay_within_the_deadband():
    from worldtrack.map.fusion import provisional_state
    from worldtrack.map.rays import map_height
    truth = [5.3, 2.5, 1.85, 0.45]                      # the rays tell ~1.85 m, the estimates 1.7 m
    for deadband, expect in ((0.25, 1.7), (0.05, 1.85)):
        cfg = MapConfig(head_rays=True, ray_height_deadband_m=deadband)
        state = FusionState()
        for b in range(50, 54):
            p, = fuse_bucket(state, b, _opposite_workers(truth, 6.0, 4.9, b / 10), cfg).people
        assert abs(p.height - expect) < 0.04
        p, = provisional_state(state, {54: _opposite_workers(truth, 6.0, 4.9, 5.4)}, cfg).people
        assert abs(p.height - expect) < 0.04           # the live map holds it too
    assert map_height([1.80, 1.84, 1.90], 1.82, 0.03) == 1.82        # within: held
    assert map_height([1.80, 1.86, 1.90], 1.82, 0.03) == 1.86        # beyond: the median
    assert map_height([1.80, 1.84, 1.90], 1.82, 0.0) == 1.84         # off: always the median
    assert map_height([1.80, 1.84, 1.90], math.nan, 0.03) == 1.84    # no height yet
