"""Seed 004's particle tracker on small rendered scenes with exact ground truth.

People are the filled outlines of upright ellipsoids (the conic of each ellipsoid at pixel centres,
drawn far to near), in saturated colours over a smooth random colour texture with seeded sensor
noise (σ = 2). One camera 3 m up looks across a 6 × 6 m floor; the entry region is a 1.2 m strip
on the left edge of the view.

Accuracy bound. An ellipsoid's silhouette is exactly what the height column tests, so the column
is sharp here; what remains is the pixel grid (one image row at the feet spans 0.03–0.08 m of floor
at 3–6 m in this 320×240, 70° view), the column's 0.1 m steps and the particles' spread. The
tracker reaches 0.02–0.04 m mean error on a walker here; 0.10 m is asserted.
"""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from worldtrack.errors import InputError
from worldtrack.foreground.background import StaticBackground
from worldtrack.geometry.quadric import ellipse_mask, ellipsoid_conics, person_ellipsoid
from worldtrack.trackers.base import Frame
from worldtrack.scene import scene_from_dict
from worldtrack.trackers import make_tracker
from worldtrack.trackers.particle import ParticleConfig, ParticleTracker, image_box, image_boxes
from worldtrack.trackers.particle.likelihood import (CameraLikelihood, column_counts_reference, hit_image,
                                                     occluder_layers, owner_image, point_values_reference,
                                                     hit_labels, thresholded_difference)
from worldtrack.trackers.particle.sampling import (FloorRegion, _lookup, _valley, _valley_reference, bimodal_split,
                                                   polygon_distance, splittable, stratified_resample,
                                                   systematic_resample)

from _render import texture  # tests/trackers/_render.py

W, H = 320, 240
CAM = {"id": "cam", "image_size": [W, H], "position": [0, -1, 3], "look_at": [0, 3.5, 0.5], "hfov_deg": 70}
CAM2 = {"id": "cam2", "image_size": [W, H], "position": [5, 7, 3], "look_at": [0, 3.5, 0.5], "hfov_deg": 70}
FLOOR = {"walkable": [{"outer": [[-3, 0.5], [3, 0.5], [3, 6.5], [-3, 6.5]]}]}
DOOR = [{"name": "door", "polygon": [[-2.9, 2.0], [-1.7, 2.0], [-1.7, 4.0], [-2.9, 4.0]]}]
COLOURS = [(40, 30, 200), (200, 60, 30), (30, 170, 40), (170, 40, 170)]
HEIGHT, WIDTH = 1.7, 0.45
FPS = 10.0


def make_scene(entry: bool = True, cameras=(CAM,)):
    d = {"name": "particle-test", "cameras": list(cameras), "floor": FLOOR,
         "people": {"height": HEIGHT, "width": WIDTH}}
    if entry:
        d["entry_regions"] = DOOR
    return scene_from_dict(d)


def render(cam, background, people, rng) -> np.ndarray:
    """``background`` with ellipsoid people ``(x, y[, height])`` drawn far to near, plus noise σ = 2."""
    img = background.astype(np.float32)
    order = sorted(range(len(people)), key=lambda k: -np.hypot(people[k][0] - cam.centre[0], people[k][1] - cam.centre[1]))
    for k in order:
        p = people[k]
        h = p[2] if len(p) > 2 else HEIGHT
        centres, radii = person_ellipsoid([p[:2]], h, WIDTH)
        C = ellipsoid_conics(cam.P, centres, radii)[0]
        img[ellipse_mask(C, (H, W))] = COLOURS[k % len(COLOURS)]
    img += rng.normal(0.0, 2.0, img.shape)
    return np.clip(img, 0, 255).astype(np.uint8)


def run(tracker, scene, backgrounds, paths, n, seed=0):
    """Step ``tracker`` over ``n`` frames; ``paths(t) -> list of (x, y[, h])``. Returns [(t, truth, tracks)]."""
    rng = np.random.default_rng(seed)
    out = []
    for k in range(n):
        t = k / FPS
        people = paths(t)
        frames = {cid: Frame(render(cam, backgrounds[cid], people, rng), t, k) for cid, cam in scene.cameras.items()}
        out.append((t, people, tracker.step(frames, t)))
    return out


def tracker_for(scene, scene_seed=0, **options):
    """A tracker with static backgrounds. An ellipsoid's lowest point is on its axis (a person's is
    the near side of the feet), so the column stands on the particle: ``surface_offset=0``."""
    bgs = {cid: texture(i + 10 * scene_seed) for i, cid in enumerate(scene.cameras)}
    fgs = {cid: StaticBackground(bg, 30.0, "colour") for cid, bg in bgs.items()}
    return ParticleTracker(scene, fgs, ParticleConfig(**{"surface_offset": 0.0, **options})), bgs


def walker(t):
    """Enters from the door region and walks right at 1 m/s."""
    return [(-2.3 + 1.0 * t, 3.0)]


# ---------------------------------------------------------------------------- kernels vs references

@pytest.mark.parametrize("dist", [None, [-0.2, 0.05, 0.001, -0.002, 0.0]])
@pytest.mark.parametrize("radius", [0.0, 0.1])
@pytest.mark.parametrize("px_scale", [0.0, 0.25])
def test_column_kernel_agrees_with_reference(dist, radius, px_scale):
    spec = dict(CAM, distortion=dist) if dist else CAM
    cam = make_scene(cameras=(spec,)).cameras["cam"]
    rng = np.random.default_rng(1)
    hit = (cv2.GaussianBlur(rng.random((H, W)).astype(np.float32), (0, 0), 4) > 0.5).astype(np.uint8)
    hit[(hit == 1) & (rng.random((H, W)) < 0.2)] = 2                      # shadows: no evidence
    xy = np.column_stack([rng.uniform(-3.5, 3.5, 3000), rng.uniform(-1.5, 7.0, 3000)])
    heights = np.concatenate([[-0.2, -0.1], np.arange(20) * 0.1, [2.0, 2.1]])
    tops = rng.uniform(1.4, 2.0, len(xy))
    boxes = [(40, 120, 30, 200), (100, 180, 0, 120), None]
    owner = owner_image((H, W), boxes)
    occluders = occluder_layers((H, W), boxes, [2.0, 4.5, 3.0])
    cl = CameraLikelihood(cam)
    for box, n_above, sigma, me in ((None, 2, 0.0, -1), (boxes[0], 2, 0.1, 0), (None, 0, 0.05, -1),
                                    (boxes[1], 2, 0.1, 1)):
        hs = heights if n_above else heights[:-2]
        args = dict(on=2.77, off=-1.56, k_min=10, radius=radius, below=-2.77, n_below=2, n_above=n_above,
                    owner=owner, box=box, tops=tops, top_sigma=sigma, px_scale=px_scale,
                    occluders=occluders if me >= 0 else None, me=me, margin=0.3)
        counts, ratio, top, seen = cl.column(hit, xy, hs, **args)
        r_counts, r_ratio, r_top, r_seen = column_counts_reference(cam, hit, xy, hs, **args)
        np.testing.assert_array_equal(counts, r_counts)
        np.testing.assert_array_equal(seen, r_seen)
        np.testing.assert_allclose(ratio, r_ratio, rtol=0, atol=1e-9)
        same = top == r_top
        # Ties between tops (equal scores up to rounding) may resolve either way.
        assert same.mean() > 0.999
        assert seen.sum() > 1000 and counts.max() > 10  # the test exercises real hits


