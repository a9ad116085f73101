"""The follower end to end on a short hard sequence: a look-alike cuts in, the white balance jumps."""

import numpy as np
import pytest

from worldtrack.errors import InputError
from worldtrack.eval.follow import counts, follow_labels, reacquisitions
from worldtrack.follow import FollowConfig, FollowTracker, frame_from_synth
from worldtrack.follow.observation import observation_from_boxes
from worldtrack.follow.planview import Candidates
from worldtrack.trackers.base import Frame


def follow(sc, bundles, preset="default", **overrides):
    tracker = FollowTracker(FollowConfig.preset(preset, **overrides), sc.scene)
    n = len(bundles)
    truth, vis, others = np.full((n, 2), np.nan), np.zeros(n), []
    reported, filtered, steps = np.full((n, 2), np.nan), np.zeros((n, 2)), []
    for b in bundles:
        people = {r["id"]: r for r in b.gt}
        truth[b.frame] = people[1]["x"], people[1]["y"]
        vis[b.frame] = people[1]["vis_robot"]
        others.append(np.array([[r["x"], r["y"]] for i, r in people.items() if i != 1]).reshape(-1, 2))
        step = tracker.follow(frame_from_synth(b), b.views["robot"].camera, start_xy=truth[0] if b.frame == 0 else None)
        if step.found:
            reported[b.frame] = step.measured
        filtered[b.frame] = step.xy
        steps.append(step)
    labels = follow_labels(truth, vis >= 0.5, reported, others)
    return labels, truth, vis, filtered, steps


def test_default_keeps_the_target_through_the_look_alike_and_the_gain_jumps(lookalike_cut_in):
    sc, bundles = lookalike_cut_in
    labels, truth, vis, filtered, steps = follow(sc, bundles)
    c = counts(labels[1:])
    assert c.b == 0 and c.recall >= 0.98
    times = np.arange(len(bundles)) / sc.fps
    occlusions = reacquisitions(labels, vis >= 0.5, np.ones(len(labels), bool), times)
    assert len(occlusions) == 2 and all(o.duration >= 0.6 and o.delay <= 0.5 for o in occlusions)
    found = labels == "A"
    assert np.sqrt(np.mean(np.sum((filtered[found] - truth[found]) ** 2, axis=1))) < 0.1
    # the white balance did jump, by up to 400 steps, while this went on
    gains = np.array([b.views["robot"].wb_gains for b in bundles])
    assert np.abs(np.diff(gains, axis=0)).sum(axis=1).max() > 150
    # the target's own D stays small, the others' large
    assert np.mean([s.D[s.chosen] for s in steps[1:] if s.found]) < 0.15


def test_colour_alone_loses_the_target_when_the_white_balance_jumps(lookalike_cut_in):
    sc, bundles = lookalike_cut_in
    labels = follow(sc, bundles, "colour-only")[0]
    assert counts(labels[1:]).recall < 0.3


def test_without_tracking_the_others_the_target_is_not_found_again_after_the_cut_in(lookalike_cut_in):
    sc, bundles = lookalike_cut_in
    labels = follow(sc, bundles, "default", track_others=False)[0]
    assert counts(labels[1:]).recall < 0.6


def test_start_needs_somebody_near_the_given_position_and_depth_of_the_image_size(lookalike_cut_in):
    sc, bundles = lookalike_cut_in
    b = bundles[0]
    tracker = FollowTracker(scene=sc.scene)
    with pytest.raises(InputError, match="nobody found within 1 m"):
        tracker.start(frame_from_synth(b), b.views["robot"].camera, (1.0, 11.0))
    frame = frame_from_synth(b)
    assert frame.meta["wb_gains"] == tuple(b.views["robot"].wb_gains) and frame.disparity is None
    bad = Frame(frame.image, frame.t, 0, frame.depth[:, :-2], meta=frame.meta)
    with pytest.raises(InputError, match="depth is 158x120 but the colour image is 160x120"):
        tracker.observe(bad, b.views["robot"].camera)
    with pytest.raises(InputError, match="start"):
        FollowTracker().step(frame, b.views["robot"].camera)