def test_kernels_read_each_particle_with_its_own_filters_box():
    """The particles of three filters in one call (interleaved): each particle reads with its own
    filter's box and occluder index — the same as one call per filter, and as the references."""
    cam = make_scene().cameras["cam"]
    rng = np.random.default_rng(4)
    hit = (cv2.GaussianBlur(rng.random((H, W)).astype(np.float32), (0, 0), 4) > 0.5).astype(np.uint8)
    hit[(hit == 1) & (rng.random((H, W)) < 0.2)] = 2
    F = thresholded_difference(rng.uniform(0, 100, (H, W)).astype(np.float32), 30.0)
    boxes = [(40, 120, 30, 200), (100, 180, 0, 120), None]
    owner = owner_image((H, W), boxes)
    occluders = occluder_layers((H, W), boxes, [2.0, 4.5, 3.0])
    n = 3000
    xy = np.column_stack([rng.uniform(-2.5, 2.5, n), rng.uniform(0.5, 6.0, n)])
    xyz = np.column_stack([xy, rng.uniform(0.0, 2.0, n)])
    which = rng.integers(0, 3, n)
    hs = np.concatenate([[-0.2, -0.1], np.arange(20) * 0.1, [2.0, 2.1]])
    args = dict(on=2.77, off=-1.56, k_min=10, radius=0.1, below=-2.77, n_below=2, n_above=2, owner=owner,
                tops=rng.uniform(1.4, 2.0, n), top_sigma=0.1, occluders=occluders, margin=0.3)
    cl = CameraLikelihood(cam)
    batched = cl.column(hit, xy, hs, box=boxes, me=[0, 1, 2], which=which, **args)
    one_by_one = [np.zeros_like(a) for a in batched]
    point, point_one = cl.point(F, xyz, owner, boxes, which), [np.zeros(n), np.zeros(n, dtype=bool)]
    for f in range(3):
        sel = which == f
        part = cl.column(hit, xy[sel], hs, box=boxes[f], me=f, **{**args, "tops": args["tops"][sel]})
        for a, b in zip(one_by_one, part):
            a[sel] = b
        for a, b in zip(point_one, cl.point(F, xyz[sel], owner, boxes[f])):
            a[sel] = b
    for a, b in zip(batched, one_by_one):
        np.testing.assert_array_equal(a, b)
    for a, b in zip(point, point_one):
        np.testing.assert_array_equal(a, b)
    reference = column_counts_reference(cam, hit, xy, hs, box=boxes, me=[0, 1, 2], which=which, **args)
    for i in (0, 3):                                                    # counts, seen
        np.testing.assert_array_equal(batched[i], reference[i])
    np.testing.assert_allclose(batched[1], reference[1], rtol=0, atol=1e-9)
    for a, b in zip(point, point_values_reference(cam, F, xyz, owner, boxes, which)):
        np.testing.assert_array_equal(a, b)
    # The boxes matter: read with the wrong filters' boxes, many particles score otherwise.
    wrong = cl.column(hit, xy, hs, box=boxes, me=[0, 1, 2], which=(which + 1) % 3, **args)
    assert (wrong[1] != batched[1]).sum() > 100
    assert (cl.point(F, xyz, owner, boxes, (which + 1) % 3)[0] != point[0]).sum() > 100


def test_batched_likelihood_equals_one_call_per_filter():
    """``step`` reads all tracking filters in one likelihood call: the same values as one call per
    filter with its own box, occluder index and colours (three people who stood apart long enough
    for each filter to learn its colours; then the third stands behind the second)."""
    scene = make_scene(entry=False)
    apart = [(-1.5, 3.0), (0.0, 2.5), (1.5, 3.5)]
    tracker, bgs = tracker_for(scene, births="none")
    for i, (x, y) in enumerate(apart, start=1):
        tracker.init_track(x, y, track_id=i)
    run(tracker, scene, bgs, lambda t: apart, 6)
    fs = sorted(tracker.filters, key=lambda f: f.track.id)
    assert len(fs) == 3 and all(f.colours["cam"].hist is not None for f in fs)
    people = apart[:2] + [(0.0, 4.5)]
    fs[2].xyz = fs[2].xyz + [-1.5, 1.0, 0.0]
    images = tracker._images({"cam": Frame(render(scene.camera("cam"), bgs["cam"], people,
                                                  np.random.default_rng(7)), 1.0, 10)})
    centres = [f.xyz[:, :2].mean(axis=0) for f in fs]
    boxes = tracker._boxes([f.track for f in fs], centres, tracker.config.box_margin)
    owners = {"cam": owner_image((H, W), boxes["cam"])}
    occluders = {"cam": occluder_layers((H, W), boxes["cam"], scene.camera("cam").floor_rays(np.array(centres))[1])}
    xyz, h = np.concatenate([f.xyz for f in fs]), np.concatenate([f.h for f in fs])
    which = np.repeat(np.arange(3), [len(f.xyz) for f in fs])
    batched = tracker.likelihood(xyz, images, owners, boxes, h, occluders, [0, 1, 2], [f.colours for f in fs], which)
    for i, f in enumerate(fs):
        one = tracker.likelihood(f.xyz, images, owners, {"cam": boxes["cam"][i]}, f.h, occluders, i, f.colours)
        for a, b in zip(batched, one):
            np.testing.assert_array_equal(a[which == i], b)
    u0, u1, v0, v1 = boxes["cam"][2]
    assert occluders["cam"].depth_for(2)[v0:v1, u0:u1].min() < 4.0      # the third is behind the second
    # Each filter's own colours and box count: swapping either changes the values.
    colours = [f.colours for f in fs]
    for swapped in (tracker.likelihood(xyz, images, owners, boxes, h, occluders, [0, 1, 2], colours[::-1], which),
                    tracker.likelihood(xyz, images, owners, {"cam": boxes["cam"][::-1]}, h, occluders, [2, 1, 0],
                                       colours, which)):
        assert not np.array_equal(swapped[0], batched[0])


def test_occluder_layers_keep_the_two_nearest_boxes():
    boxes = [(0, 10, 0, 10), (5, 15, 5, 15), None, (8, 12, 8, 12)]
    near1, id1, near2 = occluder_layers((20, 20), boxes, [3.0, 2.0, 1.0, 4.0])
    assert (near1[0, 0], id1[0, 0], near2[0, 0]) == (3.0, 0, np.inf)
    assert (near1[9, 9], id1[9, 9], near2[9, 9]) == (2.0, 1, 3.0)          # boxes 0, 1, 3 overlap here
    assert (near1[11, 11], id1[11, 11], near2[11, 11]) == (2.0, 1, 4.0)
    assert (near1[19, 19], id1[19, 19]) == (np.inf, -1)
    # Reused for other boxes: the old ones are cleared, the result is as if made afresh.
    reused = occluder_layers((20, 20), [(2, 6, 12, 18)], [5.0], out=occluder_layers((20, 20), boxes, [3, 2, 1, 4]))
    fresh = occluder_layers((20, 20), [(2, 6, 12, 18)], [5.0])
    for a, b in zip(reused, fresh):
        np.testing.assert_array_equal(a, b)
    depth = occluder_layers((20, 20), boxes, [3.0, 2.0, 1.0, 4.0]).depth_for(1)
    assert depth[9, 9] == 3.0 and depth[11, 11] == 4.0 and depth[0, 0] == 3.0


def test_a_person_behind_another_is_occluded_not_background():
    """A column standing behind a nearer tracked person reads that person's box as no evidence; in
    front of (or beside) it, the box still reads background (explained by the other person)."""
    scene = make_scene(entry=False)
    cam = scene.cameras["cam"]
    cl = CameraLikelihood(cam)
    hs = np.concatenate([[-0.2, -0.1], np.arange(20) * 0.1, [2.0, 2.1]])
    near, far = np.array([0.0, 2.0]), np.array([0.0, 4.0])      # on one line of sight of the camera
    # The far person's image: only its head shows above the near person's box.
    hit = np.zeros((H, W), np.uint8)
    far_box = image_box(cam, *far, WIDTH, HEIGHT, 0.0)
    near_box = image_box(cam, *near, WIDTH, HEIGHT, 0.05)
    hit[far_box[2]:far_box[3], far_box[0]:far_box[1]] = 1
    hit[near_box[2]:near_box[3], near_box[0]:near_box[1]] = 1
    boxes = [near_box, far_box]
    owner = owner_image((H, W), boxes)
    depth = [float(np.hypot(*(p - cam.centre[:2]))) for p in (near, far)]
    args = dict(on=2.77, off=-1.56, k_min=10, radius=0.0, below=-2.77, n_below=2, n_above=2, owner=owner)
    plain = cl.column(hit, far[None], hs, box=far_box, **args)
    occluded = cl.column(hit, far[None], hs, box=far_box, occluders=occluder_layers((H, W), boxes, depth), me=1,
                         margin=0.3, **args)
    # Behind the near person every hidden sample cost `off` before; now it costs nothing.
    assert occluded[1][0] > plain[1][0] + 5 * 1.56
    # Every sample up to the person's 1.7 m counts (hits, or no evidence behind the near person).
    assert occluded[0][0] == 18 and plain[0][0] < 18
    # The near person's column does not gain from the far person's box (it is farther, so explained).
    a = cl.column(hit, near[None], hs, box=near_box, **args)
    b = cl.column(hit, near[None], hs, box=near_box, occluders=occluder_layers((H, W), boxes, depth), me=0,
                  margin=0.3, **args)
    assert a[1][0] == b[1][0]


def test_column_stands_on_the_near_surface():
    """Each camera's column stands ``surface_offset`` nearer to it than the particle, on the floor
    line from the camera's foot point."""
    scene = make_scene(cameras=(CAM, CAM2))
    tracker = ParticleTracker(scene, {cid: StaticBackground(texture(0), 30.0, "colour") for cid in scene.cameras},
                              ParticleConfig(surface_offset=0.25))
    xy = np.array([[0.0, 3.0], [1.0, 2.0]])
    for cid, cl in tracker._cams.items():
        c = scene.cameras[cid].centre[:2]
        moved = tracker._near_surface(xy, cl)
        np.testing.assert_allclose(np.hypot(*(xy - c).T) - np.hypot(*(moved - c).T), 0.25, atol=1e-12)
        cross = (xy - c)[:, 0] * (moved - c)[:, 1] - (xy - c)[:, 1] * (moved - c)[:, 0]
        np.testing.assert_allclose(cross, 0.0, atol=1e-12)               # on the same line of sight
    plain = ParticleTracker(scene, {"cam": StaticBackground(texture(0), 30.0, "colour")},
                            ParticleConfig(surface_offset=0.0))
    assert np.array_equal(plain._near_surface(xy, plain._cams["cam"]), xy)


def test_point_kernel_agrees_with_reference():
    cam = make_scene().cameras["cam"]
    rng = np.random.default_rng(2)
    F = thresholded_difference(rng.uniform(0, 100, (H, W)).astype(np.float32), 30.0)
    xyz = np.column_stack([rng.uniform(-3.5, 3.5, 5000), rng.uniform(-1.5, 7.0, 5000), rng.uniform(-0.5, 2.5, 5000)])
    owner = owner_image((H, W), [(50, 150, 50, 150)])
    for box in (None, (50, 150, 50, 150)):
        v, s = CameraLikelihood(cam).point(F, xyz, owner, box)
        rv, rs = point_values_reference(cam, F, xyz, owner, box)
        np.testing.assert_array_equal(s, rs)
        np.testing.assert_array_equal(v, rv)
    assert s.sum() > 1000


# ---------------------------------------------------------------------------- the paper's Fig. 5 argument

def test_column_tells_the_person_from_a_point_on_the_same_line_of_sight():
    """A particle inside the person and one on the floor behind it, on the same line of sight, project
    to the same pixel: the point likelihood (eq. 7) cannot tell them apart, the column (eq. 11) can."""
    scene = make_scene(entry=False)
    cam = scene.cameras["cam"]
    bg = texture(0)
    img = render(cam, bg, [(0.0, 3.0)], np.random.default_rng(0))
    F = StaticBackground(bg, 30.0, "colour").difference(img)
    inside = np.array([0.0, 3.0, 0.85])
    ray = inside - cam.centre
    behind = cam.centre + ray * (cam.centre[2] / -ray[2])               # where the ray meets the floor
    assert behind[2] == pytest.approx(0.0, abs=1e-9) and np.hypot(*(behind[:2] - inside[:2])) > 1.0
    np.testing.assert_allclose(cam.project([inside]), cam.project([behind]), atol=1e-6)

    point = CameraLikelihood(cam).point(thresholded_difference(F, 30.0), np.array([inside, behind]))[0]
    assert point[0] == point[1] > 0

    heights = np.arange(20) * 0.1
    counts, ratio, _, _ = CameraLikelihood(cam).column(hit_image(F, 30.0), np.array([inside[:2], behind[:2]]),
                                                       heights, 2.77, -1.56, 8)
    assert counts[0] >= 16 and counts[1] <= counts[0] - 6
    assert ratio[0] > ratio[1] + 10


# ---------------------------------------------------------------------------- tracking

def test_a_track_walking_behind_another_person_is_held():
    """One person stands 2.2 m from the camera, another walks across behind them at 4.2 m. Reading
    the near person's box as occlusion, the far track coasts through and is found again; reading
    it as background (the explaining away alone) pushes the far track off."""
    def paths(t):
        return [(0.0, 2.2), (-1.5 + 1.0 * t, 4.2)]

    worst = {}
    for occlusion in (True, False):
        scene = make_scene(entry=False)
        tracker, bgs = tracker_for(scene, births="none", occlusion=occlusion)
        tracker.init_track(0.0, 2.2, track_id=1)
        tracker.init_track(-1.5, 4.2, track_id=2)
        errors = []
        for _, truth, tracks in run(tracker, scene, bgs, paths, 31):
            far = {tr.id: tr for tr in tracks}.get(2)
            errors.append(np.inf if far is None else np.hypot(far.x - truth[1][0], far.y - truth[1][1]))
        worst[occlusion] = max(errors)
        if occlusion:
            assert np.mean(errors) < 0.2 and errors[-1] < 0.15
    assert worst[True] < 0.7 < 1.0 < worst[False]