@pytest.mark.parametrize("preset, right", [("default", True), ("colour-only", False)])
def test_given_candidates_are_followed_through_a_crossing_of_look_alikes(preset, right):
    """Two people in the same clothes pass each other 0.6 m apart (boxes given, no depth): position
    keeps them apart, colour alone cannot."""
    cfg = FollowConfig.preset(preset)
    img = np.full((120, 200, 3), 120, np.uint8)
    tracker = FollowTracker(cfg)
    chosen_x = []
    for k in range(40):
        t = k / 10
        xy = np.array([[2.0 - t, 0.6], [-2.0 + t, 0.0]])            # they pass at t = 2 s; the target is 1
        u = 100 + 20 * xy[:, 0]
        boxes = np.column_stack([u - 8, np.full(2, 20.0), np.full(2, 16.0), np.full(2, 80.0)])
        frame = img.copy()
        for left in boxes[:, 0]:
            frame[20:100, int(left):int(left) + 16] = (40, 60, 160)
        obs = observation_from_boxes(frame, boxes, xy, (512, 512), cfg)
        step = tracker.start_with(obs, t, xy[1]) if k == 0 else tracker.step_with(obs, t)
        chosen_x.append(xy[step.chosen, 0] if step.found else np.nan)
    chosen_x = np.array(chosen_x)
    seen = np.isfinite(chosen_x)
    truth = -2.0 + np.arange(40) / 10
    if right:
        assert seen.sum() >= 39                   # only at t = 2 s, boxes on top of each other, is it hidden
        np.testing.assert_allclose(chosen_x[seen], truth[seen], atol=1e-9)   # always the target
    else:
        assert np.sum(np.abs(chosen_x[seen] - truth[seen]) > 1e-9) >= 5       # the other one, often


@pytest.mark.parametrize("until", [25, 32])
def test_a_person_appearing_in_front_of_the_target_as_it_vanishes_is_not_taken_for_it(until):
    """An occluder in the target's clothes steps in front of it (nearer the camera) and walks with
    it for 1.5 or 2.2 s: the target is hidden, the newcomer covers where it should be. Nobody is
    reported until the target is seen again, then the target is. Meanwhile it is reported hidden,
    and its prediction walks on at its speed (past ``COAST_S`` too: it is known to be behind them)."""
    from worldtrack.follow.silhouette import person_box
    from worldtrack.geometry.camera import Camera

    cam = Camera.look_at("c", 320, 240, position=(0, -6, 3), target=(0, 0, 0.8), hfov_deg=60)
    cfg = FollowConfig()
    tracker = FollowTracker(cfg)
    rng = np.random.default_rng(0)
    labels = []
    for k in range(until + 10):
        t = k / 10
        target = np.array([-1.5 + t, 0.0])
        occluder = target + [0.05, -0.5]
        people = [target, np.array([2.0, 2.0])]
        who = ["T", "O"]
        if 10 <= k < until:                               # the occluder in front; the target hidden
            people[0] = occluder
            who[0] = "X"
        boxes = []
        for xy in people:
            u0, v0, u1, v1 = person_box(cam, xy)
            boxes.append([u0, v0, u1 - u0, v1 - v0])
        boxes = np.array(boxes, float)
        img = np.full((240, 320, 3), 110, np.uint8)
        for left, top, w, h in boxes[np.argsort(boxes[:, 1] + boxes[:, 3])]:
            img[int(top):int(top + h), int(left):int(left + w)] = (40, 60, 160)
        img = np.clip(img + rng.normal(0, 2, img.shape), 0, 255).astype(np.uint8)
        obs = observation_from_boxes(img, boxes, np.array(people), (512, 512), cfg, cam)
        step = tracker.start_with(obs, t, target) if k == 0 else tracker.step_with(obs, t)
        labels.append(who[step.chosen] if step.found else ("h" if step.hidden else "-"))
        if k == until - 1:
            assert np.hypot(*step.velocity) > 0.9 and abs(step.xy[0] - target[0]) < 0.1
    assert "X" not in labels, "".join(labels)
    assert labels[:10].count("T") == 10 and labels[until:].count("T") >= 9, "".join(labels)
    assert labels[11:until].count("h") >= until - 13, "".join(labels)