def test_walker_is_tracked_within_bounds():
    scene = make_scene()
    tracker, bgs = tracker_for(scene)
    out = run(tracker, scene, bgs, walker, 40)
    ids = {tr.id for _, _, tracks in out for tr in tracks}
    assert ids == {1}
    first = next(k for k, (_, _, tracks) in enumerate(out) if tracks)
    assert first <= 3
    err, inside, vx = [], [], []
    for t, truth, tracks in out[first + 5:]:
        (tr,) = tracks
        x, y = truth[0]
        err.append(np.hypot(tr.x - x, tr.y - y))
        inside.append(abs(tr.x - x) <= tr.extra["sx"] + 0.02 and abs(tr.y - y) <= tr.extra["sy"] + 0.02
                      and abs(tr.extra["z"] - HEIGHT / 2) <= tr.extra["sz"])
        vx.append(tr.vx)
    assert np.mean(err) < 0.10 and np.max(err) < 0.25
    assert np.mean(inside) > 0.5
    # The region's floor size is at least the body's (a disc of the person's width: σ = width/4).
    assert tracks[0].extra["sx"] >= 0.25 * WIDTH and tracks[0].extra["sy"] >= 0.25 * WIDTH
    assert np.median(vx) == pytest.approx(1.0, abs=0.25)        # m/s, from real time stamps
    assert tracks[0].height == pytest.approx(HEIGHT, abs=0.25)


def test_detection_fires_on_entry_and_not_on_empty_frames():
    scene = make_scene()
    tracker, bgs = tracker_for(scene)
    empty = run(tracker, scene, bgs, lambda t: [], 15)
    assert all(not tracks for _, _, tracks in empty)
    rng = np.random.default_rng(5)
    found = None
    for k in range(15, 30):
        t = k / FPS
        img = render(scene.cameras["cam"], bgs["cam"], [(-2.3, 3.0)], rng)
        if tracker.step({"cam": img}, t):
            found = k
            break
    assert found is not None and found - 15 <= 3


def test_person_outside_the_entry_region_is_not_detected():
    scene = make_scene()
    tracker, bgs = tracker_for(scene)
    out = run(tracker, scene, bgs, lambda t: [(1.5, 3.0)], 15)
    assert all(not tracks for _, _, tracks in out)
    tracker, bgs = tracker_for(scene, births="anywhere")
    out = run(tracker, scene, bgs, lambda t: [(1.5, 3.0)], 15)
    assert out[-1][2] and np.hypot(out[-1][2][0].x - 1.5, out[-1][2][0].y - 3.0) < 0.15


def test_tracking_filter_ends_after_the_person_leaves():
    scene = make_scene()
    tracker, bgs = tracker_for(scene, end_after_s=0.0)
    out = run(tracker, scene, bgs, lambda t: [(-2.3 + 1.0 * t, 3.0)] if t < 2.0 else [], 30)
    assert out[19][2]
    assert all(not tracks for _, _, tracks in out[21:])


def test_people_entering_together_then_parting_get_two_tracks():
    """Two people come in side by side (0.5 m apart, across the line of sight), then walk apart."""
    scene = make_scene(entry=False)

    def pair(t):
        y = 5.5 - 0.8 * t
        s = 0.25 + max(0.0, t - 1.5) * 0.6
        return [(-s, y), (s, y)]

    tracker, bgs = tracker_for(scene)
    out = run(tracker, scene, bgs, pair, 45)
    t, truth, tracks = out[-1]
    assert len(tracks) == 2
    for x, y in truth:
        assert min(np.hypot(tr.x - x, tr.y - y) for tr in tracks) < 0.15
    assert len({tr.id for _, _, tr_ in out for tr in tr_}) == 2


def test_one_filter_on_two_people_is_split_when_they_part():
    scene = make_scene(entry=False)
    tracker, bgs = tracker_for(scene, births="none")

    def parting(t):
        s = 0.15 + 0.5 * t
        return [(-s, 3.0), (s, 3.0)]

    tracker.init_track(0.0, 3.0, spread=0.15)
    out = run(tracker, scene, bgs, parting, 25)
    t, truth, tracks = out[-1]
    assert len(tracks) == 2
    for x, y in truth:
        assert min(np.hypot(tr.x - x, tr.y - y) for tr in tracks) < 0.15


def test_duplicate_filters_on_one_person_are_merged():
    scene = make_scene(entry=False)
    tracker, bgs = tracker_for(scene, births="none", explain="detection")
    tracker.init_track(0.0, 3.0)
    tracker.init_track(0.1, 3.05)
    out = run(tracker, scene, bgs, lambda t: [(0.0, 3.0)], 8)
    assert [tr.id for tr in out[-1][2]] == [1]


def test_filters_one_behind_the_other_on_the_floor_are_merged_only_if_it_lasts():
    """Two filters whose image boxes overlap (0.86 of the smaller box here) are merged after
    ``merge_frames`` frames if they stand within ``merge_distance`` on the floor, else after
    ``merge_far_frames``: one camera's boxes also overlap while two people pass one behind the other.
    The merge ends the younger track."""
    scene = make_scene(entry=False)

    def frames_to_merge(second, **options):
        tracker, _ = tracker_for(scene, births="none", **options)
        tracker.init_track(0.0, 3.0)
        tracker.init_track(*second)
        for k in range(1, 12):
            tracker._merge()                 # the filters stay where they were put
            if len(tracker.filters) < 2:
                assert [f.track.id for f in tracker.filters] == [1]
                return k
        return None

    assert frames_to_merge((0.1, 3.3)) == 3                    # 0.32 m apart: one object
    assert frames_to_merge((0.1, 4.0)) == 6                    # 1.0 m apart: one behind the other
    assert frames_to_merge((0.1, 4.0), merge_far_frames=9) == 9
    assert frames_to_merge((0.1, 4.0), merge_distance=np.inf) == 3   # boxes alone (the former rule)
    assert frames_to_merge((1.0, 3.0)) is None                 # side by side: boxes apart
    # Beyond ``merge_depth`` from the camera the distance that counts as one object grows with it:
    # the pair stands 4 and 5 m from the camera, 1 m apart: one object when merge_depth is 2 m
    # (0.6 m × 4.5 / 2 = 1.35 m), still one behind the other when it is 4 m (0.6 m × 4.5 / 4 = 0.68 m).
    assert frames_to_merge((0.1, 4.0), merge_depth=2.0) == 3
    assert frames_to_merge((0.1, 4.0), merge_depth=4.0) == 6


def test_a_door_out_of_view_is_watched_where_its_floor_comes_into_view():
    """The only door is on floor the camera does not see (x < −6.2 at y = 3.8–4.8; the view's left
    edge is at x ≈ −4 there, more than ``entry_margin`` away). A person walks in from it along
    y = 4.3. The door's detection filter covers the floor in view next to the floor out of view
    near it (``entry_reach``), so the person gets a track soon after showing; without it the
    door is not watched at all, and the tracker says so."""
    d = {"name": "particle-test", "cameras": [CAM], "people": {"height": HEIGHT, "width": WIDTH},
         "floor": {"walkable": [{"outer": [[-7, 0.5], [3, 0.5], [3, 6.5], [-7, 6.5]]}]},
         "entry_regions": [{"name": "side", "polygon": [[-7, 3.8], [-6.2, 3.8], [-6.2, 4.8], [-7, 4.8]]}]}
    scene = scene_from_dict(d)
    cam = scene.cameras["cam"]

    def walker_from_side(t):
        return [(-6.6 + 1.0 * t, 4.3)]

    tracker, bgs = tracker_for(scene)
    side = [r for r in tracker.detectors if r.region.name == "side"]
    assert len(side) == 1
    cells = side[0].region
    j, i = np.nonzero(cells.raster.inside)
    xy = cells.origin + (np.column_stack([i, j]) + 0.5) * cells.raster.resolution
    assert np.all(tracker._in_view(xy))
    assert xy[:, 0].max() < -6.2 + 2.0 + 1.0 + 0.05              # within reach + margin of the door
    # Fully in view (feet and head in the image) from:
    shown = next(k for k in range(40) if all(cam.in_image(cam.project(
        np.array([[*walker_from_side(k / FPS)[0], z]])))[0] for z in (0.0, HEIGHT)))
    out = run(tracker, scene, bgs, walker_from_side, shown + 12)
    first = next(k for k, (_, _, tracks) in enumerate(out) if tracks)
    assert first <= shown + 5
    t, truth, tracks = out[-1]
    assert len(tracks) == 1 and np.hypot(tracks[0].x - truth[0][0], tracks[0].y - truth[0][1]) < 0.15
    with pytest.raises(InputError, match="no entry region of scene 'particle-test' is in view"):
        tracker_for(scene, entry_reach=0.0)


def test_same_seed_gives_the_same_tracks_and_another_seed_does_not():
    def tracks(seed):
        scene = make_scene()
        tracker, bgs = tracker_for(scene, seed=seed)
        return [(tr.id, tr.x, tr.y, tr.extra["sz"]) for _, _, trs in run(tracker, scene, bgs, walker, 12) for tr in trs]

    a, b, c = tracks(3), tracks(3), tracks(4)
    assert a == b and a != c


def test_two_cameras_multiply_likelihoods():
    scene = make_scene(cameras=(CAM, CAM2))
    tracker, bgs = tracker_for(scene, births="anywhere")
    out = run(tracker, scene, bgs, lambda t: [(0.5, 3.5)], 10)
    assert len(out[-1][2]) == 1 and np.hypot(out[-1][2][0].x - 0.5, out[-1][2][0].y - 3.5) < 0.1
    rng = np.random.default_rng(0)
    images = {cid: hit_image(StaticBackground(bgs[cid], 30.0, "colour").difference(
        render(cam, bgs[cid], [(0.5, 3.5)], rng)), 30.0) for cid, cam in scene.cameras.items()}
    xyz = np.column_stack([rng.uniform(-1, 2, 200), rng.uniform(2, 5, 200), np.zeros(200)])
    both = tracker.likelihood(xyz, images)[0]
    one = [tracker.likelihood(xyz, {cid: img})[0] for cid, img in images.items()]
    np.testing.assert_allclose(both, one[0] + one[1])


def test_short_objects_need_lower_height_limits():
    """A 0.6 m object (a small child): below the default min_height, tracked with lower limits."""
    scene = make_scene()
    child = lambda t: [(-2.3 + 0.5 * t, 3.0, 0.6)]
    tracker, bgs = tracker_for(scene)
    assert not any(tracks for _, _, tracks in run(tracker, scene, bgs, child, 12))
    tracker, bgs = tracker_for(scene, min_height=0.4, max_height=1.0, dz=0.05)
    out = run(tracker, scene, bgs, child, 12)
    (tr,) = out[-1][2]
    x, y, _ = out[-1][1][0]
    assert np.hypot(tr.x - x, tr.y - y) < 0.15 and tr.height == pytest.approx(0.6, abs=0.15)


def test_paper_preset_column_beats_point():
    """The method as published (weights ∝ count, line column, no extensions) against its baseline:
    both spread along the line of sight, the column much less (the paper's claim)."""
    scene = make_scene()
    bg = texture(0)
    err = {}
    for likelihood in ("column", "point"):
        tracker = make_tracker("particle", scene, {"cam": StaticBackground(bg, 30.0, "colour")}, preset="paper",
                               likelihood=likelihood)
        assert tracker.config.weighting == "count" and not tracker.config.split
        out = run(tracker, scene, {"cam": bg}, walker, 25)
        err[likelihood] = np.mean([np.hypot(trs[0].x - truth[0][0], trs[0].y - truth[0][1])
                                   for _, truth, trs in out[10:]])
    assert err["column"] < 0.7 and err["point"] > err["column"] + 0.4


# ---------------------------------------------------------------------------- pieces

def test_systematic_resampling_copies_floor_or_ceil_of_n_w():
    rng = np.random.default_rng(0)
    w = rng.random(50) ** 3
    idx = systematic_resample(w, 1000, rng)
    counts = np.bincount(idx, minlength=50)
    expected = 1000 * w / w.sum()
    assert np.all(counts >= np.floor(expected)) and np.all(counts <= np.ceil(expected))
    s = np.bincount(stratified_resample(w, 100000, rng), minlength=50)
    np.testing.assert_allclose(s / 100000, w / w.sum(), atol=0.003)


def test_resampling_rows_is_resampling_each_row():
    """F filters' weights as rows: each row resampled on its own, with the same random numbers as
    one call per row; the lookup is ``searchsorted(side="right")`` (zero weights never drawn)."""
    rng = np.random.default_rng(1)
    W = rng.random((6, 40)) ** 4
    W[:, ::3] = 0.0                                                     # ties in the cumulative weights
    W[2] = 0.0
    W[2, 7] = 1.0                                                       # one particle takes all
    for resample in (systematic_resample, stratified_resample):
        rows = resample(W, 40, np.random.default_rng(9))
        r = np.random.default_rng(9)
        np.testing.assert_array_equal(rows, [resample(w, 40, r) for w in W])
        assert rows.shape == (6, 40) and np.all(rows[2] == 7) and not np.any(rows % 3 == 0)
    u = (np.random.default_rng(2).random((6, 1)) + np.arange(40)) / 40
    c = np.cumsum(W, axis=1) / W.sum(axis=1, keepdims=True)
    expected = [np.minimum(np.searchsorted(cr, ur, side="right"), 39) for cr, ur in zip(c, u)]
    np.testing.assert_array_equal(systematic_resample(W, 40, np.random.default_rng(2)), expected)
    # A point on a cumulative weight falls after it (side="right"), past the last one stays in range.
    np.testing.assert_array_equal(_lookup(np.ones((1, 4)), np.array([[0.0, 0.25, 0.5, 0.75, 1.0]])),
                                  [[0, 1, 2, 3, 3]])