@pytest.mark.parametrize("margin, recovers", [(0.4, True), (0.0, False)])
def test_a_wrong_pick_is_undone_when_the_target_shows_itself(margin, recovers):
    """The red target walks and vanishes; a person in red and (mostly) blue steps out 0.45 m ahead of where
    it should be and is taken for it (colour half right, position right). The target reappears
    0.3 s later 0.8 m behind, having turned back, and stands. The colour evidence kept open hands
    the target back within 0.4 s of its return; without it (margin 0) the follower stays on the
    wrong person, whom position favours."""
    cfg = FollowConfig(identity_margin=margin)
    tracker = FollowTracker(cfg)
    red, blue = (50, 70, 160), (160, 70, 50)
    labels = []
    for k in range(30):
        t = k / 10
        people, who = [], []
        if k < 10 or k >= 13:
            people.append([-1.0 + 0.5 * t if k < 10 else -0.85, 0.0])
            who.append("T")
        if k >= 10:
            people.append([-0.05, 0.0])
            who.append("X")
        xy = np.array(people)
        u = 100 + 60 * xy[:, 0]
        boxes = np.column_stack([u - 8, np.full(len(xy), 20.0), np.full(len(xy), 16.0), np.full(len(xy), 80.0)])
        frame = np.full((120, 200, 3), 120, np.uint8)
        for (left, *_), name in zip(boxes, who):
            frame[20:100, int(left):int(left) + 16] = red
            if name == "X":
                frame[45:100, int(left):int(left) + 16] = blue
        obs = observation_from_boxes(frame, boxes, xy, (512, 512), cfg)
        step = tracker.start_with(obs, t, xy[0]) if k == 0 else tracker.step_with(obs, t)
        labels.append(who[step.chosen] if step.found else ".")
    assert labels[:10] == ["T"] * 10 and "X" in labels[10:13], "".join(labels)   # the wrong pick
    if recovers:
        assert labels[17:] == ["T"] * 13, "".join(labels)
    else:
        assert "T" not in labels[12:], "".join(labels)


def _seen(cam, cfg, people, colours, tops, rng):
    """An observation of ``people`` (K, 2) standing in front of ``cam``: their image boxes painted in
    ``colours`` (K of (top half, bottom half) BGR), their candidates' highest points ``tops`` (K,) m."""
    from worldtrack.follow.silhouette import person_box

    boxes = []
    for xy in people:
        u0, v0, u1, v1 = person_box(cam, xy)
        boxes.append([u0, v0, u1 - u0, v1 - v0])
    boxes = np.array(boxes, float).reshape(-1, 4)
    img = np.full((240, 320, 3), 110, np.uint8)
    for (left, top, w, h), (upper, lower) in zip(boxes, colours):
        img[int(top):int(top + h / 2), int(left):int(left + w)] = upper
        img[int(top + h / 2):int(top + h), int(left):int(left + w)] = lower
    img = np.clip(img + rng.normal(0, 2, img.shape), 0, 255).astype(np.uint8)
    obs = observation_from_boxes(img, boxes, np.array(people, float).reshape(-1, 2), (512, 512), cfg, cam)
    c = obs.candidates
    obs.candidates = Candidates(c.xy, np.asarray(tops, float), c.area, c.extent, c.depth, c.labels, c.stride)
    return obs


@pytest.mark.parametrize("who", ["taller", "other colours"])
def test_a_lost_target_is_not_taken_for_a_taller_person_or_one_whose_colours_differ(who):
    """The red target (1.65 m) walks for 2.5 s and is lost. 1.7 s later (it no longer coasts) somebody
    stands where it is predicted: in its clothes but 0.2 m taller, or of its height in red and blue
    (colours that do not agree: after that long, position no longer tells, and D under the threshold
    would take anybody near). Nobody is reported while they are there; the target, back later, is."""
    from worldtrack.geometry.camera import Camera

    cam = Camera.look_at("c", 320, 240, position=(0, -6, 3), target=(0, 0, 0.8), hfov_deg=60)
    cfg = FollowConfig()
    tracker = FollowTracker(cfg)
    rng = np.random.default_rng(1)
    red, blue = (50, 70, 160), (160, 70, 50)
    stranger = ((red, red), 1.85) if who == "taller" else ((red, blue), 1.65)
    labels = []
    for k in range(70):
        t = k / 10
        if k < 25:
            people, colours, tops, names = [[-2.0 + 0.4 * t, 0.0]], [(red, red)], [1.65], ["T"]
        elif 42 <= k < 55:
            people, colours, tops, names = [tracker.x[:2] + [0.05, 0.0]], [stranger[0]], [stranger[1]], ["X"]
        elif k >= 58:
            people, colours, tops, names = [[-0.3, 0.2]], [(red, red)], [1.65], ["T"]
        else:
            people, colours, tops, names = [], [], [], []
        obs = _seen(cam, cfg, people, colours, tops, rng)
        step = tracker.start_with(obs, t, people[0]) if k == 0 else tracker.step_with(obs, t)
        labels.append(names[step.chosen] if step.found else ".")
    assert abs(tracker.height.value - 1.65) < 1e-6 and tracker.height.seen_s >= 2.0
    assert labels[:25] == ["T"] * 25 and "X" not in labels, "".join(labels)
    assert labels[59:] == ["T"] * 11, "".join(labels)