def test_splittable_is_the_first_test_of_bimodal_split():
    rng = np.random.default_rng(0)
    clouds = []
    for k in range(60):
        gap = rng.uniform(0.0, 0.8)
        n1 = int(rng.integers(50, 450))
        lumps = np.vstack([rng.normal([0, 0], rng.uniform(0.03, 0.15), (n1, 2)),
                           rng.normal([gap, 0], rng.uniform(0.03, 0.15), (500 - n1, 2))])
        clouds.append(lumps @ [[0.6, 0.8], [-0.8, 0.6]])                # along a slanted axis
    wide = splittable(np.array(clouds), 0.35, 0.2)
    split = np.array([bimodal_split(c, 0.35, 0.5, 0.2) is not None for c in clouds])
    assert wide.any() and not wide.all() and split.any()
    assert not np.any(split & ~wide)                                    # never rules out a split
    # Wide: the std along the principal axis is at least d·sqrt(m(1 − m)).
    sd = np.sqrt([np.linalg.eigvalsh(np.cov(c.T, bias=True))[-1] for c in clouds])
    bound = 0.35 * np.sqrt(0.2 * 0.8)
    clear = np.abs(sd - bound) > 1e-9
    np.testing.assert_array_equal(wide[clear], (sd >= bound)[clear])
    assert not splittable(np.zeros((2, 7, 2)), 0.35, 0.2).any()          # too few particles


def test_valley_kernel_agrees_with_reference():
    rng = np.random.default_rng(4)
    found = 0
    for k in range(300):
        gap = rng.uniform(0.0, 0.8)
        n1 = int(rng.integers(5, 400))
        s = np.concatenate([rng.normal(0.0, rng.uniform(0.03, 0.2), n1),
                            rng.normal(gap, rng.uniform(0.03, 0.2), 500 - n1)])
        lo = s.min()
        for args in ((0.04, 0.05, 0.35, 0.5), (0.02, 0.03, 0.2, 0.8)):
            a, b = _valley(s, lo, *args), _valley_reference(s, lo, *args)
            assert a == b
            found += a >= 0
    assert 50 < found < 550                  # both outcomes are exercised


def test_bimodal_split_finds_two_lumps_not_one_long_cloud():
    rng = np.random.default_rng(0)
    two = np.vstack([rng.normal([0, 0], 0.06, (250, 2)), rng.normal([0.6, 0], 0.06, (250, 2))])
    side = bimodal_split(two, 0.35, 0.5, 0.2)
    assert side is not None and side.sum() in range(230, 271)
    long = np.column_stack([rng.uniform(-0.4, 0.4, 500), rng.normal(0, 0.05, 500)])
    assert bimodal_split(long, 0.35, 0.5, 0.2) is None
    assert bimodal_split(rng.normal(0, 0.1, (500, 2)), 0.35, 0.5, 0.2) is None


def test_floor_region_samples_uniformly_inside():
    ring = np.array([[0, 0], [2, 0], [2, 1], [0, 1]], float)
    reg = FloorRegion.rasterise("r", (0, 2, 0, 1), 0.02, lambda xy: polygon_distance(xy, ring) == 0)
    pts = reg.sample(20000, np.random.default_rng(0))
    assert reg.contains(pts).all() and reg.area == pytest.approx(2.0, rel=0.01)
    assert np.mean(pts[:, 0] < 1) == pytest.approx(0.5, abs=0.02)
    np.testing.assert_allclose(polygon_distance([[3, 0.5], [1, 0.5], [1, -0.5]], ring), [1, 0, 0.5])


def test_hit_labels_set_darkened_background_apart():
    bg = texture(0)
    img = bg.copy()
    img[100:140, 50:100] = (bg[100:140, 50:100] * 0.7).astype(np.uint8)    # a shadow
    img[100:140, 200:250] = (40, 30, 200)                                   # an object
    hit = hit_labels(img, bg, 25.0)
    assert np.mean(hit[100:140, 50:100] == 2) > 0.95 and np.mean(hit[100:140, 200:250] == 1) > 0.95
    assert np.all(hit[:90] == 0)
    # Shadows nowhere: every pixel with F > γ reads object, exactly the labels without shadows.
    where = np.zeros((H, W), bool)
    assert np.array_equal(hit_labels(img, bg, 25.0, where=where), (hit != 0).astype(np.uint8))


def test_hit_labels_tell_shadows_from_grey_clothes_by_texture():
    """Both regions are the background darkened without a change of colour; only the shadow keeps
    the background's texture. Over a plain background the test cannot tell: no evidence."""
    bg = texture(0)
    rng = np.random.default_rng(5)
    # A strongly textured floor patch (grey-level σ ≈ 25) and a plain one.
    floor = np.clip(128 + 25 * rng.standard_normal((80, 80)), 0, 255)[..., None] * np.ones(3)
    bg[140:220, 20:100] = floor.astype(np.uint8)
    bg[140:220, 200:280] = 128
    img = bg.copy()
    img[150:210, 30:60] = (bg[150:210, 30:60] * 0.7).astype(np.uint8)       # shadow on texture
    img[150:210, 60:90] = (0.7 * floor[10:70, 40:70].mean()).astype(np.uint8)  # plain grey cloth on texture
    img[150:210, 210:270] = 90                                              # darker over a plain floor
    hit = hit_labels(img, bg, 25.0, shadow=0)
    inner = (slice(153, 207),)
    assert np.mean(hit[inner[0], 33:57] == 0) > 0.9           # shadow: background
    # Cloth: object (the rest are pixels where the random floor happens to match the cloth, F ≤ γ).
    assert np.mean(hit[inner[0], 63:87] == 1) > 0.8 and np.all(hit[inner[0], 63:87] != 2)
    assert np.mean(hit[inner[0], 213:267] == 2) > 0.9         # cannot tell: no evidence
    # Without the texture test both darkened regions on the textured floor were shadows.
    old = hit_labels(img, bg, 25.0, shadow=0, texture=False)
    assert np.mean(old[inner[0], 63:87] == 1) < 0.05


def test_image_box_covers_the_person():
    scene = make_scene()
    cam = scene.cameras["cam"]
    img = render(cam, np.zeros((H, W, 3), np.uint8), [(0.5, 3.0)], np.random.default_rng(0))
    ys, xs = np.nonzero(img.max(axis=2) > 100)
    u0, u1, v0, v1 = image_box(cam, 0.5, 3.0, WIDTH, HEIGHT, 0.0)
    assert u0 <= xs.min() + 1 and u1 >= xs.max() and v0 <= ys.min() + 1 and v1 >= ys.max()
    assert (u1 - u0) < 1.3 * (xs.max() - xs.min() + 1)


OVERHEAD = {"id": "cam", "image_size": [W, H], "position": [0, 2.999, 4], "look_at": [0, 3, 0], "hfov_deg": 70}


@pytest.mark.parametrize("spec", [CAM, dict(CAM, distortion=[-0.2, 0.05, 0.001, -0.002, 0.0]), OVERHEAD])
def test_box_kernel_agrees_with_image_boxes(spec):
    cam = make_scene(cameras=(spec,)).cameras["cam"]
    rng = np.random.default_rng(6)
    xy = np.column_stack([rng.uniform(-8, 8, 3000), rng.uniform(-4, 12, 3000)])   # in view, out, behind
    xy[:2] = cam.centre[:2]                                                      # at the camera's foot
    widths, heights = rng.uniform(0.3, 0.6, len(xy)), rng.uniform(1.0, 2.0, len(xy))
    cl = CameraLikelihood(cam)
    for margin, depth in ((0.0, 0.0), (0.05, 0.0), (0.05, 0.5)):
        plain = image_boxes(cam, xy, widths, heights, margin, depth)
        assert cl.boxes(xy, widths, heights, margin, depth) == plain
        assert 100 < sum(b is None for b in plain) < len(xy) - 100
        assert sum(b is not None and (b[0] == 0 or b[1] == W) for b in plain) > 50     # clipped at the edges
        assert plain[0] is not None or spec is not OVERHEAD                            # seen at the foot


def test_image_box_with_depth_covers_the_object_nearer_and_farther():
    cam = make_scene().cameras["cam"]
    for x, y in [(0.5, 3.0), (-2.0, 5.0), (2.5, 1.5)]:       # the last one cut by the image's edges
        along = (np.array([x, y]) - cam.centre[:2]) / np.hypot(x - cam.centre[0], y - cam.centre[1])
        near, mid, far = (image_box(cam, *(np.array([x, y]) + s * along), WIDTH, HEIGHT, 0.05) for s in (-0.5, 0, 0.5))
        deep = image_box(cam, x, y, WIDTH, HEIGHT, 0.05, depth=0.5)
        together = (min(near[0], mid[0], far[0]), max(near[1], mid[1], far[1]),
                    min(near[2], mid[2], far[2]), max(near[3], mid[3], far[3]))
        np.testing.assert_allclose(deep, together, atol=1)     # the three boxes together, to a pixel
        assert deep[3] - deep[2] > mid[3] - mid[2] + 10          # stretched along the line of sight


@pytest.mark.parametrize("bad", [dict(alpha=1.5), dict(beta=-0.1), dict(particles=0), dict(dz=0),
                                 dict(likelihood="blob"), dict(min_height=2.5), dict(resampling="multinomial"),
                                 dict(hit_rate_object=0.01), dict(births="lost"), dict(births="entry+anywhere"),
                                 dict(lost_radius=-1.0), dict(lost_hold_s=float("nan")), dict(merge_distance=0.0),
                                 dict(merge_distance=float("nan")), dict(merge_far_frames=0), dict(entry_reach=-1.0),
                                 dict(merge_depth=0.0), dict(merge_depth=float("nan")),
                                 dict(top_edge=-1.0), dict(top_edge_step=0.0), dict(top_edge_samples=-1)])
def test_bad_configuration_is_an_input_error(bad):
    with pytest.raises(InputError):
        ParticleConfig(**bad)


def test_user_mistakes_are_input_errors():
    scene = make_scene()
    fgs = {"cam": StaticBackground(texture(0), 30.0, "colour")}
    with pytest.raises(InputError):
        make_tracker("particle", scene, fgs, no_such_option=1)
    with pytest.raises(InputError):
        ParticleTracker(make_scene(entry=False), fgs, ParticleConfig(births="entry"))
    with pytest.raises(InputError, match="entry\\+lost"):
        ParticleTracker(make_scene(entry=False), fgs, ParticleConfig(births="entry+lost"))
    tracker = ParticleTracker(scene, fgs)
    with pytest.raises(InputError, match="mode must be 'tracking'"):
        tracker.init_track(0.0, 3.0, mode="capture")
    tracker.step({"cam": texture(0)}, 1.0)
    with pytest.raises(InputError):
        tracker.step({"cam": texture(0)}, 0.5)
    with pytest.raises(InputError):
        tracker.step({"cam": np.zeros((10, 10, 3), np.uint8)}, 2.0)


def test_tracks_csv_gets_the_object_region_columns(tmp_path):
    from worldtrack.io.sources import ArraySource
    from worldtrack.io.tracks import read_tracks
    from worldtrack.pipeline import run_tracking

    scene = make_scene()
    tracker, bgs = tracker_for(scene)
    rng = np.random.default_rng(0)
    images = [{"cam": render(scene.cameras["cam"], bgs["cam"], walker(k / FPS), rng)} for k in range(8)]
    run_tracking(scene, ArraySource(images, fps=FPS), tracker, tmp_path, write_video=False, progress=False)
    table = read_tracks(tmp_path / "tracks.csv")
    assert len(table) >= 5 and {"z", "sx", "sy", "sz", "sigma"} <= set(table.columns)
    assert np.all(table.column("sz") > 0)


def test_shadow_kernel_agrees_with_reference():
    from worldtrack.trackers.particle.likelihood import hit_labels_reference
    rng = np.random.default_rng(3)
    bg = texture(1)
    img = np.clip(bg * rng.uniform(0.4, 1.1, (H, W, 1)) + rng.normal(0, 6, (H, W, 3)), 0, 255).astype(np.uint8)
    where = rng.random((H, W)) < 0.7
    # Shadows possible only inside the image, or only at a corner: the texture test then works on
    # the candidates' box alone, and must agree with the reference's whole image.
    inner, corner = np.zeros((H, W), bool), np.zeros((H, W), bool)
    inner[60:150, 100:220] = True
    corner[:40, -50:] = True
    for w in (None, where, inner, corner):
        a = hit_labels(img, bg, 25.0, where=w)
        b = hit_labels_reference(img, bg, 25.0, where=w)
        np.testing.assert_array_equal(a, b)
        if w is inner:
            assert 0.1 < np.mean(a[inner] == 2) < 0.9 and np.all(a[~inner] != 2)
    a = hit_labels(img, bg, 25.0, where=where)
    assert all(0.1 < np.mean(a == v) < 0.9 for v in (0, 1, 2))
    # A 3-pixel strip of shadow in a plain dark object: the texture windows of its pixels reach
    # into the object, which a box cut to the strip alone would miss (all shadow, not 84 of 120).
    floor = np.clip(128 + 25 * rng.standard_normal((H, W)), 0, 255)[..., None].repeat(3, 2).astype(np.uint8)
    img = np.full_like(floor, 60)
    img[100:140, 100:103] = (floor[100:140, 100:103] * 0.7).astype(np.uint8)
    strip = np.zeros((H, W), bool)
    strip[100:140, 100:103] = True
    a = hit_labels(img, floor, 25.0, where=strip, shadow=0)
    np.testing.assert_array_equal(a, hit_labels_reference(img, floor, 25.0, where=strip, shadow=0))
    assert 0 < np.sum(a[strip] == 2) < np.sum(a[strip] == 0)


# ---------------------------------------------------------------------------- leaving through an exit

def _walks_out_and_waits(wait_until):
    """Walks left from x = −1 at 1 m/s out through the door region to the floor's edge (x = −3),
    stands at x = −2.85 until ``wait_until`` s, then is gone."""
    return lambda t: [(max(-1.0 - 1.0 * t, -2.85), 3.0)] if t < wait_until else []