def test_a_piece_of_another_person_is_not_taken_for_the_lost_target():
    """A look-alike stands 0.7 m beside where the red target walks out of view. Near the camera a body is
    often seen as two candidates: 0.4 s after the target vanished the look-alike is, one piece 0.35 m
    nearer the target's prediction. Their own track holds the other piece, so this one is a piece of
    them, not the target (it was seen while the target was not); the target, back at 1.7 s, is followed."""
    from worldtrack.geometry.camera import Camera

    cam = Camera.look_at("c", 320, 240, position=(0, -6, 3), target=(0, 0, 0.8), hfov_deg=60)
    cfg = FollowConfig()
    tracker = FollowTracker(cfg)
    rng = np.random.default_rng(2)
    red = (50, 70, 160)
    still = np.array([0.0, 0.7])
    labels = []
    for k in range(25):
        t = k / 10
        people, names = [still], ["L"]
        if k < 10:
            people, names = [[-1.0 + 0.1 * k, 0.0], still], ["T", "L"]
        elif 14 <= k < 17:
            people, names = [still, still + [0.05, -0.35]], ["L", "P"]
        elif k >= 17:
            people, names = [[0.6 + 0.05 * (k - 17), 0.0], still], ["T", "L"]
        obs = _seen(cam, cfg, people, [(red, red)] * len(people), [np.nan] * len(people), rng)
        step = tracker.start_with(obs, t, people[0]) if k == 0 else tracker.step_with(obs, t)
        labels.append(names[step.chosen] if step.found else ".")
    assert labels[:10] == ["T"] * 10 and "P" not in labels and "L" not in labels, "".join(labels)
    assert labels[18:] == ["T"] * 7, "".join(labels)


def test_a_taller_person_is_not_taken_for_the_target_while_it_is_seen():
    """The red target (1.65 m) walks for 2.5 s (its height learnt). Then, from one frame to the next,
    the only candidate on its way is 0.2 m taller in its clothes: the target hidden behind somebody
    while they merge, or a swap during a close pass (closed-loop seed 35). The target was seen in the
    frame before, so only height tells; that candidate is not the target, seen or not."""
    from worldtrack.geometry.camera import Camera

    cam = Camera.look_at("c", 320, 240, position=(0, -6, 3), target=(0, 0, 0.8), hfov_deg=60)
    cfg = FollowConfig()
    tracker = FollowTracker(cfg)
    rng = np.random.default_rng(3)
    red = (50, 70, 160)
    labels = []
    for k in range(35):
        t = k / 10
        name, top = ("T", 1.65) if k < 25 else ("X", 1.85)
        obs = _seen(cam, cfg, [[-2.0 + 0.4 * t, 0.0]], [(red, red)], [top], rng)
        step = tracker.start_with(obs, t, [-2.0, 0.0]) if k == 0 else tracker.step_with(obs, t)
        labels.append(name if step.found else ".")
    assert labels[:25] == ["T"] * 25 and "X" not in labels, "".join(labels)


@pytest.mark.parametrize("after, recovers", [(3.0, True), (np.inf, False)])
def test_a_target_back_far_from_its_prediction_is_found_again_after_a_long_loss(after, recovers):
    """The red target walks right for 2.5 s and vanishes; 0.5 s later it comes back 3 m from where it
    was predicted (it turned round out of view) — beyond reach, so it is tracked as a stranger — and
    walks slowly across the view beside a person in blue. Once it has been unseen for
    ``reid_any_track_after`` (3 s) its track, whose colour fits the templates, may be the target:
    it is followed again from then on, and the person in blue never is. Without the rule (inf, as
    before) the target is never found again although it is in full view."""
    from worldtrack.geometry.camera import Camera

    cam = Camera.look_at("c", 320, 240, position=(0, -6, 3), target=(0, 0, 0.8), hfov_deg=60)
    cfg = FollowConfig(reid_any_track_after=after)
    tracker = FollowTracker(cfg)
    rng = np.random.default_rng(3)
    red, blue = (50, 70, 160), (160, 70, 50)
    labels = []
    for k in range(80):
        t = k / 10
        people, colours, names = [[-1.0, 1.5]], [(blue, blue)], ["B"]
        if k < 25:
            people, colours, names = [[-2.0 + 0.4 * t, 0.0]] + people, [(red, red)] + colours, ["T"] + names
        elif k >= 30:
            people, colours, names = [[2.0 - 0.2 * (t - 3.0), 1.0]] + people, [(red, red)] + colours, ["T"] + names
        obs = _seen(cam, cfg, people, colours, [np.nan] * len(people), rng)
        step = tracker.start_with(obs, t, people[0]) if k == 0 else tracker.step_with(obs, t)
        labels.append(names[step.chosen] if step.found else ".")
    text = "".join(labels)
    assert labels[:25] == ["T"] * 25 and "B" not in labels, text
    assert labels[30:54] == ["."] * 24, text               # back, but beyond reach: a stranger
    if recovers:
        assert labels[56:] == ["T"] * 24, text             # unseen 3 s at k = 55: its track may be it
    else:
        assert "T" not in labels[25:], text