def test_a_track_leaving_through_the_exit_ends_and_is_not_detected_again():
    # The object velocity: the person stops 0.15 m from the floor's edge, and the particles' own
    # velocities (velocity="state") slow down with them, so 0.3 s ahead may end short of the edge.
    scene = make_scene()
    tracks_by_frame = {}
    for name, options in (("exit", {}), ("no exit rule", {"exit_lookahead_s": 0.0}),
                          ("no hold", {"exit_hold_s": 0.0})):
        tracker, bgs = tracker_for(scene, velocity="object", **options)
        tracker.init_track(-1.0, 3.0)
        out = run(tracker, scene, bgs, _walks_out_and_waits(2.25), 35)
        tracks_by_frame[name] = [[tr.id for tr in tracks] for _, _, tracks in out]
    exit_, no_rule, no_hold = (tracks_by_frame[k] for k in ("exit", "no exit rule", "no hold"))
    # Followed through the door; ended near the floor's edge (x ≈ −2.7 at 1.7 s: 0.3 s ahead is off
    # the floor), and the person still standing there for 0.45 s is not detected as somebody new.
    assert exit_[16] == [1]
    last = max(k for k, ids in enumerate(exit_) if ids)
    assert 16 <= last <= 19
    assert all(not ids for ids in exit_[last + 1:])
    # Without the rule the filter stays on the person at the edge, past their last frame (22).
    assert no_rule[22] == [1]
    # Without the hold, the person at the edge is detected again as a new track.
    assert any(ids and ids[0] != 1 for ids in no_hold[last + 1:])


def test_exit_rule_needs_an_entry_region_and_outward_motion():
    scene = make_scene()
    tracker, _ = tracker_for(scene)
    tracker.init_track(-2.85, 3.0)
    tr = tracker.filters[0].track
    for (x, vx, vy), leaving in (((-2.85, -1.0, 0.0), True),    # in the door, walking off the edge
                                 ((-2.85, 1.0, 0.0), False),    # in the door, walking in
                                 ((-2.85, -0.2, 0.0), False),   # too slow to be walking out
                                 ((-2.5, -1.0, 0.0), False),    # 0.2 s ahead still on the floor
                                 ((2.85, 1.0, 0.0), False)):    # off the right edge, no entry region there
        tr.x, tr.vx, tr.vy = x, vx, vy
        assert tracker._left_through_exit([tr]).tolist() == [leaving], (x, vx, vy)
    tr.x, tr.vx = -2.85, -1.0
    assert tracker._left_through_exit([tr, tr]).tolist() == [True, True]      # several tracks at once
    paper = ParticleTracker(scene, tracker.foregrounds, ParticleConfig.paper())
    assert paper._left_through_exit([tr]).tolist() == [False]


def test_tracks_held_after_an_exit_are_forgotten_after_the_hold_even_without_detection():
    scene = make_scene()
    tracker, bgs = tracker_for(scene, births="none")
    tracker.init_track(-1.0, 3.0)
    out = run(tracker, scene, bgs, lambda t: [(-1.0 - 1.0 * t, 3.0)] if t < 1.95 else [], 21)
    assert not out[-1][2] and len(tracker._leaving) == 1      # ended at the edge, held
    for k in range(21, 29):                                   # 0.8 s later: past exit_hold_s
        tracker.step({"cam": bgs["cam"]}, k / FPS)
    assert tracker._leaving == []


# ---------------------------------------------------------------------------- lost tracks (births="entry+lost")

def _watches(tracker):
    return [d for d in tracker.detectors if d.until is not None]


def test_a_track_lost_mid_room_is_watched_there_for_lost_hold_s_and_not_after():
    scene = make_scene()
    tracker, bgs = tracker_for(scene, births="entry+lost", end_after_s=0.0, lost_radius=0.8, lost_hold_s=1.0)
    assert len(tracker.detectors) == 1 and not _watches(tracker)      # the door's
    tracker.init_track(1.0, 3.0)
    out = run(tracker, scene, bgs, lambda t: [(1.0, 3.0)] if t < 0.45 else [], 8)
    ended = next(k for k, (_, _, tracks) in enumerate(out) if not tracks)
    assert 5 <= ended <= 6                                            # ended by β once the person is gone
    (w,) = _watches(tracker)
    t_end = ended / FPS
    assert w.until == pytest.approx(t_end + 1.0)
    # The floor in view within lost_radius of the last position, and only there.
    last = out[ended - 1][2][0]
    assert np.hypot(last.x - 1.0, last.y - 3.0) < 0.15
    pts = w.region.sample(2000, np.random.default_rng(0))
    d = np.hypot(pts[:, 0] - last.x, pts[:, 1] - last.y)
    assert d.max() <= 0.8 + 0.05 * np.sqrt(2) and d.min() < 0.1 and w.region.area > 0.8 * np.pi * 0.8 ** 2
    assert tracker._in_view(pts).all() and w.region.contains([[1.0, 3.0]]).tolist() == [True]
    k = 8
    while k / FPS <= t_end + 1.0 + 1e-9:                              # kept for lost_hold_s ...
        tracker.step({"cam": bgs["cam"]}, k / FPS)
        assert len(_watches(tracker)) == 1, k
        k += 1
    tracker.step({"cam": bgs["cam"]}, k / FPS)                        # ... and none afterwards
    assert not _watches(tracker) and len(tracker.detectors) == 1


@pytest.mark.parametrize("births, same_id", [("entry+lost", True), ("entry+lost", False), ("entry", True)])
def test_a_lost_person_who_shows_again_nearby_is_found_with_entry_lost_only(births, same_id):
    """Gone from the image for 0.4 s mid-room, then standing 0.3 m from the track's last position:
    found again under the lost track's id (``lost_same_id``) or a new one."""
    scene = make_scene()
    tracker, bgs = tracker_for(scene, births=births, end_after_s=0.0, lost_same_id=same_id)
    tracker.init_track(1.0, 3.0)
    out = run(tracker, scene, bgs, lambda t: [(1.0, 3.0)] if t < 0.45 else [] if t < 0.85 else [(1.3, 3.0)], 16)
    assert not out[7][2]
    tracks = out[-1][2]
    if births == "entry":
        assert not tracks
        return
    assert len(tracks) == 1 and tracks[0].id == (1 if same_id else 2)
    assert np.hypot(tracks[0].x - 1.3, tracks[0].y - 3.0) < 0.15
    assert not _watches(tracker)                                       # the watch that found it is dropped


def test_no_watch_where_an_entry_region_already_watches_or_for_tracks_not_ended_by_beta():
    scene = make_scene()
    tracker, bgs = tracker_for(scene, births="entry+lost", end_after_s=0.0)
    tracker.init_track(-2.3, 3.0)                                     # in the door region, nobody there
    run(tracker, scene, bgs, lambda t: [], 3)
    assert not tracker.filters and not _watches(tracker)
    tracker, bgs = tracker_for(scene, births="entry+lost", velocity="object")   # as in the exit test
    tracker.init_track(-1.0, 3.0)                                     # leaves through the exit
    out = run(tracker, scene, bgs, _walks_out_and_waits(2.25), 22)
    assert not out[-1][2] and len(tracker._leaving) == 1 and not _watches(tracker)


def test_by_default_a_scene_with_entry_regions_watches_lost_tracks_and_the_paper_does_not():
    scene = make_scene()
    for cfg, watched in ((ParticleConfig(), True), (ParticleConfig.paper(), False)):
        tracker, bgs = tracker_for(scene, **{k: getattr(cfg, k) for k in ("births", "lost_hold_s", "lost_same_id")},
                                   end_after_s=0.0)
        tracker.init_track(1.0, 3.0)
        run(tracker, scene, bgs, lambda t: [(1.0, 3.0)] if t < 0.45 else [], 8)
        assert not tracker.filters and len(_watches(tracker)) == int(watched)
    tracker, _ = tracker_for(make_scene(entry=False))
    assert tracker._births == "anywhere"