@pytest.mark.parametrize("case", ["clearly", "not clearly", "off"])
def test_a_lost_target_held_by_another_track_is_taken_back_only_when_it_fits_clearly_better(case):
    """The red target walks for 2.5 s and is lost; a stranger in red and blue stands 3.8 m from where
    it is predicted (beyond the target's gate). At 4 s the stranger has gone and the target stands in
    their place, its lower half in another red (RBhat 0.23 against its templates, over ``reid_rbhat``
    0.1 here: painted colours give RBhat 0, 0.23 or 0.57): the stranger's track takes its candidate
    (position fits, half the colours too), and no default rule hands it back within 3 s. With
    ``reid_holder_margin`` 0.1 the templates fit it clearly better than the holder's own histogram
    does (0.23 + 0.1 < 0.52): it is the target again once within reach (2.2 s unseen). Not when it
    comes back in red and orange (0.57 against the templates, 0.56 against the holder)."""
    from worldtrack.geometry.camera import Camera

    cam = Camera.look_at("c", 320, 240, position=(0, -6, 3), target=(0, 0, 0.8), hfov_deg=60)
    cfg = FollowConfig(reid_rbhat=0.1, reid_holder_margin=np.inf if case == "off" else 0.1)
    tracker = FollowTracker(cfg)
    rng = np.random.default_rng(4)
    red, blue = (50, 70, 160), (160, 70, 50)
    back = (50, 100, 160) if case == "not clearly" else (60, 60, 210)
    there = np.array([3.0, 2.0])
    labels = []
    for k in range(54):
        t = k / 10
        if k < 25:
            people, colours, names = [[-2.0 + 0.4 * t, 0.0], there], [(red, red), (red, blue)], ["T", "B"]
        elif k < 40:
            people, colours, names = [there], [(red, blue)], ["B"]
        else:
            people, colours, names = [there + [0.05, 0.0]], [(red, back)], ["T"]
        obs = _seen(cam, cfg, people, colours, [np.nan] * len(people), rng)
        step = tracker.start_with(obs, t, people[0]) if k == 0 else tracker.step_with(obs, t)
        labels.append(names[step.chosen] if step.found else ".")
    assert labels[:25] == ["T"] * 25 and "B" not in labels, "".join(labels)
    if case == "clearly":
        assert labels[40:46] == ["."] * 6 and labels[47:] == ["T"] * 7, "".join(labels)
    else:
        assert labels[40:] == ["."] * 14, "".join(labels)


def test_a_held_candidate_counts_as_clearly_the_targets_only_against_its_holders_own_colours():
    """Histograms over 4 bins. The templates are bin 0. Track 2's own colour is bins 2-3, track 3's is
    bin 0. A bin-0 candidate held by track 2 fits the templates (RBhat 0) clearly better than its
    holder (1); the same held by track 3 fits its holder as well (0): not clearly. A candidate
    nobody holds is never counted, nor anything with the margin inf."""
    from worldtrack.follow.others import Others
    from worldtrack.follow.reid import held_by_another_clearly
    from worldtrack.follow.templates import Templates

    others = Others(4, 2.0, 0.08, 1.5)
    others.add(np.zeros((2, 2)), np.array([[0, 0, 0.5, 0.5], [1.0, 0, 0, 0]]), 0.0)
    templates = Templates(np.array([1.0, 0, 0, 0]), (1.0, 1.0))
    hists = np.array([[0.9, 0.1, 0, 0], [0.9, 0.1, 0, 0], [0.9, 0.1, 0, 0], [0, 0, 0.5, 0.5]])
    owner = np.array([2, 3, 0, 2])
    assert held_by_another_clearly(hists, owner, others, templates, 0.3).tolist() == [True, False, False, False]
    assert not held_by_another_clearly(hists, owner, others, templates, np.inf).any()
